//! The system `(I − diag(ρ) F) B = E` in files that other programs read, so that scipy,
//! MATLAB or Julia solve exactly what the `matrix` reference solves:
//!
//! - [`SparseColumns`]: the non-zero entries of a stored matrix, column by column (the
//!   compressed sparse column layout of scipy, MATLAB and Julia), each `f32` entry widened to
//!   `f64` exactly;
//! - Matrix Market ([`matrix_market`]): `F` as a `coordinate real general` file and the
//!   patches' `A`, `E` and `ρ` as an `array` file beside it (Boisvert, Pozo & Remington, "The
//!   Matrix Market exchange formats: initial design", NIST IR 5935, 1996);
//! - NumPy's `.npz` ([`npz`]): `F` under the keys `scipy.sparse.save_npz` writes (so
//!   `scipy.sparse.load_npz` reads it back as a `csc_array`), with `area`, `emission` and
//!   `reflectivity` beside it (NumPy's NEP 1, the `.npy` format).
//!
//! Every value is written so that it reads back to the same bits. [`files`] names the
//! formats by extension and writes the files a path names.

pub mod files;
pub mod matrix_market;
pub mod npz;
pub mod sparse_columns;

pub use files::{Format, write_files, write_system};
pub use sparse_columns::SparseColumns;
