//! `cg`: conjugate gradients on the symmetrized radiosity system.
//!
//! ## Hypothesis
//!
//! Per channel, multiply `(I − diag(ρ) F) B = E` by `W = diag(A / ρ)`:
//!
//! `S B = W E`, with `S = diag(A / ρ) − diag(A) F`.
//!
//! With reciprocity, `A_i F_ij = A_j F_ji`, `diag(A) F` is symmetric, so `S` is. When every
//! `ρ_i < 1` and every row of `F` sums to at most 1, `S` is strictly diagonally dominant with
//! a positive diagonal (`A_i / ρ_i − A_i F_ii > A_i Σ_{j≠i} F_ij`), hence positive definite,
//! and conjugate gradients apply. Patches with `ρ_i = 0` have `B_i = E_i`: they are left out
//! of the unknowns (weight 0 below); their emission reaches the others through the first
//! residual.
//!
//! The solver checks what it can before its first step: the form factors must state a
//! reciprocity bound ([`radiosity_core::ColumnSource::reciprocity_bound`]) of at most
//! [`RECIPROCITY_LIMIT`]; otherwise it refuses with [`SolverError::NotApplicable`], since
//! on form factors reciprocal only on average (hemicube, Monte Carlo) `S` is not symmetric
//! and CG's short recurrences do not minimise anything (`gmres-K` and `bicgstab` need no
//! symmetry). Positive definiteness it checks at every step: `⟨p, A p⟩_W > 0` for every search
//! direction, or it stops with the same error. The record states both: the bound it was given
//! (`reciprocity_bound`) and the smallest Rayleigh quotient `⟨p, A p⟩_W / ⟨p, p⟩_W` met
//! (`rayleigh_min`, an estimate from above of `λ_min`, at least `1 − max_i ρ_i Σ_j F_ij` under
//! the hypothesis).
//!
//! ## Rule
//!
//! CG on `S` with the Jacobi preconditioner `M = diag(A / ρ)` (the diagonal of `S` for
//! planar patches, `F_ii = 0`) is CG on `A = I − diag(ρ) F`, self-adjoint in the inner
//! product `⟨u, v⟩_W = Σ_i (A_i / ρ_i) u_i v_i`, and its preconditioned residual
//! `M⁻¹ (W E − S x) = E − A x` is the radiosity residual itself. From `x_0 = E` and
//! `r_0 = ρ F E` (the first step), `p_0 = r_0`; each later step is
//!
//! `q = A p`, `α = ⟨r, r⟩_W / ⟨p, q⟩_W`, `x += α p`, `r −= α q`,
//! `β = ⟨r', r'⟩_W / ⟨r, r⟩_W`, `p = r' + β p`,
//!
//! per channel, one product `F p` for all channels ([`crate::krylov::operator`]). The error
//! `x − B*` falls in the energy norm of `S` at least as
//! `2 ((√κ − 1) / (√κ + 1))^k` with `κ` the condition number of `A` in that norm, at most
//! `(1 + ρ_max) / (1 − ρ_max)` when rows sum to at most 1 (Saad 2003, §6.11.3).
//!
//! faer's matrix-free solvers (`faer::matrix_free::conjugate_gradient`) run the whole
//! iteration inside one call, so the executor could not stop, time or observe them step by
//! step; the recurrence above is a few lines on the [`crate::krylov::operator`] operator instead.
//!
//! ## References
//!
//! - Hestenes & Stiefel 1952, "Methods of conjugate gradients for solving linear systems",
//!   J. Res. Nat. Bur. Standards 49(6).
//! - Saad 2003, *Iterative Methods for Sparse Linear Systems*, 2nd ed., §6.7 and §9.2
//!   (preconditioned CG).

use crate::error::SolverError;
use crate::krylov::operator::{self, Operator, axpy, dots};
use crate::naming::{ParseSolverError, SolverParams, plain_name};
use crate::run::executor::{Solver, StepKind};
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::ResidualBound;
use crate::run::state::State;
use radiosity_core::Real;
use std::str::FromStr;

/// The largest reciprocity bound `cg` accepts: `f32` storage (about 1.8e-7) passes, rows
/// rescaled by factors that differ by more than 1e-6 do not.
pub const RECIPROCITY_LIMIT: Real = 1e-6;

/// The name `cg`: conjugate gradients take no parameters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CgParams;

impl FromStr for CgParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<CgParams, ParseSolverError> {
        plain_name(name, "cg")?;
        Ok(CgParams)
    }
}

impl SolverParams for CgParams {
    const SYNTAX: &'static str = "cg";
    const HELP: &'static str = "conjugate gradients on the symmetrized system diag(A/ρ)(I − ρF); a step is one product by F; needs reciprocal F";
    const EXAMPLES: &'static [&'static str] = &["cg"];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        Ok(Box::new(ConjugateGradients::default()))
    }
}

/// Conjugate gradients on the symmetrized system (module doc).
#[derive(Debug, Default)]
pub struct ConjugateGradients {
    operator: Operator,
    /// `A_i / ρ_ic`, 0 where `ρ_ic = 0`, patch-major.
    weights: Vec<Real>,
    residual: Vec<Real>,
    direction: Vec<Real>,
    product: Vec<Real>,
    /// `⟨r, r⟩_W` per channel.
    rr: Vec<Real>,
    started: bool,
    reciprocity: Real,
    rayleigh_min: Real,
}

impl Solver for ConjugateGradients {
    fn name(&self) -> String {
        "cg".into()
    }

    fn applicable(&self, problem: &Problem<'_>) -> Result<(), SolverError> {
        let refuse = |reason: String| SolverError::NotApplicable { solver: "cg".into(), reason };
        const NEED: &str = "cg solves the symmetrized system diag(A/ρ)(I − ρF), which needs reciprocal form factors \
             (A_i F_ij = A_j F_ji)";
        match problem.reciprocity_bound() {
            None => Err(refuse(format!(
                "{NEED}, and these form factors state no reciprocity bound (hemicube and Monte Carlo columns are \
                 reciprocal only on average); gmres-30 and bicgstab need no symmetry"
            ))),
            Some(b) if b.is_nan() || b > RECIPROCITY_LIMIT => Err(refuse(format!(
                "{NEED}, and these form factors are reciprocal only to a relative {b:.2e}, above the \
                 {RECIPROCITY_LIMIT:e} cg accepts; gmres-30 and bicgstab need no symmetry"
            ))),
            Some(_) => Ok(()),
        }
    }

    fn init(&mut self, problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        // The executor asked `applicable` first, so the bound is stated and within the limit.
        self.reciprocity = problem.reciprocity_bound().unwrap_or(Real::INFINITY);
        let k = problem.channels();
        let (areas, rho) = (problem.system().areas(), problem.system().reflectivities());
        self.weights =
            (0..problem.n() * k).map(|idx| if rho[idx] > 0.0 { areas[idx / k] / rho[idx] } else { 0.0 }).collect();
        self.operator = Operator::default();
        self.started = false;
        self.rayleigh_min = Real::INFINITY;
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let k = state.channels;
        let len = state.radiosity.len();
        if !self.started {
            self.residual.resize(len, 0.0);
            self.operator.residual(problem, &state.radiosity, &mut self.residual, state.step + 1)?;
            self.direction.clone_from(&self.residual);
            self.rr = dots(&self.weights, &self.residual, &self.residual, k);
            self.started = true;
            state.unshot.clone_from(&self.residual);
            return Ok(Record::new());
        }
        self.product.resize(len, 0.0);
        self.operator.apply(problem, &self.direction, &mut self.product, state.step + 1)?;
        let pq = dots(&self.weights, &self.direction, &self.product, k);
        let pp = dots(&self.weights, &self.direction, &self.direction, k);
        let mut alpha = vec![0.0; k];
        for c in 0..k {
            if self.rr[c] == 0.0 {
                continue;
            }
            if pq[c].is_nan() || pq[c] <= 0.0 {
                // Nothing of the state has moved yet: the run ends with it kept.
                return Err(SolverError::Breakdown {
                    solver: "cg".into(),
                    reason: format!(
                        "at step {} the symmetrized system of channel {c} is not positive definite (⟨p, A p⟩ = {:.3e}): \
                         ρ times some row sum of F reaches 1",
                        state.step + 1,
                        pq[c]
                    ),
                });
            }
            alpha[c] = self.rr[c] / pq[c];
            self.rayleigh_min = self.rayleigh_min.min(pq[c] / pp[c]);
        }
        axpy(&alpha, &self.direction, &mut state.radiosity);
        let minus: Vec<Real> = alpha.iter().map(|a| -a).collect();
        axpy(&minus, &self.product, &mut self.residual);
        let rr = dots(&self.weights, &self.residual, &self.residual, k);
        let beta: Vec<Real> = (0..k).map(|c| if self.rr[c] > 0.0 { rr[c] / self.rr[c] } else { 0.0 }).collect();
        for (p, r) in self.direction.chunks_exact_mut(k).zip(self.residual.chunks_exact(k)) {
            for c in 0..k {
                p[c] = r[c] + beta[c] * p[c];
            }
        }
        self.rr = rr;
        state.unshot.clone_from(&self.residual);
        operator::check_finite(state)?;
        Ok(Record::new())
    }

    fn residual_power(&self, problem: &Problem<'_>, _state: &State) -> Option<Real> {
        operator::power_once_known(problem, &self.residual, self.started)
    }

    fn residual_bound(&self, problem: &Problem<'_>, _state: &State) -> Option<ResidualBound> {
        Some(operator::bound_once_known(problem, &self.residual, self.started))
    }

    fn step_kind(&self) -> StepKind {
        StepKind::Product
    }

    fn record(&self) -> Record {
        let mut record = self.operator.record();
        record.set("reciprocity_bound", self.reciprocity);
        if self.rayleigh_min.is_finite() {
            record.set("rayleigh_min", self.rayleigh_min);
        }
        record
    }
}
