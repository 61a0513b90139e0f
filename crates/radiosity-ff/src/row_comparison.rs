//! Two backends compared row by row: how far a fast backend's rows of `F` are from a trusted
//! one's, on rows chosen by the caller, without assembling either matrix.
//!
//! For each row `i` it gives both row sums and `‖F̃_i − F_i‖₁ / ‖F_i‖₁`, the relative L1
//! distance: `|(F̃ x)_i − (F x)_i| ≤ ‖F̃_i − F_i‖₁ · max|x|` for that row. Over the rows
//! compared it is a sampled estimate of the operator's error, not a certified bound
//! (docs/design.md §5): the rows not compared are not known.

use radiosity_core::{ColumnSource, Real};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// One row compared.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RowDistance {
    /// The row.
    pub row: usize,
    /// Its sum in the backend compared.
    pub sum: Real,
    /// Its sum in the reference.
    pub reference_sum: Real,
    /// `‖F̃_i − F_i‖₁ / ‖F_i‖₁` (0 when both rows are zero).
    pub relative_l1: Real,
}

/// The rows compared, and their summary.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RowComparison {
    /// Each row.
    pub rows: Vec<RowDistance>,
    /// The largest relative L1 distance.
    pub max_relative_l1: Real,
    /// The mean relative L1 distance.
    pub mean_relative_l1: Real,
    /// The largest difference of row sums.
    pub max_sum_difference: Real,
}

/// `count` distinct rows of `n`, drawn with `seed`, in increasing order.
pub fn sampled_rows(n: usize, count: usize, seed: u64) -> Vec<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut all: Vec<usize> = (0..n).collect();
    let (chosen, _) = all.partial_shuffle(&mut rng, count.min(n));
    let mut rows = chosen.to_vec();
    rows.sort_unstable();
    rows
}

/// Compares the `rows` of `f` with those of `reference`, each row read with
/// [`ColumnSource::fill_row`] where the source serves rows, or else assembled from all its
/// columns (costly: use sources that serve rows).
pub fn compare_rows(f: &dyn ColumnSource, reference: &dyn ColumnSource, rows: &[usize]) -> RowComparison {
    compare_read_rows(rows, &read_rows(f, rows), &read_rows(reference, rows))
}

/// Compares rows already read: `a[k]` and `b[k]` are row `rows[k]` of the source compared and
/// of the reference.
pub fn compare_read_rows(rows: &[usize], a: &[Vec<Real>], b: &[Vec<Real>]) -> RowComparison {
    let n = a.first().map_or(0, Vec::len);
    let distances: Vec<RowDistance> = rows
        .iter()
        .zip(a.iter().zip(b))
        .map(|(&row, (x, y))| {
            debug_assert!(x.len() == n && y.len() == n);
            let l1: Real = x.iter().zip(y).map(|(p, q)| (p - q).abs()).sum();
            let norm: Real = y.iter().map(|q| q.abs()).sum();
            RowDistance {
                row,
                sum: x.iter().sum(),
                reference_sum: y.iter().sum(),
                relative_l1: if norm > 0.0 {
                    l1 / norm
                } else if l1 > 0.0 {
                    Real::INFINITY
                } else {
                    0.0
                },
            }
        })
        .collect();
    let max_relative_l1 = distances.iter().map(|d| d.relative_l1).fold(0.0, Real::max);
    let mean_relative_l1 = distances.iter().map(|d| d.relative_l1).sum::<Real>() / distances.len().max(1) as Real;
    let max_sum_difference = distances.iter().map(|d| (d.sum - d.reference_sum).abs()).fold(0.0, Real::max);
    RowComparison { rows: distances, max_relative_l1, mean_relative_l1, max_sum_difference }
}

/// The `rows` of `f`: by rows where it serves them, else from every column.
pub fn read_rows(f: &dyn ColumnSource, rows: &[usize]) -> Vec<Vec<Real>> {
    let n = f.patch_count();
    let mut out = vec![vec![0.0; n]; rows.len()];
    let served = rows.iter().zip(out.iter_mut()).all(|(&i, row)| f.fill_row(i, row));
    if !served {
        let mut column = vec![0.0; n];
        for j in 0..n {
            f.fill_column(j, &mut column);
            for (row, &i) in out.iter_mut().zip(rows) {
                row[j] = column[i];
            }
        }
    }
    out
}
