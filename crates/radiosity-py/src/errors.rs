//! The workspace's errors as Python exceptions: the command line's one-sentence messages, as
//! `ValueError` for bad input (scene specs, backend and solver names, stop rules, misshapen
//! arrays) and `IndexError` for a patch index out of range.

use pyo3::PyErr;
use pyo3::exceptions::{PyIndexError, PyValueError};
use radiosity_eval::ReferenceKind;
use radiosity_solvers::StopRules;
use std::fmt::Display;

/// A `ValueError` with `error`'s message.
pub fn value_error(error: impl Display) -> PyErr {
    PyValueError::new_err(error.to_string())
}

/// Refuses an `rms=` rule that `reference='none'` leaves nothing to measure.
pub fn check_measurable(rules: &StopRules, kind: ReferenceKind) -> Result<(), PyErr> {
    if rules.needs_error() && kind == ReferenceKind::None {
        return Err(value_error(
            "an rms= rule needs a reference to measure e_rms against, and reference='none' computes none",
        ));
    }
    Ok(())
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
