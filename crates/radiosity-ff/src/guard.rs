//! Guard rails shared by every backend: entries clamped to `[0, 1]` (and counted), and the
//! closure and reciprocity figures of an assembled matrix.
//!
//! Clamping is a guard, not a correction: a backend that needs it on more than a handful of
//! entries is wrong, so the count is reported with every matrix. Non-finite entries are set to
//! zero and counted the same way.

use radiosity_core::Real;
use std::sync::atomic::{AtomicU64, Ordering};

/// Counts entries that had to be clamped into `[0, 1]`.
#[derive(Debug, Default)]
pub struct ClampCounter(AtomicU64);

impl ClampCounter {
    /// Clamps every entry of `column` into `[0, 1]` (non-finite entries become 0), counting
    /// the entries changed.
    pub fn clamp(&self, column: &mut [Real]) {
        let mut changed = 0;
        for v in column.iter_mut() {
            let clamped = if v.is_finite() { v.clamp(0.0, 1.0) } else { 0.0 };
            if clamped != *v {
                changed += 1;
                *v = clamped;
            }
        }
        if changed > 0 {
            self.0.fetch_add(changed, Ordering::Relaxed);
        }
    }

    /// Entries clamped so far.
    pub fn count(&self) -> u64 {
        self.0.load(Ordering::Relaxed)
    }
}

/// Closure and reciprocity of a full matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatrixFigures {
    /// Smallest row sum `Σ_j F_ij`.
    pub row_sum_min: Real,
    /// Mean row sum.
    pub row_sum_mean: Real,
    /// Largest row sum.
    pub row_sum_max: Real,
    /// Largest `|A_i F_ij − A_j F_ji| / max(A_i F_ij, A_j F_ji)` over pairs with a non-zero.
    pub max_reciprocity_error: Real,
    /// Non-zero entries.
    pub nonzeros: usize,
}

/// The figures of the `n × n` matrix `f(i, j)` with patch areas `area`.
pub fn matrix_figures(area: &[Real], f: impl Fn(usize, usize) -> Real) -> MatrixFigures {
    let n = area.len();
    let mut sums = vec![0.0; n];
    let mut reciprocity: Real = 0.0;
    let mut nonzeros = 0;
    for i in 0..n {
        for j in 0..n {
            let fij = f(i, j);
            if fij != 0.0 {
                nonzeros += 1;
            }
            sums[i] += fij;
            if j > i {
                let (a, b) = (area[i] * fij, area[j] * f(j, i));
                let scale = a.max(b);
                if scale > 0.0 {
                    reciprocity = reciprocity.max((a - b).abs() / scale);
                }
            }
        }
    }
    MatrixFigures::from_row_sums(&sums, reciprocity, nonzeros)
}

impl MatrixFigures {
    /// The figures from the row sums, the largest reciprocity error and the non-zero count.
    pub fn from_row_sums(sums: &[Real], max_reciprocity_error: Real, nonzeros: usize) -> MatrixFigures {
        MatrixFigures {
            row_sum_min: sums.iter().copied().fold(Real::INFINITY, Real::min),
            row_sum_mean: sums.iter().sum::<Real>() / sums.len() as Real,
            row_sum_max: sums.iter().copied().fold(Real::NEG_INFINITY, Real::max),
            max_reciprocity_error,
            nonzeros,
        }
    }
}
