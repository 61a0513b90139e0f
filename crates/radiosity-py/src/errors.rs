//! The workspace's errors as Python exceptions: the command line's one-sentence messages, as
//! `ValueError` for bad input (scene specs, backend and solver names, stop rules, misshapen
//! arrays) and `IndexError` for a patch index out of range.

use pyo3::PyErr;
use pyo3::exceptions::{PyIndexError, PyValueError};
use std::fmt::Display;

/// A `ValueError` with `error`'s message.
pub fn value_error(error: impl Display) -> PyErr {
    PyValueError::new_err(error.to_string())
}

/// Checks that `index` names one of `n` patches.
pub fn check_patch(index: usize, n: usize) -> Result<usize, PyErr> {
    if index < n {
        Ok(index)
    } else {
        Err(PyIndexError::new_err(format!(
            "patch {index} is out of range: the scene has {n} patches (0 to {})",
            n.saturating_sub(1)
        )))
    }
}
