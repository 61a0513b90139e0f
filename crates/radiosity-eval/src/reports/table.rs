//! Convergence tables: one row per measured step of a run, written as CSV or Markdown.
//!
//! A row records where a solver stood (step, what it spent, [`radiosity_solvers::Cost`]: the
//! columns computed, the run's and the form factors' seconds, with the clock they were counted
//! on: `measured` or `charged`, [`Clock::name`]) and its metrics
//! ([`crate::reference::metrics`]). Floats are rounded to a fixed number of
//! significant digits (default 4), so tables under snapshot tests stay stable across platforms
//! and round-off. Tables write to any [`std::io::Write`]; opening files is the caller's business.
//! Timings vary from run to run, so a table can leave them out
//! ([`ConvergenceTable::without_timings`]) and stay deterministic. Every other unit of cost
//! than columns (`products`, the products by F a source computed itself, which the Krylov
//! solvers and `jacobi:sweep=product` make; `rays`, cast by a solver that samples transport;
//! `links` of a hierarchy) has a column only when some row spent it, so tables of column
//! methods read as before; likewise `std_error` (the standard error, relative as e_rms is, NaN
//! for the solvers without one), written only when some row has one. `bound` is a promise, `std_error` a spread: an unbiased
//! estimate's e_rms is expected near its standard error, and exceeds it now and then.

use crate::lab::recorder::TableRow;
use radiosity_core::{Clock, Real};
use radiosity_solvers::Unit;
use std::io::{self, Write};

/// One column of a table.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Column {
    Solver,
    Step,
    /// What the run spent in a unit of cost ([`Unit::key`] heads it).
    Spent(Unit),
    Seconds,
    FfSeconds,
    /// The clock of `seconds` and `ff_seconds` ([`Clock::name`]).
    Clock,
    ERms,
    EMax,
    Residual,
    Bound,
    StdError,
}

impl Column {
    fn name(self) -> &'static str {
        match self {
            Column::Solver => "solver",
            Column::Step => "step",
            Column::Spent(unit) => unit.key(),
            Column::Seconds => "seconds",
            Column::FfSeconds => "ff_seconds",
            Column::Clock => "clock",
            Column::ERms => "e_rms",
            Column::EMax => "e_max",
            Column::Residual => "residual",
            Column::Bound => "bound",
            Column::StdError => "std_error",
        }
    }
}

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

    /// The columns written, in order: `solver`, `step`, `columns`, then each other paid unit
    /// of cost some row spent (`products`, `rays`, `links`), the timings `seconds`,
    /// `ff_seconds` and `clock` unless left out, the metrics `e_rms`, `e_max`, `residual`,
    /// `bound`, and `std_error` when some row has a standard error.
    fn columns(&self) -> Vec<Column> {
        let mut out = vec![Column::Solver, Column::Step, Column::Spent(Unit::Columns)];
        out.extend(
            Unit::ALL
                .into_iter()
                .filter(|&u| u.paid() && u != Unit::Columns && self.rows.iter().any(|r| r.cost[u] > 0))
                .map(Column::Spent),
        );
        if self.timings {
            out.extend([Column::Seconds, Column::FfSeconds, Column::Clock]);
        }
        out.extend([Column::ERms, Column::EMax, Column::Residual, Column::Bound]);
        if self.rows.iter().any(|r| r.std_error.is_finite()) {
            out.push(Column::StdError);
        }
        out
    }

    fn header(&self) -> Vec<&'static str> {
        self.columns().into_iter().map(Column::name).collect()
    }

    fn cells(&self, row: &TableRow) -> Vec<String> {
        let d = self.digits;
        let cell = |column| match column {
            Column::Solver => row.solver.clone(),
            Column::Step => row.step.to_string(),
            Column::Spent(unit) => row.cost[unit].to_string(),
            Column::Seconds => round_significant(row.cost.seconds(), d),
            Column::FfSeconds => round_significant(row.cost.ff_seconds, d),
            Column::Clock => self.clock.name().to_string(),
            Column::ERms => round_significant(row.e_rms, d),
            Column::EMax => round_significant(row.e_max, d),
            Column::Residual => round_significant(row.residual, d),
            Column::Bound => round_significant(row.bound, d),
            Column::StdError => round_significant(row.std_error, d),
        };
        self.columns().into_iter().map(cell).collect()
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
