//! `cargo xtask ff --scene SCENE [--ff BACKEND] [--json] [--force]`: assembles the full
//! form-factor matrix of a scene with one backend and reports its closure and reciprocity, or
//! prints it as JSON (docs/cli.md, `ff`).
//!
//! Assembling costs `n` column computations and `n²` entries of memory, so scenes of more than
//! [`MAX_PATCHES`] patches are refused unless `--force` is given.
//!
//! With `--against BACKEND` the backend is not assembled: it is built, one product `F·x`
//! timed, and it is measured against the other backend ([`radiosity_eval::operator_distance`]):
//! `--rows` sampled rows, the transfer error `‖ρ (F − F̃) B̃‖ / ‖B̃‖` on them with `B̃` its own
//! exact solution (by GMRES over its product), and, up to [`SOLUTION_PATCHES`] patches,
//! `e_rms` between `B̃` and the other backend's exact solution (its stored matrix, cached like
//! a reference).
//!
//! With `--out FILE` the assembled matrix is also written for other programs
//! ([`radiosity_eval::exchange`]): `FILE.mtx` as Matrix Market, with the patches' areas,
//! emissions and reflectivities in `FILE.patches.mtx` beside it, or `FILE.npz` as NumPy's
//! archive with all of them (`scipy.sparse.load_npz` reads its `F`).
//!
//! With `--ff matrix…` the assembled (and, with `rebalance=true`, rebalanced) matrix is kept in
//! the cache ([`radiosity_eval::Cache`], `target/ff-cache/` or `$RADIOSITY_CACHE_DIR`) and
//! loaded from it next time; a file that is unreadable or has another key is reported as a
//! warning and replaced.

use crate::bars::Bars;
use crate::experiment::{cache, check_output_file, prepare};
use anyhow::{Result, bail};
use radiosity_core::LinearSystem;
use radiosity_eval::exchange::{self, Format, SparseColumns};
use radiosity_eval::{
    Lab, LabError, LabOptions, ObtainedMatrix, OperatorDistanceParams, Progress, ReferenceKind, obtain_matrix,
    operator_distance,
};
use radiosity_ff::guard::MatrixFigures;
use radiosity_ff::row_comparison::{compare_rows, sampled_rows};
use radiosity_ff::row_diagnosis::{RowDiagnosis, worst_rows};
use radiosity_ff::{BackendSpec, StoredMatrix};
use radiosity_geom::{Closure, PreparedScene};
use serde::Serialize;
use serde::ser::{SerializeSeq, Serializer};
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// Scenes with more patches are assembled only with `--force`.
pub const MAX_PATCHES: usize = 2000;
/// Rows listed with their cause.
const WORST_ROWS: usize = 5;

/// Arguments of `ff`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene: a built-in name with `:key=value` parameters, or a .gltf, .glb or .mgf path.
    #[arg(long, value_name = "SCENE")]
    scene: String,
    /// The backend, with `:key=value` parameters (for example
    /// `matrix:of=hemicube:res=64:rebalance=true`).
    #[arg(long = "ff", value_name = "BACKEND", default_value = "analytic", long_help = crate::experiment::backend_help())]
    ff: String,
    /// Print the patches, the matrix (rows), its row sums and reciprocity error as JSON.
    #[arg(long)]
    json: bool,
    /// Assemble the matrix even when the scene has more than 2000 patches.
    #[arg(long)]
    force: bool,
    /// Measure the backend against this one instead of assembling the matrix (any scene size):
    /// row sums and relative L1 distances on `--rows` sampled rows, the transfer error on them,
    /// and up to 15,000 patches the e_rms between the two systems' exact solutions.
    #[arg(long, value_name = "BACKEND")]
    against: Option<String>,
    /// Rows sampled for `--against`.
    #[arg(long, value_name = "N", default_value_t = 20)]
    rows: usize,
    /// Also write the system for other programs: `F.mtx` (Matrix Market, with the patches'
    /// areas, emissions and reflectivities in `F.patches.mtx`) or `system.npz` (NumPy, F as
    /// `scipy.sparse.load_npz` reads it, with `area`, `emission` and `reflectivity`).
    #[arg(long, value_name = "FILE", conflicts_with = "against")]
    out: Option<PathBuf>,
}

/// Runs `ff`.
pub fn run(args: &Args) -> Result<()> {
    let spec = BackendSpec::parse(&args.ff)?;
    let against = args.against.as_deref().map(BackendSpec::parse).transpose()?;
    if let Some(out) = &args.out {
        check_output_file(out)?;
        Format::of(out)?;
    }
    let prepared = prepare(&args.scene)?;
    if let Some(reference) = against {
        return compare(args, &prepared, &spec, &reference);
    }
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
    let obtained = obtain_matrix(&prepared, &spec, Some(&cache()), &Bars::new())?;
    let figures = obtained.matrix.figures(&areas(&prepared));
    let worst = worst_rows(prepared.scene(), &prepared.analysis, &obtained.matrix, WORST_ROWS);
    if let Some(out) = &args.out {
        let comments = [
            format!("form factors F of the scene {}, backend {}", args.scene, spec.canonical()),
            "the system (I - diag(rho) F) B = E, one per channel; A_i F_ij = A_j F_ji".to_string(),
        ];
        let system = LinearSystem::from_scene(prepared.scene());
        let written = exchange::write_files(out, &SparseColumns::of(&obtained.matrix), &system, &comments)?;
        eprintln!("wrote {}", written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(" and "));
    }
    if args.json {
        print_json(&prepared, &spec, &obtained, &figures, &worst)
    } else {
        print!("{}", summary(&args.scene, &prepared, &spec, &obtained, &figures, &worst));
        Ok(())
    }
}

/// `ff --against`: the backend built, one product timed, and sampled rows compared.
fn compare(args: &Args, prepared: &PreparedScene, spec: &BackendSpec, reference: &BackendSpec) -> Result<()> {
    if args.rows == 0 {
        bail!("--rows must be at least 1");
    }
    let n = prepared.scene().len();
    let start = Instant::now();
    let backend = radiosity_eval::backend(prepared, spec, Some(&cache()), &Bars::new())?;
    let built = start.elapsed().as_secs_f64();
    let truth = radiosity_eval::backend(prepared, reference, Some(&cache()), &Bars::new())?;
    let figures = backend.figures();
    let how = match &figures {
        Some(f) if f.loaded => format!("read from the cache in {built:.3} s (built in {:.3} s)", f.seconds),
        Some(f) if spec.argument().cache_kind().is_some() => {
            format!("built in {:.3} s, written to the cache in {:.3} s more", f.seconds, built - f.seconds)
        }
        _ => format!("built in {built:.3} s"),
    };
    let mut out = format!("scene        {}: {n} patches\nbackend      {} {how}\n", args.scene, spec.canonical());
    if let Some(f) = &figures {
        out += &format!("{:<12} {f}; {} held\n", spec.name(), human_bytes(f.bytes));
    }
    let x = vec![1.0; n];
    let mut y = vec![0.0; n];
    let start = Instant::now();
    let product = radiosity_core::operator::multiply(&backend, &x, 1, &mut y);
    let how = if product.native { "natively" } else { "column by column" };
    out += &format!("product      F·x in {:.3} s ({how})\n", start.elapsed().as_secs_f64());
    let rows = sampled_rows(n, args.rows, 0);
    print!("{out}");
    out = String::new();
    let distance = if prepared.analysis.emitters.value.is_empty() {
        None
    } else {
        let star = truth_solution(prepared, reference, n)?;
        let system = LinearSystem::from_scene(prepared.scene());
        let params = OperatorDistanceParams { rows: args.rows, ..OperatorDistanceParams::default() };
        let bars = Bars::new();
        bars.begin("solving the backend's system and comparing rows", 0, "");
        let distance = operator_distance(&system, &backend, &truth, star.as_ref().ok().map(Vec::as_slice), params);
        bars.end();
        Some((distance?, star))
    };
    let c = match &distance {
        Some((d, _)) => d.rows.clone(),
        None => compare_rows(&backend, &truth, &rows),
    };
    out += &format!(
        "against      {}: {} sampled rows (seed 0), relative L1 distance max {:.3e} mean {:.3e}, row sums differ by \
         at most {:.3e} (a sampled estimate, not a bound)\n",
        reference.canonical(),
        rows.len(),
        c.max_relative_l1,
        c.mean_relative_l1,
        c.max_sum_difference
    );
    for r in &c.rows {
        out += &format!(
            "   row {:>7}  sum {:.6}  reference {:.6}  relative L1 {:.3e}\n",
            r.row, r.sum, r.reference_sum, r.relative_l1
        );
    }
    if distance.is_none() {
        out += "solutions    none: nothing emits, so there is no solution to compare\n";
    }
    if let Some((d, star)) = &distance {
        let s = &d.solve;
        out += &format!(
            "transfer     ‖ρ (F − F̃) B̃‖ / ‖B̃‖ = {:.3e} on the sampled rows, B̃ the backend's exact solution (a sampled \
             estimate, not a bound)\n",
            d.transfer
        );
        out += &format!(
            "solve        B̃ by gmres-30 over the product: {} steps, residual {:.1e}{}, {:.3} s\n",
            s.steps,
            s.residual,
            if s.converged { "" } else { " (not converged)" },
            s.seconds
        );
        match (d.solution_e_rms, star) {
            (Some(e), _) => {
                out += &format!(
                    "solutions    e_rms {e:.3e} between B̃ and the exact solution of {}'s system (exact to the solves' \
                 tolerances)\n",
                    reference.canonical()
                )
            }
            (None, Err(why)) => out += &format!("solutions    not compared: {why}\n"),
            (None, Ok(_)) => {}
        }
    }
    print!("{out}");
    Ok(())
}

/// Patches up to which `ff --against` solves the truth's system exactly, by its stored matrix.
pub const SOLUTION_PATCHES: usize = 15_000;

/// The exact solution of `reference`'s system (its stored matrix, cached), or why not.
fn truth_solution(
    prepared: &PreparedScene,
    reference: &BackendSpec,
    n: usize,
) -> Result<std::result::Result<Vec<f64>, String>> {
    if n > SOLUTION_PATCHES {
        return Ok(Err(format!(
            "the scene has {n} patches, more than the {SOLUTION_PATCHES} whose matrix is assembled"
        )));
    }
    let options =
        LabOptions::default().with_cache(Some(cache())).with_reference(ReferenceKind::Matrix).with_residuals(false);
    match Lab::new(prepared, reference, options, &Bars::new()) {
        Ok(lab) => Ok(Ok(lab.reference().expect("a matrix reference was asked for").values().to_vec())),
        Err(LabError::Invalid(why)) => Ok(Err(why)),
        Err(e) => Err(e.into()),
    }
}

fn areas(prepared: &PreparedScene) -> Vec<f64> {
    prepared.loaded.scene.patches().iter().map(|p| p.area()).collect()
}

/// One patch in the JSON output.
#[derive(Serialize)]
struct PatchJson {
    id: usize,
    area: f64,
    centroid: [f64; 3],
}

/// The JSON output (docs/cli.md, `ff`: with a few keys saying how the matrix was obtained).
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
    cache: Option<&'a radiosity_eval::CacheUse>,
    worst_rows: &'a [RowDiagnosis],
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
    obtained: &ObtainedMatrix,
    figures: &MatrixFigures,
    worst: &[RowDiagnosis],
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
        worst_rows: worst,
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
    obtained: &ObtainedMatrix,
    figures: &MatrixFigures,
    worst: &[RowDiagnosis],
) -> String {
    let m = &obtained.matrix;
    let n = m.len();
    let closure = match prepared.analysis.closure.value {
        Closure::Closed { .. } => "closed: every row should sum to 1".to_string(),
        Closure::Open { escaped, sampled } => format!(
            "open ({:.2}% of sampled rays are lost): rows sum to less than 1",
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
    let g = &prepared.report().geometry;
    if g.hidden + g.touching + g.overlapping + g.covered + g.cut > 0 {
        out += &format!(
            "geometry     {} hidden patches left out, {} touching, {} overlapping coplanar patches left out and {} cut \
             (`scenes --explain` lists them)\n",
            g.hidden, g.touching, g.covered, g.cut
        );
    }
    match (worst.is_empty(), prepared.analysis.closure.value.is_closed()) {
        (true, false) => out += "worst rows   none above 1\n",
        (true, true) => {}
        (false, closed) => {
            out += &format!("worst rows   {}\n", if closed { "farthest from 1" } else { "farthest above 1" });
            for w in worst {
                out += &format!(
                    "  {:>9.6}  patch {} of '{}': {}, {}\n",
                    w.row_sum,
                    w.patch,
                    w.object,
                    w.cause.as_str(),
                    w.detail
                );
            }
        }
    }
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
