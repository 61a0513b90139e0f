//! What the Krylov solvers (`cg`, `gmres-K`, `bicgstab`) share: the operator
//! `A = I − diag(ρ) F` applied through the [`Problem`]'s product (the source's own where it
//! has one, counted as a product, else its columns, each counted), inner products per
//! channel, and what their residual tells the executor.
//!
//! ## The operator
//!
//! Per channel the system is `A B = E` with `A = I − diag(ρ) F` (docs/design.md §3.1). A Krylov
//! solver applies `A` to a vector `x` once a step. A source that multiplies a vector itself (a
//! stored matrix, the hierarchical operator) does so in one product. Otherwise
//! `F x = Σ_j F_{·j} x_j` is a sum of columns, and a
//! column serves every channel at once, so a step costs one column for each patch `j` where
//! some channel of `x` is non-zero: `n` columns for a dense vector, counted by the
//! [`Problem`] like a gathering sweep. Columns of patches where `x` is zero in every channel
//! are left out, which changes no value (their terms are zero) and is counted
//! (`columns_skipped` in the solver's record): the first step applies `F` to the emission,
//! which needs only the emitters' columns. Each row of `F x` is summed over `j` in index order,
//! whatever the thread count, so runs are deterministic.
//!
//! ## State, residual and bound
//!
//! Each solver starts from the executor's `B = E` and keeps, in `state.radiosity`, the
//! current iterate `x_k`, and in `state.unshot` its residual `r_k = E + ρ F x_k − x_k`, updated
//! by the method's recurrences (and recomputed from `F` where the method says so). Its first
//! step computes `r_0 = ρ F E` (one product, emitters' columns only) and leaves `B = E`.
//! Before it the solver knows no residual power, and its residual bound
//! ([`crate::run::residual_bound`]) is that of `B = E`: `r(E) = ρ F E`, so `d = E`, `e = 0`, and
//! the residual is non-negative. After it the residual power the executor watches is
//! `Σ A |r| / Σ A E` and the bound is `d = 0`, `e = r`: the residual itself, elementwise.
//!
//! A channel whose residual is exactly zero (a channel with `ρ = 0` everywhere, or none of
//! whose patches emits) is left as it is: its scalars would be `0 / 0`.
//!
//! ## What the bound leaves out
//!
//! The recurrences keep `r_k = E − A x_k` in exact arithmetic; in floating point the
//! recurred residual drifts from the true one by round-off, about `ε κ(A) ‖E‖`, and near
//! convergence the two part (Greenbaum 1997, on the attainable accuracy of recurred
//! residuals). At `ρ = 0.999` (`κ ≈ 2000`) the true residual stalls near 1e-13 relative while
//! the recurred one may go on falling; the stress suite judges every run on the residual
//! computed from `F` (`radiosity_eval::stress`).
//!
//! ## References
//!
//! - Saad 2003, *Iterative Methods for Sparse Linear Systems*, 2nd ed., SIAM, ch. 6–7.
//! - Greenbaum 1997, *Iterative Methods for Solving Linear Systems*, SIAM.

use crate::error::SolverError;
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::{ResidualBound, area_norms};
use crate::run::state::State;
use radiosity_core::{Real, apply_from_product, residual_from_product};

/// Applies `F` and `A = I − diag(ρ) F` through a problem's product ([`Problem::multiply`]: the
/// source's own, or its columns), counting what it did, and the public operator's `A x` and
/// residual from that product.
#[derive(Debug, Default)]
pub(crate) struct Operator {
    column: Vec<Real>,
    /// Matrix–vector products so far.
    pub(crate) products: u64,
    /// Columns left out because the vector was zero at their patch in every channel.
    pub(crate) skipped: u64,
}

impl Operator {
    /// `out = F x`, both patch-major with the problem's channels; a value of the product that
    /// is not finite (a form factor that is not) is an error naming `step` and the patch.
    pub(crate) fn f_times(
        &mut self,
        problem: &Problem<'_>,
        x: &[Real],
        out: &mut [Real],
        step: u64,
    ) -> Result<(), SolverError> {
        let k = problem.channels();
        let product = problem.multiply(x, out, &mut self.column);
        self.skipped += product.skipped;
        self.products += 1;
        match out.iter().position(|v| !v.is_finite()) {
            Some(idx) => Err(SolverError::NonFinite { step, patch: idx / k, value: out[idx] }),
            None => Ok(()),
        }
    }

    /// `out = A x = x − ρ F x` ([`Operator::f_times`]).
    pub(crate) fn apply(
        &mut self,
        problem: &Problem<'_>,
        x: &[Real],
        out: &mut [Real],
        step: u64,
    ) -> Result<(), SolverError> {
        self.f_times(problem, x, out, step)?;
        apply_from_product(problem.system(), x, out);
        Ok(())
    }

    /// `out = E − A x = E + ρ F x − x`, the residual of `x` ([`Operator::f_times`]).
    pub(crate) fn residual(
        &mut self,
        problem: &Problem<'_>,
        x: &[Real],
        out: &mut [Real],
        step: u64,
    ) -> Result<(), SolverError> {
        self.f_times(problem, x, out, step)?;
        residual_from_product(problem.system(), x, out);
        Ok(())
    }
}

/// Per channel `c`, `Σ_i w_ic u_ic v_ic` over patch-major vectors with `k` channels.
pub(crate) fn dots(weights: &[Real], u: &[Real], v: &[Real], k: usize) -> Vec<Real> {
    let mut sums = vec![0.0; k];
    for ((w, u), v) in weights.chunks_exact(k).zip(u.chunks_exact(k)).zip(v.chunks_exact(k)) {
        for c in 0..k {
            sums[c] += w[c] * u[c] * v[c];
        }
    }
    sums
}

/// `y_c += a_c x_c` for every patch, per channel.
pub(crate) fn axpy(a: &[Real], x: &[Real], y: &mut [Real]) {
    let k = a.len();
    for (y, x) in y.chunks_exact_mut(k).zip(x.chunks_exact(k)) {
        for c in 0..k {
            y[c] += a[c] * x[c];
        }
    }
}

/// Each patch's area once per channel: the weights of the area inner product
/// `⟨u, v⟩_c = Σ_i A_i u_ic v_ic`.
pub(crate) fn area_weights(problem: &Problem<'_>) -> Vec<Real> {
    let k = problem.channels();
    problem.system().areas().iter().flat_map(|&a| std::iter::repeat_n(a, k)).collect()
}

/// What every Krylov solver records: its products and the columns they left out.
impl Operator {
    pub(crate) fn record(&self) -> Record {
        let mut record = Record::new();
        record.set("matvecs", self.products).set("columns_skipped", self.skipped);
        record
    }
}

/// The residual power once the first product has measured the residual (`None` before).
pub(crate) fn power_once_known(problem: &Problem<'_>, residual: &[Real], known: bool) -> Option<Real> {
    known.then(|| residual_power(problem, residual))
}

/// The bound: the residual itself once known, that of `B = E` before (module doc).
pub(crate) fn bound_once_known(problem: &Problem<'_>, residual: &[Real], known: bool) -> ResidualBound {
    if known { bound(problem, residual) } else { bound_of_emission(problem) }
}

/// `Σ A |r| / Σ A |E|` over every channel (0 when nothing emits).
fn residual_power(problem: &Problem<'_>, residual: &[Real]) -> Real {
    let areas = problem.system().areas();
    let k = problem.channels();
    let r: Real = area_norms(areas, residual, k).iter().sum();
    let emitted: Real = area_norms(areas, problem.system().emissions(), k).iter().sum();
    if emitted > 0.0 { r / emitted } else { 0.0 }
}

/// The bound `d = 0`, `e = r` of a solver that keeps the residual `r` of its displayed
/// radiosity (module doc).
fn bound(problem: &Problem<'_>, residual: &[Real]) -> ResidualBound {
    let k = problem.channels();
    ResidualBound::new(vec![0.0; k], area_norms(problem.system().areas(), residual, k))
}

/// The bound of `B = E`, before the first product: `r(E) = ρ F E`, so `d = E`, `e = 0`, and
/// the residual is non-negative where every emission is (module doc).
fn bound_of_emission(problem: &Problem<'_>) -> ResidualBound {
    let (k, e) = (problem.channels(), problem.system().emissions());
    ResidualBound::new(area_norms(problem.system().areas(), e, k), vec![0.0; k])
        .with_nonnegative_residual(e.iter().all(|v| *v >= 0.0))
}

/// Refuses a radiosity that is not finite, naming the step about to be counted and the
/// first such patch.
pub(crate) fn check_finite(state: &State) -> Result<(), SolverError> {
    let k = state.channels;
    match state.radiosity.iter().position(|v| !v.is_finite()) {
        Some(idx) => Err(SolverError::NonFinite { step: state.step + 1, patch: idx / k, value: state.radiosity[idx] }),
        None => Ok(()),
    }
}
