//! faer's matrix-free interface (`faer::matrix_free::LinOp`) over [`RadiosityOperator`], so
//! faer's own iterative solvers (conjugate gradients, BiCGSTAB, LSMR) run on the radiosity
//! system with any form-factor source.
//!
//! ## Rule
//!
//! The operator applied is `A = I − diag(ρ) F` on patch-major vectors of length `n·k`
//! ([`crate::operator`]); each column of a right-hand side is one such vector, multiplied by
//! its own product. It is real, so its conjugate is itself. `A` is not symmetric: faer's
//! conjugate gradients need the symmetrized system `diag(A/ρ) A` of exactly reciprocal form
//! factors (`A_i F_ij = A_j F_ji`), which [`SymmetrizedOperator`] applies.
//!
//! ## References
//!
//! - faer 0.24, `faer::matrix_free`: `LinOp`, `conjugate_gradient`, `bicgstab`.

use crate::math::Real;
use crate::operator::RadiosityOperator;
use faer::dyn_stack::{MemStack, StackReq};
use faer::matrix_free::LinOp;
use faer::{MatMut, MatRef, Par};

impl LinOp<Real> for RadiosityOperator<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }

    fn nrows(&self) -> usize {
        self.dim()
    }

    fn ncols(&self) -> usize {
        self.dim()
    }

    fn apply(&self, out: MatMut<'_, Real>, rhs: MatRef<'_, Real>, _par: Par, _stack: &mut MemStack) {
        apply_by_columns(out, rhs, self.dim(), |x, y| {
            RadiosityOperator::apply(self, x, y);
        });
    }

    fn conj_apply(&self, out: MatMut<'_, Real>, rhs: MatRef<'_, Real>, par: Par, stack: &mut MemStack) {
        LinOp::apply(self, out, rhs, par, stack);
    }
}

/// `diag(A/ρ) (I − diag(ρ) F)`, symmetric where the form factors are exactly reciprocal and
/// positive definite where moreover rows sum to at most 1 and `ρ > 0`: the system faer's
/// conjugate gradients can take, with right-hand side `diag(A/ρ) E`.
#[derive(Clone, Debug)]
pub struct SymmetrizedOperator<'a> {
    operator: RadiosityOperator<'a>,
    weights: Vec<Real>,
}

impl<'a> SymmetrizedOperator<'a> {
    /// The symmetrized `operator`; `None` when a reflectivity is not positive (the weight
    /// `A/ρ` would be infinite).
    pub fn new(operator: RadiosityOperator<'a>) -> Option<SymmetrizedOperator<'a>> {
        let system = operator.system();
        let k = operator.channels();
        let rho = system.reflectivities();
        rho.iter().all(|r| *r > 0.0).then(|| {
            let weights = rho.iter().enumerate().map(|(idx, r)| system.areas()[idx / k] / r).collect();
            SymmetrizedOperator { operator, weights }
        })
    }

    /// The weights `A_i / ρ_ic`, patch-major.
    pub fn weights(&self) -> &[Real] {
        &self.weights
    }

    /// The right-hand side `diag(A/ρ) E` whose solution is the radiosity.
    pub fn rhs(&self) -> Vec<Real> {
        self.weights.iter().zip(self.operator.system().emissions()).map(|(w, e)| w * e).collect()
    }
}

impl LinOp<Real> for SymmetrizedOperator<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }

    fn nrows(&self) -> usize {
        self.operator.dim()
    }

    fn ncols(&self) -> usize {
        self.operator.dim()
    }

    fn apply(&self, out: MatMut<'_, Real>, rhs: MatRef<'_, Real>, _par: Par, _stack: &mut MemStack) {
        apply_by_columns(out, rhs, self.operator.dim(), |x, y| {
            self.operator.apply(x, y);
            y.iter_mut().zip(&self.weights).for_each(|(v, w)| *v *= w);
        });
    }

    fn conj_apply(&self, out: MatMut<'_, Real>, rhs: MatRef<'_, Real>, par: Par, stack: &mut MemStack) {
        LinOp::apply(self, out, rhs, par, stack);
    }
}

/// Applies `product` to each column of `rhs` into the same column of `out`, through
/// contiguous vectors of length `dim`.
fn apply_by_columns(
    mut out: MatMut<'_, Real>,
    rhs: MatRef<'_, Real>,
    dim: usize,
    mut product: impl FnMut(&[Real], &mut [Real]),
) {
    let (mut x, mut y) = (vec![0.0; dim], vec![0.0; dim]);
    for c in 0..rhs.ncols() {
        x.iter_mut().zip(rhs.col(c).iter()).for_each(|(x, v)| *x = *v);
        product(&x, &mut y);
        out.as_mut().col_mut(c).iter_mut().zip(&y).for_each(|(o, v)| *o = *v);
    }
}
