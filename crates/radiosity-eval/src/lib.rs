//! Reference solutions, error metrics, convergence tables, plots and experiment output. Not
//! implemented yet; with `xtask`, the only crate that will write files.
