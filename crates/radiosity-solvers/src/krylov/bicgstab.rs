//! `bicgstab`: the biconjugate gradient stabilised method.
//!
//! ## Rule
//!
//! Per channel, on `A B = E` with `A = I − diag(ρ) F` ([`crate::krylov::operator`]), with the area
//! inner product `⟨u, v⟩ = Σ_i A_i u_i v_i`. From `x_0 = E`, the first step computes
//! `r_0 = ρ F E` and sets the shadow residual `r̂ = r_0`, `p = r_0`, `ϱ = ⟨r̂, r_0⟩`. Each
//! iteration then takes two steps, one product each:
//!
//! 1. `v = A p`, `α = ϱ / ⟨r̂, v⟩`, `s = r − α v`, `x += α p` (displayed, with residual `s`);
//! 2. `t = A s`, `ω = ⟨t, s⟩ / ⟨t, t⟩`, `x += ω s`, `r = s − ω t`, `ϱ' = ⟨r̂, r⟩`,
//!    `β = (ϱ' / ϱ)(α / ω)`, `p = r + β (p − ω v)`.
//!
//! BiCGSTAB needs no symmetry, so it runs on every backend, and keeps six vectors. It can
//! break down where `⟨r̂, v⟩`, `ϱ'` or `ω` vanish while the residual does not; then the
//! channel starts again from its current residual (`r̂ = p = r`), which the record counts
//! (`breakdowns`). Its residual need not fall monotonically.
//!
//! ## References
//!
//! - van der Vorst 1992, "Bi-CGSTAB: a fast and smoothly converging variant of Bi-CG for the
//!   solution of nonsymmetric linear systems", SIAM J. Sci. Stat. Comput. 13(2).
//! - Saad 2003, *Iterative Methods for Sparse Linear Systems*, 2nd ed., §7.4.2.

use crate::error::SolverError;
use crate::krylov::operator::{self, Operator, area_weights, axpy, dots};
use crate::naming::{ParseSolverError, SolverParams, plain_name};
use crate::run::executor::{Solver, StepKind};
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::ResidualBound;
use crate::run::state::State;
use radiosity_core::Real;
use std::str::FromStr;

/// The name `bicgstab`: it takes no parameters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BicgstabParams;

impl FromStr for BicgstabParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<BicgstabParams, ParseSolverError> {
        plain_name(name, "bicgstab")?;
        Ok(BicgstabParams)
    }
}

impl SolverParams for BicgstabParams {
    const SYNTAX: &'static str = "bicgstab";
    const HELP: &'static str = "BiCGSTAB: two products by F an iteration, one a step; needs no symmetry";
    const EXAMPLES: &'static [&'static str] = &["bicgstab"];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        Ok(Box::new(Bicgstab::default()))
    }
}

/// Which half of an iteration the next step takes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Phase {
    /// The first step: `r_0` from F.
    #[default]
    Start,
    /// `v = A p` and the step along `p`.
    AlongP,
    /// `t = A s` and the step along `s`.
    AlongS,
}

/// BiCGSTAB (module doc).
#[derive(Debug, Default)]
pub struct Bicgstab {
    operator: Operator,
    weights: Vec<Real>,
    phase: Phase,
    /// The residual of the displayed radiosity: `r`, or `s` after the first half.
    residual: Vec<Real>,
    shadow: Vec<Real>,
    direction: Vec<Real>,
    /// `v = A p`.
    v: Vec<Real>,
    /// `t = A s`.
    t: Vec<Real>,
    /// Per channel: `ϱ`, `α`.
    rho: Vec<Real>,
    alpha: Vec<Real>,
    breakdowns: u64,
}

impl Bicgstab {
    /// Starts channel `c` of `k` again from its current residual: `r̂ = p = r`, `ϱ = ⟨r, r⟩`
    /// (given as `rr`).
    fn restart_channel(&mut self, c: usize, k: usize, rr: Real) {
        for idx in (c..self.residual.len()).step_by(k) {
            self.shadow[idx] = self.residual[idx];
            self.direction[idx] = self.residual[idx];
        }
        self.rho[c] = rr;
    }
}

impl Solver for Bicgstab {
    fn name(&self) -> String {
        "bicgstab".into()
    }

    fn init(&mut self, problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        self.weights = area_weights(problem);
        self.operator = Operator::default();
        self.phase = Phase::Start;
        self.breakdowns = 0;
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let (k, len) = (state.channels, state.radiosity.len());
        match self.phase {
            Phase::Start => {
                self.residual.resize(len, 0.0);
                self.operator.residual(problem, &state.radiosity, &mut self.residual, state.step + 1)?;
                self.shadow.clone_from(&self.residual);
                self.direction.clone_from(&self.residual);
                self.rho = dots(&self.weights, &self.residual, &self.residual, k);
                self.alpha = vec![0.0; k];
                self.phase = Phase::AlongP;
            }
            Phase::AlongP => {
                self.v.resize(len, 0.0);
                self.operator.apply(problem, &self.direction, &mut self.v, state.step + 1)?;
                let rv = dots(&self.weights, &self.shadow, &self.v, k);
                for ((alpha, rho), rv) in self.alpha.iter_mut().zip(&self.rho).zip(&rv) {
                    *alpha = if *rho != 0.0 && *rv != 0.0 { rho / rv } else { 0.0 };
                }
                axpy(&self.alpha, &self.direction, &mut state.radiosity);
                let minus: Vec<Real> = self.alpha.iter().map(|a| -a).collect();
                axpy(&minus, &self.v, &mut self.residual);
                self.phase = Phase::AlongS;
            }
            Phase::AlongS => {
                self.t.resize(len, 0.0);
                self.operator.apply(problem, &self.residual, &mut self.t, state.step + 1)?;
                let ts = dots(&self.weights, &self.t, &self.residual, k);
                let tt = dots(&self.weights, &self.t, &self.t, k);
                let omega: Vec<Real> = (0..k).map(|c| if tt[c] > 0.0 { ts[c] / tt[c] } else { 0.0 }).collect();
                axpy(&omega, &self.residual, &mut state.radiosity);
                let minus: Vec<Real> = omega.iter().map(|w| -w).collect();
                axpy(&minus, &self.t, &mut self.residual);
                let rho = dots(&self.weights, &self.shadow, &self.residual, k);
                let rr = dots(&self.weights, &self.residual, &self.residual, k);
                for c in 0..k {
                    if rr[c] == 0.0 {
                        // Solved: nothing left to move along.
                        self.rho[c] = 0.0;
                        for idx in (c..len).step_by(k) {
                            self.direction[idx] = 0.0;
                        }
                        continue;
                    }
                    if self.rho[c] == 0.0 || rho[c] == 0.0 || omega[c] == 0.0 || self.alpha[c] == 0.0 {
                        self.breakdowns += 1;
                        self.restart_channel(c, k, rr[c]);
                        continue;
                    }
                    let beta = (rho[c] / self.rho[c]) * (self.alpha[c] / omega[c]);
                    for idx in (c..len).step_by(k) {
                        let p = self.direction[idx];
                        self.direction[idx] = self.residual[idx] + beta * (p - omega[c] * self.v[idx]);
                    }
                    self.rho[c] = rho[c];
                }
                self.phase = Phase::AlongP;
            }
        }
        state.unshot.clone_from(&self.residual);
        operator::check_finite(state)?;
        Ok(Record::new())
    }

    fn residual_power(&self, problem: &Problem<'_>, _state: &State) -> Option<Real> {
        operator::power_once_known(problem, &self.residual, self.phase != Phase::Start)
    }

    fn residual_bound(&self, problem: &Problem<'_>, _state: &State) -> Option<ResidualBound> {
        Some(operator::bound_once_known(problem, &self.residual, self.phase != Phase::Start))
    }

    fn step_kind(&self) -> StepKind {
        StepKind::Product
    }

    fn record(&self) -> Record {
        let mut record = self.operator.record();
        record.set("breakdowns", self.breakdowns);
        record
    }
}
