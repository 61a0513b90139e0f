//! The form-factor matrix held in memory, and the one pass over `F` that every residual needs.
//!
//! Geometric backends compute `F` one column at a time, and a column is the expensive unit.
//! The reference solve and repeated metric evaluations need every column, often many times,
//! so [`FormFactors`] fetches each column once and keeps the matrix dense, in `f64`, stored
//! **row-major**: Gauss–Seidel and the product `F B` read rows. Its size is `8 n²` bytes
//! (0.97 GB at n = 11 000, 20 GB at 50 000); assembly refuses matrices larger than the limit
//! it is given. A stored-matrix backend serving rows directly can replace it later.
//!
//! Columns are fetched in fixed blocks, each block in parallel with rayon, and every sum is
//! taken in a fixed order (row `i` of `F B` over `j = 0, 1, …`; weighted column sums over
//! `i = 0, 1, …`), so results do not depend on the thread count. Streaming the columns
//! ([`Residual::from_columns`](crate::Residual::from_columns)) and reading the stored matrix
//! ([`FormFactors`]) add in the same order and give bit-identical results.

use crate::error::EvalError;
use radiosity_core::{ColumnSource, LinearSystem, Real};
use rayon::prelude::*;

/// Columns fetched together, in parallel, before they are scattered or accumulated.
const BLOCK: usize = 128;

/// A dense form-factor matrix in memory, row-major: `get(i, j) = F_ij`.
///
/// It is itself a [`ColumnSource`], so solvers can run on it without recomputing columns
/// (a column is gathered from the rows, which costs `n` strided reads).
#[derive(Clone, Debug, PartialEq)]
pub struct FormFactors {
    n: usize,
    rows: Vec<Real>,
}

impl FormFactors {
    /// Fetches every column of `f` once (in parallel) and stores the matrix, refusing it if
    /// `8 n²` bytes exceed `max_bytes`, or if an entry is negative or not finite.
    pub fn assemble(f: &(impl ColumnSource + ?Sized), max_bytes: usize) -> Result<FormFactors, EvalError> {
        assemble_dyn(&f, max_bytes)
    }

    /// The number of patches `n`.
    pub fn patch_count(&self) -> usize {
        self.n
    }

    /// `F_ij`.
    pub fn get(&self, i: usize, j: usize) -> Real {
        self.rows[i * self.n + j]
    }

    /// Row `i`: `F_ij` for every `j`.
    pub fn row(&self, i: usize) -> &[Real] {
        &self.rows[i * self.n..(i + 1) * self.n]
    }

    /// Rescales every row with a positive sum to sum to 1, in `f64`, and returns the smallest
    /// and largest factor applied (`(1, 1)` when nothing changed).
    ///
    /// For a closed scene only: there every row of the exact `F` sums to 1, so with uniform
    /// `ρ` and `E` the furnace identity `B = E / (1 − ρ)` becomes the exact solution of the
    /// rescaled system to round-off, whatever the backend's closure error was. That is what
    /// lets a stiff furnace (`ρ = 0.999`, where a row-sum error `δ` moves the answer by about
    /// `δ / (1 − ρ)`) test solvers against a closed form. It breaks reciprocity by the spread
    /// of the factors, which the caller reports. `radiosity-ff`'s stored-matrix rebalancing
    /// does the same in `f32`, which leaves row sums off by about 1e-7: too much at `ρ =
    /// 0.999`.
    pub fn close_rows(&mut self) -> (Real, Real) {
        let (mut lo, mut hi) = (1.0, 1.0);
        for row in self.rows.chunks_mut(self.n.max(1)) {
            let sum: Real = row.iter().sum();
            if sum > 0.0 {
                let factor = 1.0 / sum;
                row.iter_mut().for_each(|v| *v *= factor);
                lo = Real::min(lo, factor);
                hi = Real::max(hi, factor);
            }
        }
        (lo, hi)
    }

    /// The largest row sum `max_i Σ_j F_ij` (at most 1 in a scene that loses no energy).
    pub fn max_row_sum(&self) -> Real {
        self.rows.par_chunks(self.n.max(1)).map(|row| row.iter().sum::<Real>()).reduce(|| 0.0, Real::max)
    }
}

impl ColumnSource for FormFactors {
    fn patch_count(&self) -> usize {
        self.n
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        for (i, v) in column.iter_mut().enumerate() {
            *v = self.rows[i * self.n + j];
        }
    }

    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        row.copy_from_slice(self.row(i));
        true
    }
}

fn assemble_dyn(f: &dyn ColumnSource, max_bytes: usize) -> Result<FormFactors, EvalError> {
    let n = f.patch_count();
    let bytes = n.checked_mul(n).and_then(|m| m.checked_mul(size_of::<Real>())).unwrap_or(usize::MAX);
    if bytes > max_bytes {
        return Err(EvalError::MatrixTooLarge { n, bytes, limit: max_bytes });
    }
    let mut rows = vec![0.0; n * n];
    for_each_column_block(f, |j0, block| {
        let w = block.len() / n;
        rows.par_chunks_mut(n).enumerate().for_each(|(i, row)| {
            for dj in 0..w {
                row[j0 + dj] = block[dj * n + i];
            }
        });
    })?;
    Ok(FormFactors { n, rows })
}

/// Fetches the columns of `f` in blocks of [`BLOCK`] (each block in parallel), checks every
/// entry, and hands each block to `visit` as `(first column, column-major n × w entries)`.
pub(crate) fn for_each_column_block(
    f: &dyn ColumnSource,
    mut visit: impl FnMut(usize, &[Real]),
) -> Result<(), EvalError> {
    let n = f.patch_count();
    if n == 0 {
        return Ok(());
    }
    let mut buffer = vec![0.0; n * BLOCK.min(n)];
    for j0 in (0..n).step_by(BLOCK) {
        let w = BLOCK.min(n - j0);
        let block = &mut buffer[..n * w];
        block.par_chunks_mut(n).enumerate().for_each(|(dj, column)| f.fill_column(j0 + dj, column));
        if let Some(k) = block.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(EvalError::InvalidFormFactor { i: k % n, j: j0 + k / n, value: block[k] });
        }
        visit(j0, block);
    }
    Ok(())
}

/// What one pass over `F` gives for a vector `b` (patch-major, `k` channels).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Pass {
    /// `(F b)_ic`, patch-major.
    pub fb: Vec<Real>,
    /// `max_i Σ_j F_ij`.
    pub max_row_sum: Real,
    /// Per channel, `max_j Σ_i A_i ρ_ic F_ij / A_j`.
    pub kappa: Vec<Real>,
}

/// Checks that `f` has `n` patches and that `b`, if given, has `n · k` entries.
pub(crate) fn check_sizes(system: &LinearSystem, n_f: usize, b: Option<&[Real]>) -> Result<(), EvalError> {
    let n = system.len();
    if n_f != n {
        return Err(EvalError::SizeMismatch { what: "the form-factor matrix", expected: n, found: n_f });
    }
    check_vector(system, b)
}

/// Checks that `b`, if given, has `n · k` entries.
pub(crate) fn check_vector(system: &LinearSystem, b: Option<&[Real]>) -> Result<(), EvalError> {
    let n = system.len();
    if let Some(b) = b {
        let len = n * system.channels().count();
        if b.len() != len {
            return Err(EvalError::SizeMismatch { what: "the radiosity vector", expected: len, found: b.len() });
        }
    }
    Ok(())
}

/// One pass over streamed columns: `n` column computations, `O(n)` memory.
pub(crate) fn pass_columns(system: &LinearSystem, f: &dyn ColumnSource, b: &[Real]) -> Result<Pass, EvalError> {
    let n = system.len();
    let k = system.channels().count();
    let (area, rho) = (system.areas(), system.reflectivities());
    // Per row: k sums of F b, then the row sum.
    let mut acc = vec![0.0; n * (k + 1)];
    let mut kappa = vec![0.0_f64; k];
    for_each_column_block(f, |j0, block| {
        let w = block.len() / n;
        acc.par_chunks_mut(k + 1).enumerate().for_each(|(i, a)| {
            for dj in 0..w {
                let fij = block[dj * n + i];
                let j = j0 + dj;
                for c in 0..k {
                    a[c] += fij * b[j * k + c];
                }
                a[k] += fij;
            }
        });
        for (dj, column) in block.chunks(n).enumerate() {
            let j = j0 + dj;
            for (c, kc) in kappa.iter_mut().enumerate() {
                let mut s = 0.0;
                for (i, fij) in column.iter().enumerate() {
                    s += area[i] * rho[i * k + c] * fij;
                }
                *kc = kc.max(s / area[j]);
            }
        }
    })?;
    let mut fb = vec![0.0; n * k];
    let mut max_row_sum = 0.0_f64;
    for (i, a) in acc.chunks(k + 1).enumerate() {
        fb[i * k..(i + 1) * k].copy_from_slice(&a[..k]);
        max_row_sum = max_row_sum.max(a[k]);
    }
    Ok(Pass { fb, max_row_sum, kappa })
}

/// Per channel, `max_j Σ_i A_i ρ_ic F_ij / A_j`, from the stored matrix (`n²` reads).
pub(crate) fn kappa_matrix(system: &LinearSystem, m: &FormFactors) -> Vec<Real> {
    let n = m.n;
    let k = system.channels().count();
    let (area, rho) = (system.areas(), system.reflectivities());
    // Column chunks in parallel; inside a chunk, rows in order (the streaming pass's order).
    let chunk = BLOCK;
    let partial: Vec<Vec<Real>> = (0..n.div_ceil(chunk))
        .into_par_iter()
        .map(|b| {
            let (j0, j1) = (b * chunk, ((b + 1) * chunk).min(n));
            let mut sums = vec![0.0; (j1 - j0) * k];
            for i in 0..n {
                let row = &m.rows[i * n + j0..i * n + j1];
                for c in 0..k {
                    let w = area[i] * rho[i * k + c];
                    for (dj, fij) in row.iter().enumerate() {
                        sums[dj * k + c] += w * fij;
                    }
                }
            }
            let mut best = vec![0.0_f64; k];
            for (dj, s) in sums.chunks(k).enumerate() {
                for c in 0..k {
                    best[c] = best[c].max(s[c] / area[j0 + dj]);
                }
            }
            best
        })
        .collect();
    partial.into_iter().fold(vec![0.0; k], |a, p| a.iter().zip(&p).map(|(x, y)| x.max(*y)).collect())
}

/// `F b` from the stored matrix, rows in parallel, each row summed in column order.
pub(crate) fn multiply_matrix(m: &FormFactors, b: &[Real], k: usize) -> Vec<Real> {
    let n = m.n;
    let mut fb = vec![0.0; n * k];
    fb.par_chunks_mut(k).enumerate().for_each(|(i, out)| {
        let row = &m.rows[i * n..(i + 1) * n];
        for (j, fij) in row.iter().enumerate() {
            for c in 0..k {
                out[c] += fij * b[j * k + c];
            }
        }
    });
    fb
}
