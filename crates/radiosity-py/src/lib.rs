//! The Python package `radiosity`: scenes, form factors and solvers of the workspace as numpy
//! arrays and scipy operators.
//!
//! This crate is the extension module `radiosity._radiosity`; the package's Python side
//! (`python/radiosity/__init__.py`) re-exports it and adds what is Python's own (scipy's
//! `LinearOperator`). Every capability is a library function of the workspace's crates; this
//! crate only converts between them and Python:
//!
//! - [`scene`]: `radiosity.load(spec)` and the `Scene` with its arrays;
//! - [`form_factors`]: `scene.form_factors(spec)`, a backend's columns, rows and products;
//! - [`solve`]: `radiosity.solve(scene, solver, ...)`, one run of a built-in solver;
//! - [`lab`]: `radiosity.Lab(scene, ff).compare([...])`, built-in and Python solvers in one
//!   comparison;
//! - [`errors`]: the workspace's errors as Python exceptions, with the command line's
//!   one-sentence messages.
//!
//! The GIL is released wherever the work is Rust's (loading, building a backend, batches of
//! columns, products, solves), and a panic inside becomes a Python exception (pyo3's
//! `PanicException`) instead of ending the interpreter.

pub mod arrays;
pub mod errors;
pub mod form_factors;
pub mod lab;
pub mod scene;
pub mod solve;

use pyo3::prelude::*;

/// The extension module, imported by `radiosity/__init__.py`.
#[pymodule]
fn _radiosity(m: &Bound<'_, PyModule>) -> PyResult<()> {
    radiosity_eval::return_freed_blocks();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(scene::load, m)?)?;
    m.add_function(wrap_pyfunction!(solve::solve, m)?)?;
    m.add_function(wrap_pyfunction!(lab::compare, m)?)?;
    m.add_class::<lab::PyProblem>()?;
    m.add_class::<lab::PyComparison>()?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<form_factors::FormFactors>()?;
    m.add_class::<solve::Run>()?;
    Ok(())
}
