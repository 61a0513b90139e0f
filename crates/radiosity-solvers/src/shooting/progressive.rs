//! `pr`: progressive refinement, shooting from the patch with the most unshot power.
//!
//! Rule: pick `j = argmax_j A_j Σ_c |ΔB_jc|` (the lowest index on ties), shoot `s = ΔB_j`
//! ([`crate::shooting::rule::shoot`]), then `ΔB_j = ρ_j F_jj s`, the shooter's own share (zero for
//! planar patches, [`crate::shooting::rule::own_share`]). Each step costs one column.
//!
//! ## References
//!
//! - Cohen, Chen, Wallace & Greenberg 1988, "A progressive refinement approach to fast
//!   radiosity image generation", SIGGRAPH.
//! - Gortler, Cohen & Slusallek 1993, "Radiosity and relaxation methods": PR is Southwell
//!   iteration with an area-weighted choice.

use crate::error::SolverError;
use crate::run::executor::Solver;
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::{self, ResidualBound};
use crate::run::state::State;
use crate::shooting::rule::{own_share, set_unshot, shoot, unshot_power};
use radiosity_core::Real;

/// Progressive refinement.
#[derive(Debug, Default)]
pub struct ProgressiveRefinement {
    column: Vec<Real>,
    amount: Vec<Real>,
}

/// The patch maximising `weight(i) · Σ_c |ΔB_ic|`, lowest index on ties.
pub(crate) fn select(state: &State, weight: impl Fn(usize) -> Real) -> usize {
    let k = state.channels;
    let mut best = (0, Real::NEG_INFINITY);
    for (i, unshot) in state.unshot.chunks_exact(k).enumerate() {
        let v = weight(i) * unshot.iter().map(|u| u.abs()).sum::<Real>();
        if v > best.1 {
            best = (i, v);
        }
    }
    best.0
}

/// Shoots all of `j`'s unshot radiosity, leaving `j` only its own share of the shot
/// ([`own_share`], zero for a planar patch).
pub(crate) fn shoot_all(
    problem: &Problem<'_>,
    state: &mut State,
    j: usize,
    amount: &mut Vec<Real>,
    column: &mut Vec<Real>,
) -> Result<(), SolverError> {
    let k = state.channels;
    column.resize(problem.n(), 0.0);
    amount.clear();
    amount.extend_from_slice(&state.unshot[j * k..(j + 1) * k]);
    shoot(problem, state, j, amount, column)?;
    for (c, &s) in amount.iter().enumerate() {
        set_unshot(state, j * k + c, own_share(problem, j, c, s, column))?;
    }
    Ok(())
}

impl Solver for ProgressiveRefinement {
    fn name(&self) -> String {
        "pr".into()
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let area = problem.system().areas();
        let j = select(state, |i| area[i]);
        shoot_all(problem, state, j, &mut self.amount, &mut self.column)?;
        Ok(Record::new())
    }

    fn residual_power(&self, problem: &Problem<'_>, state: &State) -> Option<Real> {
        Some(unshot_power(problem, state))
    }

    fn residual_bound(&self, problem: &Problem<'_>, state: &State) -> Option<ResidualBound> {
        Some(residual_bound::shooting(problem, state))
    }
}
