//! What a comparison writes: its CSV, Markdown report, plots and terminal summary
//! ([`comparison`]), built from convergence tables ([`table`]) and plots ([`plot`]), and the
//! paper's figures and claims judged on comparisons ([`paper`]).

pub(crate) mod comparison;
pub mod paper;
pub(crate) mod plot;
pub mod report_text;
pub(crate) mod run_text;
pub(crate) mod table;
