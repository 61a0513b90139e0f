//! `cargo xtask ff --scene SCENE [--ff BACKEND] [--json] [--force]`: assembles the full
//! form-factor matrix of a scene with one backend and reports its closure and reciprocity, or
//! prints it as JSON (DESIGN §7).
//!
//! Assembling costs `n` column computations and `n²` entries of memory, so scenes of more than
//! [`MAX_PATCHES`] patches are refused unless `--force` is given.
//!
//! ## Cache of the `matrix` backend
//!
//! With `--ff matrix…` the assembled (and, with `rebalance=true`, rebalanced) matrix is written
//! to a cache file and loaded from it next time. The directory is `$RADIOSITY_CACHE_DIR` when
//! set, otherwise `target/ff-cache/` of the workspace this binary was built from (found from
//! the compile-time `CARGO_MANIFEST_DIR` of xtask, so it is the same whatever directory the
//! command runs in). A file is named by the xxh3 hash of its key, and the key itself is stored
//! inside the file and checked on load. The key holds the crate version, the scene name, the
//! patch count, a fingerprint of every patch's vertices (a glTF file edited in place keeps its
//! name, not its geometry) and the canonical backend argument. A file that is unreadable or
//! has another key is reported as a warning and replaced.

use crate::scene_report::{PreparedScene, prepare, print_warnings};
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use radiosity_core::ColumnSource;
use radiosity_ff::guard::MatrixFigures;
use radiosity_ff::matrix::RebalanceReport;
use radiosity_ff::{Backend, BackendSpec, StoredMatrix};
use radiosity_geom::Closure;
use serde::Serialize;
use serde::ser::{SerializeSeq, Serializer};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;
use xxhash_rust::xxh3::{Xxh3Default, xxh3_64};

/// Scenes with more patches are assembled only with `--force`.
pub const MAX_PATCHES: usize = 2000;

/// The environment variable that overrides the cache directory.
const CACHE_DIR_VAR: &str = "RADIOSITY_CACHE_DIR";

/// Arguments of `ff`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene: a built-in name with `:key=value` parameters, or a .gltf/.glb path.
    #[arg(long, value_name = "SCENE")]
    scene: String,
    /// The backend: analytic, hemicube, montecarlo or matrix, with `:key=value` parameters
    /// (for example `matrix:of=hemicube:res=64:rebalance=true`).
    #[arg(long = "ff", value_name = "BACKEND", default_value = "analytic")]
    ff: String,
    /// Print the patches, the matrix (rows), its row sums and reciprocity error as JSON.
    #[arg(long)]
    json: bool,
    /// Assemble the matrix even when the scene has more than 2000 patches.
    #[arg(long)]
    force: bool,
}

/// Where the matrix came from.
pub(crate) struct Obtained {
    pub(crate) matrix: StoredMatrix,
    /// Seconds to assemble (and rebalance) or load it.
    seconds: f64,
    /// Entries clamped while assembling; unknown when loaded from the cache.
    clamped: Option<u64>,
    /// Figures before rebalancing and what rebalancing did, when it was done now.
    rebalanced: Option<(MatrixFigures, RebalanceReport)>,
    cache: Option<CacheUse>,
}

/// How the cache was used.
#[derive(Serialize)]
struct CacheUse {
    path: PathBuf,
    /// Loaded from the file (otherwise assembled and written to it).
    loaded: bool,
    /// Why the file could not be written, if it could not.
    #[serde(skip_serializing_if = "Option::is_none")]
    write_error: Option<String>,
}

/// Runs `ff`.
pub fn run(args: &Args) -> Result<()> {
    let spec = BackendSpec::parse(&args.ff)?;
    let prepared = prepare(&args.scene)?;
    print_warnings(&prepared.report());
    let n = prepared.loaded.scene.len();
    if n > MAX_PATCHES && !args.force {
        bail!(
            "scene {} has {n} patches; the full matrix would have {} entries ({} as dense f32) — pass --force to \
             assemble it anyway",
            args.scene,
            n * n,
            human_bytes(4 * n * n)
        );
    }
    let obtained = obtain(&prepared, &spec)?;
    let figures = obtained.matrix.figures(&areas(&prepared));
    if args.json {
        print_json(&prepared, &spec, &obtained, &figures)
    } else {
        print!("{}", summary(&args.scene, &prepared, &spec, &obtained, &figures));
        Ok(())
    }
}

fn areas(prepared: &PreparedScene) -> Vec<f64> {
    prepared.loaded.scene.patches().iter().map(|p| p.area()).collect()
}

/// Assembles the matrix, or for `matrix` loads it from the cache.
pub(crate) fn obtain(prepared: &PreparedScene, spec: &BackendSpec) -> Result<Obtained> {
    let BackendSpec::Matrix { rebalance, .. } = spec else {
        let start = Instant::now();
        let (matrix, clamped, _) = assemble_stored(prepared, spec, false)?;
        let seconds = start.elapsed().as_secs_f64();
        return Ok(Obtained { matrix, seconds, clamped: Some(clamped), rebalanced: None, cache: None });
    };
    let key = cache_key(prepared, spec);
    let path = cache_dir().join(format!("ff-{:016x}.bin", xxh3_64(key.as_bytes())));
    let start = Instant::now();
    match std::fs::read(&path) {
        Ok(bytes) => match StoredMatrix::from_bytes(&bytes, &key) {
            Ok(matrix) => {
                let seconds = start.elapsed().as_secs_f64();
                let cache = Some(CacheUse { path, loaded: true, write_error: None });
                return Ok(Obtained { matrix, seconds, clamped: None, rebalanced: None, cache });
            }
            Err(e) => eprintln!("warning: replacing cache file {}: {e}", path.display()),
        },
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => eprintln!("warning: cannot read cache file {}: {e}", path.display()),
    }
    let start = Instant::now();
    let (matrix, clamped, rebalanced) = assemble_stored(prepared, spec, *rebalance)?;
    let seconds = start.elapsed().as_secs_f64();
    let write_error = write_atomically(&path, &matrix.to_bytes(&key)).err().map(|e| format!("{e:#}"));
    if let Some(e) = &write_error {
        eprintln!("warning: the matrix was not cached: {e}");
    }
    let cache = Some(CacheUse { path, loaded: false, write_error });
    Ok(Obtained { matrix, seconds, clamped: Some(clamped), rebalanced, cache })
}

/// What [`assemble_stored`] gives: the matrix, the entries clamped, and the figures before
/// rebalancing with what rebalancing did.
pub(crate) type Assembled = (StoredMatrix, u64, Option<(MatrixFigures, RebalanceReport)>);

/// Assembles the full matrix of the backend `spec` names (for `matrix:of=…`, of the backend
/// it stores), and rebalances it when asked, without the cache: the matrix, the entries clamped, and the figures before
/// rebalancing with what rebalancing did.
pub(crate) fn assemble_stored(prepared: &PreparedScene, spec: &BackendSpec, rebalance: bool) -> Result<Assembled> {
    let backend = Backend::columns(spec, prepared.ff_input());
    let mut matrix = assemble(&backend);
    let rebalanced = if rebalance {
        let area = areas(prepared);
        let before = matrix.figures(&area);
        let report = matrix.rebalance(&area, prepared.analysis.closure.value.is_closed())?;
        Some((before, report))
    } else {
        None
    };
    Ok((matrix, backend.clamped(), rebalanced))
}

/// The backend `spec` names, with a `matrix` assembled now (and rebalanced when asked), never
/// read from the cache: what runs that time or stress the assembly itself need.
pub(crate) fn fresh_backend<'p>(prepared: &'p PreparedScene, spec: &BackendSpec) -> Result<Backend<'p>> {
    Ok(match spec {
        BackendSpec::Matrix { rebalance, .. } => Backend::Matrix(assemble_stored(prepared, spec, *rebalance)?.0),
        _ => Backend::columns(spec, prepared.ff_input()),
    })
}

/// Assembles every column with a progress bar on stderr (hidden when stderr is not a
/// terminal).
fn assemble(source: &impl ColumnSource) -> StoredMatrix {
    let n = source.patch_count() as u64;
    let bar = if std::io::stderr().is_terminal() { ProgressBar::new(n) } else { ProgressBar::hidden() };
    if let Ok(style) = ProgressStyle::with_template("{prefix} [{bar:40}] {pos}/{len} columns, {elapsed} (eta {eta})") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix("assembling");
    let matrix = StoredMatrix::assemble(source, &|_| bar.inc(1));
    bar.finish_and_clear();
    matrix
}

/// The cache directory: `$RADIOSITY_CACHE_DIR`, or `target/ff-cache` of this workspace.
fn cache_dir() -> PathBuf {
    match std::env::var_os(CACHE_DIR_VAR) {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap_or(Path::new(".")).join("target").join("ff-cache"),
    }
}

/// Everything a stored matrix depends on, as one string.
fn cache_key(prepared: &PreparedScene, spec: &BackendSpec) -> String {
    let scene = &prepared.loaded.scene;
    let mut geometry = Xxh3Default::new();
    for p in scene.patches() {
        geometry.update(&(p.vertices().len() as u64).to_le_bytes());
        for v in p.vertices() {
            for c in v.to_array() {
                geometry.update(&c.to_bits().to_le_bytes());
            }
        }
    }
    format!(
        "radiosity {}; scene {}; {} patches; geometry {:016x}; backend {}",
        env!("CARGO_PKG_VERSION"),
        scene.name(),
        scene.len(),
        geometry.digest(),
        spec.canonical()
    )
}

/// Writes `bytes` to a temporary file beside `path`, then renames it, so that an interrupted
/// or concurrent run never leaves half a file under the final name.
fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    std::fs::write(&tmp, bytes).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("cannot rename {} to {}", tmp.display(), path.display()))
}

/// One patch in the JSON output.
#[derive(Serialize)]
struct PatchJson {
    id: usize,
    area: f64,
    centroid: [f64; 3],
}

/// The JSON output (DESIGN §7, plus a few keys saying how the matrix was obtained).
#[derive(Serialize)]
struct FfJson<'a> {
    scene: &'a str,
    backend: String,
    patches: Vec<PatchJson>,
    #[serde(rename = "F")]
    f: Rows<'a>,
    row_sums: Vec<f64>,
    max_reciprocity_error: f64,
    nonzeros: usize,
    storage: &'static str,
    clamped: Option<u64>,
    seconds: f64,
    cache: Option<&'a CacheUse>,
}

/// The matrix as rows of `f32` (the stored precision), written without building them.
struct Rows<'a>(&'a StoredMatrix);

/// Row `i` of the matrix.
struct Row<'a>(&'a StoredMatrix, usize);

impl Serialize for Rows<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut seq = serializer.serialize_seq(Some(self.0.len()))?;
        for i in 0..self.0.len() {
            seq.serialize_element(&Row(self.0, i))?;
        }
        seq.end()
    }
}

impl Serialize for Row<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut seq = serializer.serialize_seq(Some(self.0.len()))?;
        for j in 0..self.0.len() {
            seq.serialize_element(&(self.0.get(self.1, j) as f32))?;
        }
        seq.end()
    }
}

fn print_json(
    prepared: &PreparedScene,
    spec: &BackendSpec,
    obtained: &Obtained,
    figures: &MatrixFigures,
) -> Result<()> {
    let scene = &prepared.loaded.scene;
    let m = &obtained.matrix;
    let json = FfJson {
        scene: scene.name(),
        backend: spec.canonical(),
        patches: scene
            .patches()
            .iter()
            .enumerate()
            .map(|(id, p)| PatchJson { id, area: p.area(), centroid: p.centroid().to_array() })
            .collect(),
        f: Rows(m),
        row_sums: m.row_sums(),
        max_reciprocity_error: figures.max_reciprocity_error,
        nonzeros: m.nonzeros(),
        storage: m.storage().as_str(),
        clamped: obtained.clamped,
        seconds: obtained.seconds,
        cache: obtained.cache.as_ref(),
    };
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let written = serde_json::to_writer(&mut out, &json)
        .map_err(std::io::Error::from)
        .and_then(|()| writeln!(out))
        .and_then(|()| out.flush());
    match written {
        // A reader that stopped early (`| head`) is not an error of ours.
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        other => Ok(other?),
    }
}

fn summary(
    arg: &str,
    prepared: &PreparedScene,
    spec: &BackendSpec,
    obtained: &Obtained,
    figures: &MatrixFigures,
) -> String {
    let m = &obtained.matrix;
    let n = m.len();
    let closure = match prepared.analysis.closure.value {
        Closure::Closed { .. } => "closed: every row should sum to 1".to_string(),
        Closure::Open { escaped, sampled } => format!(
            "open ({:.2}% of sampled rays escape): rows sum to less than 1",
            100.0 * escaped as f64 / sampled.max(1) as f64
        ),
    };
    let mut out = format!("scene        {arg}: {n} patches, {closure}\n");
    out += &format!("backend      {}\n", spec.canonical());
    let rate = if obtained.seconds > 0.0 { n as f64 / obtained.seconds } else { f64::INFINITY };
    match &obtained.cache {
        Some(c) if c.loaded => {
            out += &format!("matrix       loaded from cache {} in {:.3} s\n", c.path.display(), obtained.seconds)
        }
        _ => {
            out += &format!(
                "matrix       assembled in {:.3} s ({rate:.0} columns/s on {} threads)\n",
                obtained.seconds,
                rayon::current_num_threads()
            );
            if let Some(c) = &obtained.cache {
                match &c.write_error {
                    None => out += &format!("cache        written to {}\n", c.path.display()),
                    Some(e) => out += &format!("cache        not written: {e}\n"),
                }
            }
        }
    }
    out += &format!(
        "storage      {} f32, {}; {} non-zeros ({:.1}% of {} entries)\n",
        m.storage(),
        human_bytes(m.bytes()),
        m.nonzeros(),
        100.0 * m.nonzeros() as f64 / (n * n).max(1) as f64,
        n * n
    );
    out += &format!(
        "row sums     min {:.6}  mean {:.6}  max {:.6}\n",
        figures.row_sum_min, figures.row_sum_mean, figures.row_sum_max
    );
    out += &format!("reciprocity  max relative error {:.3e}\n", figures.max_reciprocity_error);
    out += &match obtained.clamped {
        Some(c) => format!("clamped      {c} entries\n"),
        None => "clamped      not recorded (the matrix was loaded from the cache)\n".to_string(),
    };
    if let Some((before, r)) = &obtained.rebalanced {
        out += &format!(
            "rebalance    assembled: row sums min {:.6}  mean {:.6}  max {:.6}, reciprocity error {:.3e}\n",
            before.row_sum_min, before.row_sum_mean, before.row_sum_max, before.max_reciprocity_error
        );
        let s = &r.symmetrised;
        out += &format!(
            "             symmetrised A·F: row sums min {:.6}  mean {:.6}  max {:.6}, reciprocity error {:.3e}\n",
            s.row_sum_min, s.row_sum_mean, s.row_sum_max, s.max_reciprocity_error
        );
        out += &format!(
            "             symmetrising changed entries by at most {:.3e} ({:.3}% relative, mean {:.3}%), {} zeros filled\n",
            r.max_change,
            100.0 * r.max_relative_change,
            100.0 * r.mean_relative_change,
            r.filled
        );
        if r.rescaled {
            out += &format!(
                "             rows rescaled to sum to 1 by factors in [{:.6}, {:.6}], which breaks reciprocity again\n",
                r.scale_min, r.scale_max
            );
        } else {
            out += "             rows not rescaled (the scene is open)\n";
        }
    }
    out
}

/// `bytes` in B, KiB, MiB or GiB.
fn human_bytes(bytes: usize) -> String {
    let b = bytes as f64;
    match bytes {
        0..1024 => format!("{bytes} B"),
        1024..1_048_576 => format!("{:.1} KiB", b / 1024.0),
        1_048_576..1_073_741_824 => format!("{:.1} MiB", b / 1_048_576.0),
        _ => format!("{:.2} GiB", b / 1_073_741_824.0),
    }
}
