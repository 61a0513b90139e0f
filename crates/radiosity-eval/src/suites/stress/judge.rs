//! How a run is judged (module doc of [`crate::stress`]): F assembled once per scene and
//! backend, its row sums, contraction and condition, the reference and the furnace identity,
//! then every solver run on it and measured, and what the suite measured ([`StressReport`]).
//! The solvers that sample transport cast their rays on the same F, sampled exactly
//! ([`ColumnTransport`], built once per scene and backend when one of them runs), so that the
//! reference is the exact answer of the system they estimate.

use crate::error::LabError;
use crate::lab::backends::fresh_backend;
use crate::lab::recorder::Recorder;
use crate::progress::NoProgress;
use crate::reference::certificate::{Contraction, Residual};
use crate::reference::matrix::FormFactors;
use crate::reference::metrics::errors_against;
use crate::reference::solution::{ReferenceParams, ReferenceSolution};
use crate::suites::stress::cases::{
    CONVERGED, Case, RESIDUAL_TARGET, STEP_CAP, STOCHASTIC_RAYS_PER_PATCH, STOCHASTIC_SPREADS, STOCHASTIC_TOLERANCE,
    SuiteBackend,
};
use radiosity_core::dense_lu::solve_m_matrix;
use radiosity_core::{ColumnTransport, LinearSystem, Real, TransportSampler};
use radiosity_ff::BackendRegistry;
use radiosity_geom::PreparedScene;
use radiosity_solvers::Unit;
use radiosity_solvers::{
    Count, Executor, ObserverMode, Problem, Record, SolverRegistry, State, StepKind, StopRule, StopRules,
    TerminationReason,
};
use rayon::prelude::*;
use std::time::Instant;

/// What the suite measured.
pub struct StressReport {
    pub(super) results: Vec<CaseResult>,
    pub(super) solvers: Vec<String>,
}

/// What one scene gave on every backend.
pub(super) struct CaseResult {
    pub(super) case: Case,
    pub(super) patches: usize,
    pub(super) runs: Vec<BackendResult>,
}

/// What one backend gave on one scene.
pub(super) struct BackendResult {
    pub(super) backend: SuiteBackend,
    /// Why the backend was left out (an open scene cannot have its rows closed).
    pub(super) left_out: Option<String>,
    /// Smallest and largest row sum of F as the solvers see it.
    pub(super) row_sums: (Real, Real),
    /// Factors of the `f64` row closure, when applied.
    pub(super) closure_factors: Option<(Real, Real)>,
    /// The reference, or why it failed.
    pub(super) reference: Result<ReferenceSummary, String>,
    /// The furnace identity, when it applies.
    pub(super) exact: Option<Vec<Real>>,
    /// The reference's e_rms against the furnace identity.
    pub(super) reference_vs_exact: Option<Real>,
    /// `q = max_c max(ρ_max,c, κ_c)`: the certified bound needs `q < 1`.
    pub(super) contraction: Real,
    /// `κ_∞` of the whole system, or `None` when it is not an M-matrix.
    pub(super) condition: Option<Real>,
    /// One per solver.
    pub(super) solvers: Vec<SolverResult>,
}

/// The reference of one system.
pub(super) struct ReferenceSummary {
    pub(super) values: Vec<Real>,
    pub(super) certified: bool,
    pub(super) relative_bound: Real,
}

/// One solver's run.
pub(super) struct SolverResult {
    pub(super) solver: String,
    pub(super) outcome: Outcome,
}

pub(super) enum Outcome {
    /// The run ended on a termination reason.
    Ended(Box<Ended>),
    /// The run stopped with an error (a non-finite value, an impossible system).
    Failed(String),
}

pub(super) struct Ended {
    pub(super) termination: TerminationReason,
    pub(super) state: State,
    /// The solver's own figures (group condition numbers and fallbacks).
    pub(super) record: Record,
    /// Columns at which e_rms against the reference first reached 1e-3 and 1e-6.
    pub(super) reached: [Option<u64>; 2],
    /// e_rms against the reference and against the furnace identity.
    pub(super) e_reference: Option<Real>,
    pub(super) e_exact: Option<Real>,
    /// The certified relative L1 error bound (infinite when not certifiable).
    pub(super) bound: Real,
    pub(super) non_finite: usize,
    pub(super) negative: usize,
    /// `Σ A·B / Σ A·B_exact − 1`.
    pub(super) energy: Option<Real>,
    /// Whether the solver samples transport (judged by its standard error).
    pub(super) sampled: bool,
    /// The solver's standard error of its final radiosity, relative as e_rms is, and the
    /// replicates it rests on, when it has one.
    pub(super) spread: Option<(Real, usize)>,
}

/// Why a stochastic run did not converge, when it did not (module doc of [`crate::stress`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Unsettled {
    /// No standard error, or no reference to measure against.
    Unmeasured,
    /// The standard error is above [`STOCHASTIC_TOLERANCE`].
    Noisy(Real),
    /// e_rms against the reference is above [`STOCHASTIC_TOLERANCE`].
    Inaccurate(Real),
    /// e_rms against the reference is more than [`STOCHASTIC_SPREADS`] standard errors.
    Off { e_rms: Real, spread: Real },
}

impl Ended {
    pub(super) fn converged(&self) -> bool {
        if self.sampled { self.unsettled().is_none() } else { self.bound <= CONVERGED }
    }

    /// For a stochastic run, why it did not converge (`None` when it did): its standard error
    /// and its e_rms against the reference must both be at most [`STOCHASTIC_TOLERANCE`], and
    /// its e_rms at most [`STOCHASTIC_SPREADS`] standard errors.
    pub(super) fn unsettled(&self) -> Option<Unsettled> {
        let (Some((spread, _)), Some(e_rms)) = (self.spread, self.e_reference) else {
            return Some(Unsettled::Unmeasured);
        };
        // A NaN fails both tests.
        let precise = spread <= STOCHASTIC_TOLERANCE;
        let accurate = e_rms <= STOCHASTIC_TOLERANCE;
        let unbiased = e_rms <= STOCHASTIC_SPREADS * spread;
        match (precise, unbiased, accurate) {
            (false, _, _) => Some(Unsettled::Noisy(spread)),
            (true, false, _) => Some(Unsettled::Off { e_rms, spread }),
            (true, true, false) => Some(Unsettled::Inaccurate(e_rms)),
            (true, true, true) => None,
        }
    }
}

/// Assembles F with `backend` (its argument parsed by `backends`), solves the reference and
/// runs every solver.
pub(super) fn run_backend(
    prepared: &PreparedScene,
    backend: SuiteBackend,
    backends: &BackendRegistry,
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
    let mut matrix = assemble(prepared, backend, backends)?;
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
    // The stored matrix sampled exactly, once, when some solver samples transport.
    let sampled = solvers.iter().any(|name| registry.build(name).is_ok_and(|s| s.step_kind() == StepKind::Sampled));
    let transport = match sampled {
        true => Some(ColumnTransport::new(&matrix, system.areas()).map_err(|e| e.to_string())),
        false => None,
    };
    let truth = Truth { reference, exact, transport: transport.as_ref() };
    result.solvers = solvers
        .par_iter()
        .map(|name| SolverResult {
            solver: name.clone(),
            outcome: run_solver(&system, &matrix, name, registry, &truth)
                .unwrap_or_else(|e| Outcome::Failed(e.to_string())),
        })
        .collect();
    Ok(result)
}

/// F of `backend` (its argument parsed by `backends`) on the prepared scene, in `f64`.
fn assemble(
    prepared: &PreparedScene,
    backend: SuiteBackend,
    backends: &BackendRegistry,
) -> Result<FormFactors, LabError> {
    let spec = backends.parse(backend.spec)?;
    let limit = ReferenceParams::default().max_matrix_bytes;
    Ok(FormFactors::assemble(&fresh_backend(prepared, &spec, &NoProgress)?, limit)?)
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

/// What a run is measured against, and the sampler of the stored matrix (or why it could not
/// be built) when some solver samples transport.
struct Truth<'t> {
    reference: Option<&'t [Real]>,
    exact: Option<&'t [Real]>,
    transport: Option<&'t Result<ColumnTransport, String>>,
}

/// Runs one solver on the stored matrix and measures its final state. A solver that samples
/// transport casts its rays on the matrix sampled exactly, and runs to its rays budget
/// ([`STOCHASTIC_RAYS_PER_PATCH`]) rather than to the residual target.
fn run_solver(
    system: &LinearSystem,
    matrix: &FormFactors,
    name: &str,
    registry: &SolverRegistry,
    truth: &Truth<'_>,
) -> Result<Outcome, LabError> {
    let (reference, exact) = (truth.reference, truth.exact);
    let mut solver = registry.build(name)?;
    let sampled = solver.step_kind() == StepKind::Sampled;
    let (problem, rules) = if sampled {
        let sampler: &dyn TransportSampler = match truth.transport {
            Some(Ok(sampler)) => sampler,
            Some(Err(why)) => return Ok(Outcome::Failed(format!("the stored matrix cannot be sampled: {why}"))),
            None => return Err(LabError::Invalid(format!("{name} samples transport and no sampler was built"))),
        };
        // The rays budget ends the run; the step cap only guards it.
        let rays = StopRule::Spent(Unit::Rays, Count::PerPatch(STOCHASTIC_RAYS_PER_PATCH));
        (Problem::sampled(system, sampler)?, StopRules { rules: vec![rays], step_cap: 1e6 })
    } else {
        (
            Problem::new(system, matrix)?,
            StopRules { rules: vec![StopRule::Residual(RESIDUAL_TARGET)], step_cap: STEP_CAP },
        )
    };
    // e_rms after every step against the reference, when there is one.
    let mut recorder = reference.map(|r| Recorder::errors(system, r, Instant::now()));
    let mut executor = Executor::new(solver.as_mut(), rules);
    if let Some(recorder) = &mut recorder {
        executor = executor.add_observer(recorder, ObserverMode::Always);
    }
    let run = match executor.run(&problem) {
        Ok(run) => run,
        Err(e) => return Ok(Outcome::Failed(e.to_string())),
    };
    let spread = solver
        .standard_error(&problem, &run.state)
        .map(|s| (s.relative_rms(system, &run.state.radiosity), s.replicates));
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
            points.iter().find(|p| p.e_rms <= target).map(|p| p.cost[Unit::Columns])
        }),
        e_reference: error(reference),
        e_exact: error(exact),
        bound,
        non_finite: b.iter().filter(|v| !v.is_finite()).count(),
        negative: b.iter().filter(|v| **v < 0.0).count(),
        energy,
        sampled,
        spread,
        state: run.state,
        record: run.record,
    })))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stochastic run's end with standard error `spread` and e_rms `e_rms`.
    fn sampled(spread: Real, e_rms: Real) -> Ended {
        Ended {
            termination: TerminationReason::Spent(Unit::Rays, 1),
            state: State::from_emission(&[1.0], 1),
            record: Record::new(),
            reached: [None, None],
            e_reference: Some(e_rms),
            e_exact: None,
            bound: Real::INFINITY,
            non_finite: 0,
            negative: 0,
            energy: None,
            sampled: true,
            spread: Some((spread, 16)),
        }
    }

    #[test]
    fn a_stochastic_run_converges_only_where_its_e_rms_meets_the_tolerance() {
        let tol = STOCHASTIC_TOLERANCE;
        assert!(sampled(tol, 0.5 * tol).converged());
        assert!(sampled(tol, tol).converged());
        // Within 4 standard errors, yet 4 times the tolerance: no answer to it.
        assert_eq!(sampled(tol, 4.0 * tol).unsettled(), Some(Unsettled::Inaccurate(4.0 * tol)));
        assert!(!sampled(tol, 1.01 * tol).converged());
        assert_eq!(sampled(2.0 * tol, 0.5 * tol).unsettled(), Some(Unsettled::Noisy(2.0 * tol)));
        assert_eq!(
            sampled(0.1 * tol, 0.5 * tol).unsettled(),
            Some(Unsettled::Off { e_rms: 0.5 * tol, spread: 0.1 * tol })
        );
        assert!(!sampled(tol, Real::NAN).converged());
    }
}
