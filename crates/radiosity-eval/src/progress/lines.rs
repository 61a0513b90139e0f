//! Progress as lines on stderr, for a log or a pipe where bars cannot be drawn: a task still
//! running after [`QUIET_SECONDS`] says, in one line, what it does, how far it is, about how
//! long it has left and what it last reported, and again every [`EVERY_SECONDS`] while it runs.
//! A ticker says it even when the task reports nothing (one long step, a phase with no count),
//! so that a long phase is never silent.

use super::Progress;
use std::sync::{Arc, Mutex, MutexGuard, Once, Weak};
use std::time::{Duration, Instant};

/// How long a task runs before it is announced.
pub const QUIET_SECONDS: f64 = 10.0;
/// How often a task still running is announced again.
pub const EVERY_SECONDS: f64 = 30.0;

/// Progress as lines on stderr (module doc).
pub struct Lines {
    /// The task under way; the ticker holds it weakly and stops when the lines go.
    task: Arc<Mutex<Option<Task>>>,
    ticking: Once,
}

/// A task under way.
struct Task {
    name: String,
    total: u64,
    unit: String,
    start: Instant,
    /// How far it is and what it said, as last reported.
    position: u64,
    message: String,
    /// When it was last announced, in seconds from its start.
    announced: Option<f64>,
}

impl Task {
    fn new(name: &str, total: u64, unit: &str) -> Task {
        Task {
            name: name.into(),
            total,
            unit: unit.into(),
            start: Instant::now(),
            position: 0,
            message: String::new(),
            announced: None,
        }
    }

    /// The line that announces the task after `seconds` when it is due (first at
    /// [`QUIET_SECONDS`], then every [`EVERY_SECONDS`]), marked as made: what it does, how
    /// far it is, the time left at its rate so far, and what it last said.
    fn announce(&mut self, seconds: f64) -> Option<String> {
        let due = match self.announced {
            None => seconds >= QUIET_SECONDS,
            Some(last) => seconds >= last + EVERY_SECONDS,
        };
        if !due {
            return None;
        }
        self.announced = Some(seconds);
        let (p, total) = (self.position, self.total);
        let done = if total > 0 { format!(": {p} of {total} {}", self.unit) } else { String::new() };
        let left = if p > 0 && total > p {
            format!(", about {:.0} s to go", seconds * (total - p) as f64 / p as f64)
        } else {
            String::new()
        };
        let said = if self.message.is_empty() { String::new() } else { format!(" ({})", self.message) };
        Some(format!("{}{done} after {seconds:.0} s{left}{said}", self.name))
    }
}

impl Default for Lines {
    fn default() -> Lines {
        Lines { task: Arc::default(), ticking: Once::new() }
    }
}

impl Lines {
    /// Lines on stderr, no task under way.
    pub fn new() -> Lines {
        Lines::default()
    }

    fn task(&self) -> MutexGuard<'_, Option<Task>> {
        self.task.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Starts, once, the ticker that announces the task under way when it is due, whether or
    /// not it reports: it looks every second and ends with the lines.
    fn tick(&self) {
        self.ticking.call_once(|| {
            let task: Weak<Mutex<Option<Task>>> = Arc::downgrade(&self.task);
            std::thread::spawn(move || {
                while let Some(task) = task.upgrade() {
                    if let Some(t) = task.lock().unwrap_or_else(|e| e.into_inner()).as_mut() {
                        if let Some(line) = t.announce(t.start.elapsed().as_secs_f64()) {
                            eprintln!("{line}");
                        }
                    }
                    drop(task);
                    std::thread::sleep(Duration::from_secs(1));
                }
            });
        });
    }
}

impl Progress for Lines {
    fn begin(&self, task: &str, total: u64, unit: &str) {
        *self.task() = Some(Task::new(task, total, unit));
        self.tick();
    }

    fn advance(&self, position: u64, message: &str) {
        if let Some(t) = self.task().as_mut() {
            t.position = position;
            t.message = message.to_string();
            if let Some(line) = t.announce(t.start.elapsed().as_secs_f64()) {
                eprintln!("{line}");
            }
        }
    }

    fn end(&self) {
        *self.task() = None;
    }

    fn warn(&self, message: &str) {
        eprintln!("warning: {message}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_task_is_announced_once_it_has_run_long_with_the_time_left_at_its_rate() {
        let mut task = Task { position: 100, ..Task::new("reference", 400, "columns") };
        assert_eq!(task.announce(5.0), None);
        assert_eq!(task.announce(12.0).unwrap(), "reference: 100 of 400 columns after 12 s, about 36 s to go");
        let mut spinner = Task::new("reference", 0, "");
        assert_eq!(spinner.announce(20.0).unwrap(), "reference after 20 s");
    }

    #[test]
    fn a_task_is_announced_again_every_thirty_seconds_with_what_it_last_said() {
        let mut task = Task { position: 3, message: "bound 1.2e-2".into(), ..Task::new("h-southwell", 0, "steps") };
        assert_eq!(task.announce(9.0), None);
        assert_eq!(task.announce(10.5).unwrap(), "h-southwell after 10 s (bound 1.2e-2)");
        // Not again before thirty seconds more, whatever is asked in between.
        assert_eq!(task.announce(11.0), None);
        assert_eq!(task.announce(40.0), None);
        task.message.clear();
        assert_eq!(task.announce(40.5).unwrap(), "h-southwell after 40 s");
        assert_eq!(task.announce(70.5).unwrap(), "h-southwell after 70 s");
        assert_eq!(task.announce(71.0), None);
    }
}
