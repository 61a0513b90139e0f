//! The clock a run's seconds are counted on ([`Clock`]): the wall time its columns and its
//! solving took, or, for columns a source serves from a stored matrix in place of the
//! backend, the backend's modelled cost of each ([`crate::ColumnSource::charged_seconds`]).
//!
//! Rule: every figure in seconds that a run reports (tables, plots, CSV and JSON, Python
//! results) and every rule that reads a run's seconds (a `time=` stop rule, a timed group
//! frequency) reads the same clock, and whatever prints the seconds names it with
//! [`Clock::name`], so that the label and the clock cannot disagree.

use std::fmt;

/// How a run's form-factor seconds are counted (module doc). Solving time is always measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Clock {
    /// Columns computed when a solver asks for them, and timed: wall seconds.
    #[default]
    Measured,
    /// Columns read from a stored matrix and each charged what the backend would have cost
    /// to compute it (a modelled cost, [`crate::ColumnSource::charged_seconds`]).
    Charged,
}

impl Clock {
    /// Both clocks, in a fixed order.
    pub const ALL: [Clock; 2] = [Clock::Measured, Clock::Charged];

    /// The clock's one name, as every table, plot, file and result labels its seconds:
    /// `measured` or `charged`.
    pub fn name(self) -> &'static str {
        match self {
            Clock::Measured => "measured",
            Clock::Charged => "charged",
        }
    }

    /// A label for a quantity in seconds on this clock: `seconds (charged)`.
    pub fn seconds_label(self) -> String {
        format!("seconds ({})", self.name())
    }
}

/// The clock's name ([`Clock::name`]).
impl fmt::Display for Clock {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
