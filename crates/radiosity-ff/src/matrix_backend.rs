//! The stored matrix as a backend: [`StoredMatrix`] implements [`FormFactorBackend`] (exact
//! rows, clamped when it was assembled), and is assembled from another backend as a stage of a
//! [`BuildObserver`] ([`StoredMatrix::assemble_backend`], [`StoredMatrix::assemble_observed`]):
//! each pair once when the backend gives single entries reciprocal by construction, column by
//! column otherwise. What is stored and how it is assembled, held and written: [`crate::matrix`].

use crate::backend::{BuildObserver, FormFactorBackend};
use crate::error::FfError;
use crate::matrix::StoredMatrix;
use radiosity_core::{ColumnSource, Real};
use std::sync::atomic::{AtomicU64, Ordering};

impl StoredMatrix {
    /// Assembles the matrix of `source` (areas `area`), a stage of `observer`: each unordered
    /// pair once when it gives single entries ([`FormFactorBackend::pairs`],
    /// [`Self::assemble_reciprocal`]), column by column otherwise ([`Self::assemble`]). Returns
    /// the matrix and the entries clamped into `[0, 1]` (the source's own count for columns).
    pub fn assemble_backend(
        area: &[Real],
        source: &dyn FormFactorBackend,
        observer: &dyn BuildObserver,
    ) -> Result<(StoredMatrix, u64), FfError> {
        let pair = source.pairs().map(|p| move |i: usize, j: usize| p.pair(i, j));
        let pair = pair.as_ref().map(|f| f as &(dyn Fn(usize, usize) -> Real + Sync));
        let (matrix, clamped) = Self::assemble_observed(area, source, pair, observer)?;
        Ok((matrix, clamped.unwrap_or_else(|| source.clamped())))
    }

    /// Assembles the matrix of `source` (areas `area`), a stage of `observer`: with `pair`
    /// (`F_ij` before clamping, for a source whose entries are reciprocal by construction),
    /// each unordered pair once ([`Self::assemble_reciprocal`]); without, column by column
    /// ([`Self::assemble`]). Returns the matrix and, with `pair`, the entries clamped into
    /// `[0, 1]` (a column source counts its own).
    pub fn assemble_observed(
        area: &[Real],
        source: &dyn ColumnSource,
        pair: Option<&(dyn Fn(usize, usize) -> Real + Sync)>,
        observer: &dyn BuildObserver,
    ) -> Result<(StoredMatrix, Option<u64>), FfError> {
        let n = source.patch_count() as u64;
        let done = AtomicU64::new(0);
        Ok(match pair {
            Some(pair) => {
                observer.begin("assembling the matrix (each pair once)", n * (n + 1) / 2, "pairs");
                let m = StoredMatrix::assemble_reciprocal(area, pair, &|k| {
                    let k = done.fetch_max(k as u64, Ordering::Relaxed).max(k as u64);
                    observer.advance(k, "");
                });
                observer.end();
                let (m, clamped) = m?;
                (m, Some(clamped))
            }
            None => {
                observer.begin("assembling the matrix", n, "columns");
                let m = StoredMatrix::assemble(source, &|_| {
                    let k = done.fetch_add(1, Ordering::Relaxed) + 1;
                    observer.advance(k, "");
                });
                observer.end();
                (m, None)
            }
        })
    }
}

/// Clamped when it was assembled.
impl FormFactorBackend for StoredMatrix {
    fn serves_rows(&self) -> bool {
        true
    }

    fn stored(&self) -> Option<&StoredMatrix> {
        Some(self)
    }
}
