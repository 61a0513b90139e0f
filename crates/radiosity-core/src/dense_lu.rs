//! Dense LU with partial pivoting (faer), for the systems `Φ x = b` that the reference solves
//! whole and group solvers solve on a group.
//!
//! faer rather than nalgebra: the `lu` bench compares the two (`docs/bench-office.md`).

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

/// Solves `(I − N) y = b` for a non-negative `n × n` matrix `N` (row-major, `N_ab` at
/// `a * n + b`) and returns `y` with the condition number `κ_∞(I − N)`, or `None` when
/// `I − N` is not a nonsingular M-matrix (an entry of `N` negative or not finite, a zero
/// pivot, or `(I − N)⁻¹ 1` not positive).
///
/// `I − N` with `N ≥ 0` is a nonsingular M-matrix exactly when the spectral radius of `N` is
/// below 1, and then `(I − N)⁻¹ ≥ 0` entrywise, so `‖(I − N)⁻¹‖_∞ = max (I − N)⁻¹ 1`: one more
/// right-hand side on the same factorisation gives `κ_∞` exactly (Berman & Plemmons 1994,
/// ch. 6). A group step solves `Φ_rr y = s` with it, and `cargo xtask stress` measures the
/// whole system's `κ_∞`.
pub fn solve_m_matrix(n: usize, nonnegative: &[Real], b: Vec<Real>) -> Option<(Vec<Real>, Real)> {
    if nonnegative.iter().any(|&v| !(v.is_finite() && v >= 0.0)) {
        return None;
    }
    let phi = |a: usize, c: usize| Real::from(a == c) - nonnegative[a * n + c];
    let mut solved = lu_solve_columns(n, false, phi, &[b, vec![1.0; n]]).ok()?;
    let z = solved.pop()?;
    let y = solved.pop()?;
    Some((y, m_matrix_condition(n, nonnegative, &z)?))
}

/// `κ_∞(I − N)` from `z = (I − N)⁻¹ 1`, for a caller that solved with `1` as one of its
/// right-hand sides ([`solve_m_matrix`] does): `‖I − N‖_∞ max z`, or `None` when `I − N` is
/// not a nonsingular M-matrix (an entry of `N` negative or not finite, or `z` not positive).
pub fn m_matrix_condition(n: usize, nonnegative: &[Real], z: &[Real]) -> Option<Real> {
    if nonnegative.iter().any(|&v| !(v.is_finite() && v >= 0.0)) || z.iter().any(|&v| !(v.is_finite() && v > 0.0)) {
        return None;
    }
    let phi = |a: usize, c: usize| Real::from(a == c) - nonnegative[a * n + c];
    let norm = (0..n).map(|a| (0..n).map(|c| phi(a, c).abs()).sum::<Real>()).fold(0.0, Real::max);
    // Finite and positive factors: the product is never NaN (at worst it overflows to ∞).
    Some(norm * z.iter().copied().fold(0.0, Real::max))
}
