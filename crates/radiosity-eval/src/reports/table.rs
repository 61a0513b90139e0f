//! Convergence tables: one row per measured step of a run, written as CSV or Markdown.
//!
//! A row records where a solver stood (step, columns computed, the run's and the form factors'
//! seconds, with the clock they were counted on: `measured` or `charged`, [`Clock::name`]) and
//! its metrics ([`crate::reference::metrics`]). Floats are rounded to a fixed number of
//! significant digits (default 4), so tables under snapshot tests stay stable across platforms
//! and round-off. Tables write to any [`std::io::Write`]; opening files is the caller's business.
//! Timings vary from run to run, so a table can leave them out
//! ([`ConvergenceTable::without_timings`]) and stay deterministic. The `products` column (the
//! products by F a source computed itself, which the Krylov solvers and `jacobi:sweep=product`
//! make) is written only when some row made one, so tables of column methods read as before;
//! likewise `rays` (rays cast by a solver that samples transport) and `std_error` (its standard
//! error, relative as e_rms is, NaN for the solvers without one), written only when some row
//! cast rays or has a standard error. `bound` is a promise, `std_error` a spread: an unbiased
//! estimate's e_rms is expected near its standard error, and exceeds it now and then.

use crate::lab::recorder::TableRow;
use radiosity_core::{Clock, Real};
use std::io::{self, Write};

/// The columns of a table, in order; `clock` names the clock of `seconds` and `ff_seconds`
/// ([`Clock::name`]).
pub const HEADER: [&str; 13] = [
    "solver",
    "step",
    "columns",
    "products",
    "rays",
    "seconds",
    "ff_seconds",
    "clock",
    "e_rms",
    "e_max",
    "residual",
    "bound",
    "std_error",
];

/// The position in [`HEADER`] of `products`.
const PRODUCTS_COLUMN: usize = 3;

/// The positions in [`HEADER`] of the columns of the solvers that sample transport, `rays`
/// and `std_error`.
const SAMPLED_COLUMNS: [usize; 2] = [4, 12];

/// The positions in [`HEADER`] of the timing columns, `seconds`, `ff_seconds` and `clock`.
const TIMING_COLUMNS: [usize; 3] = [5, 6, 7];

/// Rows of convergence data, the clock of their seconds, the precision they are written
/// with, and whether their timings are written.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvergenceTable {
    rows: Vec<TableRow>,
    clock: Clock,
    digits: usize,
    timings: bool,
}

impl Default for ConvergenceTable {
    fn default() -> Self {
        ConvergenceTable { rows: Vec::new(), clock: Clock::Measured, digits: 4, timings: true }
    }
}

impl ConvergenceTable {
    /// An empty table writing floats with 4 significant digits, its seconds measured.
    pub fn new() -> Self {
        Self::default()
    }

    /// The table with its seconds counted on `clock` (written in its `clock` column).
    pub fn with_clock(mut self, clock: Clock) -> Self {
        self.clock = clock;
        self
    }

    /// The clock its seconds were counted on.
    pub fn clock(&self) -> Clock {
        self.clock
    }

    /// Writes floats with `digits` significant digits (at least 1).
    pub fn with_significant_digits(mut self, digits: usize) -> Self {
        self.digits = digits.max(1);
        self
    }

    /// Leaves the `seconds`, `ff_seconds` and `clock` columns out of CSV and Markdown: a table
    /// without them is deterministic, so it can sit under a snapshot test.
    pub fn without_timings(mut self) -> Self {
        self.timings = false;
        self
    }

    /// Appends a row.
    pub fn push(&mut self, row: TableRow) {
        self.rows.push(row);
    }

    /// The rows so far.
    pub fn rows(&self) -> &[TableRow] {
        &self.rows
    }

    /// The columns written, in order: [`HEADER`], less the timings if left out, `products` if
    /// no row made one, and `rays` and `std_error` if no row cast rays or has a standard
    /// error.
    fn header(&self) -> Vec<&'static str> {
        self.written(HEADER)
    }

    /// The entries of `all` (one per column of [`HEADER`]) that are written.
    fn written<T>(&self, all: [T; 13]) -> Vec<T> {
        let products = self.rows.iter().any(|r| r.products > 0);
        let sampled = self.rows.iter().any(|r| r.rays > 0 || r.std_error.is_finite());
        let keep = |i: &usize| {
            (self.timings || !TIMING_COLUMNS.contains(i))
                && (products || *i != PRODUCTS_COLUMN)
                && (sampled || !SAMPLED_COLUMNS.contains(i))
        };
        all.into_iter().enumerate().filter(|(i, _)| keep(i)).map(|(_, cell)| cell).collect()
    }

    fn cells(&self, row: &TableRow) -> Vec<String> {
        let d = self.digits;
        self.written([
            row.solver.clone(),
            row.step.to_string(),
            row.columns.to_string(),
            row.products.to_string(),
            row.rays.to_string(),
            round_significant(row.seconds, d),
            round_significant(row.ff_seconds, d),
            self.clock.name().to_string(),
            round_significant(row.e_rms, d),
            round_significant(row.e_max, d),
            round_significant(row.residual, d),
            round_significant(row.bound, d),
            round_significant(row.std_error, d),
        ])
    }

    /// Writes the table as CSV (RFC 4180, with a header line).
    pub fn write_csv(&self, out: impl Write) -> io::Result<()> {
        let mut w = csv::Writer::from_writer(out);
        w.write_record(self.header())?;
        for row in &self.rows {
            w.write_record(self.cells(row))?;
        }
        w.flush()
    }

    /// Writes the table as a GitHub-flavoured Markdown table, numbers right-aligned.
    pub fn write_markdown(&self, mut out: impl Write) -> io::Result<()> {
        let header = self.header();
        writeln!(out, "| {} |", header.join(" | "))?;
        writeln!(out, "|---|{}", "--:|".repeat(header.len() - 1))?;
        for row in &self.rows {
            let mut cells = self.cells(row);
            cells[0] = cells[0].replace('|', "\\|");
            writeln!(out, "| {} |", cells.join(" | "))?;
        }
        Ok(())
    }
}

/// `x` rounded to `digits` significant digits (at least 1): plain notation for magnitudes in
/// `[1e-4, 1e6)`, scientific (`1.235e-7`) outside; `0`, `NaN`, `inf` and `-inf` as such.
/// Trailing zeros are kept, so every value shows its precision.
pub fn round_significant(x: Real, digits: usize) -> String {
    let digits = digits.max(1);
    if x == 0.0 {
        return "0".to_string();
    }
    if !x.is_finite() {
        return x.to_string();
    }
    // Round once, in scientific notation, and read the exponent after rounding (9.9996
    // becomes 1.000e1).
    let sci = format!("{:.*e}", digits - 1, x);
    let exponent: i32 = sci.split_once('e').and_then(|(_, e)| e.parse().ok()).unwrap_or(0);
    if (-4..6).contains(&exponent) {
        let decimals = (digits as i32 - 1 - exponent).max(0) as usize;
        let rounded: Real = sci.parse().unwrap_or(x);
        format!("{rounded:.decimals$}")
    } else {
        sci
    }
}
