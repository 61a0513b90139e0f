//! What the subcommands share: the `--scene --solver --ff --transport --until` arguments of
//! `solve`, `render` and `export`, checked before any geometry is built; loading a scene with
//! its warnings printed; the cache directory; and the checks on output paths.

use crate::bars::Bars;
use anyhow::{Result, bail};
use radiosity_eval::Phases;
use radiosity_eval::ReferenceKind;
use radiosity_eval::{Cache, ColumnCost, FinalMetrics, Lab, LabOptions, Progress, Transport};
use radiosity_ff::{BackendRegistry, BackendSpec};
use radiosity_geom::PreparedScene;
use radiosity_solvers::{Solver, SolverError, SolverRegistry, StopRules};
use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// The arguments that name one solved scene, shared by `solve`, `render` and `export`.
#[derive(Debug, clap::Args)]
pub struct SolveArgs {
    /// The scene: a built-in name with `:key=value` parameters, or a .gltf, .glb or .mgf path
    /// (`cargo xtask scenes` lists them).
    #[arg(long, value_name = "SCENE")]
    pub scene: String,
    /// The solver (`cargo xtask solve --help` lists every family), or reference for the exact
    /// solution.
    #[arg(long, value_name = "SOLVER", long_help = solver_help())]
    pub solver: String,
    /// The form-factor backend, with `:key=value` parameters.
    #[arg(long = "ff", value_name = "BACKEND", default_value = "analytic", long_help = backend_help())]
    pub ff: String,
    #[command(flatten)]
    pub transport: TransportArg,
    /// Stop rules, the first to hold stops the run: columns=N, columns=2n, steps=N, rays=1e7,
    /// rms=1e-3, residual=1e-4, time=30s.
    #[arg(long, value_name = "RULES", default_value = "columns=2n")]
    pub until: String,
    #[command(flatten)]
    pub reference: ReferenceArg,
}

/// `--transport scene|matrix`, shared by every command that takes `--ff` and runs solvers.
#[derive(Debug, clap::Args)]
pub struct TransportArg {
    /// Where the solvers that sample transport (stochastic-jacobi, random-walk) cast their
    /// rays: scene (through the scene's BVH, the exact geometry) or matrix (the stored matrix
    /// of a matrix reference, sampled exactly: the very system the reference solves). The
    /// other solvers ignore it.
    #[arg(long = "transport", value_name = "WHERE", default_value_t = Transport::default(), value_parser = parse_transport)]
    pub transport: Transport,
}

/// Reads `--transport` ([`Transport::name`]).
fn parse_transport(value: &str) -> Result<Transport, String> {
    value.parse().map_err(|e: radiosity_eval::EvalError| e.to_string())
}

/// `--reference auto|matrix|shooting|none`, shared by every command that measures.
#[derive(Debug, clap::Args)]
pub struct ReferenceArg {
    /// The reference to measure against: matrix (the stored matrix, certified to 1e-10),
    /// shooting (a long shooting run without a matrix, certified to 1e-8), none (no e_rms: the
    /// certified bound alone), or auto (matrix when it fits RADIOSITY_MEMORY, by default a
    /// quarter of the machine's memory; shooting otherwise).
    #[arg(long = "reference", value_name = "KIND", default_value = "auto")]
    pub kind: String,
}

impl ReferenceArg {
    /// The kind, checked.
    pub fn parse(&self) -> Result<ReferenceKind> {
        Ok(self.kind.parse()?)
    }
}

/// The `--solver` help: every family the registry builds.
fn solver_help() -> String {
    format!(
        "The solver, or `reference` for the exact solution. Every family, with examples:\n{}",
        SolverRegistry::builtin().help()
    )
}

/// What [`SolveArgs::check`] gives: the backend, the solver (`None` for the reference), the
/// stop rules and the reference's kind.
pub type Checked = (BackendSpec, Option<Box<dyn Solver>>, StopRules, ReferenceKind);

impl SolveArgs {
    /// Checks the backend, the solver (or `reference`) and the stop rules before any geometry
    /// is built, so a typo fails at once; gives the solver (`None` for the reference).
    pub fn check(&self) -> Result<Checked> {
        self.check_on(&crate::ranks::Ranks::default())
    }

    /// [`SolveArgs::check`] for a process that is one of `ranks` (the backend is its part).
    pub fn check_on(&self, ranks: &crate::ranks::Ranks) -> Result<Checked> {
        let spec = ranks.backend(&self.ff)?;
        let solver = match self.solver.as_str() {
            "reference" => None,
            name => Some(SolverRegistry::builtin().build(name).map_err(|e| match e {
                // `reference` is no solver of the registry's, but these commands take it.
                SolverError::UnknownSolver { suggestion: None, .. }
                    if radiosity_core::suggest::nearest(name, ["reference"]).is_some() =>
                {
                    anyhow::anyhow!("unknown solver '{name}' (did you mean 'reference', the exact solution?)")
                }
                e => e.into(),
            })?),
        };
        let kind = self.reference.parse()?;
        if solver.is_none() && kind == ReferenceKind::None {
            bail!("--solver reference needs a reference: use --reference auto, matrix or shooting, not none");
        }
        let rules = StopRules::parse(&self.until)?;
        check_measurable(&rules, kind)?;
        if let Some(solver) = &solver {
            radiosity_eval::check_rules(solver.as_ref(), &rules)?;
        }
        Ok((spec, solver, rules, kind))
    }
}

/// Refuses, before any work, an `rms=` rule that `--reference none` leaves nothing to measure.
pub fn check_measurable(rules: &StopRules, kind: ReferenceKind) -> Result<()> {
    if rules.needs_error() && kind == ReferenceKind::None {
        bail!("an rms= rule needs a reference to measure e_rms against, and --reference none computes none");
    }
    Ok(())
}

/// Loads and prepares a scene with a spinner for each stage, printing its load warnings (the
/// loaders name the file).
pub fn prepare(arg: &str) -> Result<PreparedScene> {
    prepare_over(arg, None, None)
}

/// As [`prepare`], each stage a phase of `phases` where given, the analysis's probes dealt to
/// `ranks` when this process is one of several (`PreparedScene::load_over`).
pub fn prepare_over(
    arg: &str,
    phases: Option<&RefCell<Phases>>,
    ranks: Option<&dyn radiosity_core::Collective>,
) -> Result<PreparedScene> {
    let bars = Bars::new();
    let stage = |stage: &str| {
        bars.end();
        bars.begin(stage, 0, "");
        if let Some(phases) = phases {
            phases.borrow_mut().begin(stage);
        }
    };
    let prepared = PreparedScene::load_over(arg, &stage, ranks);
    if let Some(phases) = phases {
        phases.borrow_mut().end();
    }
    bars.end();
    let prepared = prepared?;
    for w in &prepared.loaded.warnings {
        eprintln!("warning: {w}");
    }
    Ok(prepared)
}

/// The cache: `$RADIOSITY_CACHE_DIR`, or `target/ff-cache` of the workspace this binary was
/// built from (found from the compile-time `CARGO_MANIFEST_DIR` of xtask, so it is the same
/// whatever directory the command runs in).
pub fn cache() -> Cache {
    Cache::from_env(Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap_or(Path::new(".")).join("target/ff-cache"))
}

/// A lab on `prepared` with the backend `spec`, the cache, the reference `kind`, F kept when
/// `residuals`, columns paid for as `columns` says and rays cast as `transport` says, its
/// progress reported to `progress` (bars, or bars behind a [`radiosity_eval::ReferenceMark`]).
pub fn lab<'p>(
    prepared: &'p PreparedScene,
    spec: &BackendSpec,
    residuals: bool,
    kind: ReferenceKind,
    columns: ColumnCost,
    transport: Transport,
    progress: &dyn Progress,
) -> Result<Lab<'p>> {
    let options = LabOptions::default()
        .with_residuals(residuals)
        .with_cache(Some(cache()))
        .with_reference(kind)
        .with_columns(columns)
        .with_transport(transport);
    let lab = Lab::new(prepared, spec, options, progress)?;
    let chosen = lab.chosen();
    // Only the choice that costs a long run is announced; reports say which was used.
    if kind == ReferenceKind::Auto && chosen.kind == ReferenceKind::Shooting {
        eprintln!("reference: shooting ({})", chosen.why);
    }
    Ok(lab)
}

/// Checks, before any work, that `path` can be written as a file: it is not a folder, and the
/// folder it goes into is made (with its missing parents) and written to (docs/cli.md, "Output
/// paths"), so that a bad `--out` costs nothing.
pub fn check_output_file(path: &Path) -> Result<()> {
    if path.is_dir() {
        bail!("cannot write {}: it is a directory; --out names the file to write", path.display());
    }
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    writable_dir(parent).map_err(|why| anyhow::anyhow!("cannot write {}: {why}", path.display()))
}

/// Checks, before any work, that `dir` can hold a command's output: it is made (with its
/// missing parents) and written to (docs/cli.md, "Output paths").
pub fn check_out_dir(dir: &Path) -> Result<()> {
    writable_dir(dir).map_err(|why| anyhow::anyhow!("cannot write into the output folder {}: {why}", dir.display()))
}

/// Makes `dir` with its missing parents and writes and removes a probe file in it; why not,
/// as a clause.
fn writable_dir(dir: &Path) -> Result<(), String> {
    if let Some(file) = dir.ancestors().find(|a| !a.as_os_str().is_empty() && a.exists() && !a.is_dir()) {
        return Err(format!("{} is a file, not a folder", file.display()));
    }
    let reason = |e: std::io::Error| match e.kind() {
        std::io::ErrorKind::PermissionDenied => "permission denied".to_string(),
        std::io::ErrorKind::ReadOnlyFilesystem => "the file system is read-only".to_string(),
        std::io::ErrorKind::NotFound => "the folder cannot be made there".to_string(),
        _ => e.to_string(),
    };
    std::fs::create_dir_all(dir).map_err(reason)?;
    let probe = dir.join(format!(".radiosity-write-check-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(reason)?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// The folder name for a run: scene name (without parameters or path) and UTC date-time,
/// under `results/`.
pub fn default_out(scene: &str) -> PathBuf {
    let stem = Path::new(scene.split(':').next().unwrap_or(scene))
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let stamp = humantime::format_rfc3339_seconds(SystemTime::now()).to_string().replace(':', "-");
    PathBuf::from("results").join(format!("{stem}-{stamp}"))
}

/// The RGB radiosity of every patch of `prepared` solved as `args` say (the reference for
/// `reference`), and the backend's label: what `render` and export show. How the run ended
/// goes to stderr, with its certified bound; an `rms=` rule is measured against the
/// reference, so it stops the run. With `--reference auto` a run with no `rms=` rule
/// computes no reference.
pub fn solved_rgb(
    args: &SolveArgs,
    prepared: &PreparedScene,
    spec: &BackendSpec,
    solver: Option<Box<dyn Solver>>,
    rules: &StopRules,
    kind: ReferenceKind,
) -> Result<(Vec<[radiosity_core::Real; 3]>, String)> {
    // A picture needs no reference unless it is the reference, an rms= rule measures against
    // it or rays sample its matrix: `auto` then computes none, which on a large scene saves
    // the long shooting run that would stand in for a matrix that does not fit.
    let transport = args.transport.transport;
    let kind = match kind {
        ReferenceKind::Auto if solver.is_some() && !rules.needs_error() && transport != Transport::Matrix => {
            ReferenceKind::None
        }
        kind => kind,
    };
    // One solver's run: its columns are computed, whether or not the reference was cached.
    let lab = lab(prepared, spec, false, kind, ColumnCost::Computed, transport, &Bars::new())?;
    let rgb = match solver {
        None => lab.radiosity_rgb(None, rules, &Bars::new())?,
        Some(mut solver) => {
            let o = lab.run(solver.as_mut(), rules, &radiosity_eval::RecordPlan::errors_only(), &Bars::new())?;
            if let Some(note) = o.cap_note() {
                eprintln!("warning: {note}");
            }
            eprintln!(
                "{} stopped: {}; {} steps, {}, {:.3} s, {}",
                args.solver,
                o.termination,
                o.state.step,
                o.state.cost,
                o.seconds(),
                error_phrase(&o.last)
            );
            radiosity_eval::rgb(&o.state)
        }
    };
    Ok((rgb, lab.backend().to_string()))
}

/// The final error of a run in words: e_rms where there is a reference, the certified bound
/// where the solver knows one, and the standard error where the solver has one.
pub fn error_phrase(last: &FinalMetrics) -> String {
    let mut parts = Vec::new();
    if let Some(e) = last.e_rms {
        parts.push(format!("e_rms {e:.3e}"));
    }
    match last.bound {
        Some(b) => parts.push(format!("certified relative L1 bound {b:.3e}")),
        None => parts.push("no certified bound".into()),
    }
    if let Some(s) = last.standard_error {
        let replicates = last.replicates.map_or(String::new(), |r| format!(" of {r} replicates"));
        parts.push(format!("standard error {s:.3e}{replicates}"));
    }
    parts.join(", ")
}

/// The `--ff` help: every backend the registry parses, with its parameters.
pub fn backend_help() -> String {
    format!(
        "The form-factor backend, NAME[:key=value…] (for example `matrix:of=hemicube:res=64:rebalance=true`). \
         Every backend, with its parameters and their defaults:\n{}",
        BackendRegistry::builtin().help().trim_end()
    )
}

/// The camera a picture of `prepared` (the scene argument `scene`) starts from, for an image
/// of aspect `aspect`: `given` with the scene's up axis, or the default framing; with how it
/// was chosen and why its up axis is up.
pub fn start_camera(
    scene: &str,
    prepared: &PreparedScene,
    given: Option<radiosity_eval::Camera>,
    aspect: radiosity_core::Real,
) -> Result<(radiosity_eval::Camera, &'static str, String)> {
    let spec = radiosity_geom::SceneSpec::parse(scene)?;
    let (up, why) = radiosity_eval::up_axis(&spec, &prepared.loaded.scene);
    Ok(match given {
        Some(camera) => (camera.with_up(up), "as given", why.to_string()),
        None => {
            let framing = radiosity_eval::default_view(
                &spec,
                &prepared.loaded.scene,
                &prepared.visibility_for("framing the view")?,
                aspect,
            );
            let how = if framing.inside { "the default, inside the enclosure" } else { "the default, from outside" };
            (framing.camera, how, why.to_string())
        }
    })
}
