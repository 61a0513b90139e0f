//! The gathering update shared by Jacobi and Gauss–Seidel/SOR: gather patch `i` from a
//! radiosity vector, and track each sweep's residual.
//!
//! Gathering patch `i` from `B` gives `G_ic = E_ic + ρ_ic Σ_j F_ij B_jc`, whose difference
//! from `B_ic` is the residual `r_ic` of `B` at `i`. Row `i` costs one column, so a sweep
//! costs `n` columns.
//!
//! The row must be row `i` of the matrix the columns assemble, which the reference solves.
//! The analytic backend and a stored matrix give it exactly
//! ([`radiosity_core::ColumnSource::fill_row`]). Hemicube and Monte Carlo columns are not
//! reciprocal, and their rows are taken from column `i` by reciprocity: gathering then solves
//! a slightly different system from the one shooting solves, by as much as the backend's
//! reciprocity error (`cargo xtask ff` reports it; docs/solvers.md shows what that did before
//! analytic rows were exact).

use crate::error::SolverError;
use crate::run::problem::Problem;
use crate::run::state::State;
use radiosity_core::Real;

/// The residual bookkeeping of a sweep.
#[derive(Debug, Default, Clone)]
pub struct SweepResidual {
    /// The next patch of the sweep.
    pub next: usize,
    running: Real,
    last: Option<Real>,
}

impl SweepResidual {
    /// The residual power of the last completed sweep, relative to the emitted power.
    pub fn last(&self) -> Option<Real> {
        self.last
    }

    /// Adds patch `i`'s residual and moves to the next patch, closing the sweep at `n`.
    pub fn add(&mut self, problem: &Problem<'_>, i: usize, residual: &[Real]) {
        let system = problem.system();
        self.running += system.areas()[i] * residual.iter().map(|r| r.abs()).sum::<Real>();
        self.next += 1;
        if self.next == problem.n() {
            let k = problem.channels();
            let emitted: Real =
                (0..problem.n()).map(|p| system.areas()[p] * (0..k).map(|c| system.e(p, c).abs()).sum::<Real>()).sum();
            self.last = Some(if emitted > 0.0 { self.running / emitted } else { 0.0 });
            self.running = 0.0;
            self.next = 0;
        }
    }
}

/// `G_i − B_i` per channel into `residual`: the residual of `from` at patch `i`, using `row`
/// as scratch space.
pub fn gather(problem: &Problem<'_>, from: &[Real], i: usize, row: &mut Vec<Real>, residual: &mut [Real]) {
    row.resize(problem.n(), 0.0);
    problem.row(i, row);
    let system = problem.system();
    let k = problem.channels();
    for (c, r) in residual.iter_mut().enumerate() {
        let mut incoming = 0.0;
        for (j, &f) in row.iter().enumerate() {
            incoming += f * from[j * k + c];
        }
        *r = system.e(i, c) + system.rho(i, c) * incoming - from[i * k + c];
    }
}

/// Moves patch `i` of `state` by `step` times the residual, recording the change.
pub fn relax(state: &mut State, i: usize, step: Real, residual: &[Real]) -> Result<(), SolverError> {
    let k = state.channels;
    for (c, &r) in residual.iter().enumerate() {
        let change = step * r;
        state.radiosity[i * k + c] += change;
        state.unshot[i * k + c] = change;
        if !state.radiosity[i * k + c].is_finite() {
            return Err(SolverError::NonFinite { step: state.step + 1, patch: i, value: state.radiosity[i * k + c] });
        }
    }
    Ok(())
}
