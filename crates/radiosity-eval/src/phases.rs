//! Where a command's time and memory went, phase by phase ([`Phases`]): loading the scene,
//! building its BVH, probing for hidden geometry, analysing it, setting up the backend and the
//! reference, solving, writing the output. `cargo xtask solve --verbose` prints the table and
//! `solve --json` stores it (docs/cli.md); docs/scale.md reads it at a million patches.
//!
//! A phase's seconds are wall seconds; its peak bytes are the process's peak resident memory
//! when the phase ended (`VmHWM` of `/proc/self/status`), so they only grow: the phase that raised the
//! peak is the one whose figure rose.

use crate::memory::peak_rss;
use crate::progress::Progress;
use crate::reports::report_text::human_bytes;
use serde::Serialize;
use std::fmt::Write as _;
use std::sync::Mutex;
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

    /// Ends the phase under way at `at`, the peak memory then `peak`, and begins `name` from
    /// `at`: a phase split after the fact, where a task under way said when its second part
    /// began ([`ReferenceMark`]).
    pub fn begin_at(&mut self, name: &str, at: Instant, peak: Option<u64>) {
        if let Some((open, start)) = self.open.take() {
            let seconds = at.saturating_duration_since(start).as_secs_f64();
            self.done.push(Phase { name: open, seconds, peak_bytes: peak });
        }
        self.open = Some((name.to_string(), at));
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

/// Progress passed on to another, noting when the lab's reference began (its first task named
/// `reference …` or `reading the reference`, as `Lab::new` names them) and the peak memory
/// then: the set-up of the backend and that of the reference, one call apart, become two phases
/// ([`Phases::begin_at`]).
pub struct ReferenceMark<'a> {
    inner: &'a dyn Progress,
    began: Mutex<Option<(Instant, Option<u64>)>>,
}

impl<'a> ReferenceMark<'a> {
    /// Passes everything on to `inner`.
    pub fn new(inner: &'a dyn Progress) -> ReferenceMark<'a> {
        ReferenceMark { inner, began: Mutex::new(None) }
    }

    /// When the reference began and the peak memory then, if it did.
    pub fn began(&self) -> Option<(Instant, Option<u64>)> {
        *self.began.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Progress for ReferenceMark<'_> {
    fn begin(&self, task: &str, total: u64, unit: &str) {
        if task.starts_with("reference") || task == "reading the reference" {
            self.began.lock().unwrap_or_else(|e| e.into_inner()).get_or_insert_with(|| (Instant::now(), peak_rss()));
        }
        self.inner.begin(task, total, unit);
    }

    fn advance(&self, position: u64, message: &str) {
        self.inner.advance(position, message);
    }

    fn end(&self) {
        self.inner.end();
    }

    fn warn(&self, message: &str) {
        self.inner.warn(message);
    }
}
