//! `southwell`: Southwell iteration, shooting from the patch with the largest residual.
//!
//! Rule: pick `j = argmax_j Σ_c |ΔB_jc|` (the residual of the shot radiosity, not weighted
//! by area; the lowest index on ties), shoot `s = ΔB_j`, then `ΔB_j = ρ_j F_jj s`, the
//! shooter's own share (zero for planar patches, [`crate::shooting::rule::own_share`]). One
//! column a step.
//!
//! ## References
//!
//! - Southwell 1946, *Relaxation Methods in Theoretical Physics*.
//! - Gortler, Cohen & Slusallek 1993, "Radiosity and relaxation methods", IEEE CG&A.

use crate::error::SolverError;
use crate::run::executor::Solver;
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::{self, ResidualBound};
use crate::run::state::State;
use crate::shooting::progressive::{select, shoot_all};
use crate::shooting::rule::unshot_power;
use radiosity_core::Real;

/// Southwell iteration.
#[derive(Debug, Default)]
pub struct Southwell {
    column: Vec<Real>,
    amount: Vec<Real>,
}

impl Solver for Southwell {
    fn name(&self) -> String {
        "southwell".into()
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let j = select(state, |_| 1.0);
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
