//! The laboratory: a prepared scene set up for measurement (its linear system, a form-factor
//! backend, F and the reference solution), running any [`Solver`] value under stop rules with
//! one recorder, and comparing many.
//!
//! ```no_run
//! use radiosity_eval::{Lab, LabOptions, NoProgress};
//! use radiosity_ff::BackendSpec;
//! use radiosity_solvers::{SolverRegistry, StopRules};
//!
//! let scene = radiosity_geom::PreparedScene::load("cornell:res=4")?;
//! let lab = Lab::new(&scene, &BackendSpec::parse("analytic")?, LabOptions::default(), &NoProgress)?;
//! let registry = SolverRegistry::builtin();
//! let solvers = vec![registry.build("pr")?, registry.build("xu-g30-m480")?];
//! let comparison = lab.compare(solvers, &StopRules::parse("columns=2n")?, &NoProgress)?;
//! comparison.write("results/my-study".as_ref())?;
//! print!("{}", comparison.summary());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## What is measured, and when
//!
//! The reference is obtained once, outside every run, as [`LabOptions::kind`] says
//! ([`crate::reference_kind`]): from the stored matrix (`matrix`), by a long shooting run
//! without a matrix (`shooting`), or not at all (`none`); `auto` takes the matrix when it fits
//! the memory budget. A run's columns, steps and seconds are the solver's alone. The
//! [`Recorder`] is an observer: the executor calls it between steps, outside the timed region.
//! After every step it computes e_rms against the reference (`O(n)`, when there is one) and the
//! certified bound on the displayed radiosity's relative L1 error from what the solver knows
//! without extra columns ([`SolverBound`], `O(n)`, with or without a reference); at about 100
//! points of a run and at `n/4`, `n/2`, `n` and `2n` columns it also computes, when the stored
//! matrix is kept, e_max and the residual power of the displayed radiosity (a product with F,
//! `O(nnz)`). Its own time is reported apart, as measurement.
//!
//! **The bound's hypothesis.** With a stored matrix the contraction `κ_c` is measured on it;
//! without one it is DESIGN §5's hypothesis, rows of F summing to at most 1 and F reciprocal,
//! so `κ_c ≤ ρ_max,c` ([`Contraction::assumed`]). The analytic backend is exactly reciprocal
//! and its rows sum to 1 within its stated accuracy.
//!
//! ## The reference cache
//!
//! With a [`Cache`], the reference solution is stored on disk with its certificate, under a key
//! of the scene ([`crate::cache::scene_key`]), the backend's label (for built-in backends, the
//! canonical argument with every parameter), a fingerprint of three of its columns (so that a
//! backend whose numbers change never reads an old entry), the reference's kind and parameters
//! and the format version, and read back next time. A lab that does not keep residuals
//! ([`LabOptions::residuals`] false: `solve`, `render`, `export`) then assembles no F at all
//! when the reference is in the cache, so a second run on a large scene starts at once; its
//! final residual is then the solver's own (for shooting methods that of the shot radiosity
//! `B − ΔB`, whose residual is `ΔB`), and [`FinalMetrics`] says which it has. Comparisons
//! keep the matrix whenever the reference is `matrix`, so their residual columns never
//! depend on the cache.

use crate::cache::{Cache, Lookup, scene_key};
use crate::error::LabError;
use crate::matrix::{F32Columns, FormFactors, StoredColumns};
use crate::certificate::{Contraction, SolverBound, relative_without_reference};
use crate::metrics::{Evaluator, errors, errors_against};
use crate::progress::Progress;
use crate::reference::{ReferenceParams, ReferenceSolution};
use crate::reference_kind::{MEMORY_VARIABLE, MemoryBudget, ReferenceKind, gib, matrix_bytes};
use crate::reference_shooting::{ShootingParams, solve_by_shooting};
use crate::table::TableRow;
use radiosity_core::{ColumnSource, LinearSystem, Real};
use radiosity_ff::{Backend, BackendSpec};
use radiosity_geom::{PreparedScene, SceneReport};
use radiosity_solvers::{
    Executor, Observer, Problem, Record, ResidualBound, Solver, State, StopRule, StopRules,
};
use std::sync::Arc;
use std::time::Instant;

/// How a lab is set up.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct LabOptions {
    /// Keep the stored matrix whenever the reference is `matrix`, so that recorded steps carry
    /// the residual of the displayed radiosity (default). Without it, the matrix is assembled
    /// only when the reference is not in the cache (and then kept, since it is there).
    pub residuals: bool,
    /// Where reference solutions (and stored matrices) are cached; none by default.
    pub cache: Option<Cache>,
    /// How a `matrix` reference is solved.
    pub reference: ReferenceParams,
    /// Which reference to measure against (default `auto`, [`crate::reference_kind`]).
    pub kind: ReferenceKind,
    /// How a `shooting` reference is run.
    pub shooting: ShootingParams,
    /// The memory a stored matrix may take; `None`: [`MemoryBudget::from_env`].
    pub memory: Option<MemoryBudget>,
    /// How solvers pay for their columns (default [`ColumnCost::Charged`]).
    pub columns: ColumnCost,
}

/// How a lab's solvers pay for the columns (and rows) of F they fetch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum ColumnCost {
    /// Every column is computed through the backend when a solver asks for it, and its time is
    /// the run's form-factor time.
    Computed,
    /// Where the lab keeps the stored matrix of a geometric backend (a `matrix` reference),
    /// solvers read their columns from it, the same `f32` entries the backend's columns give,
    /// and each column fetched is charged the backend's median time for a fresh column,
    /// measured once on a seeded sample ([`ColumnCharge`]). Elsewhere as `Computed`.
    #[default]
    Charged,
}

/// What each column a solver fetches is charged, when a lab serves columns from its stored
/// matrix ([`ColumnCost::Charged`]): the median time of a fresh column of the backend, one
/// column at a time (as solvers fetch them), over a seeded sample, measured with the
/// backend's memory of earlier columns forgotten first.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ColumnCharge {
    /// Seconds charged for each column or row fetched.
    pub seconds_per_column: Real,
    /// Columns timed.
    pub sampled: usize,
}

impl ColumnCharge {
    /// Columns timed to measure the charge.
    pub const SAMPLE: usize = 8;

    /// Times [`ColumnCharge::SAMPLE`] seeded fresh columns of `source` (fewer when it has
    /// fewer patches), one at a time, and takes the median.
    pub fn measure(source: &dyn ColumnSource) -> ColumnCharge {
        let n = source.patch_count();
        let sample = crate::bench::columns::sample(n, Self::SAMPLE.min(n), 0);
        source.reset_memory();
        let mut column = vec![0.0; n];
        let times: Vec<f64> = sample
            .iter()
            .map(|&j| {
                let start = Instant::now();
                source.fill_column(j, &mut column);
                start.elapsed().as_secs_f64()
            })
            .collect();
        source.reset_memory();
        ColumnCharge { seconds_per_column: crate::bench::median(&times), sampled: sample.len() }
    }

    /// The form-factor seconds of `columns` fetched.
    pub fn seconds(&self, columns: u64) -> Real {
        columns as Real * self.seconds_per_column
    }

    /// One sentence saying how a run's columns were paid for, for reports.
    pub fn describe(&self) -> String {
        format!(
            "columns read from the stored matrix, each charged {:.3} ms (median of {} fresh columns of the backend, one at a time)",
            self.seconds_per_column * 1e3,
            self.sampled
        )
    }
}

impl Default for LabOptions {
    fn default() -> Self {
        LabOptions {
            residuals: true,
            cache: None,
            reference: ReferenceParams::default(),
            kind: ReferenceKind::Auto,
            shooting: ShootingParams::default(),
            memory: None,
            columns: ColumnCost::default(),
        }
    }
}

impl LabOptions {
    /// Sets [`LabOptions::residuals`].
    pub fn with_residuals(mut self, residuals: bool) -> Self {
        self.residuals = residuals;
        self
    }

    /// Sets [`LabOptions::cache`].
    pub fn with_cache(mut self, cache: Option<Cache>) -> Self {
        self.cache = cache;
        self
    }

    /// Sets [`LabOptions::kind`].
    pub fn with_reference(mut self, kind: ReferenceKind) -> Self {
        self.kind = kind;
        self
    }

    /// Sets [`LabOptions::memory`].
    pub fn with_memory(mut self, memory: MemoryBudget) -> Self {
        self.memory = Some(memory);
        self
    }

    /// Sets [`LabOptions::columns`].
    pub fn with_columns(mut self, columns: ColumnCost) -> Self {
        self.columns = columns;
        self
    }

    /// Sets [`LabOptions::shooting`].
    pub fn with_shooting(mut self, shooting: ShootingParams) -> Self {
        self.shooting = shooting;
        self
    }
}

/// Where the reference came from.
#[derive(Clone, Debug, PartialEq)]
pub enum ReferenceOrigin {
    /// Solved now, after assembling the matrix (`matrix`), or by a long run (`shooting`, no
    /// assembly).
    Solved {
        /// Seconds to assemble the matrix (0 without one).
        assembly_seconds: Real,
        /// Seconds to solve once the matrix was assembled.
        solve_seconds: Real,
    },
    /// Read from the cache.
    Cached {
        /// The cache file.
        path: String,
        /// Seconds to read it.
        seconds: Real,
    },
    /// There is no reference (`none`).
    NotComputed,
}

/// The reference a lab measures against, once `auto` is decided, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct ChosenReference {
    /// `matrix`, `shooting` or `none`.
    pub kind: ReferenceKind,
    /// Why: asked for, or what `auto` weighed.
    pub why: String,
}

/// A prepared scene with everything solvers are measured against.
pub struct Lab<'p> {
    prepared: &'p PreparedScene,
    report: SceneReport,
    backend: String,
    system: LinearSystem,
    source: Box<dyn ColumnSource + 'p>,
    serves_rows: bool,
    matrix: Option<Arc<FormFactors>>,
    reference: Option<ReferenceSolution>,
    origin: ReferenceOrigin,
    chosen: ChosenReference,
    contraction: Contraction,
    order: Vec<usize>,
    charge: Option<ColumnCharge>,
}

/// How the matrix of a lab's source is obtained, when a `matrix` reference needs it.
enum Assembly<'s> {
    /// The backend is a stored matrix: it is the matrix.
    Stored(Arc<FormFactors>),
    /// Each unordered pair once (`F_rs` for the smaller patch `r`), the other by reciprocity.
    Reciprocal(&'s (dyn Fn(usize, usize) -> Real + Sync)),
    /// Column by column from the source.
    Columns,
}

/// What [`Lab::setup`] works out.
struct Setup {
    system: LinearSystem,
    matrix: Option<Arc<FormFactors>>,
    reference: Option<ReferenceSolution>,
    origin: ReferenceOrigin,
    chosen: ChosenReference,
    contraction: Contraction,
}

impl<'p> Lab<'p> {
    /// Builds the backend `spec` (a stored matrix from the options' cache when it is there),
    /// and sets the lab up with it. A `matrix` reference of the analytic backend is assembled
    /// by reciprocity (each pair once); of a stored matrix, it is that matrix.
    pub fn new(
        prepared: &'p PreparedScene,
        spec: &BackendSpec,
        options: LabOptions,
        progress: &dyn Progress,
    ) -> Result<Lab<'p>, LabError> {
        // Before the backend: a stored matrix would be assembled for nothing.
        require_emitters(prepared)?;
        let label = spec.canonical();
        let backend = crate::backends::backend(prepared, spec, options.cache.as_ref(), progress)?;
        let serves_rows = backend.serves_rows();
        match backend {
            Backend::Matrix(stored) => {
                let matrix = Arc::new(FormFactors::from_stored(stored));
                // The backend and the lab's matrix, held once.
                let source = matrix.clone();
                let setup = Lab::setup(prepared, &label, &source, Assembly::Stored(matrix), &options, progress)?;
                // The backend is the matrix: its columns cost what they cost.
                Ok(Lab::finish(prepared, &label, Box::new(source), serves_rows, setup, ColumnCost::Computed))
            }
            Backend::Analytic(analytic) => {
                let source = F32Columns(Backend::Analytic(analytic));
                let pair = |i: usize, j: usize| match &source.0 {
                    Backend::Analytic(a) => a.pair(i, j),
                    _ => unreachable!("built analytic above"),
                };
                let setup = Lab::setup(prepared, &label, &source, Assembly::Reciprocal(&pair), &options, progress)?;
                Ok(Lab::finish(prepared, &label, Box::new(source), serves_rows, setup, options.columns))
            }
            other => {
                let source = F32Columns(other);
                let setup = Lab::setup(prepared, &label, &source, Assembly::Columns, &options, progress)?;
                Ok(Lab::finish(prepared, &label, Box::new(source), serves_rows, setup, options.columns))
            }
        }
    }

    /// Sets a lab up with any column source, labelled `backend` in reports and in cache keys
    /// (which also hold a fingerprint of three of its columns, so an edited source is not
    /// taken for the old one). `serves_rows` says
    /// whether [`ColumnSource::fill_row`] gives exact rows of the matrix its columns assemble.
    /// Solvers read its columns rounded to `f32`, as a stored matrix holds them, so that a
    /// `matrix` reference solves exactly their system.
    pub fn with_source(
        prepared: &'p PreparedScene,
        backend: &str,
        source: Box<dyn ColumnSource + 'p>,
        serves_rows: bool,
        options: LabOptions,
        progress: &dyn Progress,
    ) -> Result<Lab<'p>, LabError> {
        require_emitters(prepared)?;
        let scene = prepared.scene();
        if source.patch_count() != scene.len() {
            return Err(LabError::Invalid(format!(
                "the form factors of '{backend}' have {} patches, the scene {}",
                source.patch_count(),
                scene.len()
            )));
        }
        let source = F32Columns(source);
        let setup = Lab::setup(prepared, backend, &source, Assembly::Columns, &options, progress)?;
        Ok(Lab::finish(prepared, backend, Box::new(source), serves_rows, setup, options.columns))
    }

    fn finish(
        prepared: &'p PreparedScene,
        backend: &str,
        source: Box<dyn ColumnSource + 'p>,
        serves_rows: bool,
        setup: Setup,
        columns: ColumnCost,
    ) -> Lab<'p> {
        let scene = prepared.scene();
        // Charged columns: the stored matrix serves them (exact rows too), at the backend's
        // measured price.
        let (source, charge) = match (&setup.matrix, columns) {
            (Some(matrix), ColumnCost::Charged) => {
                let charge = ColumnCharge::measure(&*source);
                let stored = StoredColumns {
                    matrix: matrix.clone(),
                    rows: serves_rows,
                    reciprocity: source.reciprocity_bound(),
                };
                (Box::new(stored) as Box<dyn ColumnSource + 'p>, Some(charge))
            }
            _ => (source, None),
        };
        Lab {
            prepared,
            report: prepared.report(),
            backend: backend.to_string(),
            system: setup.system,
            source,
            serves_rows,
            matrix: setup.matrix,
            reference: setup.reference,
            origin: setup.origin,
            chosen: setup.chosen,
            contraction: setup.contraction,
            order: radiosity_geom::spatial_order(scene),
            charge,
        }
    }

    /// Decides the reference (module doc of [`crate::reference_kind`]), reads it from the
    /// cache or computes it.
    fn setup(
        prepared: &PreparedScene,
        backend: &str,
        source: &dyn ColumnSource,
        assembly: Assembly<'_>,
        options: &LabOptions,
        progress: &dyn Progress,
    ) -> Result<Setup, LabError> {
        let scene = prepared.scene();
        let system = LinearSystem::from_scene(scene);
        let stored = match &assembly {
            Assembly::Stored(m) => Some(m.clone()),
            _ => None,
        };
        let chosen = choose(source, stored.is_some(), options)?;
        let none = |chosen| {
            let contraction = match &stored {
                Some(m) => Contraction::from_matrix(&system, m)?,
                None => Contraction::assumed(&system),
            };
            Ok::<_, LabError>(Setup {
                system: system.clone(),
                matrix: stored.clone(),
                reference: None,
                origin: ReferenceOrigin::NotComputed,
                chosen,
                contraction,
            })
        };
        if chosen.kind == ReferenceKind::None {
            return none(chosen);
        }
        let params = options.reference.clone();
        let kind = chosen.kind;
        // The key costs three columns: only worked out when there is a cache to look in.
        let key = match &options.cache {
            Some(_) => {
                let how = match kind {
                    ReferenceKind::Shooting => format!("shooting {:?}", options.shooting),
                    _ => format!("matrix {params:?}"),
                };
                format!(
                    "{}; backend {backend}; columns {:016x}; reference {how}",
                    scene_key(scene),
                    source_fingerprint(source)
                )
            }
            None => String::new(),
        };
        let start = Instant::now();
        let mut cached = None;
        if let Some(cache) = &options.cache {
            progress.begin("reading the reference", 0, "");
            match cache.read("reference", &key) {
                Lookup::Hit(bytes) => match ReferenceSolution::from_bytes(&bytes, &key, &system) {
                    Ok(r) => cached = Some(r),
                    Err(e) => progress.warn(&format!("replacing {}: {e}", cache.path("reference", &key).display())),
                },
                Lookup::Miss => {}
                Lookup::Unreadable(why) => progress.warn(&why),
            }
            progress.end();
        }
        let keep_matrix = kind == ReferenceKind::Matrix && (options.residuals || cached.is_none());
        let (matrix, assembly_seconds) = match (keep_matrix, assembly) {
            (false, _) => (stored, 0.0),
            (true, Assembly::Stored(m)) => (Some(m), 0.0),
            (true, Assembly::Reciprocal(pair)) => {
                let start = Instant::now();
                let m = assemble(&system, source, Some(pair), progress)?;
                (Some(Arc::new(m)), start.elapsed().as_secs_f64())
            }
            (true, Assembly::Columns) => {
                let start = Instant::now();
                let m = assemble(&system, source, None, progress)?;
                (Some(Arc::new(m)), start.elapsed().as_secs_f64())
            }
        };
        let (reference, origin) = match cached {
            Some(reference) => {
                let path = options.cache.as_ref().map(|c| c.path("reference", &key).display().to_string());
                (
                    reference,
                    ReferenceOrigin::Cached { path: path.unwrap_or_default(), seconds: start.elapsed().as_secs_f64() },
                )
            }
            None => {
                let solve_start = Instant::now();
                let reference = match &matrix {
                    Some(m) if kind == ReferenceKind::Matrix => {
                        progress.begin("reference (matrix)", 0, "");
                        let r = ReferenceSolution::solve_matrix(&system, m, params);
                        progress.end();
                        r?
                    }
                    _ => solve_by_shooting(&system, source, &options.shooting, progress)?,
                };
                if let Some(cache) = &options.cache {
                    if let Err(e) = cache.write("reference", &key, &reference.to_bytes(&key)) {
                        progress.warn(&format!("the reference was not cached: {e}"));
                    }
                }
                let solve_seconds = solve_start.elapsed().as_secs_f64();
                (reference, ReferenceOrigin::Solved { assembly_seconds, solve_seconds })
            }
        };
        let contraction = reference.certificate().contraction.clone();
        Ok(Setup { system, matrix, reference: Some(reference), origin, chosen, contraction })
    }

    /// The prepared scene.
    pub fn prepared(&self) -> &'p PreparedScene {
        self.prepared
    }

    /// The report of the scene.
    pub fn report(&self) -> &SceneReport {
        &self.report
    }

    /// The backend's label (for built-in backends, the canonical argument).
    pub fn backend(&self) -> &str {
        &self.backend
    }

    /// The linear system.
    pub fn system(&self) -> &LinearSystem {
        &self.system
    }

    /// The column source solvers read.
    pub fn source(&self) -> &dyn ColumnSource {
        &*self.source
    }

    /// What each column a solver fetches is charged, when the lab serves them from its stored
    /// matrix ([`ColumnCost::Charged`]); `None` when solvers compute their columns.
    pub fn charge(&self) -> Option<&ColumnCharge> {
        self.charge.as_ref()
    }

    /// The stored matrix, when it is kept ([`LabOptions::residuals`], assembled for the
    /// reference, or the backend itself).
    pub fn matrix(&self) -> Option<&FormFactors> {
        self.matrix.as_deref()
    }

    /// The exact solution of the same discrete system, unless the reference is `none`.
    pub fn reference(&self) -> Option<&ReferenceSolution> {
        self.reference.as_ref()
    }

    /// Where the reference came from.
    pub fn origin(&self) -> &ReferenceOrigin {
        &self.origin
    }

    /// The reference measured against, once `auto` is decided, and why.
    pub fn chosen(&self) -> &ChosenReference {
        &self.chosen
    }

    /// The contraction every certified bound of this lab rests on: measured on the stored
    /// matrix when there is one, DESIGN §5's hypothesis otherwise ([`Contraction::assumed`]).
    pub fn contraction(&self) -> &Contraction {
        &self.contraction
    }

    /// Measures against the reference with F, when both are kept; the contraction is the one
    /// measured on the same F.
    fn evaluator(&self) -> Result<Option<Evaluator<'_>>, LabError> {
        let (Some(m), Some(reference)) = (&self.matrix, &self.reference) else { return Ok(None) };
        Ok(Some(Evaluator::with_contraction(&self.system, m, reference, self.contraction.clone())?))
    }

    /// The number of patches.
    pub fn n(&self) -> usize {
        self.system.len()
    }

    /// Why `solver` will not converge to the reference on this source, if it will not: it
    /// gathers along rows the source cannot give exactly.
    pub fn row_warning(&self, solver: &dyn Solver) -> Option<String> {
        (solver.gathers_rows() && !self.serves_rows).then(|| {
            format!(
                "{} gathers along rows of F, which {} cannot give exactly; they are taken from its columns by \
                 reciprocity, which these form factors do not satisfy, so the run converges to another system's \
                 solution, off the reference by as much as their reciprocity error (`cargo xtask ff` reports it)",
                solver.name(),
                self.backend
            )
        })
    }

    /// Runs `solver` under `rules`, recording as `plan` says, reporting to `progress`.
    pub fn run(
        &self,
        solver: &mut dyn Solver,
        rules: &StopRules,
        plan: &RecordPlan,
        progress: &dyn Progress,
    ) -> Result<Outcome, LabError> {
        if let Some(w) = self.row_warning(solver) {
            progress.warn(&w);
        }
        let name = solver.name();
        let evaluator = self.evaluator()?;
        let (target, unit) = progress_target(rules, self.n());
        let n = self.n() as u64;
        let mut recorder = Recorder {
            system: &self.system,
            reference: self.reference.as_ref().map(|r| r.values()),
            contraction: Some(&self.contraction),
            known: None,
            clock: Instant::now(),
            evaluator: evaluator.as_ref(),
            solver: name.clone(),
            // A step that is a whole product by F is a sweep's worth of columns: every one is
            // recorded.
            every: plan.every.unwrap_or(if solver.step_is_sweep() { 1 } else { (target / 100).max(1) }),
            marks: if plan.marks { vec![n / 4, n / 2, n, 2 * n] } else { Vec::new() },
            points: Vec::new(),
            rows: Vec::new(),
            overhead: 0.0,
            progress: Some(progress),
            by_columns: unit == "columns",
            charge: self.charge,
        };
        progress.begin(&name, target, unit);
        // Every run starts from columns as costly as the first ones: what an earlier run left
        // in the source's memory (the analytic backend's visible fractions) would make later
        // solvers look faster.
        self.source.reset_memory();
        let problem = Problem::new(&self.system, &*self.source)?.with_patch_order(&self.order)?;
        let run = Executor::new(solver, rules.clone()).run(&problem, &mut recorder);
        progress.end();
        let mut run = run?;
        if let Some(charge) = self.charge {
            run.state.ff_seconds = charge.seconds(run.state.columns);
        }
        let solver_residual = solver.residual_power(&problem, &run.state);
        let known = solver.residual_bound(&problem, &run.state);
        let solver_bound =
            known.map(|k| SolverBound::new(&self.system, &self.contraction, &k, &run.state.radiosity).relative);
        let last = match (&evaluator, &self.reference) {
            (Some(e), _) => {
                let m = e.evaluate(&run.state.radiosity)?;
                let matrix_bound =
                    m.bound.certified.then(|| matrix_relative_bound(&self.system, &m, &run.state.radiosity));
                FinalMetrics {
                    e_rms: Some(m.e_rms),
                    e_max: Some(m.e_max),
                    residual: Some(m.residual),
                    bound: solver_bound.or(matrix_bound),
                    solver_residual,
                }
            }
            (None, Some(reference)) => {
                let e = errors(&self.system, reference, &run.state.radiosity)?;
                FinalMetrics {
                    e_rms: Some(e.e_rms),
                    e_max: Some(e.e_max),
                    residual: None,
                    bound: solver_bound,
                    solver_residual,
                }
            }
            (None, None) => {
                FinalMetrics { e_rms: None, e_max: None, residual: None, bound: solver_bound, solver_residual }
            }
        };
        Ok(Outcome {
            solver: run.solver,
            points: recorder.points,
            rows: recorder.rows,
            termination: run.termination.to_string(),
            record: run.record,
            overhead: recorder.overhead,
            last,
            state: run.state,
        })
    }

    /// The reference as a final state: its cost is assembling F (form-factor time) and
    /// solving it, or reading it from the cache. Fails when the reference is `none`.
    pub fn reference_state(&self) -> Result<State, LabError> {
        let reference = self.reference.as_ref().ok_or_else(no_reference)?;
        let mut state = State::from_emission(self.system.emissions(), self.system.channels().count());
        state.radiosity.copy_from_slice(reference.values());
        state.unshot.fill(0.0);
        state.columns = match reference.method() {
            crate::reference::Method::Shooting { columns, .. } => *columns,
            _ => self.system.len() as u64,
        };
        match self.origin {
            ReferenceOrigin::Solved { assembly_seconds, solve_seconds } => {
                state.ff_seconds = assembly_seconds;
                state.solve_seconds = solve_seconds;
            }
            ReferenceOrigin::Cached { seconds, .. } => state.solve_seconds = seconds,
            ReferenceOrigin::NotComputed => {}
        }
        Ok(state)
    }

    /// The metrics of the reference itself (zero error; its residual when F is kept, and its
    /// certificate's bound).
    pub fn reference_metrics(&self) -> Result<FinalMetrics, LabError> {
        let reference = self.reference.as_ref().ok_or_else(no_reference)?;
        let residual = match self.evaluator()? {
            Some(e) => Some(e.evaluate(reference.values())?),
            None => None,
        };
        let certificate = reference.certificate();
        Ok(FinalMetrics {
            e_rms: Some(0.0),
            e_max: Some(0.0),
            residual: residual.map(|m| m.residual),
            bound: certificate.certified.then_some(certificate.relative_bound),
            solver_residual: None,
        })
    }

    /// The RGB radiosity of every patch after running `solver` under `rules` (the reference
    /// when `solver` is `None`): what renders and exports show. An `rms=` rule is measured.
    pub fn radiosity_rgb(
        &self,
        solver: Option<&mut dyn Solver>,
        rules: &StopRules,
        progress: &dyn Progress,
    ) -> Result<Vec<[Real; 3]>, LabError> {
        let state = match solver {
            None => self.reference_state()?,
            Some(solver) => self.run(solver, rules, &RecordPlan::errors_only(), progress)?.state,
        };
        Ok(rgb(&state))
    }
}

/// The error of asking for the reference of a lab without one.
fn no_reference() -> LabError {
    LabError::Invalid("there is no reference solution with --reference none".into())
}

/// The F-based certified bound of `b` relative to `Σ A |B*|`, in the reference-free form of
/// [`SolverBound`] (so that it reads like the solver's own).
fn matrix_relative_bound(system: &LinearSystem, m: &crate::metrics::Metrics, b: &[Real]) -> Real {
    relative_without_reference(system, m.bound.bound, b, false)
}

/// Decides the reference: as asked, or for `auto` a stored backend's matrix, else `matrix`
/// when its estimated size fits the budget and `shooting` when it does not. An explicit
/// `matrix` that does not fit is refused before anything is assembled.
fn choose(source: &dyn ColumnSource, stored: bool, options: &LabOptions) -> Result<ChosenReference, LabError> {
    let asked = |kind| ChosenReference { kind, why: "asked for".into() };
    match options.kind {
        ReferenceKind::None => return Ok(asked(ReferenceKind::None)),
        ReferenceKind::Shooting => return Ok(asked(ReferenceKind::Shooting)),
        ReferenceKind::Matrix | ReferenceKind::Auto if stored => {
            let why = match options.kind {
                ReferenceKind::Auto => "auto: the backend is a stored matrix".to_string(),
                _ => "asked for; the backend is a stored matrix".to_string(),
            };
            return Ok(ChosenReference { kind: ReferenceKind::Matrix, why });
        }
        _ => {}
    }
    let budget = match &options.memory {
        Some(b) => b.clone(),
        None => MemoryBudget::from_env()?,
    };
    let (bytes, _) = matrix_bytes(source, budget.bytes);
    let fits = bytes <= budget.bytes;
    let n = source.patch_count();
    let weighed = format!("the matrix of {n} patches needs about {} of the {budget}", gib(bytes));
    match (options.kind, fits) {
        (ReferenceKind::Matrix, true) => {
            Ok(ChosenReference { kind: ReferenceKind::Matrix, why: format!("asked for; {weighed}") })
        }
        (ReferenceKind::Matrix, false) => Err(LabError::Invalid(format!(
            "--reference matrix: {weighed}; raise {MEMORY_VARIABLE} (e.g. {MEMORY_VARIABLE}=16G) or use --reference \
             shooting or none"
        ))),
        (_, true) => Ok(ChosenReference { kind: ReferenceKind::Matrix, why: format!("auto: {weighed}") }),
        (_, false) => Ok(ChosenReference {
            kind: ReferenceKind::Shooting,
            why: format!("auto: {weighed}, so a long shooting run stands in for it"),
        }),
    }
}

/// The xxh3 of three columns of `source` (the first, the middle and the last), bit for bit:
/// part of the reference's cache key, so that a backend whose numbers change (another build,
/// an edited source of one's own) never reads an entry computed by the old one.
fn source_fingerprint(source: &dyn ColumnSource) -> u64 {
    let n = source.patch_count();
    let mut column = vec![0.0; n];
    let mut bytes = Vec::with_capacity(3 * 8 * n);
    for j in [0, n / 2, n.saturating_sub(1)] {
        source.fill_column(j, &mut column);
        bytes.extend(column.iter().flat_map(|v| v.to_bits().to_le_bytes()));
    }
    crate::cache::checksum(&bytes)
}

/// Refuses a scene that emits nothing: its radiosity is zero everywhere, so there is no error
/// relative to the reference to measure.
pub fn require_emitters(prepared: &PreparedScene) -> Result<(), LabError> {
    if prepared.analysis.emitters.value.is_empty() {
        return Err(LabError::NoEmitters(prepared.scene().name().to_string()));
    }
    Ok(())
}

/// Assembles the stored matrix of `source` for a `matrix` reference: each pair once by
/// reciprocity when the backend can give single entries, column by column otherwise.
fn assemble(
    system: &LinearSystem,
    source: &dyn ColumnSource,
    pair: Option<&(dyn Fn(usize, usize) -> Real + Sync)>,
    progress: &dyn Progress,
) -> Result<FormFactors, LabError> {
    let (matrix, _) = crate::backends::assemble_matrix(system.areas(), source, pair, progress)?;
    Ok(FormFactors::from_stored(matrix))
}

/// The radiosity of every patch of `state` as RGB (a grey channel repeated three times).
pub fn rgb(state: &State) -> Vec<[Real; 3]> {
    let k = state.channels;
    state.radiosity.chunks_exact(k).map(|b| if k == 1 { [b[0]; 3] } else { [b[0], b[1], b[2]] }).collect()
}

/// The count a run's progress is measured against: its first `columns=` or `steps=` rule
/// (`2n` columns otherwise), and its unit.
fn progress_target(rules: &StopRules, n: usize) -> (u64, &'static str) {
    rules
        .rules
        .iter()
        .find_map(|r| match r {
            StopRule::Columns(c) => Some((c.resolve(n), "columns")),
            StopRule::Steps(c) => Some((c.resolve(n), "steps")),
            _ => None,
        })
        .unwrap_or((2 * n as u64, "columns"))
}

/// How often a run's metrics are recorded.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct RecordPlan {
    /// Every metric every this many steps (`None`: about 100 points over the run's budget, and
    /// every step of a solver whose step is a whole product by F, `Solver::step_is_sweep`).
    /// e_rms is recorded after every step regardless.
    pub every: Option<u64>,
    /// Also record every metric at `n/4`, `n/2`, `n` and `2n` columns.
    pub marks: bool,
}

impl Default for RecordPlan {
    fn default() -> Self {
        RecordPlan { every: None, marks: true }
    }
}

impl RecordPlan {
    /// Every metric every `steps` steps, and at the marks.
    pub fn every(steps: u64) -> RecordPlan {
        RecordPlan { every: Some(steps.max(1)), marks: true }
    }

    /// e_rms after every step, and every metric only on the initial state: the cheapest
    /// recording that still serves an `rms=` rule.
    pub fn errors_only() -> RecordPlan {
        RecordPlan { every: Some(u64::MAX), marks: false }
    }
}

/// One step of a run: where it stood, its e_rms and its certified bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Steps done.
    pub step: u64,
    /// Columns computed.
    pub columns: u64,
    /// The run's seconds so far (form factors and solving; measurement excluded).
    pub seconds: Real,
    /// Wall seconds since the recorder's clock started (for a lab's runs, when the run was
    /// set up), its own measuring taken out: the run's seconds and the executor's bookkeeping.
    pub wall: Real,
    /// e_rms against the reference (NaN without one).
    pub e_rms: Real,
    /// The certified bound on the displayed radiosity's area-weighted L1 error relative to the
    /// reference's, from what the solver knows without extra columns ([`SolverBound`]); NaN
    /// when the solver knows none.
    pub bound: Real,
}

/// The metrics of a run's final radiosity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FinalMetrics {
    /// e_rms against the reference, when there is one.
    pub e_rms: Option<Real>,
    /// e_max against the reference, when there is one.
    pub e_max: Option<Real>,
    /// The residual power of the displayed radiosity, when F is kept.
    pub residual: Option<Real>,
    /// The certified bound on its area-weighted L1 error relative to the reference's L1 norm:
    /// the solver's own ([`SolverBound`]), or from F's residual when the solver knows none and F
    /// is kept; `None` when neither is there.
    pub bound: Option<Real>,
    /// The residual power the solver knows without F (for shooting methods, that of the shot
    /// radiosity), when it knows one.
    pub solver_residual: Option<Real>,
}

/// Records e_rms and the certified bound after every step and every metric at planned steps
/// (module doc).
pub struct Recorder<'a> {
    system: &'a LinearSystem,
    /// The exact answer, patch-major like the system's vectors, when there is one.
    reference: Option<&'a [Real]>,
    /// The contraction the certified bound rests on; no bound without one.
    contraction: Option<&'a Contraction>,
    /// The solver's residual bound on the state about to be observed.
    known: Option<ResidualBound>,
    /// Where [`Point::wall`] counts from.
    clock: Instant,
    evaluator: Option<&'a Evaluator<'a>>,
    solver: String,
    every: u64,
    marks: Vec<u64>,
    points: Vec<Point>,
    rows: Vec<TableRow>,
    overhead: Real,
    /// Where each step is reported, if anywhere (no message is formatted otherwise).
    progress: Option<&'a dyn Progress>,
    by_columns: bool,
    /// The price of a column, when columns are charged rather than timed.
    charge: Option<ColumnCharge>,
}

impl<'a> Recorder<'a> {
    /// A recorder of e_rms after every step against `reference` (patch-major, like the
    /// system's vectors) and nothing else, for a caller with a reference of its own (read
    /// from a file, or a closed form); [`Point::wall`] counts from `clock`.
    pub fn errors(system: &'a LinearSystem, reference: &'a [Real], clock: Instant) -> Recorder<'a> {
        Recorder {
            system,
            reference: Some(reference),
            contraction: None,
            known: None,
            clock,
            evaluator: None,
            solver: String::new(),
            every: u64::MAX,
            marks: Vec::new(),
            points: Vec::new(),
            rows: Vec::new(),
            overhead: 0.0,
            progress: None,
            by_columns: true,
            charge: None,
        }
    }

    /// Also records the certified bound after every step, on `contraction` (measured on a
    /// stored matrix, or [`Contraction::assumed`]).
    pub fn with_bound(mut self, contraction: &'a Contraction) -> Recorder<'a> {
        self.contraction = Some(contraction);
        self
    }

    /// The points recorded so far.
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// Seconds spent measuring so far.
    pub fn overhead(&self) -> Real {
        self.overhead
    }
}

impl Observer for Recorder<'_> {
    fn observe_step(&mut self, state: &State) -> Option<Real> {
        let start = Instant::now();
        let errors = match self.reference {
            Some(reference) => Some(errors_against(self.system, reference, &state.radiosity).ok()?),
            None => None,
        };
        let e_rms = errors.map_or(Real::NAN, |e| e.e_rms);
        let bound = match (self.known.take(), self.contraction) {
            (Some(known), Some(c)) => SolverBound::new(self.system, c, &known, &state.radiosity).relative,
            _ => Real::NAN,
        };
        let ff_seconds = self.charge.map_or(state.ff_seconds, |c| c.seconds(state.columns));
        let seconds = ff_seconds + state.solve_seconds;
        let new_mark =
            self.marks.contains(&state.columns) && self.points.last().is_none_or(|p| p.columns != state.columns);
        if state.step % self.every == 0 || new_mark {
            let row = |e_max, residual, bound| TableRow {
                solver: self.solver.clone(),
                step: state.step,
                columns: state.columns,
                seconds,
                ff_seconds,
                e_rms,
                e_max,
                residual,
                bound,
            };
            match self.evaluator.map(|e| e.evaluate(&state.radiosity)) {
                Some(Ok(m)) => {
                    let fallback = if m.bound.certified {
                        matrix_relative_bound(self.system, &m, &state.radiosity)
                    } else {
                        Real::INFINITY
                    };
                    self.rows.push(row(m.e_max, m.residual, if bound.is_nan() { fallback } else { bound }))
                }
                Some(Err(_)) => {}
                None => self.rows.push(row(errors.map_or(Real::NAN, |e| e.e_max), Real::NAN, bound)),
            }
        }
        let wall = (start - self.clock).as_secs_f64() - self.overhead;
        self.points.push(Point { step: state.step, columns: state.columns, seconds, wall, e_rms, bound });
        if let Some(progress) = self.progress {
            let message = match (e_rms.is_nan(), bound.is_nan()) {
                (false, _) => format!("e_rms {e_rms:.2e}"),
                (true, false) => format!("bound {bound:.2e}"),
                (true, true) => String::new(),
            };
            progress.advance(if self.by_columns { state.columns } else { state.step }, &message);
        }
        self.overhead += start.elapsed().as_secs_f64();
        (!e_rms.is_nan()).then_some(e_rms)
    }

    fn measures_error(&self) -> bool {
        self.reference.is_some()
    }

    fn wants_residual_bound(&self) -> bool {
        self.contraction.is_some()
    }

    fn observe_residual_bound(&mut self, _state: &State, bound: Option<&ResidualBound>) {
        self.known = bound.cloned();
    }
}

/// What one run did and measured.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The solver's name.
    pub solver: String,
    /// e_rms after every step.
    pub points: Vec<Point>,
    /// Every metric at the planned steps.
    pub rows: Vec<TableRow>,
    /// The final state.
    pub state: State,
    /// Why the run ended.
    pub termination: String,
    /// The solver's own figures (group sizes, condition numbers, fallbacks).
    pub record: Record,
    /// Seconds spent measuring, outside the run.
    pub overhead: Real,
    /// The final radiosity's metrics.
    pub last: FinalMetrics,
}

impl Outcome {
    /// e_rms after `step` steps (the last point if the run ended before).
    pub fn at_step(&self, step: u64) -> Option<Real> {
        self.points.iter().take_while(|p| p.step <= step).last().map(|p| p.e_rms)
    }

    /// The columns computed after `step` steps.
    pub fn columns_at_step(&self, step: u64) -> Option<u64> {
        self.points.iter().take_while(|p| p.step <= step).last().map(|p| p.columns)
    }

    /// e_rms when `columns` columns had been computed (the first step there).
    pub fn at_columns(&self, columns: u64) -> Option<Real> {
        self.at_columns_point(columns).map(|p| p.e_rms)
    }

    /// The point where `columns` columns had been computed (the first step there).
    pub fn at_columns_point(&self, columns: u64) -> Option<Point> {
        self.points.iter().find(|p| p.columns >= columns).filter(|p| p.columns == columns).copied()
    }

    /// The first point whose certified bound is at or below `target`.
    pub fn bound_reached(&self, target: Real) -> Option<&Point> {
        self.points.iter().find(|p| p.bound <= target)
    }

    /// The first point at or below `target`.
    pub fn reached(&self, target: Real) -> Option<&Point> {
        self.points.iter().find(|p| p.e_rms <= target)
    }

    /// The points where e_rms first fell to each power of ten from 1e-1 down.
    pub fn reached_powers(&self) -> Vec<(Real, Point)> {
        let mut out = Vec::new();
        for k in 1..=15 {
            let target = 10f64.powi(-k);
            match self.reached(target) {
                Some(p) => out.push((target, *p)),
                None => break,
            }
        }
        out
    }

    /// The group-solve share of the run's time.
    pub fn group_share(&self) -> Real {
        let total = self.state.ff_seconds + self.state.solve_seconds;
        if total > 0.0 { self.state.group_seconds / total } else { 0.0 }
    }

    /// The run's own seconds: form factors and solving.
    pub fn seconds(&self) -> Real {
        self.state.ff_seconds + self.state.solve_seconds
    }
}
