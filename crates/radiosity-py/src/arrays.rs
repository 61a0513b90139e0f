//! The workspace's patch-major vectors (`values[i · width + c]`) as `n × width` numpy arrays,
//! the one layout every array of a scene, a state or a problem takes.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use radiosity_core::Real;

/// `values`, patch-major with `width` values a patch, as an `n × width` array.
pub fn patch_major<'py>(py: Python<'py>, values: Vec<Real>, width: usize) -> Bound<'py, PyArray2<Real>> {
    let n = values.len() / width.max(1);
    Array2::from_shape_vec((n, width), values).expect("patch-major values of n × width").into_pyarray(py)
}
