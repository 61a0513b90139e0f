//! The [`ColumnSource`] trait: the only thing a solver knows about form factors.
//!
//! Column `j` of the form-factor matrix is `(F_ij)_i`, what shooting from patch `j` needs;
//! row `j` follows from the same column by reciprocity, `F_ji = F_ij A_i / A_j`. One column
//! computation is therefore the unit of cost of every solver, as in Rousselle & Renaud, where
//! form factors take 95–99% of the time.
//!
//! Reciprocity holds for the exact form factors, not for every estimate of them: a hemicube or
//! a Monte Carlo column is reciprocal only on average, and an analytic one up to its quadrature
//! error. The matrix a backend defines is the one its columns assemble. A source that can give
//! a row of *that* matrix at the cost of a column (the analytic backend computes every pair on
//! its own; a stored matrix reads it) says so through [`ColumnSource::fill_row`], and gathering
//! solvers then solve exactly the system the reference solves. Others leave the default, and
//! callers fall back on reciprocity.
//!
//! A source may also state how reciprocal its entries are ([`ColumnSource::reciprocity_bound`]):
//! `Some(δ)` promises `|A_i F_ij − A_j F_ji| ≤ δ · max(A_i F_ij, A_j F_ji)` for every pair,
//! with the areas of the system it was built for. Solvers whose hypothesis is reciprocity
//! (conjugate gradients on the symmetrized system) read it and refuse a source that states
//! none, which is the default: a hemicube or Monte Carlo column is reciprocal only on average.
//! Entries computed once per pair in `f64`, the other by reciprocity, state
//! [`F64_PAIR_RECIPROCITY`]; rounding them to `f32` adds [`F32_ROUNDING`]
//! ([`reciprocity_after_f32`]).
//!
//! Implementations must be `Sync`, so columns can be computed in parallel. A blanket
//! `impl ColumnSource for &T` lets wrappers borrow a backend (the ripgrep `Matcher` pattern).
//!
//! Here also live two implementations that need no geometry: [`DenseColumns`], a matrix in
//! memory (for tests and small systems), and [`CountingColumns`], a wrapper that counts the
//! columns computed and the time spent computing them.

use crate::collective::Collective;
use crate::error::CoreError;
use crate::link_source::LinkSource;
use crate::math::Real;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// A provider of form-factor columns.
pub trait ColumnSource: Sync {
    /// The number of patches `n`; columns have length `n`.
    fn patch_count(&self) -> usize;

    /// Writes `F_ij` for every patch `i` into `column[i]`. `column.len()` is `patch_count()`.
    fn fill_column(&self, j: usize, column: &mut [Real]);

    /// Writes `F_ij` for every patch `j` into `row[j]`, exactly the entries the columns hold,
    /// and returns `true`; or returns `false`, leaving `row` unspecified, when the source
    /// cannot do that at the cost of one column (the default). `row.len()` is `patch_count()`.
    fn fill_row(&self, _i: usize, _row: &mut [Real]) -> bool {
        false
    }

    /// A bound `δ` on the relative reciprocity error of every pair,
    /// `|A_i F_ij − A_j F_ji| ≤ δ · max(A_i F_ij, A_j F_ji)` with the areas of the system the
    /// source was built for, when the source knows one (module doc); `None` (the default) when
    /// it states none.
    fn reciprocity_bound(&self) -> Option<Real> {
        None
    }

    /// Forgets whatever the source keeps to make later columns cheaper than the first ones
    /// (the analytic backend's record of visible fractions), so that runs measured one after
    /// another each start from the same cost; no entry changes. The default keeps nothing.
    fn reset_memory(&self) {}

    /// The seconds charged for the columns, rows and products fetched since the last
    /// [`ColumnSource::reset_memory`], when the source charges a modelled cost for them rather
    /// than the time it takes to give them (a stored matrix serving in place of the backend
    /// whose columns it holds, each charged what the backend would have cost): a run's
    /// form-factor seconds are then this charge ([`crate::Clock::Charged`]). `None` (the
    /// default): they cost the time they take ([`crate::Clock::Measured`]).
    fn charged_seconds(&self) -> Option<Real> {
        None
    }

    /// Writes `F x` into `out` and returns `true` when the source multiplies a whole vector
    /// cheaper than its `n` columns (a stored matrix: one pass over its entries); returns
    /// `false`, leaving `out` unspecified, otherwise (the default), and callers sum columns
    /// ([`crate::operator::multiply`]). `x` and `out` are patch-major with `channels` channels,
    /// of length `patch_count() · channels`; the product must be the one the columns give, up
    /// to the order of summation, and deterministic whatever the thread count.
    fn multiply(&self, _x: &[Real], _channels: usize, _out: &mut [Real]) -> bool {
        false
    }

    /// The ranks the source is split over, when it is distributed ([`crate::Collective`]):
    /// every rank then serves the same columns, rows and products in the same order, each a
    /// collective sum, and callers take any decision that may differ between ranks (one that
    /// reads a clock) through [`Collective::agree`]. `None` (the default): one process.
    fn collective(&self) -> Option<&dyn Collective> {
        None
    }

    /// The source's links, when it exposes them ([`LinkSource`]: a hierarchical operator), so
    /// that solvers can shoot from the nodes of its tree; `None` (the default) otherwise.
    fn link_source(&self) -> Option<&dyn LinkSource> {
        None
    }
}

/// The reciprocity bound of entries computed once per pair in `f64`, the other entry taken
/// as `F_ji = F_ij A_i / A_j`: a product and a quotient, each rounded, `2⁻⁵²` between them,
/// doubled for slack.
pub const F64_PAIR_RECIPROCITY: Real = 2.0 * Real::EPSILON;

/// What rounding both entries of a pair to `f32` adds to a reciprocity bound: each moves by
/// at most half of `ε_f32 = f32::EPSILON` of its value, so `|a' − b'| ≤ |a − b| + ε_f32
/// max(a, b)`, and `max(a', b')` is at least `(1 − ε_f32 / 2) max(a, b)`; half as much again
/// covers both with room to spare.
pub const F32_ROUNDING: Real = 1.5 * f32::EPSILON as Real;

/// The reciprocity bound of a source's entries once rounded to `f32` ([`F32_ROUNDING`]).
pub fn reciprocity_after_f32(bound: Option<Real>) -> Option<Real> {
    bound.map(|b| b + F32_ROUNDING)
}

/// The largest relative reciprocity error `|A_i F_ij − A_j F_ji| / max(A_i F_ij, A_j F_ji)`
/// over the pairs of `f` (0 for pairs whose entries are both zero; infinite when an entry is
/// not finite), with patch areas `area`:
/// what a source in memory can state as its [`ColumnSource::reciprocity_bound`]. Reads every
/// column, so for small systems and tests.
pub fn measured_reciprocity(f: &(impl ColumnSource + ?Sized), area: &[Real]) -> Result<Real, CoreError> {
    let n = f.patch_count();
    if area.len() != n {
        return Err(CoreError::SizeMismatch { what: "patch areas", expected: n, found: area.len() });
    }
    let mut columns = vec![0.0; n * n];
    for (j, column) in columns.chunks_exact_mut(n.max(1)).enumerate().take(n) {
        f.fill_column(j, column);
    }
    if columns.iter().any(|v| !v.is_finite()) {
        return Ok(Real::INFINITY);
    }
    let mut worst: Real = 0.0;
    for j in 0..n {
        for i in j + 1..n {
            let (a, b) = (area[i] * columns[j * n + i], area[j] * columns[i * n + j]);
            let scale = a.abs().max(b.abs());
            if scale > 0.0 {
                worst = worst.max((a - b).abs() / scale);
            }
        }
    }
    Ok(worst)
}

impl<T: ColumnSource + ?Sized> ColumnSource for &T {
    fn patch_count(&self) -> usize {
        (**self).patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        (**self).fill_column(j, column)
    }

    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        (**self).fill_row(i, row)
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        (**self).reciprocity_bound()
    }

    fn reset_memory(&self) {
        (**self).reset_memory()
    }

    fn charged_seconds(&self) -> Option<Real> {
        (**self).charged_seconds()
    }

    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        (**self).multiply(x, channels, out)
    }

    fn collective(&self) -> Option<&dyn Collective> {
        (**self).collective()
    }

    fn link_source(&self) -> Option<&dyn LinkSource> {
        (**self).link_source()
    }
}

impl<T: ColumnSource + ?Sized> ColumnSource for Box<T> {
    fn patch_count(&self) -> usize {
        (**self).patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        (**self).fill_column(j, column)
    }

    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        (**self).fill_row(i, row)
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        (**self).reciprocity_bound()
    }

    fn reset_memory(&self) {
        (**self).reset_memory()
    }

    fn charged_seconds(&self) -> Option<Real> {
        (**self).charged_seconds()
    }

    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        (**self).multiply(x, channels, out)
    }

    fn collective(&self) -> Option<&dyn Collective> {
        (**self).collective()
    }

    fn link_source(&self) -> Option<&dyn LinkSource> {
        (**self).link_source()
    }
}

impl<T: ColumnSource + ?Sized + Send> ColumnSource for std::sync::Arc<T> {
    fn patch_count(&self) -> usize {
        (**self).patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        (**self).fill_column(j, column)
    }

    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        (**self).fill_row(i, row)
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        (**self).reciprocity_bound()
    }

    fn reset_memory(&self) {
        (**self).reset_memory()
    }

    fn charged_seconds(&self) -> Option<Real> {
        (**self).charged_seconds()
    }

    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        (**self).multiply(x, channels, out)
    }

    fn collective(&self) -> Option<&dyn Collective> {
        (**self).collective()
    }

    fn link_source(&self) -> Option<&dyn LinkSource> {
        (**self).link_source()
    }
}

/// A form-factor matrix held in memory, column-major.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseColumns {
    n: usize,
    columns: Vec<Real>,
    reciprocity: Option<Real>,
}

impl DenseColumns {
    /// From `n × n` entries in row-major order: `rows[i * n + j] = F_ij`.
    pub fn from_rows(n: usize, rows: &[Real]) -> Result<DenseColumns, CoreError> {
        if rows.len() != n * n {
            return Err(CoreError::SizeMismatch { what: "form-factor matrix", expected: n * n, found: rows.len() });
        }
        let mut columns = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                columns[j * n + i] = rows[i * n + j];
            }
        }
        Ok(DenseColumns { n, columns, reciprocity: None })
    }

    /// From a function of `(i, j)` giving `F_ij`.
    pub fn from_fn(n: usize, mut f: impl FnMut(usize, usize) -> Real) -> DenseColumns {
        let mut columns = vec![0.0; n * n];
        for j in 0..n {
            for i in 0..n {
                columns[j * n + i] = f(i, j);
            }
        }
        DenseColumns { n, columns, reciprocity: None }
    }

    /// `F_ij`.
    pub fn get(&self, i: usize, j: usize) -> Real {
        self.columns[j * self.n + i]
    }

    /// Column `j` as a slice.
    pub fn column(&self, j: usize) -> &[Real] {
        &self.columns[j * self.n..(j + 1) * self.n]
    }

    /// The same matrix, stating as its reciprocity bound the error measured with patch areas
    /// `area` ([`measured_reciprocity`]); refuses areas of the wrong length.
    pub fn with_measured_reciprocity(mut self, area: &[Real]) -> Result<DenseColumns, CoreError> {
        self.reciprocity = Some(measured_reciprocity(&self, area)?);
        Ok(self)
    }
}

impl ColumnSource for DenseColumns {
    fn patch_count(&self) -> usize {
        self.n
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        column.copy_from_slice(self.column(j));
    }

    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        for (j, f) in row.iter_mut().enumerate() {
            *f = self.get(i, j);
        }
        true
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        self.reciprocity
    }
}

/// What a [`CountingColumns`] has counted so far.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ColumnStats {
    /// Columns computed.
    pub columns: u64,
    /// Seconds spent computing them, summed over threads.
    pub seconds: f64,
}

/// Wraps a [`ColumnSource`] and counts the columns computed and the time they took.
///
/// Counters are atomic, so the wrapper stays `Sync` and counts columns computed in parallel.
#[derive(Debug, Default)]
pub struct CountingColumns<S> {
    inner: S,
    columns: AtomicU64,
    nanos: AtomicU64,
}

impl<S: ColumnSource> CountingColumns<S> {
    /// Starts counting from zero.
    pub fn new(inner: S) -> Self {
        CountingColumns { inner, columns: AtomicU64::new(0), nanos: AtomicU64::new(0) }
    }

    /// The counts so far.
    pub fn stats(&self) -> ColumnStats {
        ColumnStats {
            columns: self.columns.load(Ordering::Relaxed),
            seconds: self.nanos.load(Ordering::Relaxed) as f64 * 1e-9,
        }
    }

    /// Sets the counts back to zero.
    pub fn reset(&self) {
        self.columns.store(0, Ordering::Relaxed);
        self.nanos.store(0, Ordering::Relaxed);
    }

    /// The wrapped source.
    pub fn inner(&self) -> &S {
        &self.inner
    }

    /// Gives the wrapped source back.
    pub fn into_inner(self) -> S {
        self.inner
    }
}

impl<S: ColumnSource> ColumnSource for CountingColumns<S> {
    fn patch_count(&self) -> usize {
        self.inner.patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        let start = Instant::now();
        self.inner.fill_column(j, column);
        let nanos = start.elapsed().as_nanos().min(u64::MAX as u128) as u64;
        self.columns.fetch_add(1, Ordering::Relaxed);
        self.nanos.fetch_add(nanos, Ordering::Relaxed);
    }

    /// Counts a row as one column, and counts nothing when the inner source has no rows.
    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        let start = Instant::now();
        if !self.inner.fill_row(i, row) {
            return false;
        }
        let nanos = start.elapsed().as_nanos().min(u64::MAX as u128) as u64;
        self.columns.fetch_add(1, Ordering::Relaxed);
        self.nanos.fetch_add(nanos, Ordering::Relaxed);
        true
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        self.inner.reciprocity_bound()
    }

    fn reset_memory(&self) {
        self.inner.reset_memory()
    }

    fn charged_seconds(&self) -> Option<Real> {
        self.inner.charged_seconds()
    }

    /// Counts a product's time, not as a column.
    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        let start = Instant::now();
        let done = self.inner.multiply(x, channels, out);
        let nanos = start.elapsed().as_nanos().min(u64::MAX as u128) as u64;
        self.nanos.fetch_add(nanos, Ordering::Relaxed);
        done
    }
    fn collective(&self) -> Option<&dyn Collective> {
        self.inner.collective()
    }

    fn link_source(&self) -> Option<&dyn LinkSource> {
        self.inner.link_source()
    }
}
