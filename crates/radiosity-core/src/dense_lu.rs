//! Dense LU with partial pivoting (faer), for the systems `Φ x = b` that the reference solves
//! whole and group solvers solve on a group.
//!
//! faer was measured 17× faster than nalgebra at n = 3400 (the `lu` bench of
//! radiosity-eval), and is as fast on the small group systems.

use crate::math::Real;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::{Conj, Mat, Par};

/// A zero or non-finite pivot met by [`lu_solve`] or [`lu_solve_columns`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingularPivot {
    /// The pivot's index.
    pub pivot: usize,
    /// Its value.
    pub value: Real,
}

/// Solves the `n × n` system `a x = b` by faer's LU with partial pivoting, one right-hand
/// side, on one thread or (`parallel`) on rayon's. The dense reference solves each channel
/// with it, and the `lu` bench times it. A thin wrapper over [`lu_solve_columns`].
pub fn lu_solve(
    n: usize,
    parallel: bool,
    a: impl Fn(usize, usize) -> Real,
    b: impl Fn(usize) -> Real,
) -> Result<Vec<Real>, SingularPivot> {
    let rhs = [(0..n).map(b).collect::<Vec<Real>>()];
    let mut solved = lu_solve_columns(n, parallel, a, &rhs)?;
    Ok(solved.pop().expect("one right-hand side gives one solution"))
}

/// Solves the `n × n` systems `a x_r = rhs[r]` for every right-hand side `rhs[r]` (each of
/// length `n`) with one factorisation: faer's LU with partial pivoting, on one thread or
/// (`parallel`) on rayon's. Group solvers use it to solve `Φ_rr y = s` and `Φ_rr z = 1`
/// together, the second for the condition estimate.
///
/// Returns the solutions in the order of `rhs`, or the first pivot of the factorisation that
/// is zero or not finite.
///
/// # Panics
///
/// If a right-hand side does not have `n` entries.
pub fn lu_solve_columns(
    n: usize,
    parallel: bool,
    a: impl Fn(usize, usize) -> Real,
    rhs: &[Vec<Real>],
) -> Result<Vec<Vec<Real>>, SingularPivot> {
    assert!(rhs.iter().all(|b| b.len() == n), "every right-hand side needs {n} entries");
    let par = if parallel { Par::rayon(0) } else { Par::Seq };
    let columns = rhs.len();
    let mut a = Mat::from_fn(n, n, a);
    let mut fwd = vec![0usize; n];
    let mut bwd = vec![0usize; n];
    let mut mem = MemBuffer::new(
        factor::lu_in_place_scratch::<usize, Real>(n, n, par, Default::default())
            .or(solve::solve_in_place_scratch::<usize, Real>(n, columns, par)),
    );
    let (_, perm) =
        factor::lu_in_place(a.as_mut(), &mut fwd, &mut bwd, par, MemStack::new(&mut mem), Default::default());
    if let Some(pivot) = (0..n).find(|&p| !(a[(p, p)].is_finite() && a[(p, p)] != 0.0)) {
        return Err(SingularPivot { pivot, value: a[(pivot, pivot)] });
    }
    if columns == 0 {
        return Ok(Vec::new());
    }
    let mut x = Mat::from_fn(n, columns, |i, r| rhs[r][i]);
    solve::solve_in_place_with_conj(a.as_ref(), a.as_ref(), perm, Conj::No, x.as_mut(), par, MemStack::new(&mut mem));
    Ok((0..columns).map(|r| (0..n).map(|i| x[(i, r)]).collect()).collect())
}
