//! `jacobi`: point Jacobi gathering.
//!
//! Rule: a sweep gathers every patch from the radiosity at the start of the sweep,
//! `B_i^{k+1} = E_i + ρ_i Σ_j F_ij B_j^k`; one step gathers one patch (one column, the row by
//! reciprocity), so a sweep is `n` steps. The residual reported is that of `B^k`, exactly, at
//! the end of each sweep.
//!
//! `jacobi:sweep=product` takes a whole sweep a step, one product `F B^k`
//! ([`Problem::multiply`]): the same iterates at the end of each sweep, up to the order of
//! summation. Over a source that multiplies a whole vector itself (a stored matrix, the
//! hierarchical operator, where a product costs as much as a few hundred columns) that is one
//! product in place of `n` rows; over any other, the columns of the patches where `B^k` is not
//! zero. The step's change is the residual `r^k` of `B^k`, and the residual of
//! `B^{k+1} = B^k + r^k` is exactly `ρ F r^k`: the bound of a shooting method with `ΔB = r^k`,
//! non-negative when `r^k` is. The default, `sweep=rows`, is the paper's: a patch a step, its
//! cost counted in columns like every method it is compared with.
//!
//! ## References
//!
//! - Cohen & Greenberg 1985, "The hemi-cube", SIGGRAPH (radiosity by gathering iterations).
//! - Saad 2003, *Iterative Methods for Sparse Linear Systems*, §4.1.

use crate::error::SolverError;
use crate::gathering::rule::{SweepResidual, gather, relax};
use crate::naming::{ParseSolverError, SolverParams, split_params};
use crate::run::executor::{Solver, StepKind};
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::{ResidualBound, SweepChanges, shooting};
use crate::run::state::State;
use radiosity_core::Real;
use std::str::FromStr;

/// The name `jacobi[:sweep=rows|product]`: a patch a step (the default) or a sweep a step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct JacobiParams {
    /// Whether a step is a whole sweep by one product (`sweep=product`, module doc).
    pub by_products: bool,
}

impl FromStr for JacobiParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<JacobiParams, ParseSolverError> {
        let (head, params) = split_params(name);
        if head != "jacobi" {
            return Err(ParseSolverError::OtherFamily);
        }
        match params {
            "" | "sweep=rows" => Ok(JacobiParams { by_products: false }),
            "sweep=product" => Ok(JacobiParams { by_products: true }),
            other => {
                Err(SolverError::BadParams(format!("solver 'jacobi' takes sweep=rows or sweep=product, not '{other}'"))
                    .into())
            }
        }
    }
}

impl SolverParams for JacobiParams {
    const SYNTAX: &'static str = "jacobi[:sweep=rows|product]";
    const HELP: &'static str = "point Jacobi gathering: a sweep gathers every patch from the sweep before, a patch a step or (sweep=product) a sweep a step by one product";
    const EXAMPLES: &'static [&'static str] = &["jacobi", "jacobi:sweep=product"];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        Ok(Box::new(Jacobi { by_products: self.by_products, ..Jacobi::default() }))
    }
}

/// Point Jacobi.
#[derive(Debug, Default)]
pub struct Jacobi {
    sweep_start: Vec<Real>,
    row: Vec<Real>,
    residual: Vec<Real>,
    sweep: SweepResidual,
    changes: SweepChanges,
    /// Whether a step is a whole sweep by one product (`sweep=product`).
    by_products: bool,
    /// `F B^k`, when sweeping by products.
    product: Vec<Real>,
    /// The residual power of `B^k`, when sweeping by products.
    product_residual: Option<Real>,
}

impl Solver for Jacobi {
    fn name(&self) -> String {
        if self.by_products { "jacobi:sweep=product".into() } else { "jacobi".into() }
    }

    fn init(&mut self, _problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        self.sweep = SweepResidual::default();
        self.changes = SweepChanges::default();
        self.product_residual = None;
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        if self.by_products {
            return self.sweep_by_product(problem, state);
        }
        let i = self.sweep.next;
        if i == 0 {
            self.sweep_start.clone_from(&state.radiosity);
        }
        self.residual.resize(state.channels, 0.0);
        gather(problem, &self.sweep_start, i, &mut self.row, &mut self.residual);
        // Step from the sweep's start value: B_i = B_i^k + r_i.
        let k = state.channels;
        state.radiosity[i * k..(i + 1) * k].copy_from_slice(&self.sweep_start[i * k..(i + 1) * k]);
        self.changes.replacing(problem, state, i);
        relax(state, i, 1.0, &self.residual)?;
        self.sweep.add(problem, i, &self.residual);
        if self.sweep.next == 0 {
            self.changes.end_sweep();
        }
        Ok(Record::new())
    }

    fn residual_power(&self, _problem: &Problem<'_>, _state: &State) -> Option<Real> {
        if self.by_products { self.product_residual } else { self.sweep.last() }
    }

    fn residual_bound(&self, problem: &Problem<'_>, state: &State) -> Option<ResidualBound> {
        if self.by_products {
            return Some(shooting(problem, state));
        }
        Some(self.changes.bound(problem, state, true, 1.0))
    }

    /// A gather, or a product with `sweep=product`.
    fn step_kind(&self) -> StepKind {
        if self.by_products { StepKind::Product } else { StepKind::Gather }
    }
}

impl Jacobi {
    /// A whole sweep by one product (module doc): `B^{k+1} = B^k + r^k`, the change `r^k` kept
    /// in `state.unshot`.
    fn sweep_by_product(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let (n, k) = (problem.n(), state.channels);
        self.product.resize(n * k, 0.0);
        problem.multiply(&state.radiosity, &mut self.product, &mut self.row);
        let system = problem.system();
        let (mut residual, mut emitted) = (0.0, 0.0);
        for (idx, &fb) in self.product.iter().enumerate() {
            let (i, c) = (idx / k, idx % k);
            let r = system.e(i, c) + system.rho(i, c) * fb - state.radiosity[idx];
            state.radiosity[idx] += r;
            state.unshot[idx] = r;
            if !state.radiosity[idx].is_finite() {
                return Err(SolverError::NonFinite { step: state.step + 1, patch: i, value: state.radiosity[idx] });
            }
            residual += system.areas()[i] * r.abs();
            emitted += system.areas()[i] * system.e(i, c).abs();
        }
        self.product_residual = Some(if emitted > 0.0 { residual / emitted } else { 0.0 });
        Ok(Record::new())
    }
}
