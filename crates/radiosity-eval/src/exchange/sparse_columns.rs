//! A stored matrix's non-zero entries, column by column: what every exchange format writes.

use radiosity_ff::StoredMatrix;

/// A square matrix's non-zero entries in compressed sparse column layout: column `j` holds
/// rows `indices[indptr[j]..indptr[j + 1]]` (ascending) with `values` there.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseColumns {
    /// The matrix is `n × n`.
    pub n: usize,
    /// Where each column starts in `indices` and `values`, and where the last one ends.
    pub indptr: Vec<u64>,
    /// The rows of the entries.
    pub indices: Vec<u64>,
    /// The entries.
    pub values: Vec<f64>,
}

impl SparseColumns {
    /// The non-zero entries of `matrix`, its `f32` values widened exactly.
    pub fn of(matrix: &StoredMatrix) -> SparseColumns {
        let n = matrix.len();
        let mut columns =
            SparseColumns { n, indptr: Vec::with_capacity(n + 1), indices: Vec::new(), values: Vec::new() };
        columns.indptr.push(0);
        for j in 0..n {
            matrix.for_each_in_column(j, |i, v| {
                if v != 0.0 {
                    columns.indices.push(i as u64);
                    columns.values.push(f64::from(v));
                }
            });
            columns.indptr.push(columns.indices.len() as u64);
        }
        columns
    }

    /// The number of non-zero entries.
    pub fn nonzeros(&self) -> usize {
        self.values.len()
    }
}
