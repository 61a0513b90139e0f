//! Progress bars on stderr for the library's long calls ([`radiosity_eval::Progress`]). When
//! stderr is not a terminal there are no bars, so logs and tests see only results and
//! warnings; but a task still running after [`QUIET_SECONDS`] says, in one line, what it does,
//! how far it is, about how long it has left and what it last reported, and again every
//! [`EVERY_SECONDS`] while it runs: a ticker says it even when the task reports nothing (one
//! long step, a phase with no count), so that a long phase is never silent.

use indicatif::{ProgressBar, ProgressStyle};
use radiosity_eval::Progress;
use std::io::IsTerminal;
use std::sync::{Arc, Mutex, Weak};
use std::time::{Duration, Instant};

/// How long a task runs before it is announced on a stderr that is not a terminal.
pub const QUIET_SECONDS: f64 = 10.0;
/// How often a task still running is announced again, without a terminal.
pub const EVERY_SECONDS: f64 = 30.0;

/// One bar at a time, replaced at each task.
pub struct Bars {
    bar: Mutex<ProgressBar>,
    visible: bool,
    /// The task under way, for the announcements without a terminal; the ticker holds it
    /// weakly and stops when the bars go.
    task: Arc<Mutex<Option<Task>>>,
    ticking: std::sync::Once,
}

/// A task under way, without a terminal.
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
    /// Whether the task is to be announced after `seconds`: first at [`QUIET_SECONDS`], then
    /// every [`EVERY_SECONDS`].
    fn due(&self, seconds: f64) -> bool {
        match self.announced {
            None => seconds >= QUIET_SECONDS,
            Some(last) => seconds >= last + EVERY_SECONDS,
        }
    }

    /// The announcement when it is due ([`Task::due`]), marked as made.
    fn announce(&mut self, seconds: f64) -> Option<String> {
        if !self.due(seconds) {
            return None;
        }
        self.announced = Some(seconds);
        self.announcement(self.position, seconds).map(|line| match self.message.is_empty() {
            true => line,
            false => format!("{line} ({})", self.message),
        })
    }

    /// The line that announces the task at `position` after `seconds`, once it has run for
    /// [`QUIET_SECONDS`]: what it does, how far it is, and the time left at its rate so far.
    fn announcement(&self, position: u64, seconds: f64) -> Option<String> {
        if seconds < QUIET_SECONDS {
            return None;
        }
        let left = match (position, self.total) {
            (p, total) if p > 0 && total > p => {
                format!(", about {:.0} s to go", seconds * (total - p) as f64 / p as f64)
            }
            _ => String::new(),
        };
        let done = if self.total > 0 { format!(": {position} of {} {}", self.total, self.unit) } else { String::new() };
        Some(format!("{}{done} after {seconds:.0} s{left}", self.name))
    }
}

impl Bars {
    /// Bars on stderr when it is a terminal.
    pub fn new() -> Bars {
        Bars {
            bar: Mutex::new(ProgressBar::hidden()),
            visible: std::io::stderr().is_terminal(),
            task: Arc::new(Mutex::new(None)),
            ticking: std::sync::Once::new(),
        }
    }

    fn bar(&self) -> std::sync::MutexGuard<'_, ProgressBar> {
        self.bar.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn task(&self) -> std::sync::MutexGuard<'_, Option<Task>> {
        self.task.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Starts, once, the ticker that announces the task under way when it is due, whether or
    /// not it reports: it looks every second and ends with the bars.
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

impl Progress for Bars {
    fn begin(&self, task: &str, total: u64, unit: &str) {
        if !self.visible {
            let task = Task {
                name: task.into(),
                total,
                unit: unit.into(),
                start: Instant::now(),
                position: 0,
                message: String::new(),
                announced: None,
            };
            *self.task() = Some(task);
            self.tick();
            return;
        }
        let bar = if total == 0 {
            let spinner = ProgressBar::new_spinner();
            spinner.enable_steady_tick(Duration::from_millis(120));
            spinner
        } else {
            ProgressBar::new(total)
        };
        let template = if total == 0 {
            "{spinner} {prefix} {msg} {elapsed}".to_string()
        } else {
            format!("{{spinner}} {{prefix:24}} {{msg:16}} [{{bar:30}}] {{pos}}/{{len}} {unit} {{elapsed}}")
        };
        bar.set_style(ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar()));
        bar.set_prefix(task.to_string());
        *self.bar() = bar;
    }

    fn advance(&self, position: u64, message: &str) {
        if !self.visible {
            if let Some(t) = self.task().as_mut() {
                t.position = position;
                t.message = message.to_string();
                if let Some(line) = t.announce(t.start.elapsed().as_secs_f64()) {
                    eprintln!("{line}");
                }
            }
            return;
        }
        let bar = self.bar();
        bar.set_position(position);
        if !message.is_empty() {
            bar.set_message(message.to_string());
        }
    }

    fn end(&self) {
        *self.task() = None;
        self.bar().finish_and_clear();
    }

    fn warn(&self, message: &str) {
        self.bar().suspend(|| eprintln!("warning: {message}"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_task_is_announced_once_it_has_run_long_with_the_time_left_at_its_rate() {
        let task = Task {
            name: "reference".into(),
            total: 400,
            unit: "columns".into(),
            start: Instant::now(),
            position: 100,
            message: String::new(),
            announced: None,
        };
        assert_eq!(task.announcement(100, 5.0), None);
        assert_eq!(task.announcement(100, 12.0).unwrap(), "reference: 100 of 400 columns after 12 s, about 36 s to go");
        let spinner = Task { total: 0, unit: String::new(), ..task };
        assert_eq!(spinner.announcement(0, 20.0).unwrap(), "reference after 20 s");
    }

    #[test]
    fn a_task_is_announced_again_every_thirty_seconds_with_what_it_last_said() {
        let mut task = Task {
            name: "h-southwell".into(),
            total: 0,
            unit: "steps".into(),
            start: Instant::now(),
            position: 3,
            message: "bound 1.2e-2".into(),
            announced: None,
        };
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
