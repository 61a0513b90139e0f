//! Where a command's time and memory went, phase by phase ([`Phases`]): loading the scene,
//! building its BVH, probing for hidden geometry, analysing it, setting up the backend and the
//! reference, solving, writing the output. `cargo xtask solve --verbose` prints the table and
//! `solve --json` stores it (docs/cli.md); docs/scale.md reads it at a million patches.
//!
//! A phase's seconds are wall seconds; its peak bytes are the process's peak resident memory
//! when the phase ended (`VmHWM` of `/proc/self/status`), so they only grow: the phase that raised the
//! peak is the one whose figure rose.

use crate::memory::peak_rss;
use crate::reports::report_text::human_bytes;
use serde::Serialize;
use std::fmt::Write as _;
use std::time::Instant;

/// One phase: its name, wall seconds and the peak resident bytes when it ended.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Phase {
    /// What it did (`loading`, `building the BVH`, `solving`).
    pub name: String,
    /// Wall seconds.
    pub seconds: f64,
    /// The process's peak resident memory when the phase ended, in bytes; `None` where the
    /// system does not say.
    pub peak_bytes: Option<u64>,
}

/// The phases of one command, in order, the one under way not among them yet.
#[derive(Clone, Debug, Default)]
pub struct Phases {
    done: Vec<Phase>,
    open: Option<(String, Instant)>,
}

impl Phases {
    /// No phase yet.
    pub fn new() -> Phases {
        Phases::default()
    }

    /// Ends the phase under way, if any, and begins `name`.
    pub fn begin(&mut self, name: &str) {
        self.end();
        self.open = Some((name.to_string(), Instant::now()));
    }

    /// Ends the phase under way, if any.
    pub fn end(&mut self) {
        if let Some((name, start)) = self.open.take() {
            self.done.push(Phase { name, seconds: start.elapsed().as_secs_f64(), peak_bytes: peak_rss() });
        }
    }

    /// The phases ended so far.
    pub fn list(&self) -> &[Phase] {
        &self.done
    }

    /// The phases ended so far as a table: a line each, then their total.
    pub fn text(&self) -> String {
        let mut out = format!("{:<38} {:>8} {:>12}\n", "phase", "seconds", "peak memory");
        let bytes = |b: Option<u64>| b.map_or("n/a".into(), human_bytes);
        for p in &self.done {
            let _ = writeln!(out, "{:<38} {:>8.3} {:>12}", p.name, p.seconds, bytes(p.peak_bytes));
        }
        let total: f64 = self.done.iter().map(|p| p.seconds).sum();
        let _ =
            writeln!(out, "{:<38} {:>8.3} {:>12}", "total", total, bytes(self.done.last().and_then(|p| p.peak_bytes)));
        out
    }
}
