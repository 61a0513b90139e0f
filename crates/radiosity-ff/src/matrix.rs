//! The `matrix` backend's matrix: the full form-factor matrix of another backend, assembled
//! once and served column by column from memory. Its role as a backend (the
//! [`FormFactorBackend`](crate::FormFactorBackend) it is, its assembly from one as an observed
//! build stage) is [`crate::matrix_backend`]'s.
//!
//! ## Assembly
//!
//! [`StoredMatrix::assemble`] computes every column of a [`ColumnSource`] with rayon, in blocks
//! of consecutive columns. Each column is computed on its own and blocks are collected in
//! order, so the result is the same whatever the number of threads. Entries are stored as
//! `f32` (7 significant digits, far below the error of any backend).
//!
//! ## Assembly by reciprocity
//!
//! [`StoredMatrix::assemble_reciprocal`] computes each unordered pair once, from a source that
//! can give single entries (the analytic backend's [`AnalyticColumns::pair`]): for the pair
//! `{i, j}` it computes the entry whose **receiver is the smaller patch**, say `F_ij` with
//! `A_i ≤ A_j`, and derives `F_ji = A_i F_ij / A_j` (docs/design.md §3.3). That halves the work of
//! [`StoredMatrix::assemble`], which computes every column and so every pair twice.
//!
//! What it changes numerically, for the analytic backend: visibility is the same either way
//! (its shadow rays are identical for `(i, j)` and `(j, i)`), but `F_ji` is no longer
//! integrated over receiver `j`; it inherits the quadrature error of the integral over the
//! smaller receiver `i`, which is the more accurate of the two (the error of the rule grows
//! with the receiver's size relative to its distance; a distant pair uses the receiver's
//! centroid). Reciprocity becomes exact up to the `f32` rounding of the entries, where column
//! assembly leaves the quadrature error (largest for a receiver straddling the shooter's
//! plane). The entries of the larger
//! patch of each pair, and so the row sums of large patches, move by that quadrature
//! error. Entries are clamped into `[0, 1]` like every backend's (the computed one first, so
//! the derived one, never larger, stays reciprocal). What that changes on `multi-cubes`, and
//! what it saves: docs/form-factors.md, "Stored matrices".
//!
//! Memory: the pairs are kept compressed (`12` bytes per pair with a non-zero entry) until
//! every one is computed, then written into the smaller storage, each pair's list dropped
//! once written: the peak is about the final size plus `6` bytes per non-zero.
//!
//! [`AnalyticColumns::pair`]: crate::AnalyticColumns::pair
//!
//! ## Storage
//!
//! Whichever is smaller, decided from the number of non-zeros `nnz`:
//!
//! - dense: column-major `f32`, `4n²` bytes;
//! - sparse: compressed sparse columns ([`sprs::CsMatI<f32, u32>`]; a column is a contiguous
//!   slice), `8·nnz + 4(n+1)` bytes. It is used only while `nnz` fits in `u32`.
//!
//! Closed empty rooms are about half non-zero, so either can win; furnished, occluded or open
//! scenes are sparser (docs/form-factors.md, "Stored matrices"). Assembly keeps the columns
//! computed so far in compressed blocks; as soon as `nnz` shows that sparse storage can no
//! longer be the smaller (`nnz` only grows), it scatters them into a dense array, dropping
//! each block as it goes, and writes later columns there. The
//! dense array is allocated zeroed, so its pages are committed as they are written. The
//! matrix is therefore never held twice at full size: memory peaks near the larger of the two
//! sizes, not at their sum. (At `n ≈ 11k` the dense form is 0.48 GB.)
//!
//! ## Rebalancing
//!
//! [`StoredMatrix::rebalance`] symmetrises the power exchange `G = A·F`,
//! `G_ij = (A_i F_ij + A_j F_ji) / 2`, `F_ij ← G_ij / A_i`, which makes reciprocity exact (up
//! to `f32` rounding); then, for a closed scene, it rescales each row to sum to 1. The second
//! step breaks exact reciprocity again (rows are scaled by different factors), so a
//! rebalanced closed-scene matrix sums to 1 but is only as reciprocal as the spread of the row
//! sums it corrected. Both steps are reported by [`RebalanceReport`].
//!
//! The analytic backend is exactly reciprocal (each pair is integrated once), so symmetrising
//! changes nothing, and its rows are as close to 1 as its visibility estimate makes them;
//! rescaling them would move whole rows, which is not more accurate: a larger `budget` is.
//! Hemicube and Monte Carlo estimate each row on its own, so an entry can be zero one way and
//! not the other; symmetrising averages the two estimates of each pair, and that is where
//! rebalancing earns its keep. What it changed on two closed scenes, and what the stored
//! matrices of the built-in scenes take and cost: docs/form-factors.md ("Stored matrices") and
//! docs/bench-office.md.
//!
//! ## Files
//!
//! [`StoredMatrix::to_bytes`] writes a header (a magic string, the format version, the key the
//! caller computed the matrix from, `n`, the number of non-zeros, and the length and xxh3
//! checksum of the body; the frame of `framing`) followed by the entries, all with postcard.
//! [`StoredMatrix::from_bytes`] refuses another format version, another key, a truncated or
//! corrupted body, and entries that do not fit the header, each with a clear
//! [`FfError::StoredMatrix`]. Where files live is the caller's business (only `eval` and
//! `xtask` write files).

use crate::error::FfError;
use crate::framing::{frame, unframe};
use crate::guard::{MatrixFigures, matrix_figures};
use radiosity_core::column::reciprocity_after_f32;
use radiosity_core::{ColumnSource, Real};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sprs::CsMatI;
use std::fmt;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

/// The first field of a stored-matrix file, before [`FORMAT_VERSION`].
pub const MAGIC: &str = "radiosity-ff stored form-factor matrix";

/// The version of the file layout; files of another version are refused.
pub const FORMAT_VERSION: u32 = 2;

/// How a [`StoredMatrix`] holds its entries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// Column-major `f32`, `4n²` bytes.
    Dense,
    /// Compressed sparse columns, `8·nnz + 4(n+1)` bytes.
    Sparse,
}

impl Storage {
    /// `"dense"` or `"sparse"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Storage::Dense => "dense",
            Storage::Sparse => "sparse",
        }
    }
}

impl fmt::Display for Storage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

#[derive(Clone, PartialEq, Serialize, Deserialize)]
enum Entries {
    /// `F_ij` at `j * n + i`.
    Dense(Vec<f32>),
    /// CSC: column `j` is a contiguous slice of row indices and values.
    Sparse(CsMatI<f32, u32>),
}

/// A full form-factor matrix held in memory, dense or sparse, whichever is smaller.
#[derive(Clone)]
pub struct StoredMatrix {
    n: usize,
    nonzeros: usize,
    entries: Entries,
    /// The sparse entries row by row (CSR), built on the first [`ColumnSource::fill_row`]:
    /// gathering solvers read whole rows, and a row of a CSC matrix costs a binary search per
    /// column (19 s a Gauss–Seidel sweep on `office`) where CSR reads it in place. It costs
    /// as much memory again as the sparse entries, and only once a row is asked for.
    row_major: OnceLock<CsMatI<f32, u32>>,
    /// The reciprocity bound the entries satisfy ([`ColumnSource::reciprocity_bound`]):
    /// measured on the `f32` entries after assembly by reciprocity and after rebalancing, the
    /// source's own bound plus `f32` rounding after assembly column by column.
    reciprocity: Option<Real>,
}

/// What [`StoredMatrix::rebalance`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RebalanceReport {
    /// Figures after symmetrising `A·F`, before rows are rescaled.
    pub symmetrised: MatrixFigures,
    /// Largest `|F'_ij − F_ij|` of the symmetrising step.
    pub max_change: Real,
    /// Largest `|F'_ij − F_ij| / F_ij` of the symmetrising step, over entries that were
    /// non-zero.
    pub max_relative_change: Real,
    /// Mean `|F'_ij − F_ij| / F_ij` of the symmetrising step, over entries that were non-zero.
    pub mean_relative_change: Real,
    /// Entries that were zero and became non-zero (`F_ij = 0` but `F_ji ≠ 0`).
    pub filled: usize,
    /// Whether rows were rescaled to sum to 1.
    pub rescaled: bool,
    /// Smallest row factor of the rescaling step (1 when rows were not rescaled).
    pub scale_min: Real,
    /// Largest row factor of the rescaling step (1 when rows were not rescaled).
    pub scale_max: Real,
}

/// Bytes of dense storage.
fn dense_bytes(n: usize) -> usize {
    4 * n * n
}

/// Bytes of sparse storage.
fn sparse_bytes(n: usize, nonzeros: usize) -> usize {
    8 * nonzeros + 4 * (n + 1)
}

/// Whether sparse storage is the smaller (ties go to dense, which is faster to read) and
/// possible (`u32` offsets). False for some `nnz` means false for every larger one.
fn sparse_is_smaller(n: usize, nonzeros: usize) -> bool {
    nonzeros <= u32::MAX as usize && sparse_bytes(n, nonzeros) < dense_bytes(n)
}

/// Consecutive columns in compressed form.
#[derive(Default)]
struct Block {
    /// End of each column in `rows` and `values`.
    ends: Vec<usize>,
    rows: Vec<u32>,
    values: Vec<f32>,
}

impl Block {
    /// Appends a column, keeping its non-zero `f32` entries.
    fn push_column(&mut self, column: impl Iterator<Item = (usize, f32)>) {
        for (i, v) in column {
            if v != 0.0 {
                self.rows.push(i as u32);
                self.values.push(v);
            }
        }
        self.ends.push(self.values.len());
    }

    /// Concatenates compressed columns.
    fn from_columns(columns: Vec<Block>) -> Block {
        let nonzeros = columns.iter().map(|c| c.values.len()).sum();
        let mut block = Block {
            ends: Vec::with_capacity(columns.iter().map(|c| c.ends.len()).sum()),
            rows: Vec::with_capacity(nonzeros),
            values: Vec::with_capacity(nonzeros),
        };
        for c in columns {
            let offset = block.values.len();
            block.ends.extend(c.ends.iter().map(|e| e + offset));
            block.rows.extend_from_slice(&c.rows);
            block.values.extend_from_slice(&c.values);
        }
        block
    }

    /// `(start, end)` of each column in `rows` and `values`.
    fn ranges(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.ends.iter().scan(0, |start, &end| {
            let range = (*start, end);
            *start = end;
            Some(range)
        })
    }
}

/// Builds a matrix column block by column block into the smaller storage.
struct Builder {
    n: usize,
    nonzeros: usize,
    columns: usize,
    state: BuildState,
}

enum BuildState {
    Sparse(Vec<Block>),
    Dense(Vec<f32>),
}

impl Builder {
    fn new(n: usize) -> Builder {
        let mut builder = Builder { n, nonzeros: 0, columns: 0, state: BuildState::Sparse(Vec::new()) };
        if !sparse_is_smaller(n, 0) {
            builder.go_dense();
        }
        builder
    }

    fn push(&mut self, block: Block) {
        self.nonzeros += block.values.len();
        match &mut self.state {
            BuildState::Sparse(blocks) => {
                self.columns += block.ends.len();
                blocks.push(block);
                if !sparse_is_smaller(self.n, self.nonzeros) {
                    self.go_dense();
                }
            }
            BuildState::Dense(entries) => {
                scatter(entries, self.n, self.columns, &block);
                self.columns += block.ends.len();
            }
        }
    }

    /// Moves the blocks so far into a dense array, dropping each once scattered.
    fn go_dense(&mut self) {
        let n = self.n;
        let BuildState::Sparse(blocks) = std::mem::replace(&mut self.state, BuildState::Sparse(Vec::new())) else {
            return;
        };
        let mut entries = vec![0.0f32; n * n];
        let mut first = 0;
        for block in blocks {
            scatter(&mut entries, n, first, &block);
            first += block.ends.len();
        }
        self.state = BuildState::Dense(entries);
    }

    fn finish(self) -> StoredMatrix {
        let n = self.n;
        debug_assert_eq!(self.columns, n);
        let entries = match self.state {
            BuildState::Dense(entries) => Entries::Dense(entries),
            BuildState::Sparse(blocks) => {
                let mut indptr = Vec::with_capacity(n + 1);
                let mut rows = Vec::with_capacity(self.nonzeros);
                let mut values = Vec::with_capacity(self.nonzeros);
                indptr.push(0u32);
                for block in blocks {
                    let offset = values.len();
                    indptr.extend(block.ends.iter().map(|e| (e + offset) as u32));
                    rows.extend_from_slice(&block.rows);
                    values.extend_from_slice(&block.values);
                }
                let matrix = CsMatI::try_new_csc((n, n), indptr, rows, values)
                    .map_err(|(_, _, _, e)| e)
                    .expect("columns are built in order with increasing row indices");
                Entries::Sparse(matrix)
            }
        };
        StoredMatrix { n, nonzeros: self.nonzeros, entries, row_major: OnceLock::new(), reciprocity: None }
    }
}

/// Writes the columns of `block`, the first being column `first`, into a dense array.
fn scatter(entries: &mut [f32], n: usize, first: usize, block: &Block) {
    for (k, (start, end)) in block.ranges().enumerate() {
        let column = &mut entries[(first + k) * n..(first + k + 1) * n];
        for (&i, &v) in block.rows[start..end].iter().zip(&block.values[start..end]) {
            column[i as usize] = v;
        }
    }
}

impl StoredMatrix {
    /// Assembles every column of `source`, in parallel; `progress` is called, from any
    /// thread, with the number of columns done so far each time one finishes (calls may
    /// arrive slightly out of order: the largest value seen is the count).
    ///
    /// The result does not depend on the number of threads.
    pub fn assemble(source: &(impl ColumnSource + ?Sized), progress: &(dyn Fn(usize) + Sync)) -> StoredMatrix {
        Self::assemble_dyn(&source, progress)
    }

    fn assemble_dyn(source: &dyn ColumnSource, progress: &(dyn Fn(usize) + Sync)) -> StoredMatrix {
        let n = source.patch_count();
        let done = AtomicUsize::new(0);
        // Blocks bound the memory of columns in flight; their size does not change the result.
        let block_len = (32 * rayon::current_num_threads()).max(256);
        let column_of = |scratch: &mut Vec<Real>, j: usize| {
            source.fill_column(j, scratch);
            let nonzeros = scratch.iter().filter(|&&v| v as f32 != 0.0).count();
            let mut column = Block {
                ends: Vec::with_capacity(1),
                rows: Vec::with_capacity(nonzeros),
                values: Vec::with_capacity(nonzeros),
            };
            column.push_column(scratch.iter().map(|&v| v as f32).enumerate());
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            column
        };
        let mut builder = Builder::new(n);
        for first in (0..n).step_by(block_len) {
            let block = first..(first + block_len).min(n);
            // A source split over ranks serves one column at a time, in the same order on
            // every rank (each column is a collective sum), on the calling thread.
            let columns: Vec<Block> = if source.collective().is_some() {
                let mut scratch = vec![0.0; n];
                block.map(|j| column_of(&mut scratch, j)).collect()
            } else {
                block.into_par_iter().map_init(|| vec![0.0; n], column_of).collect()
            };
            builder.push(Block::from_columns(columns));
        }
        let mut matrix = builder.finish();
        matrix.reciprocity = reciprocity_after_f32(source.reciprocity_bound());
        matrix
    }

    /// Assembles the matrix by reciprocity (see the module documentation): for every
    /// unordered pair `{i, j}`, `pair(r, s)` (`F_rs` before clamping) is called once, with `r`
    /// the patch of smaller area (the lower index on a tie), and `F_sr = A_r F_rs / A_s`;
    /// `pair(j, j)` is called for the diagonal. Both entries are clamped into `[0, 1]`,
    /// non-finite ones set to 0. `progress` is called, from any thread, with the number of
    /// pairs done so far, out of `n (n + 1) / 2`, each time a shooter's pairs finish (calls
    /// may arrive slightly out of order: the largest value seen is the count).
    ///
    /// Returns the matrix and the number of entries clamped. The result does not depend on
    /// the number of threads. Refuses areas that are not finite and positive.
    pub fn assemble_reciprocal(
        area: &[Real],
        pair: &(dyn Fn(usize, usize) -> Real + Sync),
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<(StoredMatrix, u64), FfError> {
        if let Some(i) = area.iter().position(|a| !(a.is_finite() && *a > 0.0)) {
            return Err(FfError::StoredMatrix(format!(
                "assembly by reciprocity needs positive areas, patch {i} has area {}",
                area[i]
            )));
        }
        let n = area.len();
        let done = AtomicUsize::new(0);
        let clamped = AtomicU64::new(0);
        let clamp = |v: Real, changed: &mut u64| {
            let c = if v.is_finite() { v.clamp(0.0, 1.0) } else { 0.0 };
            *changed += u64::from(c != v);
            c
        };
        // Shooter j's pairs with the receivers below the diagonal: (i, F_ij, F_ji), i > j,
        // where either is non-zero; and F_jj.
        let lower: Vec<ShooterPairs> = (0..n)
            .into_par_iter()
            .map(|j| {
                let mut changed = 0;
                let diagonal = clamp(pair(j, j), &mut changed) as f32;
                let mut entries = Vec::new();
                for i in j + 1..n {
                    let (r, s) = if area[i] < area[j] { (i, j) } else { (j, i) };
                    let f_rs = clamp(pair(r, s), &mut changed);
                    let f_sr = clamp(f_rs * area[r] / area[s], &mut changed);
                    let (f_ij, f_ji) = if r == i { (f_rs, f_sr) } else { (f_sr, f_rs) };
                    let (a, b) = (f_ij as f32, f_ji as f32);
                    if a != 0.0 || b != 0.0 {
                        entries.push((i as u32, a, b));
                    }
                }
                entries.shrink_to_fit();
                if changed > 0 {
                    clamped.fetch_add(changed, Ordering::Relaxed);
                }
                progress(done.fetch_add(n - j, Ordering::Relaxed) + n - j);
                (diagonal, entries)
            })
            .collect();
        let nonzeros: usize = lower
            .iter()
            .map(|(d, e)| {
                usize::from(*d != 0.0)
                    + e.iter().map(|&(_, a, b)| usize::from(a != 0.0) + usize::from(b != 0.0)).sum::<usize>()
            })
            .sum();
        let entries = if sparse_is_smaller(n, nonzeros) {
            Entries::Sparse(reciprocal_csc(n, nonzeros, lower))
        } else {
            let mut e = vec![0.0f32; n * n];
            for (j, (diagonal, pairs)) in lower.into_iter().enumerate() {
                e[j * n + j] = diagonal;
                for (i, a, b) in pairs {
                    let i = i as usize;
                    e[j * n + i] = a;
                    e[i * n + j] = b;
                }
            }
            Entries::Dense(e)
        };
        let mut matrix = StoredMatrix { n, nonzeros, entries, row_major: OnceLock::new(), reciprocity: None };
        // Measured, not assumed: clamping and `f32` rounding each move a pair's entries.
        matrix.reciprocity = Some(matrix.figures(area).max_reciprocity_error);
        Ok((matrix, clamped.load(Ordering::Relaxed)))
    }

    /// The number of patches `n`.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the matrix is `0 × 0`.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// `F_ij`.
    ///
    /// # Panics
    ///
    /// If `i` or `j` is not below `n`, like slice indexing.
    pub fn get(&self, i: usize, j: usize) -> Real {
        assert!(i < self.n && j < self.n, "entry ({i}, {j}) of a {0} × {0} matrix", self.n);
        match &self.entries {
            Entries::Dense(e) => Real::from(e[j * self.n + i]),
            Entries::Sparse(m) => {
                let range = m.indptr().outer_inds_sz(j);
                match m.indices()[range.clone()].binary_search(&(i as u32)) {
                    Ok(k) => Real::from(m.data()[range.start + k]),
                    Err(_) => 0.0,
                }
            }
        }
    }

    /// Non-zero entries.
    pub fn nonzeros(&self) -> usize {
        self.nonzeros
    }

    /// How the entries are held.
    pub fn storage(&self) -> Storage {
        match self.entries {
            Entries::Dense(_) => Storage::Dense,
            Entries::Sparse(_) => Storage::Sparse,
        }
    }

    /// Bytes taken by the entries (and, when sparse, their indices and column offsets).
    pub fn bytes(&self) -> usize {
        match self.storage() {
            Storage::Dense => dense_bytes(self.n),
            Storage::Sparse => sparse_bytes(self.n, self.nonzeros),
        }
    }

    /// `Σ_j F_ij` for every row `i`, summed in `f64` in column order.
    pub fn row_sums(&self) -> Vec<Real> {
        let mut sums = vec![0.0; self.n];
        self.for_each_entry(|i, _, v| sums[i] += Real::from(v));
        sums
    }

    /// Calls `f(i, F_ij)` for the stored entries of column `j`, rows in increasing order
    /// (every entry when dense, the non-zeros when sparse): what products, column sums and
    /// column-ordered sweeps over a stored matrix read, without a copy of the column.
    ///
    /// # Panics
    ///
    /// If `j` is not below `n`, like slice indexing.
    pub fn for_each_in_column(&self, j: usize, mut f: impl FnMut(usize, f32)) {
        assert!(j < self.n, "column {j} of a {0} × {0} matrix", self.n);
        match &self.entries {
            Entries::Dense(e) => {
                for (i, &v) in e[j * self.n..(j + 1) * self.n].iter().enumerate() {
                    f(i, v);
                }
            }
            Entries::Sparse(m) => {
                let range = m.indptr().outer_inds_sz(j);
                for (&i, &v) in m.indices()[range.clone()].iter().zip(&m.data()[range]) {
                    f(i as usize, v);
                }
            }
        }
    }

    /// Calls `f(i, j, F_ij)` for the stored entries, column by column (every entry when
    /// dense, the non-zeros when sparse).
    fn for_each_entry(&self, mut f: impl FnMut(usize, usize, f32)) {
        match &self.entries {
            Entries::Dense(e) => {
                for (j, column) in e.chunks_exact(self.n.max(1)).enumerate() {
                    for (i, &v) in column.iter().enumerate() {
                        f(i, j, v);
                    }
                }
            }
            Entries::Sparse(m) => {
                for j in 0..self.n {
                    let range = m.indptr().outer_inds_sz(j);
                    for (&i, &v) in m.indices()[range.clone()].iter().zip(&m.data()[range]) {
                        f(i as usize, j, v);
                    }
                }
            }
        }
    }

    /// Closure and reciprocity figures, as [`matrix_figures`] computes them (the same
    /// numbers; sparse matrices are read non-zero by non-zero rather than entry by entry).
    pub fn figures(&self, area: &[Real]) -> MatrixFigures {
        let Entries::Sparse(m) = &self.entries else {
            return matrix_figures(area, |i, j| self.get(i, j));
        };
        let n = self.n;
        let (indptr, rows, values) = (m.indptr(), m.indices(), m.data());
        // Row sums add each row's entries in column order, as the guard does (zeros change
        // nothing), and the pair error is symmetric in (i, j), so visiting each pair from its
        // non-zeros, once or twice, finds the same largest error. `F_ji` is found in column i
        // by a cursor that only moves forward, as j grows: linear time, no transpose.
        let mut cursor: Vec<usize> = (0..n).map(|i| indptr.outer_inds_sz(i).start).collect();
        let mut sums = vec![0.0; n];
        let (mut reciprocity, mut nonzeros): (Real, usize) = (0.0, 0);
        for j in 0..n {
            let range = indptr.outer_inds_sz(j);
            for (&i, &v) in rows[range.clone()].iter().zip(&values[range]) {
                let (i, fij) = (i as usize, Real::from(v));
                if fij != 0.0 {
                    nonzeros += 1;
                }
                sums[i] += fij;
                if i == j {
                    continue;
                }
                let end = indptr.outer_inds_sz(i).end;
                while cursor[i] < end && (rows[cursor[i]] as usize) < j {
                    cursor[i] += 1;
                }
                let fji =
                    if cursor[i] < end && rows[cursor[i]] as usize == j { Real::from(values[cursor[i]]) } else { 0.0 };
                let (a, b) = if i < j { (area[i] * fij, area[j] * fji) } else { (area[j] * fji, area[i] * fij) };
                let scale = a.max(b);
                if scale > 0.0 {
                    reciprocity = reciprocity.max((a - b).abs() / scale);
                }
            }
        }
        MatrixFigures::from_row_sums(&sums, reciprocity, nonzeros)
    }

    /// Symmetrises `A·F`, then, if `closed`, rescales each row to sum to 1 (see the module
    /// documentation). Rows that sum to zero are left as they are.
    ///
    /// Symmetrising can turn zeros into non-zeros (where `F_ij = 0` but `F_ji ≠ 0`), so the
    /// storage is chosen again. Refuses `area` of the wrong length or with an entry that is
    /// not finite and positive.
    pub fn rebalance(&mut self, area: &[Real], closed: bool) -> Result<RebalanceReport, FfError> {
        self.row_major = OnceLock::new();
        let n = self.n;
        if area.len() != n {
            return Err(FfError::StoredMatrix(format!(
                "rebalancing needs the areas of its {n} patches, got {} areas",
                area.len()
            )));
        }
        if let Some(i) = area.iter().position(|a| !(a.is_finite() && *a > 0.0)) {
            return Err(FfError::StoredMatrix(format!(
                "rebalancing needs positive areas, patch {i} has area {}",
                area[i]
            )));
        }
        let mut change = Change::default();
        match &mut self.entries {
            Entries::Dense(e) => {
                let mut nonzeros = 0;
                for j in 0..n {
                    for i in 0..j {
                        let (a, b) = (e[j * n + i], e[i * n + j]);
                        let g = 0.5 * (area[i] * Real::from(a) + area[j] * Real::from(b));
                        let (new_a, new_b) = ((g / area[i]) as f32, (g / area[j]) as f32);
                        change.record(a, new_a);
                        change.record(b, new_b);
                        e[j * n + i] = new_a;
                        e[i * n + j] = new_b;
                        nonzeros += usize::from(new_a != 0.0) + usize::from(new_b != 0.0);
                    }
                    nonzeros += usize::from(e[j * n + j] != 0.0);
                }
                self.nonzeros = nonzeros;
            }
            Entries::Sparse(columns) => {
                let rows = columns.to_other_storage();
                let mut builder = Builder::new(n);
                let mut block = Block::default();
                for j in 0..n {
                    let c = columns.indptr().outer_inds_sz(j);
                    let r = rows.indptr().outer_inds_sz(j);
                    let column = merge(
                        &columns.indices()[c.clone()],
                        &columns.data()[c],
                        &rows.indices()[r.clone()],
                        &rows.data()[r],
                    );
                    block.push_column(column.map(|(i, a, b)| {
                        let g = 0.5 * (area[i] * Real::from(a) + area[j] * Real::from(b));
                        let new = (g / area[i]) as f32;
                        change.record(a, new);
                        (i, new)
                    }));
                    if block.ends.len() == 256 {
                        builder.push(std::mem::take(&mut block));
                    }
                }
                builder.push(block);
                drop(rows);
                *self = builder.finish();
            }
        }
        let symmetrised = self.figures(area);
        let (mut scale_min, mut scale_max) = (1.0, 1.0);
        if closed {
            let scale: Vec<Real> = self.row_sums().iter().map(|&s| if s > 0.0 { 1.0 / s } else { 1.0 }).collect();
            scale_min = scale.iter().copied().fold(Real::INFINITY, Real::min);
            scale_max = scale.iter().copied().fold(Real::NEG_INFINITY, Real::max);
            let n = self.n;
            match &mut self.entries {
                Entries::Dense(e) => {
                    for column in e.chunks_exact_mut(n.max(1)) {
                        for (v, s) in column.iter_mut().zip(&scale) {
                            *v = (Real::from(*v) * s) as f32;
                        }
                    }
                }
                Entries::Sparse(m) => {
                    let rows: Vec<u32> = m.indices().to_vec();
                    for (v, i) in m.data_mut().iter_mut().zip(rows) {
                        *v = (Real::from(*v) * scale[i as usize]) as f32;
                    }
                }
            }
        }
        self.reciprocity = Some(self.figures(area).max_reciprocity_error);
        Ok(RebalanceReport {
            symmetrised,
            max_change: change.max_abs,
            max_relative_change: change.max_rel,
            mean_relative_change: if change.count > 0 { change.sum_rel / change.count as Real } else { 0.0 },
            filled: change.filled,
            rescaled: closed,
            scale_min: if n == 0 { 1.0 } else { scale_min },
            scale_max: if n == 0 { 1.0 } else { scale_max },
        })
    }

    /// Encodes the matrix with `key` (what it was computed from) for a cache file.
    pub fn to_bytes(&self, key: &str) -> Vec<u8> {
        let header = Header {
            key: key.to_string(),
            n: self.n as u64,
            nonzeros: self.nonzeros as u64,
            reciprocity: self.reciprocity,
            body_len: [0; 8],
            body_checksum: [0; 8],
        };
        let capacity = self.bytes() + self.n + key.len() + 128;
        frame(MAGIC, FORMAT_VERSION, &header, capacity, |out| {
            postcard::to_extend(&self.entries, out).expect("postcard encodes vectors and matrices into a Vec")
        })
    }

    /// Decodes a matrix written by [`StoredMatrix::to_bytes`] with the same `key`.
    pub fn from_bytes(bytes: &[u8], key: &str) -> Result<StoredMatrix, FfError> {
        let refuse = |why: String| FfError::StoredMatrix(why);
        let (header, body) =
            unframe(bytes, (MAGIC, FORMAT_VERSION), ("a stored form-factor matrix", "the entries"), |h: &Header| {
                (h.body_len, h.body_checksum)
            })
            .map_err(refuse)?;
        if header.key != key {
            return Err(refuse(format!("it was computed for '{}', not for '{key}'", header.key)));
        }
        let entries: Entries =
            postcard::from_bytes(body).map_err(|e| refuse(format!("the entries cannot be decoded ({e})")))?;
        let n = usize::try_from(header.n).map_err(|_| refuse(format!("n = {} is too large", header.n)))?;
        let (size_ok, nonzeros) = match &entries {
            Entries::Dense(e) => (Some(e.len()) == n.checked_mul(n), e.iter().filter(|&&v| v != 0.0).count()),
            Entries::Sparse(m) => (m.is_csc() && m.rows() == n && m.cols() == n, m.nnz()),
        };
        if !size_ok {
            return Err(refuse(format!("the entries are not those of a {n} × {n} matrix")));
        }
        if nonzeros as u64 != header.nonzeros {
            return Err(refuse(format!("{nonzeros} non-zero entries where the header promises {}", header.nonzeros)));
        }
        Ok(StoredMatrix { n, nonzeros, entries, row_major: OnceLock::new(), reciprocity: header.reciprocity })
    }
}

/// What [`StoredMatrix::assemble_reciprocal`] keeps of shooter `j`: `F_jj`, and its pairs with
/// the receivers below the diagonal as `(i, F_ij, F_ji)`, `i > j`, where either is non-zero.
type ShooterPairs = (f32, Vec<(u32, f32, f32)>);

/// The compressed columns of the matrix whose lower triangle (and diagonal) `lower` holds
/// by shooter (see [`StoredMatrix::assemble_reciprocal`]), with `nonzeros` non-zeros in all.
///
/// Column `c` is its entries above the diagonal (rows `j < c`, the `F_jc` of shooters `j`),
/// then `F_cc`, then those below (rows `i > c`, shooter `c`'s own list). Shooters are visited
/// in order, so every column's rows come out sorted, and each list is dropped once written.
fn reciprocal_csc(n: usize, nonzeros: usize, lower: Vec<ShooterPairs>) -> CsMatI<f32, u32> {
    let mut counts = vec![0usize; n];
    for (j, (diagonal, pairs)) in lower.iter().enumerate() {
        counts[j] += usize::from(*diagonal != 0.0);
        for &(i, a, b) in pairs {
            counts[j] += usize::from(a != 0.0);
            counts[i as usize] += usize::from(b != 0.0);
        }
    }
    let mut indptr = Vec::with_capacity(n + 1);
    indptr.push(0u32);
    let mut cursor = Vec::with_capacity(n);
    let mut total = 0usize;
    for &c in &counts {
        cursor.push(total);
        total += c;
        indptr.push(total as u32);
    }
    debug_assert_eq!(total, nonzeros);
    let mut rows = vec![0u32; nonzeros];
    let mut values = vec![0.0f32; nonzeros];
    let mut put = |column: usize, row: u32, value: f32, cursor: &mut [usize]| {
        rows[cursor[column]] = row;
        values[cursor[column]] = value;
        cursor[column] += 1;
    };
    for (j, (diagonal, pairs)) in lower.into_iter().enumerate() {
        // Every shooter before j has written its row-j entry into column j: what remains of
        // column j is the diagonal and the rows below it, in order.
        if diagonal != 0.0 {
            put(j, j as u32, diagonal, &mut cursor);
        }
        for &(i, a, _) in &pairs {
            if a != 0.0 {
                put(j, i, a, &mut cursor);
            }
        }
        for &(i, _, b) in &pairs {
            if b != 0.0 {
                put(i as usize, j as u32, b, &mut cursor);
            }
        }
    }
    CsMatI::try_new_csc((n, n), indptr, rows, values)
        .map_err(|(_, _, _, e)| e)
        .expect("columns are filled in order with increasing row indices")
}

/// The header after the magic string and version. The last two fields are fixed-size
/// (little-endian), so that [`StoredMatrix::to_bytes`] can fill them in after the body.
#[derive(Serialize, Deserialize)]
struct Header {
    key: String,
    n: u64,
    nonzeros: u64,
    reciprocity: Option<Real>,
    body_len: [u8; 8],
    body_checksum: [u8; 8],
}

/// Changes made by the symmetrising step.
#[derive(Default)]
struct Change {
    max_abs: Real,
    max_rel: Real,
    sum_rel: Real,
    count: usize,
    filled: usize,
}

impl Change {
    fn record(&mut self, old: f32, new: f32) {
        let (old, new) = (Real::from(old), Real::from(new));
        self.max_abs = self.max_abs.max((new - old).abs());
        if old != 0.0 {
            let rel = (new - old).abs() / old.abs();
            self.max_rel = self.max_rel.max(rel);
            self.sum_rel += rel;
            self.count += 1;
        } else if new != 0.0 {
            self.filled += 1;
        }
    }
}

/// Merges column `j` (`F_ij` at rows `i`) with row `j` (`F_ji` at columns `i`), both sorted:
/// yields `(i, F_ij, F_ji)` over the union of indices.
fn merge<'a>(
    col_idx: &'a [u32],
    col_val: &'a [f32],
    row_idx: &'a [u32],
    row_val: &'a [f32],
) -> impl Iterator<Item = (usize, f32, f32)> + 'a {
    let (mut a, mut b) = (0, 0);
    std::iter::from_fn(move || {
        let next_a = col_idx.get(a).copied();
        let next_b = row_idx.get(b).copied();
        match (next_a, next_b) {
            (None, None) => None,
            (Some(i), Some(k)) if i == k => {
                let out = (i as usize, col_val[a], row_val[b]);
                a += 1;
                b += 1;
                Some(out)
            }
            (Some(i), Some(k)) if i < k => {
                a += 1;
                Some((i as usize, col_val[a - 1], 0.0))
            }
            (Some(i), None) => {
                a += 1;
                Some((i as usize, col_val[a - 1], 0.0))
            }
            (_, Some(k)) => {
                b += 1;
                Some((k as usize, 0.0, row_val[b - 1]))
            }
        }
    })
}

/// Two matrices are equal when their entries are, whether or not a row-major copy was built.
impl PartialEq for StoredMatrix {
    fn eq(&self, other: &StoredMatrix) -> bool {
        (self.n, self.nonzeros, &self.entries, self.reciprocity)
            == (other.n, other.nonzeros, &other.entries, other.reciprocity)
    }
}

impl fmt::Debug for StoredMatrix {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("StoredMatrix")
            .field("n", &self.n)
            .field("storage", &self.storage())
            .field("nonzeros", &self.nonzeros)
            .field("bytes", &self.bytes())
            .finish()
    }
}

impl ColumnSource for StoredMatrix {
    fn patch_count(&self) -> usize {
        self.n
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        match &self.entries {
            Entries::Dense(e) => {
                for (f, &v) in column.iter_mut().zip(&e[j * self.n..(j + 1) * self.n]) {
                    *f = Real::from(v);
                }
            }
            Entries::Sparse(m) => {
                column.fill(0.0);
                let range = m.indptr().outer_inds_sz(j);
                for (&i, &v) in m.indices()[range.clone()].iter().zip(&m.data()[range]) {
                    column[i as usize] = Real::from(v);
                }
            }
        }
    }

    /// Reads row `i` from the stored columns when dense, and from the row-major copy of the
    /// sparse entries, built on the first call, when sparse.
    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        match &self.entries {
            Entries::Dense(e) => {
                for (j, f) in row.iter_mut().enumerate() {
                    *f = Real::from(e[j * self.n + i]);
                }
            }
            Entries::Sparse(m) => {
                let rows = self.row_major.get_or_init(|| m.to_other_storage());
                row.fill(0.0);
                let range = rows.indptr().outer_inds_sz(i);
                for (&j, &v) in rows.indices()[range.clone()].iter().zip(&rows.data()[range]) {
                    row[j as usize] = Real::from(v);
                }
            }
        }
        true
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        self.reciprocity
    }
}

#[cfg(test)]
mod reciprocal_tests {
    use super::*;
    use crate::{AnalyticColumns, BackendSpec};
    use radiosity_geom::{SceneAnalysis, Visibility, load_scene};

    /// `F_ij = G_ij / A_i` with `G` symmetric (reciprocal by construction) and zero where
    /// `(i + j) % sparsity != 0`.
    fn symmetric(n: usize, sparsity: usize) -> (Vec<Real>, impl Fn(usize, usize) -> Real + Sync) {
        let area: Vec<Real> = (0..n).map(|i| 0.5 + (i * 7 % 5) as Real * 0.25).collect();
        let a = area.clone();
        let f = move |i: usize, j: usize| {
            if i == j || (i + j) % sparsity != 0 {
                return 0.0;
            }
            let g = 1.0 / (1.0 + (i.min(j) * 31 + i.max(j) * 17) as Real % 13.0) / n as Real;
            g / a[i]
        };
        (area, f)
    }

    #[test]
    fn reciprocal_assembly_of_a_reciprocal_source_is_its_column_assembly() {
        for (n, sparsity, storage) in [(40, 1, Storage::Dense), (300, 5, Storage::Sparse)] {
            let (area, f) = symmetric(n, sparsity);
            let columns = radiosity_core::DenseColumns::from_fn(n, &f);
            let by_columns = StoredMatrix::assemble(&columns, &|_| {});
            let done = AtomicUsize::new(0);
            let (by_pairs, clamped) =
                StoredMatrix::assemble_reciprocal(&area, &f, &|k| _ = done.fetch_max(k, Ordering::Relaxed)).unwrap();
            assert_eq!(done.into_inner(), n * (n + 1) / 2);
            assert_eq!(clamped, 0);
            assert_eq!(by_pairs.storage(), storage);
            assert_eq!(by_pairs.nonzeros(), by_columns.nonzeros());
            for i in 0..n {
                for j in 0..n {
                    let (a, b) = (by_pairs.get(i, j), by_columns.get(i, j));
                    assert!((a - b).abs() <= 1e-6 * b.abs(), "F_{i}{j}: {a} against {b}");
                }
            }
        }
    }

    #[test]
    fn reciprocal_assembly_is_reciprocal_clamped_and_thread_independent() {
        let scene = load_scene("multi-cubes").unwrap().scene;
        let visibility = Visibility::new(&scene);
        let analysis = SceneAnalysis::new(&scene, &visibility);
        let params = *BackendSpec::parse("analytic").unwrap().params::<crate::AnalyticParams>().expect("analytic");
        let analytic = AnalyticColumns::new(&scene, &visibility, &analysis, params);
        let area: Vec<Real> = scene.patches().iter().map(|p| p.area()).collect();
        let assemble = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| StoredMatrix::assemble_reciprocal(&area, &|i, j| analytic.pair(i, j), &|_| {}).unwrap())
        };
        let (one, clamped) = assemble(1);
        let (two, _) = assemble(2);
        assert!(one == two, "the thread count changed the matrix");
        assert_eq!(clamped, 0);
        let figures = one.figures(&area);
        assert!(figures.max_reciprocity_error < 1e-6, "{figures:?}");
        // The same matrix as column by column, but for the quadrature error of the larger
        // receiver of each pair.
        let by_columns = StoredMatrix::assemble(&analytic, &|_| {});
        let reference = by_columns.figures(&area);
        assert!((figures.row_sum_mean - reference.row_sum_mean).abs() < 1e-3, "{figures:?} {reference:?}");
        // A derived entry is non-zero with its pair, where the centroid rule can give zero to
        // a receiver straddling the shooter's plane: the patterns differ a little.
        let (a, b) = (figures.nonzeros as Real, reference.nonzeros as Real);
        assert!((a - b).abs() < 0.01 * b, "{a} non-zeros against {b}");
        // Entries whose receiver is the smaller patch are computed the same way.
        for j in (0..scene.len()).step_by(37) {
            for i in 0..scene.len() {
                if area[i] < area[j] || (area[i] == area[j] && i < j) {
                    assert_eq!(one.get(i, j), by_columns.get(i, j), "F_{i}{j}");
                }
            }
        }
    }

    #[test]
    fn reciprocal_assembly_refuses_bad_areas() {
        let e = StoredMatrix::assemble_reciprocal(&[1.0, 0.0], &|_, _| 0.0, &|_| {}).unwrap_err();
        assert!(e.to_string().contains("patch 1 has area 0"), "{e}");
    }
}
