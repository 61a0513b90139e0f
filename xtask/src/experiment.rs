//! A scene set up for experiments: its linear system, form-factor backend, stored matrix and
//! reference solution, and running solvers on it. Shared by `solve`, `compare`, `render` and
//! `export`, so each measures and reports the same way.
//!
//! F is fetched once, outside every run, and serves both the reference and the metrics; a
//! run's columns, steps and seconds are the solver's alone.

use crate::ff::obtain;
use crate::scene_report::PreparedScene;
use anyhow::{Context, Result, bail};
use radiosity_core::{LinearSystem, Real};
use radiosity_eval::{FormFactors, ReferenceParams, ReferenceSolution};
use radiosity_ff::{Backend, BackendSpec};
use radiosity_solvers::{Executor, NoObserver, Observer, Problem, Run, SolverError, State, StopRules, solver_by_name};
use std::path::Path;
use std::time::Instant;

/// The arguments that name one solved scene, shared by `solve`, `render` and `export`.
#[derive(Debug, clap::Args)]
pub struct SolveArgs {
    /// The scene: a built-in name with `:key=value` parameters, or a .gltf/.glb path.
    #[arg(long, value_name = "SCENE")]
    pub scene: String,
    /// The solver: jacobi, gauss-seidel, sor-ω, southwell, pr, feda, shao, xu, xu-direct,
    /// xu-ambient, relax-ω; group-jacobi-gM, `group-gs-gM[:groups=spatial]` (group gathering);
    /// group-S-gM (group shooting); `S-gM[-mK][:f=N|:f=auto]` (group accelerated); reference
    /// (the exact solution).
    #[arg(long, value_name = "SOLVER")]
    pub solver: String,
    /// The form-factor backend, with `:key=value` parameters.
    #[arg(long = "ff", value_name = "BACKEND", default_value = "analytic")]
    pub ff: String,
    /// Stop rules, the first to hold stops the run: columns=N, columns=2n, steps=N, rms=1e-3,
    /// residual=1e-4, time=30s.
    #[arg(long, value_name = "RULES", default_value = "columns=2n")]
    pub until: String,
}

impl SolveArgs {
    /// Checks the backend, the solver (or `reference`) and the stop rules before any geometry
    /// is built, so a typo fails at once.
    pub fn check(&self) -> Result<(BackendSpec, StopRules)> {
        let spec = BackendSpec::parse(&self.ff)?;
        if self.solver != "reference" {
            solver_by_name(&self.solver).map_err(|e| solver_error(&e, "; or reference, the exact solution"))?;
        }
        Ok((spec, StopRules::parse(&self.until)?))
    }
}

/// The error for a solver name that `solver_by_name` refused (its message names the solver as
/// written). `list_end` is appended to the list of known solvers when the name is
/// unknown (`solve` also takes `reference`); other refusals (a parameter out of range) do not
/// get it, since the list is not what is wrong.
fn solver_error(e: &SolverError, list_end: &str) -> anyhow::Error {
    match e {
        SolverError::UnknownSolver { .. } => anyhow::anyhow!("{e}{list_end}"),
        _ => anyhow::anyhow!("{e}"),
    }
}

/// Checks, before any work, that `path` can be written as a file: it is not a directory and
/// the directory it goes into exists.
pub fn check_output_file(path: &Path) -> Result<()> {
    if path.is_dir() {
        bail!("cannot write {}: it is a directory; --out names the file to write", path.display());
    }
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        if parent.exists() && !parent.is_dir() {
            bail!("cannot write {}: {} is not a directory", path.display(), parent.display());
        }
        if !parent.exists() {
            bail!("cannot write {}: the directory {} does not exist", path.display(), parent.display());
        }
    }
    Ok(())
}

/// Refuses a scene that emits nothing before any form factor is computed: its radiosity is
/// zero everywhere, so there is no error relative to the reference to measure.
pub fn require_emitters(prepared: &PreparedScene) -> Result<()> {
    if prepared.analysis.emitters.value.is_empty() {
        bail!(
            "scene '{}' emits no light (no patch has an emission above 0), so its radiosity is zero everywhere and \
             there is no error to measure",
            prepared.loaded.scene.name()
        );
    }
    Ok(())
}

/// A prepared scene with everything solvers are measured against.
pub struct Experiment<'p> {
    /// The scene, its BVH and analysis.
    pub prepared: &'p PreparedScene,
    /// The form-factor backend as the user named it.
    pub spec: BackendSpec,
    /// The linear system.
    pub system: LinearSystem,
    /// Where solvers get their columns.
    pub backend: Backend<'p>,
    /// F, stored once for the reference and the metrics.
    pub matrix: FormFactors,
    /// The exact solution of the same discrete system.
    pub reference: ReferenceSolution,
    /// Seconds to assemble F.
    pub assembly_seconds: Real,
    /// Seconds to solve the reference once F was assembled.
    pub reference_seconds: Real,
    /// A spatially coherent patch order, for group gathering by space.
    order: Vec<usize>,
}

impl<'p> Experiment<'p> {
    /// Builds the backend `spec`, assembles F and solves the reference.
    pub fn new(prepared: &'p PreparedScene, spec: BackendSpec) -> Result<Experiment<'p>> {
        let scene = &prepared.loaded.scene;
        let system = LinearSystem::from_scene(scene);
        let backend = match spec {
            BackendSpec::Matrix { .. } => Backend::Matrix(obtain(prepared, &spec)?.matrix),
            _ => Backend::columns(&spec, prepared.ff_input()),
        };
        let params = ReferenceParams::default();
        let start = Instant::now();
        let matrix =
            FormFactors::assemble(&backend, params.max_matrix_bytes).context("the reference solution failed")?;
        let assembly_seconds = start.elapsed().as_secs_f64();
        let reference =
            ReferenceSolution::solve_matrix(&system, &matrix, params).context("the reference solution failed")?;
        let reference_seconds = start.elapsed().as_secs_f64() - assembly_seconds;
        let order = radiosity_geom::spatial_order::spatial_order(scene);
        Ok(Experiment {
            prepared,
            spec,
            system,
            backend,
            matrix,
            reference,
            assembly_seconds,
            reference_seconds,
            order,
        })
    }

    /// Runs solver `name` under `rules`, calling `observer` between steps. Warns when a
    /// gathering solver must take rows the backend cannot give exactly.
    pub fn run(&self, name: &str, rules: StopRules, observer: &mut dyn Observer) -> Result<Run> {
        let mut solver = solver_by_name(name)?;
        if solver.gathers_rows() && !self.backend.serves_rows() {
            eprintln!(
                "warning: {} gathers along rows of F, which {} cannot give exactly; they are taken from its \
                 columns by reciprocity, which these form factors do not satisfy, so the run converges to another \
                 system's solution, off the reference by as much as their reciprocity error (`cargo xtask ff` \
                 reports it)",
                solver.name(),
                self.spec.canonical()
            );
        }
        let problem = Problem::new(&self.system, &self.backend)?.with_patch_order(&self.order)?;
        Ok(Executor::new(solver.as_mut(), rules).run(&problem, observer)?)
    }

    /// The reference as a final state: its cost is assembling F (form-factor time) and
    /// solving it.
    pub fn exact_state(&self) -> State {
        let mut state = State::from_emission(self.system.emissions(), self.system.channels().count());
        state.radiosity.copy_from_slice(self.reference.values());
        state.unshot.fill(0.0);
        state.columns = self.system.len() as u64;
        state.ff_seconds = self.assembly_seconds;
        state.solve_seconds = self.reference_seconds;
        state
    }

    /// The RGB radiosity of every patch after running `solver` under `until` (`reference` for
    /// the exact solution): what `render` and `export` show.
    pub fn radiosity_rgb(&self, solver: &str, until: &str) -> Result<Vec<[Real; 3]>> {
        let state = if solver == "reference" {
            self.exact_state()
        } else {
            self.run(solver, StopRules::parse(until)?, &mut NoObserver)?.state
        };
        Ok(rgb(&state))
    }
}

/// The radiosity of every patch of `state` as RGB (a grey channel repeated three times).
pub fn rgb(state: &State) -> Vec<[Real; 3]> {
    let k = state.channels;
    state.radiosity.chunks_exact(k).map(|b| if k == 1 { [b[0]; 3] } else { [b[0], b[1], b[2]] }).collect()
}
