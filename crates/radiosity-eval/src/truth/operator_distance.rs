//! A fast form-factor operator measured against a trusted one (issue 33's item 3): how far
//! the operator `F̃` is from the truth `F` in what a solution sees, not only entry by entry.
//!
//! Three figures, each named by what it rests on (docs/design.md §6):
//!
//! - **sampled rows**: row sums and the relative L1 distance `‖F̃_i − F_i‖₁ / ‖F_i‖₁` on rows
//!   drawn with a seed ([`radiosity_ff::row_comparison`]): a sampled estimate;
//! - **transfer**: with `B̃` the exact solution of the operator's own system, the
//!   area-weighted RMS of `ρ_i ((F − F̃) B̃)_i` over `B̃`'s on the same sampled rows, an estimate
//!   of `‖ρ (F − F̃) B̃‖ / ‖B̃‖`. Since `B − B̃ = (I − ρF)⁻¹ ρ (F − F̃) B̃`, it is the error of
//!   `B̃` before the system's amplification `(I − ρF)⁻¹` spreads it: a sampled estimate, not a
//!   bound;
//! - **solutions**: `e_rms` of `B̃` against the exact solution `B` of the truth's system, when
//!   the caller has it (the truth's stored matrix must fit): exact up to the two solves'
//!   tolerances, which the caller's reference certifies for `B` and `residual` bounds for
//!   `B̃`.
//!
//! `B̃` is solved by restarted GMRES over the operator's native product
//! ([`radiosity_solvers::Gmres`]), to a residual power of [`OperatorDistanceParams::residual`].

use crate::error::{EvalError, LabError};
use crate::reference::metrics::errors_against;
use radiosity_core::{ColumnSource, LinearSystem, Real};
use radiosity_ff::row_comparison::{RowComparison, compare_read_rows, read_rows, sampled_rows};
use radiosity_solvers::{Executor, Gmres, Problem, StopRules, TerminationReason};
use std::time::Instant;

/// What to measure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OperatorDistanceParams {
    /// Rows sampled (at least 1).
    pub rows: usize,
    /// The seed of the sample.
    pub seed: u64,
    /// The residual power (relative to the emitted power) `B̃` is solved to.
    pub residual: Real,
    /// GMRES steps at most.
    pub max_steps: u64,
}

impl Default for OperatorDistanceParams {
    fn default() -> Self {
        OperatorDistanceParams { rows: 20, seed: 0, residual: 1e-10, max_steps: 3000 }
    }
}

/// How `B̃` was solved.
#[derive(Clone, Debug, PartialEq)]
pub struct OperatorSolve {
    /// GMRES steps (each one product).
    pub steps: u64,
    /// The residual power reached (relative to the emitted power).
    pub residual: Real,
    /// Seconds.
    pub seconds: f64,
    /// Whether the residual target was reached.
    pub converged: bool,
}

/// The operator against the truth.
#[derive(Clone, Debug, PartialEq)]
pub struct OperatorDistance {
    /// The sampled rows.
    pub rows: RowComparison,
    /// `‖ρ (F − F̃) B̃‖ / ‖B̃‖` over the sampled rows (area-weighted RMS, every channel).
    pub transfer: Real,
    /// The operator's own exact solution, and how it was solved.
    pub solve: OperatorSolve,
    /// `e_rms` of `B̃` against the truth's exact solution, when one was given.
    pub solution_e_rms: Option<Real>,
    /// `B̃`, patch-major.
    pub operator_solution: Vec<Real>,
}

/// Measures `operator` against `truth` on `system` (module doc); `truth_solution` is the
/// truth's exact solution when the caller has it, patch-major like the system.
pub fn operator_distance(
    system: &LinearSystem,
    operator: &dyn ColumnSource,
    truth: &dyn ColumnSource,
    truth_solution: Option<&[Real]>,
    params: OperatorDistanceParams,
) -> Result<OperatorDistance, LabError> {
    let n = system.len();
    if operator.patch_count() != n || truth.patch_count() != n {
        return Err(EvalError::SizeMismatch {
            what: "the form factors",
            expected: n,
            found: if operator.patch_count() != n { operator.patch_count() } else { truth.patch_count() },
        }
        .into());
    }
    if params.rows == 0 {
        return Err(LabError::Invalid("at least one row must be sampled".into()));
    }
    let (solve, b) = solve_operator(system, operator, params)?;
    let rows = sampled_rows(n, params.rows, params.seed);
    let (ours, theirs) = (read_rows(operator, &rows), read_rows(truth, &rows));
    let comparison = compare_read_rows(&rows, &ours, &theirs);
    let k = system.channels().count();
    let (mut num, mut den) = (0.0, 0.0);
    for ((&i, x), y) in rows.iter().zip(&ours).zip(&theirs) {
        let a = system.areas()[i];
        for c in 0..k {
            let d: Real = x.iter().zip(y).enumerate().map(|(j, (p, q))| (q - p) * b[j * k + c]).sum();
            let t = system.reflectivities()[i * k + c] * d;
            num += a * t * t;
            den += a * b[i * k + c] * b[i * k + c];
        }
    }
    let transfer = if den > 0.0 { (num / den).sqrt() } else { 0.0 };
    let solution_e_rms = truth_solution.map(|star| errors_against(system, star, &b).map(|e| e.e_rms)).transpose()?;
    Ok(OperatorDistance { rows: comparison, transfer, solve, solution_e_rms, operator_solution: b })
}

/// `B̃` by GMRES(30) over the operator's product.
fn solve_operator(
    system: &LinearSystem,
    operator: &dyn ColumnSource,
    params: OperatorDistanceParams,
) -> Result<(OperatorSolve, Vec<Real>), LabError> {
    let start = Instant::now();
    let problem = Problem::new(system, operator)?;
    let mut gmres = Gmres::new(30)?;
    let rules = StopRules::parse(&format!("residual={:e},steps={}", params.residual, params.max_steps))?;
    let run = Executor::new(&mut gmres, rules).run(&problem)?;
    let (converged, residual) = match run.termination {
        TerminationReason::Residual(r) => (true, r),
        TerminationReason::RoundOff => (true, 0.0),
        _ => (false, Real::NAN),
    };
    let solve = OperatorSolve { steps: run.state.step, residual, seconds: start.elapsed().as_secs_f64(), converged };
    Ok((solve, run.state.radiosity))
}
