//! The stress suite: every solver on every form-factor backend over stiff and extreme scenes,
//! judged by certified error bounds, with what went wrong and why (`cargo xtask stress` prints
//! and writes it).
//!
//! ## The suite
//!
//! [`CASES`]: closed boxes with `ρ = 0.99` and `0.999`, channels with `ρ` of 0.99, 0.5 and 0,
//! a box inside a closed box at `ρ = 0.999`,
//! patch areas 1e6 apart, a tiny emitter of 1e6, a box touching the floor along its edges
//! and one 1e-6 above it, a thin slab, and one scene at coordinate scales 1e-4 and 1e4 (the
//! scenes are `furnace` and `inner-box`, whose module docs describe them). Each runs on
//! [`BACKENDS`]: `analytic`, the same with every row rescaled to sum to 1 in `f64` (closed
//! scenes only, see [`FormFactors::close_rows`]), `hemicube`, `montecarlo` and
//! `matrix:rebalance=true`. Every solver of `POINT_SOLVERS`, `GROUP_SOLVERS`,
//! `BEYOND_PAPER_SOLVERS` and `KRYLOV_SOLVERS` runs on each (`cg` refuses, in one sentence,
//! the backends that state no reciprocity bound or one above its limit).
//!
//! ## How a run is judged
//!
//! F is assembled once per scene and backend, and every solver reads its columns (and exact
//! rows) from it, so the suite measures solvers on one system and takes seconds. A run stops
//! at residual power 1e-13, at round-off, on divergence (the executor's rule), or after
//! [`STEP_CAP`]`·n` steps. Then:
//!
//! - **converged** means the *certified* bound on the final radiosity's relative L1 error,
//!   `Σ A|r| / (1 − q)` over `Σ A|B|` (DESIGN §5, `radiosity_eval::metrics`), is at most
//!   [`CONVERGED`]; no claim rests on the change between iterates or on the solver's own
//!   estimate. Where `q ≥ 1` (ρ times some row sum of F reaches 1) nothing is certifiable;
//! - the **exact answer** is the furnace identity `E / (1 − ρ)` where the scene is closed and
//!   uniform, otherwise the reference solution of the same system; both errors are kept;
//! - columns to reach e_rms 1e-3 and 1e-6 are counted against the reference;
//! - non-finite values stop a run with an error naming the step and the patch; negative
//!   radiosities are counted;
//! - the **energy** is `Σ A·B` against the same sum for the exact answer;
//! - group systems report the largest `κ_∞` estimate met and how many fell back to point
//!   shots; the whole system's `κ_∞ = ‖Φ‖_∞ ‖Φ⁻¹‖_∞` is in each case's header, where
//!   `‖Φ⁻¹‖_∞ = max (Φ⁻¹ 1)` because `Φ⁻¹ ≥ 0` for an M-matrix (one extra solve).
//!
//! Everything written is deterministic (no timings), so the report is snapshot-tested.

use crate::backends::fresh_backend;
use crate::error::LabError;
use crate::lab::Recorder;
use crate::metrics::errors_against;
use crate::progress::Progress;
use crate::table::round_significant;
use crate::{Contraction, FormFactors, ReferenceParams, ReferenceSolution, Residual};
use radiosity_core::dense_lu::solve_m_matrix;
use radiosity_core::{LinearSystem, Real};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::{
    BEYOND_PAPER_SOLVERS, Executor, GROUP_SOLVERS, KRYLOV_SOLVERS, NoObserver, Observer, POINT_SOLVERS, Problem,
    Record, SolverRegistry, State, StopRule, StopRules, TerminationReason,
};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Steps allowed to a run, in multiples of the patch count.
pub const STEP_CAP: f64 = 200.0;
/// The residual power at which a run stops.
pub const RESIDUAL_TARGET: Real = 1e-13;
/// The certified relative L1 error bound below which a run counts as converged.
pub const CONVERGED: Real = 1e-6;

/// One scene of the suite.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    /// A short name, as `--cases` takes it.
    pub key: &'static str,
    /// The scene argument.
    pub scene: &'static str,
    /// What it stresses.
    pub what: &'static str,
}

/// The stiff and extreme scenes.
pub const CASES: &[Case] = &[
    Case { key: "rho-0.99", scene: "furnace:res=3:rho=0.99", what: "closed box, ρ = 0.99" },
    Case { key: "rho-0.999", scene: "furnace:res=3:rho=0.999", what: "closed box, ρ = 0.999" },
    Case { key: "channels", scene: "furnace:res=3:rho=0.99/0.5/0", what: "channels with ρ of 0.99, 0.5 and 0" },
    Case {
        key: "inner-rho-0.999",
        scene: "inner-box:rho=0.999",
        what: "a box inside a closed box, ρ = 0.999: occluded and stiff",
    },
    Case {
        key: "area-ratio",
        scene: "inner-box:res=2:size=5e-4:height=5e-4",
        what: "patch areas 1e6 apart (a 5e-4 cube in a unit box)",
    },
    Case {
        key: "bright-emitter",
        scene: "inner-box:res=2:size=5e-4:height=5e-4:emission=0:inner-emission=1e6",
        what: "a tiny emitter of 1e6, the only light",
    },
    Case { key: "touching", scene: "inner-box:gap=0", what: "a box on the floor, touching it along its edges" },
    Case { key: "near-touching", scene: "inner-box:gap=1e-6", what: "a box 1e-6 above the floor" },
    Case { key: "thin-slab", scene: "inner-box:size=0.8:height=1e-4:gap=0.45", what: "a slab 1e-4 thick" },
    Case { key: "scale-1e-4", scene: "inner-box:scale=1e-4", what: "the default inner box at scale 1e-4" },
    Case { key: "scale-1e4", scene: "inner-box:scale=1e4", what: "the default inner box at scale 1e4" },
];

/// One form-factor backend of the suite.
#[derive(Clone, Copy, Debug)]
pub struct SuiteBackend {
    /// Its name in the report, as `--backends` takes it.
    pub label: &'static str,
    /// The backend argument.
    pub spec: &'static str,
    /// Whether rows are rescaled to sum to 1 in `f64` (closed scenes only).
    pub close_rows: bool,
}

/// The backends of the suite.
pub const BACKENDS: &[SuiteBackend] = &[
    SuiteBackend { label: "analytic", spec: "analytic", close_rows: false },
    SuiteBackend { label: "analytic+closure", spec: "analytic", close_rows: true },
    SuiteBackend { label: "hemicube", spec: "hemicube", close_rows: false },
    SuiteBackend { label: "montecarlo", spec: "montecarlo", close_rows: false },
    SuiteBackend { label: "matrix:rebalance=true", spec: "matrix:rebalance=true", close_rows: false },
];

/// Keeps the items of `all` named in the comma list `list` (all of them when `list` is
/// `None`), refusing unknown names; `what` names the items in errors.
pub fn select<T: Copy>(
    list: Option<&str>,
    all: &[T],
    name: impl Fn(&T) -> &str,
    what: &str,
) -> Result<Vec<T>, LabError> {
    let Some(list) = list else { return Ok(all.to_vec()) };
    let mut chosen = Vec::new();
    for wanted in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        match all.iter().find(|item| name(item) == wanted) {
            Some(item) => chosen.push(*item),
            None => {
                let valid: Vec<&str> = all.iter().map(&name).collect();
                return Err(LabError::Invalid(format!("unknown {what} '{wanted}'; {what}s are {}", valid.join(", "))));
            }
        }
    }
    if chosen.is_empty() {
        return Err(LabError::Invalid(format!("--{what}s names no {what}")));
    }
    Ok(chosen)
}

/// Every point, group, beyond-the-paper and Krylov solver, by name: the suite's default
/// solvers.
pub fn all_solvers() -> Vec<String> {
    POINT_SOLVERS
        .iter()
        .chain(&GROUP_SOLVERS)
        .chain(&BEYOND_PAPER_SOLVERS)
        .chain(&KRYLOV_SOLVERS)
        .map(|s| s.to_string())
        .collect()
}

/// The suite to run: cases, backends and solvers (built by name from a registry, so that a
/// researcher's own solver, registered there, runs beside the built-in ones).
pub struct StressSuite<'r> {
    /// The scenes.
    pub cases: Vec<Case>,
    /// The backends.
    pub backends: Vec<SuiteBackend>,
    /// The solvers' names.
    pub solvers: Vec<String>,
    /// Where the solvers are built from.
    pub registry: &'r SolverRegistry,
}

impl<'r> StressSuite<'r> {
    /// Every case, backend and solver.
    pub fn full(registry: &'r SolverRegistry) -> StressSuite<'r> {
        StressSuite { cases: CASES.to_vec(), backends: BACKENDS.to_vec(), solvers: all_solvers(), registry }
    }

    /// Runs the suite; `progress` counts scene-and-backend pairs.
    pub fn run(&self, progress: &dyn Progress) -> Result<StressReport, LabError> {
        if self.solvers.is_empty() {
            return Err(LabError::Invalid("--solvers names no solver".into()));
        }
        for name in &self.solvers {
            self.registry.build(name)?;
        }
        progress.begin("stress", (self.cases.len() * self.backends.len()) as u64, "runs");
        let mut results = Vec::new();
        let mut done = 0;
        for case in &self.cases {
            let prepared = PreparedScene::load(case.scene)?;
            let mut runs = Vec::new();
            for backend in &self.backends {
                progress.advance(done, &format!("{} · {}", case.key, backend.label));
                runs.push(run_backend(&prepared, *backend, &self.solvers, self.registry)?);
                done += 1;
            }
            results.push(CaseResult { case: *case, patches: prepared.scene().len(), runs });
        }
        progress.end();
        Ok(StressReport { results, solvers: self.solvers.clone() })
    }
}

/// What the suite measured.
pub struct StressReport {
    results: Vec<CaseResult>,
    solvers: Vec<String>,
}

impl StressReport {
    /// The Markdown report (deterministic: no timings), as `stress.md`.
    pub fn markdown(&self) -> String {
        report_markdown(&self.results, &self.solvers)
    }

    /// Writes every run as CSV to `path`.
    pub fn write_csv(&self, path: &Path) -> Result<(), LabError> {
        write_csv(path, &self.results).map_err(|e| LabError::write(path, e))
    }

    /// Writes `stress.md` and `stress.csv` into `dir` (created if needed).
    pub fn write(&self, dir: &Path) -> Result<(), LabError> {
        std::fs::create_dir_all(dir).map_err(|e| LabError::write(dir, e))?;
        let md = dir.join("stress.md");
        std::fs::write(&md, self.markdown()).map_err(|e| LabError::write(&md, e))?;
        self.write_csv(&dir.join("stress.csv"))
    }

    /// Per case and backend: how many runs converged, and which did not.
    pub fn summary(&self) -> String {
        summary(&self.results)
    }
}

/// What one scene gave on every backend.
struct CaseResult {
    case: Case,
    patches: usize,
    runs: Vec<BackendResult>,
}

/// What one backend gave on one scene.
struct BackendResult {
    backend: SuiteBackend,
    /// Why the backend was left out (an open scene cannot have its rows closed).
    left_out: Option<String>,
    /// Smallest and largest row sum of F as the solvers see it.
    row_sums: (Real, Real),
    /// Factors of the `f64` row closure, when applied.
    closure_factors: Option<(Real, Real)>,
    /// The reference, or why it failed.
    reference: Result<ReferenceSummary, String>,
    /// The furnace identity, when it applies.
    exact: Option<Vec<Real>>,
    /// The reference's e_rms against the furnace identity.
    reference_vs_exact: Option<Real>,
    /// `q = max_c max(ρ_max,c, κ_c)`: the certified bound needs `q < 1`.
    contraction: Real,
    /// `κ_∞` of the whole system, or `None` when it is not an M-matrix.
    condition: Option<Real>,
    /// One per solver.
    solvers: Vec<SolverResult>,
}

/// The reference of one system.
struct ReferenceSummary {
    values: Vec<Real>,
    certified: bool,
    relative_bound: Real,
}

/// One solver's run.
struct SolverResult {
    solver: String,
    outcome: Outcome,
}

enum Outcome {
    /// The run ended on a termination reason.
    Ended(Box<Ended>),
    /// The run stopped with an error (a non-finite value, an impossible system).
    Failed(String),
}

struct Ended {
    termination: TerminationReason,
    state: State,
    /// The solver's own figures (group condition numbers and fallbacks).
    record: Record,
    /// Columns at which e_rms against the reference first reached 1e-3 and 1e-6.
    reached: [Option<u64>; 2],
    /// e_rms against the reference and against the furnace identity.
    e_reference: Option<Real>,
    e_exact: Option<Real>,
    /// The certified relative L1 error bound (infinite when not certifiable).
    bound: Real,
    non_finite: usize,
    negative: usize,
    /// `Σ A·B / Σ A·B_exact − 1`.
    energy: Option<Real>,
}

impl Ended {
    fn converged(&self) -> bool {
        self.bound <= CONVERGED
    }
}

/// Assembles F with `backend`, solves the reference and runs every solver.
fn run_backend(
    prepared: &PreparedScene,
    backend: SuiteBackend,
    solvers: &[String],
    registry: &SolverRegistry,
) -> Result<BackendResult, LabError> {
    let scene = &prepared.loaded.scene;
    let system = LinearSystem::from_scene(scene);
    let closed = prepared.analysis.closure.value.is_closed();
    let mut result = BackendResult {
        backend,
        left_out: None,
        row_sums: (0.0, 0.0),
        closure_factors: None,
        reference: Err(String::new()),
        exact: None,
        reference_vs_exact: None,
        contraction: 0.0,
        condition: None,
        solvers: Vec::new(),
    };
    if backend.close_rows && !closed {
        result.left_out = Some("the scene is open, so its rows need not sum to 1".into());
        return Ok(result);
    }
    let mut matrix = assemble(prepared, backend)?;
    if backend.close_rows {
        result.closure_factors = Some(matrix.close_rows());
    }
    let sums: Vec<Real> = matrix.row_sums();
    result.row_sums = (sums.iter().copied().fold(Real::INFINITY, Real::min), sums.iter().copied().fold(0.0, Real::max));
    let contraction = Contraction::from_matrix(&system, &matrix)?;
    result.contraction = contraction.max_factor();
    result.condition = condition(&system, &matrix);
    result.exact = closed.then(|| furnace_identity(&system)).flatten();
    result.reference = match ReferenceSolution::solve_matrix(&system, &matrix, ReferenceParams::default()) {
        Ok(r) => Ok(ReferenceSummary {
            values: r.values().to_vec(),
            certified: r.certificate().certified,
            relative_bound: r.certificate().relative_bound,
        }),
        Err(e) => Err(e.to_string()),
    };
    if let (Ok(r), Some(exact)) = (&result.reference, &result.exact) {
        result.reference_vs_exact = errors_against(&system, exact, &r.values).ok().map(|e| e.e_rms);
    }
    let reference = result.reference.as_ref().ok().map(|r| r.values.as_slice());
    let exact = result.exact.as_deref();
    result.solvers = solvers
        .par_iter()
        .map(|name| SolverResult {
            solver: name.clone(),
            outcome: run_solver(&system, &matrix, name, registry, reference, exact)
                .unwrap_or_else(|e| Outcome::Failed(e.to_string())),
        })
        .collect();
    Ok(result)
}

/// F of `backend` on the prepared scene, in `f64`.
fn assemble(prepared: &PreparedScene, backend: SuiteBackend) -> Result<FormFactors, LabError> {
    let spec = BackendSpec::parse(backend.spec)?;
    let limit = ReferenceParams::default().max_matrix_bytes;
    Ok(FormFactors::assemble(&fresh_backend(prepared, &spec, &crate::progress::NoProgress)?, limit)?)
}

/// `E / (1 − ρ)` per channel when every patch has the same reflectivity and emission.
fn furnace_identity(system: &LinearSystem) -> Option<Vec<Real>> {
    let k = system.channels().count();
    let (rho, e) = (system.reflectivities(), system.emissions());
    let uniform = |v: &[Real]| v.chunks_exact(k).all(|x| x == &v[..k]);
    (uniform(rho) && uniform(e)).then(|| e.iter().zip(rho).map(|(e, r)| e / (1.0 - r)).collect())
}

/// `κ_∞(Φ)` of the whole system, the largest over channels
/// ([`radiosity_core::dense_lu::solve_m_matrix`]), or `None` when `Φ` is not a nonsingular
/// M-matrix.
fn condition(system: &LinearSystem, matrix: &FormFactors) -> Option<Real> {
    let (n, k) = (system.len(), system.channels().count());
    let mut worst: Real = 0.0;
    for c in 0..k {
        let rho_f: Vec<Real> = (0..n * n).map(|idx| system.rho(idx / n, c) * matrix.get(idx / n, idx % n)).collect();
        let (_, kappa) = solve_m_matrix(n, &rho_f, vec![1.0; n])?;
        worst = worst.max(kappa);
    }
    Some(worst)
}

/// Runs one solver on the stored matrix and measures its final state.
fn run_solver(
    system: &LinearSystem,
    matrix: &FormFactors,
    name: &str,
    registry: &SolverRegistry,
    reference: Option<&[Real]>,
    exact: Option<&[Real]>,
) -> Result<Outcome, LabError> {
    let mut solver = registry.build(name)?;
    let problem = Problem::new(system, matrix)?;
    let rules = StopRules { rules: vec![StopRule::Residual(RESIDUAL_TARGET)], step_cap: STEP_CAP };
    // e_rms after every step against the reference, when there is one.
    let mut recorder = reference.map(|r| Recorder::errors(system, r, Instant::now()));
    let mut none = NoObserver;
    let observer: &mut dyn Observer = match &mut recorder {
        Some(r) => r,
        None => &mut none,
    };
    let run = match Executor::new(solver.as_mut(), rules).run(&problem, observer) {
        Ok(run) => run,
        Err(e) => return Ok(Outcome::Failed(e.to_string())),
    };
    let b = &run.state.radiosity;
    let residual = Residual::from_matrix(system, matrix, b)?;
    let k = system.channels().count();
    let weighted =
        |v: &[Real]| -> Real { v.iter().enumerate().map(|(idx, x)| system.areas()[idx / k] * x.abs()).sum() };
    let norm = weighted(b);
    let bound = residual.bound().bound;
    let bound = if bound == 0.0 { 0.0 } else { bound / norm };
    let error = |truth: Option<&[Real]>| truth.and_then(|t| errors_against(system, t, b).ok()).map(|e| e.e_rms);
    let truth = exact.or(reference);
    let energy = truth.map(|t| {
        let total = |v: &[Real]| -> Real { v.iter().enumerate().map(|(idx, x)| system.areas()[idx / k] * x).sum() };
        total(b) / total(t) - 1.0
    });
    Ok(Outcome::Ended(Box::new(Ended {
        termination: run.termination,
        reached: [1e-3, 1e-6].map(|target| {
            let points = recorder.as_ref().map_or(&[][..], |r| r.points());
            points.iter().find(|p| p.e_rms <= target).map(|p| p.columns)
        }),
        e_reference: error(reference),
        e_exact: error(exact),
        bound,
        non_finite: b.iter().filter(|v| !v.is_finite()).count(),
        negative: b.iter().filter(|v| **v < 0.0).count(),
        energy,
        state: run.state,
        record: run.record,
    })))
}

/// Errors below this are shown as round-off, so that the snapshot of the report does not
/// move with the order of a sum.
const ROUND_OFF: Real = 1e-12;

/// `v` to `digits` significant digits, or `<1e-12` below [`ROUND_OFF`].
fn small(v: Real, digits: usize) -> String {
    if v.abs() < ROUND_OFF { format!("<{ROUND_OFF:e}") } else { round_significant(v, digits) }
}

/// Two significant digits (round-off shown as such), or `—`.
fn sig(v: Option<Real>) -> String {
    v.map_or_else(|| "—".into(), |v| small(v, 2))
}

/// A number for the CSV: full precision, empty when unknown.
fn raw(v: Option<Real>) -> String {
    v.map_or_else(String::new, |v| format!("{v:e}"))
}

fn count(v: Option<u64>) -> String {
    v.map_or_else(String::new, |v| v.to_string())
}

/// A short name for how a run ended.
fn stop_kind(t: &TerminationReason) -> &'static str {
    match t {
        TerminationReason::Columns(_) | TerminationReason::Steps(_) => "budget",
        TerminationReason::Rms(_) => "rms",
        TerminationReason::Residual(_) => "residual",
        TerminationReason::Time(_) => "time",
        TerminationReason::RoundOff => "round-off",
        TerminationReason::StepCap(_) => "step cap",
        TerminationReason::Diverged { .. } => "diverged",
    }
}

/// One grid cell: status, then the final error against the exact answer (or the reference).
fn cell(outcome: &Outcome) -> String {
    match outcome {
        Outcome::Failed(_) => "**failed**".into(),
        Outcome::Ended(e) => {
            let status = if e.non_finite > 0 {
                "NaN"
            } else if e.converged() {
                "✓"
            } else {
                match e.termination {
                    TerminationReason::StepCap(_) => "cap",
                    TerminationReason::Diverged { .. } => "div",
                    _ => "✗",
                }
            };
            let error = e.e_exact.or(e.e_reference);
            let mut s = format!("{status} {}", error.map_or_else(|| "—".into(), |v| small(v, 1)));
            if e.negative > 0 {
                s.push_str(" neg");
            }
            if e.record.count("group_fallbacks").unwrap_or(0) > 0 {
                s.push_str(" fb");
            }
            s
        }
    }
}

/// Why a run did not converge: its reason in words, and its certified error bound (`None`
/// for a run that failed or whose system is not certifiable).
fn why(result: &BackendResult, outcome: &Outcome) -> Option<(String, Option<Real>)> {
    let e = match outcome {
        Outcome::Failed(message) => return Some((message.clone(), None)),
        Outcome::Ended(e) if e.converged() => return None,
        Outcome::Ended(e) => e,
    };
    let mut why = e.termination.to_string();
    if result.contraction >= 1.0 {
        write!(
            why,
            "; not certifiable: ρ times some row sum of F reaches {}, so the system need not have a non-negative \
             solution nor any iteration converge",
            round_significant(result.contraction, 4)
        )
        .ok();
    }
    if e.negative > 0 {
        write!(why, "; {} negative radiosities", e.negative).ok();
    }
    Some((why, (result.contraction < 1.0).then_some(e.bound)))
}

/// The runs of one case that did not converge, one line per solver and reason, naming the
/// backends and the range of their certified error bounds.
fn failures(case: &CaseResult, solvers: &[String]) -> Vec<String> {
    let shown: Vec<&BackendResult> = case.runs.iter().filter(|b| b.left_out.is_none()).collect();
    let mut lines = Vec::new();
    for (s, name) in solvers.iter().enumerate() {
        let mut groups: Vec<(String, Vec<&str>, Vec<Real>)> = Vec::new();
        for b in &shown {
            let Some((reason, bound)) = why(b, &b.solvers[s].outcome) else { continue };
            let at = match groups.iter().position(|g| g.0 == reason) {
                Some(at) => at,
                None => {
                    groups.push((reason, Vec::new(), Vec::new()));
                    groups.len() - 1
                }
            };
            groups[at].1.push(b.backend.label);
            groups[at].2.extend(bound);
        }
        for (reason, backends, bounds) in groups {
            let mut line = format!("- `{name}` on {}: {reason}", backends.join(", "));
            if !bounds.is_empty() {
                let lo = bounds.iter().copied().fold(Real::INFINITY, Real::min);
                let hi = bounds.iter().copied().fold(0.0, Real::max);
                let range = if round_significant(lo, 2) == round_significant(hi, 2) {
                    round_significant(lo, 2)
                } else {
                    format!("{} to {}", round_significant(lo, 2), round_significant(hi, 2))
                };
                write!(line, "; certified error bound {range}").ok();
            }
            lines.push(line);
        }
    }
    lines
}

fn report_markdown(results: &[CaseResult], solvers: &[String]) -> String {
    let mut md = String::new();
    writeln!(md, "# Stress suite: stiff and extreme scenes\n").ok();
    writeln!(
        md,
        "Every solver on every backend. A run stops at residual power {RESIDUAL_TARGET:e}, at round-off, on divergence \
         or after {STEP_CAP}n steps. Cells give the status and the final e_rms against the exact answer (the furnace \
         identity where the scene is closed and uniform, otherwise the reference of the same system):\n\n\
         - `✓`: converged, the certified relative L1 error bound is at most {CONVERGED:e};\n\
         - `cap`: the step cap came first; `div`: the residual diverged; `✗`: stopped otherwise without a certified bound;\n\
         - `NaN`: non-finite values; `neg`: negative radiosities; `fb`: group systems fell back to point shots;\n\
         - `**failed**`: the run stopped with an error.\n\n\
         Each case's first table describes the systems: row sums of F, the contraction `q` the certificate needs \
         below 1, the condition number `κ_∞` of `I − diag(ρ) F` (— where it is not an M-matrix), the reference and its \
         distance from the furnace identity. Details of every run are in `stress.csv`.\n"
    )
    .ok();
    for case in results {
        writeln!(md, "## `{}`: {}\n", case.case.key, case.case.what).ok();
        writeln!(md, "`{}`, {} patches.\n", case.case.scene, case.patches).ok();
        writeln!(md, "| backend | row sums | q | κ_∞ | reference | reference vs exact |").ok();
        writeln!(md, "|---|---|--:|--:|---|--:|").ok();
        for b in &case.runs {
            if let Some(why) = &b.left_out {
                writeln!(md, "| {} | left out: {why} | | | | |", b.backend.label).ok();
                continue;
            }
            let reference = match &b.reference {
                Ok(r) if r.certified => format!("certified to {}", small(r.relative_bound, 1)),
                Ok(_) => "not certified".into(),
                Err(e) => format!("failed: {e}"),
            };
            let closure = b
                .closure_factors
                .map(|(lo, hi)| {
                    format!(" (after closing rows by {}–{})", round_significant(lo, 6), round_significant(hi, 6))
                })
                .unwrap_or_default();
            writeln!(
                md,
                "| {} | {}–{}{closure} | {} | {} | {reference} | {} |",
                b.backend.label,
                round_significant(b.row_sums.0, 6),
                round_significant(b.row_sums.1, 6),
                round_significant(b.contraction, 6),
                sig(b.condition),
                sig(b.reference_vs_exact),
            )
            .ok();
        }
        let shown: Vec<&BackendResult> = case.runs.iter().filter(|b| b.left_out.is_none()).collect();
        writeln!(md).ok();
        write!(md, "| solver |").ok();
        for b in &shown {
            write!(md, " {} |", b.backend.label).ok();
        }
        writeln!(md).ok();
        writeln!(md, "|---|{}", "---|".repeat(shown.len())).ok();
        for (s, name) in solvers.iter().enumerate() {
            write!(md, "| `{name}` |").ok();
            for b in &shown {
                write!(md, " {} |", cell(&b.solvers[s].outcome)).ok();
            }
            writeln!(md).ok();
        }
        let failures = failures(case, solvers);
        if !failures.is_empty() {
            writeln!(md, "\nRuns that did not converge:\n").ok();
            for f in failures {
                writeln!(md, "{f}").ok();
            }
        }
        writeln!(md).ok();
    }
    md
}

fn write_csv(path: &Path, results: &[CaseResult]) -> Result<(), csv::Error> {
    let mut w = csv::Writer::from_path(path)?;
    w.write_record([
        "case",
        "scene",
        "backend",
        "solver",
        "stop",
        "detail",
        "converged",
        "steps",
        "columns",
        "columns_to_1e-3",
        "columns_to_1e-6",
        "e_rms_reference",
        "e_rms_exact",
        "certified_bound",
        "non_finite",
        "negative",
        "energy",
        "group_condition",
        "group_fallbacks",
    ])?;
    for case in results {
        for b in case.runs.iter().filter(|b| b.left_out.is_none()) {
            for r in &b.solvers {
                let head = [case.case.key, case.case.scene, b.backend.label, r.solver.as_str()];
                let record: Vec<String> = match &r.outcome {
                    Outcome::Failed(message) => {
                        let mut v: Vec<String> = head.iter().map(|s| s.to_string()).collect();
                        v.extend(["failed".to_string(), message.clone()]);
                        v.resize(19, String::new());
                        v
                    }
                    Outcome::Ended(e) => {
                        let mut v: Vec<String> = head.iter().map(|s| s.to_string()).collect();
                        v.extend([
                            stop_kind(&e.termination).to_string(),
                            e.termination.to_string(),
                            e.converged().to_string(),
                            e.state.step.to_string(),
                            e.state.columns.to_string(),
                            count(e.reached[0]),
                            count(e.reached[1]),
                            raw(e.e_reference),
                            raw(e.e_exact),
                            raw(Some(e.bound)),
                            e.non_finite.to_string(),
                            e.negative.to_string(),
                            raw(e.energy),
                            raw(e.record.real("group_condition").or(Some(0.0))),
                            e.record.count("group_fallbacks").unwrap_or(0).to_string(),
                        ]);
                        v
                    }
                };
                w.write_record(&record)?;
            }
        }
    }
    w.flush()?;
    Ok(())
}

/// Per case and backend: how many runs converged, and which did not.
fn summary(results: &[CaseResult]) -> String {
    let mut out = String::new();
    for case in results {
        for b in case.runs.iter().filter(|b| b.left_out.is_none()) {
            let failed: Vec<&str> = b
                .solvers
                .iter()
                .filter(|r| !matches!(&r.outcome, Outcome::Ended(e) if e.converged()))
                .map(|r| r.solver.as_str())
                .collect();
            let total = b.solvers.len();
            let _ = write!(
                out,
                "{:<15} {:<22} {:>2}/{total} converged",
                case.case.key,
                b.backend.label,
                total - failed.len()
            );
            if failed.is_empty() {
                out.push('\n');
            } else {
                let _ = writeln!(out, "; not: {}", failed.join(", "));
            }
        }
    }
    out
}
