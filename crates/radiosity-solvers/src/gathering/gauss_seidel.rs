//! `gauss-seidel` and `sor-ω`: point Gauss–Seidel gathering and successive over-relaxation.
//!
//! Rule: patches are gathered in index order from the current radiosity, and moved by `ω`
//! times their residual: `B_i ← B_i + ω (E_i + ρ_i Σ_j F_ij B_j − B_i)`; `ω = 1` is
//! Gauss–Seidel. One step gathers one patch (one column); `n` steps make a sweep. The
//! residual reported is the sum over the last sweep of each patch's residual at the moment
//! it was gathered (of a vector that changes during the sweep, so an estimate).
//!
//! ## References
//!
//! - Cohen & Greenberg 1985, "The hemi-cube", SIGGRAPH (Gauss–Seidel for radiosity).
//! - Young 1971, *Iterative Solution of Large Linear Systems* (SOR).

use crate::error::SolverError;
use crate::gathering::rule::{SweepResidual, gather, relax};
use crate::naming::{ParseSolverError, SolverParams, no_params, split_params, validated};
use crate::run::executor::{Solver, StepKind};
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::{ResidualBound, SweepChanges};
use crate::run::state::State;
use radiosity_core::Real;
use std::str::FromStr;

/// The names `gauss-seidel` (`ω = 1`) and `sor-ω`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussSeidelParams {
    /// The over-relaxation factor, in `(0, 2)`.
    pub omega: Real,
}

impl Default for GaussSeidelParams {
    /// Plain Gauss–Seidel.
    fn default() -> GaussSeidelParams {
        GaussSeidelParams { omega: 1.0 }
    }
}

impl FromStr for GaussSeidelParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<GaussSeidelParams, ParseSolverError> {
        let (head, params) = split_params(name);
        let omega = if head == "gauss-seidel" {
            1.0
        } else {
            head.strip_prefix("sor-").and_then(|w| w.parse::<Real>().ok()).ok_or(ParseSolverError::OtherFamily)?
        };
        no_params(head, params)?;
        validated(name, GaussSeidelParams { omega })
    }
}

impl SolverParams for GaussSeidelParams {
    const SYNTAX: &'static str = "gauss-seidel, sor-ω";
    const HELP: &'static str = "point Gauss–Seidel gathering, over-relaxed by 0 < ω < 2 (SOR)";
    const EXAMPLES: &'static [&'static str] = &["gauss-seidel", "sor-1.2"];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        Ok(Box::new(GaussSeidel::new(self.omega)?))
    }
}

/// Point Gauss–Seidel with over-relaxation factor `omega` (1 for plain Gauss–Seidel).
#[derive(Debug)]
pub struct GaussSeidel {
    omega: Real,
    row: Vec<Real>,
    residual: Vec<Real>,
    sweep: SweepResidual,
    changes: SweepChanges,
}

impl GaussSeidel {
    /// Gauss–Seidel with over-relaxation `omega`, which must lie in `(0, 2)`.
    pub fn new(omega: Real) -> Result<GaussSeidel, SolverError> {
        if !(omega > 0.0 && omega < 2.0) {
            return Err(SolverError::BadParams(format!("SOR needs 0 < ω < 2, not {omega}")));
        }
        Ok(GaussSeidel {
            omega,
            row: Vec::new(),
            residual: Vec::new(),
            sweep: SweepResidual::default(),
            changes: SweepChanges::default(),
        })
    }
}

impl Solver for GaussSeidel {
    fn name(&self) -> String {
        if self.omega == 1.0 { "gauss-seidel".into() } else { format!("sor-{}", self.omega) }
    }

    fn init(&mut self, _problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        self.sweep = SweepResidual::default();
        self.changes = SweepChanges::default();
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let i = self.sweep.next;
        self.residual.resize(state.channels, 0.0);
        gather(problem, &state.radiosity, i, &mut self.row, &mut self.residual);
        self.changes.replacing(problem, state, i);
        relax(state, i, self.omega, &self.residual)?;
        self.sweep.add(problem, i, &self.residual);
        if self.sweep.next == 0 {
            self.changes.end_sweep();
        }
        Ok(Record::new())
    }

    fn residual_power(&self, _problem: &Problem<'_>, _state: &State) -> Option<Real> {
        self.sweep.last()
    }

    fn residual_bound(&self, problem: &Problem<'_>, state: &State) -> Option<ResidualBound> {
        Some(self.changes.bound(problem, state, false, self.omega))
    }

    fn step_kind(&self) -> StepKind {
        StepKind::Gather
    }
}
