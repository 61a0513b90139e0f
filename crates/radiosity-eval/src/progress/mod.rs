//! How long-running library calls report progress: a trait the command line implements with
//! progress bars, [`Lines`] for a log or a pipe (a line every 30 s), and [`NoProgress`] for
//! callers that want silence.
//!
//! Calls report through `&dyn Progress` from any thread, so implementations use interior
//! mutability (progress bars do). Messages are for people, not for parsing.

mod lines;

pub use lines::{EVERY_SECONDS, Lines, QUIET_SECONDS};

/// Receives progress reports of one task at a time.
pub trait Progress: Sync {
    /// A task begins: `total` units of `unit` (`columns`, `steps`; 0 when unknown).
    fn begin(&self, task: &str, total: u64, unit: &str) {
        let _ = (task, total, unit);
    }

    /// The task stands at `position` units; `message` says how it is going.
    fn advance(&self, position: u64, message: &str) {
        let _ = (position, message);
    }

    /// The task ended.
    fn end(&self) {}

    /// Something the user should know that is not an error (a load warning, an approximation
    /// the run makes).
    fn warn(&self, message: &str) {
        let _ = message;
    }
}

/// Reports nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {}
