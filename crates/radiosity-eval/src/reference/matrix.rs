//! The form-factor matrix held in memory, and the one pass over `F` that every residual needs.
//!
//! Geometric backends compute `F` one column at a time, and a column is the expensive unit.
//! The reference solve and repeated metric evaluations need every column, often many times,
//! so [`FormFactors`] holds the matrix in one of two ways:
//!
//! - **stored** ([`FormFactors::from_stored`]): a [`StoredMatrix`] of `radiosity-ff`, values
//!   in `f32`, dense or sparse, whichever is smaller (each pair of the analytic backend
//!   computed once, the other entry by reciprocity). Every sum over it is taken in `f64`. This
//!   is what a [`crate::Lab`] holds: `4 n²` bytes at most (0.48 GB at n = 11 000), less for
//!   occluded and open scenes, and never a dense `f64` copy;
//! - **dense `f64`** ([`FormFactors::assemble`]), row-major, `8 n²` bytes: for the small
//!   systems of tests and of the stress suite, whose stiff furnaces need rows rescaled to sum
//!   to 1 in `f64` ([`FormFactors::close_rows`]). Assembly refuses matrices larger than the
//!   limit it is given.
//!
//! Columns are fetched in fixed blocks, each block in parallel with rayon, and every sum is
//! taken in a fixed order (row `i` of `F B` over `j = 0, 1, …`; weighted column sums over
//! `i = 0, 1, …`), so results do not depend on the thread count. Streaming the columns
//! ([`Residual::from_columns`](crate::Residual::from_columns)) and reading a dense matrix
//! ([`FormFactors`]) add in the same order and give bit-identical results.

use crate::error::EvalError;
use radiosity_core::column::reciprocity_after_f32;
use radiosity_core::{ColumnSource, LinearSystem, Real};
use radiosity_ff::StoredMatrix;
use rayon::prelude::*;

/// Columns fetched together, in parallel, before they are scattered or accumulated.
const BLOCK: usize = 128;

/// A form-factor matrix in memory: `get(i, j) = F_ij`.
///
/// It is itself a [`ColumnSource`], so solvers can run on it without recomputing columns.
#[derive(Clone, Debug, PartialEq)]
pub struct FormFactors {
    n: usize,
    entries: Entries,
    /// The reciprocity bound the entries satisfy ([`ColumnSource::reciprocity_bound`]).
    reciprocity: Option<Real>,
}

#[derive(Clone, Debug, PartialEq)]
enum Entries {
    /// Row-major `f64`: `F_ij` at `i * n + j`.
    Dense(Vec<Real>),
    /// A stored matrix of `f32` values, column-major.
    Stored(Box<StoredMatrix>),
}

impl FormFactors {
    /// Fetches every column of `f` once (in parallel) and stores the matrix dense in `f64`,
    /// refusing it if `8 n²` bytes exceed `max_bytes`, or if an entry is negative or not finite.
    pub fn assemble(f: &(impl ColumnSource + ?Sized), max_bytes: usize) -> Result<FormFactors, EvalError> {
        assemble_dyn(&f, max_bytes)
    }

    /// Holds a stored matrix of `radiosity-ff` as it is (`f32` values, sums in `f64`).
    pub fn from_stored(matrix: StoredMatrix) -> FormFactors {
        FormFactors {
            n: matrix.len(),
            reciprocity: matrix.reciprocity_bound(),
            entries: Entries::Stored(Box::new(matrix)),
        }
    }

    /// The number of patches `n`.
    pub fn patch_count(&self) -> usize {
        self.n
    }

    /// Bytes taken by the entries.
    pub fn bytes(&self) -> usize {
        match &self.entries {
            Entries::Dense(rows) => rows.len() * size_of::<Real>(),
            Entries::Stored(m) => m.bytes(),
        }
    }

    /// The stored matrix, when the entries are held as one.
    pub fn stored(&self) -> Option<&StoredMatrix> {
        match &self.entries {
            Entries::Dense(_) => None,
            Entries::Stored(m) => Some(m),
        }
    }

    /// `F_ij`.
    ///
    /// # Panics
    ///
    /// If `i` or `j` is not below `n`, like slice indexing.
    pub fn get(&self, i: usize, j: usize) -> Real {
        match &self.entries {
            Entries::Dense(rows) => rows[i * self.n + j],
            Entries::Stored(m) => m.get(i, j),
        }
    }

    /// `Σ_j F_ij` for every row `i`, summed in `f64` in column order.
    pub fn row_sums(&self) -> Vec<Real> {
        match &self.entries {
            Entries::Dense(rows) => rows.par_chunks(self.n.max(1)).map(|row| row.iter().sum()).collect(),
            Entries::Stored(m) => m.row_sums(),
        }
    }

    /// Rescales every row with a positive sum to sum to 1, in `f64`, and returns the smallest
    /// and largest factor applied (`(1, 1)` when nothing changed). A stored matrix is first
    /// copied dense in `f64`, so this is for small systems only.
    ///
    /// For a closed scene only: there every row of the exact `F` sums to 1, so with uniform
    /// `ρ` and `E` the furnace identity `B = E / (1 − ρ)` becomes the exact solution of the
    /// rescaled system to round-off, whatever the backend's closure error was. That is what
    /// lets a stiff furnace (`ρ = 0.999`, where a row-sum error `δ` moves the answer by about
    /// `δ / (1 − ρ)`) test solvers against a closed form. It breaks reciprocity by the spread
    /// of the factors, which the caller reports, and which the matrix's reciprocity bound then
    /// includes (`hi / lo − 1` beside the bound it had). `radiosity-ff`'s stored-matrix rebalancing
    /// does the same in `f32`, which leaves row sums off by about 1e-7: too much at `ρ =
    /// 0.999`.
    pub fn close_rows(&mut self) -> (Real, Real) {
        if let Entries::Stored(m) = &self.entries {
            let n = self.n;
            let mut rows = vec![0.0; n * n];
            for j in 0..n {
                m.for_each_in_column(j, |i, v| rows[i * n + j] = Real::from(v));
            }
            self.entries = Entries::Dense(rows);
        }
        let Entries::Dense(rows) = &mut self.entries else { unreachable!("made dense above") };
        let (mut lo, mut hi) = (1.0, 1.0);
        for row in rows.chunks_mut(self.n.max(1)) {
            let sum: Real = row.iter().sum();
            if sum > 0.0 {
                let factor = 1.0 / sum;
                row.iter_mut().for_each(|v| *v *= factor);
                lo = Real::min(lo, factor);
                hi = Real::max(hi, factor);
            }
        }
        // `A_i F_ij s_i` against `A_j F_ji s_j`: the factors' ratio, at most `hi / lo`, moves
        // the pair's error by at most `hi / lo − 1` of the larger, beside the error it had.
        self.reciprocity = self.reciprocity.map(|b| (1.0 + b) * (hi / lo) - 1.0);
        (lo, hi)
    }

    /// The largest row sum `max_i Σ_j F_ij` (at most 1 in a scene that loses no energy).
    pub fn max_row_sum(&self) -> Real {
        self.row_sums().into_iter().fold(0.0, Real::max)
    }

    /// Row `i` of a dense `f64` matrix.
    pub(crate) fn dense_row(&self, i: usize) -> Option<&[Real]> {
        match &self.entries {
            Entries::Dense(rows) => Some(&rows[i * self.n..(i + 1) * self.n]),
            Entries::Stored(_) => None,
        }
    }
}

impl ColumnSource for FormFactors {
    fn patch_count(&self) -> usize {
        self.n
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        match &self.entries {
            Entries::Dense(rows) => {
                for (i, v) in column.iter_mut().enumerate() {
                    *v = rows[i * self.n + j];
                }
            }
            Entries::Stored(m) => m.fill_column(j, column),
        }
    }

    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        match &self.entries {
            Entries::Dense(rows) => row.copy_from_slice(&rows[i * self.n..(i + 1) * self.n]),
            Entries::Stored(m) => _ = m.fill_row(i, row),
        }
        true
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        self.reciprocity
    }

    /// One pass over the entries (`multiply_matrix`), deterministic whatever the thread
    /// count.
    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        multiply_matrix(self, x, channels, out);
        true
    }
}

/// A column source whose entries are rounded to `f32`, as a stored matrix holds them: a lab's
/// solvers read these, so that they solve exactly the system its stored reference solves.
/// Rounding costs `n` conversions a column, nothing beside computing one.
///
/// A source's own product ([`ColumnSource::multiply`], the hierarchical operator's) is passed
/// through unrounded: it has no entries to round. Its values differ from the rounded
/// entries' product by the `f32` rounding of each entry, a relative `6e-8` at most, which is
/// then the floor of `e_rms` against a stored reference of the rounded columns.
pub struct F32Columns<S>(pub S);

impl<S: ColumnSource> ColumnSource for F32Columns<S> {
    fn patch_count(&self) -> usize {
        self.0.patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        self.0.fill_column(j, column);
        column.iter_mut().for_each(|v| *v = Real::from(*v as f32));
    }

    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        let exact = self.0.fill_row(i, row);
        row.iter_mut().for_each(|v| *v = Real::from(*v as f32));
        exact
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        reciprocity_after_f32(self.0.reciprocity_bound())
    }

    fn reset_memory(&self) {
        self.0.reset_memory()
    }

    fn charged_seconds(&self) -> Option<Real> {
        self.0.charged_seconds()
    }

    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        self.0.multiply(x, channels, out)
    }
    fn collective(&self) -> Option<&dyn radiosity_core::Collective> {
        self.0.collective()
    }

    fn link_source(&self) -> Option<&dyn radiosity_core::LinkSource> {
        self.0.link_source()
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
    Ok(FormFactors { n, entries: Entries::Dense(rows), reciprocity: f.reciprocity_bound() })
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
        if f.collective().is_some() {
            // A source split over ranks serves one column at a time, in the same order on
            // every rank (each column is a collective sum), on the calling thread.
            block.chunks_mut(n).enumerate().for_each(|(dj, column)| f.fill_column(j0 + dj, column));
        } else {
            block.par_chunks_mut(n).enumerate().for_each(|(dj, column)| f.fill_column(j0 + dj, column));
        }
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

/// Per channel, `max_j Σ_i A_i ρ_ic F_ij / A_j`, from the matrix in memory (`n²` reads).
pub(crate) fn kappa_matrix(system: &LinearSystem, m: &FormFactors) -> Vec<Real> {
    let n = m.n;
    let k = system.channels().count();
    let (area, rho) = (system.areas(), system.reflectivities());
    let rows = match &m.entries {
        Entries::Dense(rows) => rows,
        Entries::Stored(stored) => {
            // Columns in parallel, each summed over its rows in order.
            return (0..n)
                .into_par_iter()
                .map(|j| {
                    let mut sums = vec![0.0; k];
                    stored.for_each_in_column(j, |i, v| {
                        for (c, s) in sums.iter_mut().enumerate() {
                            *s += area[i] * rho[i * k + c] * Real::from(v);
                        }
                    });
                    sums.into_iter().map(|s| s / area[j]).collect::<Vec<_>>()
                })
                .reduce(|| vec![0.0; k], |a, b| a.iter().zip(&b).map(|(x, y)| x.max(*y)).collect());
        }
    };
    // Column chunks in parallel; inside a chunk, rows in order (the streaming pass's order).
    let chunk = BLOCK;
    let partial: Vec<Vec<Real>> = (0..n.div_ceil(chunk))
        .into_par_iter()
        .map(|b| {
            let (j0, j1) = (b * chunk, ((b + 1) * chunk).min(n));
            let mut sums = vec![0.0; (j1 - j0) * k];
            for i in 0..n {
                let row = &rows[i * n + j0..i * n + j1];
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

/// `fb = F b` from the matrix in memory, patch-major with `k` channels. Dense: rows in parallel,
/// each row summed in column order. Stored: columns in fixed chunks (as many whatever the
/// thread count), each chunk's partial product accumulated in column order and the partials
/// added in chunk order, so the sums do not depend on the thread count either.
fn multiply_matrix(m: &FormFactors, b: &[Real], k: usize, fb: &mut [Real]) {
    let n = m.n;
    fb.fill(0.0);
    match &m.entries {
        Entries::Dense(rows) => fb.par_chunks_mut(k).enumerate().for_each(|(i, out)| {
            let row = &rows[i * n..(i + 1) * n];
            for (j, fij) in row.iter().enumerate() {
                for c in 0..k {
                    out[c] += fij * b[j * k + c];
                }
            }
        }),
        Entries::Stored(stored) => {
            let chunks = n.div_ceil(PRODUCT_CHUNK_COLUMNS).clamp(1, PRODUCT_CHUNKS);
            let width = n.div_ceil(chunks.max(1)).max(1);
            let partials: Vec<Vec<Real>> = (0..chunks)
                .into_par_iter()
                .map(|chunk| {
                    let mut out = vec![0.0; n * k];
                    for j in chunk * width..((chunk + 1) * width).min(n) {
                        let bj = &b[j * k..(j + 1) * k];
                        stored.for_each_in_column(j, |i, v| {
                            let v = Real::from(v);
                            for c in 0..k {
                                out[i * k + c] += v * bj[c];
                            }
                        });
                    }
                    out
                })
                .collect();
            for partial in partials {
                fb.iter_mut().zip(partial).for_each(|(s, p)| *s += p);
            }
        }
    }
}

/// At most this many partial products in a product with a stored matrix ...
const PRODUCT_CHUNKS: usize = 16;
/// ... and at least this many columns in each.
const PRODUCT_CHUNK_COLUMNS: usize = 1024;
