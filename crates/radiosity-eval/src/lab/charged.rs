//! The stored matrix serving a lab's solvers in place of the backend, each column charged as
//! the backend would have cost it ([`crate::ColumnCost::Charged`], [`ColumnCharge`]): the
//! charge is the run's clock ([`ColumnSource::charged_seconds`],
//! [`radiosity_core::Clock::Charged`]), which its stop rules and timed group frequencies read
//! and its reports print.

use crate::lab::options::ColumnCharge;
use crate::reference::matrix::FormFactors;
use radiosity_core::{ColumnSource, Real};
use std::sync::{Arc, Mutex, PoisonError};

/// The columns of a lab's stored matrix, served in place of the backend's own: the same `f32`
/// entries, exact rows only where the backend served them, and the backend's stated
/// reciprocity, so that every solver takes the same path and gets the same numbers as over
/// the backend. It keeps the run's charge ([`ColumnSource::charged_seconds`]), which
/// [`ColumnSource::reset_memory`] sets back to zero with the columns it has seen.
pub(crate) struct ChargedColumns {
    matrix: Arc<FormFactors>,
    rows: bool,
    reciprocity: Option<Real>,
    charge: ColumnCharge,
    ledger: Mutex<Ledger>,
}

/// The columns fetched so far in a run, and their charge.
#[derive(Default)]
struct Ledger {
    seen: Vec<bool>,
    known: usize,
    seconds: Real,
}

impl ChargedColumns {
    /// Serves `matrix` in place of a backend that serves exact rows if `rows`, states
    /// `reciprocity`, and costs what `charge` measured.
    pub(crate) fn new(matrix: Arc<FormFactors>, rows: bool, reciprocity: Option<Real>, charge: ColumnCharge) -> Self {
        let n = matrix.patch_count();
        let ledger = Mutex::new(Ledger { seen: vec![false; n], ..Ledger::default() });
        ChargedColumns { matrix, rows, reciprocity, charge, ledger }
    }

    /// The same matrix, rows and reciprocity, charged at `charge`'s prices, with nothing
    /// charged yet.
    pub(crate) fn repriced(&self, charge: ColumnCharge) -> ChargedColumns {
        ChargedColumns::new(self.matrix.clone(), self.rows, self.reciprocity, charge)
    }

    /// The prices it charges.
    pub(crate) fn charge(&self) -> &ColumnCharge {
        &self.charge
    }

    /// Charges the column (or row) of patch `j`.
    fn bill(&self, j: usize) {
        let mut ledger = self.ledger.lock().unwrap_or_else(PoisonError::into_inner);
        let n = ledger.seen.len();
        let repeated = ledger.seen[j];
        ledger.seconds += self.charge.column_seconds(n, ledger.known, repeated);
        if !repeated {
            ledger.seen[j] = true;
            ledger.known += 1;
        }
    }
}

impl ColumnSource for ChargedColumns {
    fn patch_count(&self) -> usize {
        self.matrix.patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        self.matrix.fill_column(j, column);
        self.bill(j);
    }

    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        if !(self.rows && self.matrix.fill_row(i, row)) {
            return false;
        }
        self.bill(i);
        true
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        self.reciprocity
    }

    /// The seconds charged since the last [`ColumnSource::reset_memory`]: a run's clock is
    /// [`radiosity_core::Clock::Charged`].
    fn charged_seconds(&self) -> Option<Real> {
        Some(self.ledger.lock().unwrap_or_else(PoisonError::into_inner).seconds)
    }

    /// A new run: no column seen, nothing charged.
    fn reset_memory(&self) {
        let mut ledger = self.ledger.lock().unwrap_or_else(PoisonError::into_inner);
        ledger.seen.fill(false);
        (ledger.known, ledger.seconds) = (0, 0.0);
    }
}
