//! Dense LU with partial pivoting (faer), for the systems `Φ x = b` that the reference solves
//! whole and group solvers solve on a group.
//!
//! faer was measured 17× faster than nalgebra at n = 3400 (the `lu` bench of
//! radiosity-eval), and is as fast on the small group systems.

use crate::math::Real;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::{Conj, Mat, Par};

/// A zero or non-finite pivot met by [`lu_solve`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingularPivot {
    /// The pivot's index.
    pub pivot: usize,
    /// Its value.
    pub value: Real,
}

/// Solves the `n × n` system `a x = b` by faer's LU with partial pivoting, one right-hand
/// side, on one thread or (`parallel`) on rayon's. The dense reference solves each channel
/// with it, group solvers each group, and the `lu` bench times it.
pub fn lu_solve(
    n: usize,
    parallel: bool,
    a: impl Fn(usize, usize) -> Real,
    b: impl Fn(usize) -> Real,
) -> Result<Vec<Real>, SingularPivot> {
    let par = if parallel { Par::rayon(0) } else { Par::Seq };
    let mut a = Mat::from_fn(n, n, a);
    let mut fwd = vec![0usize; n];
    let mut bwd = vec![0usize; n];
    let mut mem = MemBuffer::new(
        factor::lu_in_place_scratch::<usize, Real>(n, n, par, Default::default())
            .or(solve::solve_in_place_scratch::<usize, Real>(n, 1, par)),
    );
    let (_, perm) =
        factor::lu_in_place(a.as_mut(), &mut fwd, &mut bwd, par, MemStack::new(&mut mem), Default::default());
    if let Some(pivot) = (0..n).find(|&p| !(a[(p, p)].is_finite() && a[(p, p)] != 0.0)) {
        return Err(SingularPivot { pivot, value: a[(pivot, pivot)] });
    }
    let mut rhs = Mat::from_fn(n, 1, |i, _| b(i));
    solve::solve_in_place_with_conj(a.as_ref(), a.as_ref(), perm, Conj::No, rhs.as_mut(), par, MemStack::new(&mut mem));
    Ok((0..n).map(|i| rhs[(i, 0)]).collect())
}
