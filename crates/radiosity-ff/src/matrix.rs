//! The `matrix` backend (stub: the interface is fixed, the method is not written yet).

use crate::error::FfError;
use crate::guard::MatrixFigures;
use radiosity_core::{ColumnSource, Real};

/// A full form-factor matrix held in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct StoredMatrix {
    n: usize,
    columns: Vec<f32>,
}

impl StoredMatrix {
    /// Assembles every column of `source`; `progress` is called with the number of columns done.
    pub fn assemble(source: &(impl ColumnSource + ?Sized), progress: &(dyn Fn(usize) + Sync)) -> StoredMatrix {
        let n = source.patch_count();
        let mut columns = vec![0.0f32; n * n];
        let mut column = vec![0.0; n];
        for j in 0..n {
            source.fill_column(j, &mut column);
            for i in 0..n {
                columns[j * n + i] = column[i] as f32;
            }
            progress(j + 1);
        }
        StoredMatrix { n, columns }
    }

    /// `F_ij`.
    pub fn get(&self, i: usize, j: usize) -> Real {
        Real::from(self.columns[j * self.n + i])
    }

    /// Closure and reciprocity figures.
    pub fn figures(&self, area: &[Real]) -> MatrixFigures {
        crate::guard::matrix_figures(area, |i, j| self.get(i, j))
    }

    /// Encodes the matrix with `key` (what it was computed from) for a cache file.
    pub fn to_bytes(&self, _key: &str) -> Vec<u8> {
        Vec::new()
    }

    /// Decodes a matrix written by [`StoredMatrix::to_bytes`] with the same `key`.
    pub fn from_bytes(_bytes: &[u8], _key: &str) -> Result<StoredMatrix, FfError> {
        Err(FfError::StoredMatrix("not written yet".into()))
    }
}

impl ColumnSource for StoredMatrix {
    fn patch_count(&self) -> usize {
        self.n
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        for (i, f) in column.iter_mut().enumerate() {
            *f = self.get(i, j);
        }
    }
}
