//! Where a command's time and memory went, phase by phase ([`Phases`]): loading the scene,
//! building its BVH, probing for hidden geometry, analysing it, setting up the backend and the
//! reference, solving, writing the output. `cargo xtask solve --verbose` prints the table and
//! `solve --json` stores it (docs/cli.md); docs/scale.md reads it at a million patches.
//!
//! A phase's seconds are wall seconds, with the CPU seconds of all the process's threads beside
//! them (one thread busy: about the wall seconds; two: up to twice, more than the wall seconds
//! only where both worked); its peak bytes are the process's peak resident memory
//! when the phase ended (`VmHWM` of `/proc/self/status`), so they only grow: the phase that raised the
//! peak is the one whose figure rose.

use crate::memory::{cpu_seconds, peak_rss};
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
    /// CPU seconds of all the process's threads; `None` where the system does not say, or for
    /// a phase split after the fact ([`Phases::begin_at`]).
    pub cpu_seconds: Option<f64>,
    /// The process's peak resident memory when the phase ended, in bytes; `None` where the
    /// system does not say.
    pub peak_bytes: Option<u64>,
}

/// The phases of one command, in order, the one under way not among them yet.
#[derive(Clone, Debug, Default)]
pub struct Phases {
    done: Vec<Phase>,
    open: Option<(String, Instant, Option<f64>)>,
}

impl Phases {
    /// No phase yet.
    pub fn new() -> Phases {
        Phases::default()
    }

    /// Ends the phase under way, if any, and begins `name`.
    pub fn begin(&mut self, name: &str) {
        self.end();
        self.open = Some((name.to_string(), Instant::now(), cpu_seconds()));
    }

    /// Ends the phase under way at `at`, the peak memory then `peak`, and begins `name` from
    /// `at`: a phase split after the fact, where a task under way said when its second part
    /// began ([`ReferenceMark`]).
    pub fn begin_at(&mut self, name: &str, at: Instant, peak: Option<u64>) {
        if let Some((open, start, _)) = self.open.take() {
            let seconds = at.saturating_duration_since(start).as_secs_f64();
            self.done.push(Phase { name: open, seconds, cpu_seconds: None, peak_bytes: peak });
        }
        self.open = Some((name.to_string(), at, None));
    }

    /// Ends the phase under way, if any.
    pub fn end(&mut self) {
        if let Some((name, start, cpu)) = self.open.take() {
            let seconds = start.elapsed().as_secs_f64();
            let cpu_seconds = cpu.zip(cpu_seconds()).map(|(before, now)| now - before);
            self.done.push(Phase { name, seconds, cpu_seconds, peak_bytes: peak_rss() });
        }
    }

    /// The phases ended so far.
    pub fn list(&self) -> &[Phase] {
        &self.done
    }

    /// The phases ended so far as a table: a line each, then their total.
    pub fn text(&self) -> String {
        let mut out = format!("{:<38} {:>8} {:>8} {:>12}\n", "phase", "seconds", "cpu", "peak memory");
        let bytes = |b: Option<u64>| b.map_or("n/a".into(), human_bytes);
        let cpu = |c: Option<f64>| c.map_or("n/a".into(), |c| format!("{c:.2}"));
        for p in &self.done {
            let _ = writeln!(
                out,
                "{:<38} {:>8.3} {:>8} {:>12}",
                p.name,
                p.seconds,
                cpu(p.cpu_seconds),
                bytes(p.peak_bytes)
            );
        }
        let total: f64 = self.done.iter().map(|p| p.seconds).sum();
        let cpu_total = self.done.iter().map(|p| p.cpu_seconds).sum::<Option<f64>>();
        let peak = bytes(self.done.last().and_then(|p| p.peak_bytes));
        let _ = writeln!(out, "{:<38} {:>8.3} {:>8} {:>12}", "total", total, cpu(cpu_total), peak);
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
