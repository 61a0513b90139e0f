//! Progress bars on stderr for the library's long calls ([`radiosity_eval::Progress`]). When
//! stderr is not a terminal there are no bars, so logs and tests see only results and
//! warnings; but a task still running after [`QUIET_SECONDS`] says once, in one line, what it
//! does, how far it is and about how long it has left, so that a long phase is never silent.

use indicatif::{ProgressBar, ProgressStyle};
use radiosity_eval::Progress;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How long a task runs before it is announced on a stderr that is not a terminal.
pub const QUIET_SECONDS: f64 = 10.0;

/// One bar at a time, replaced at each task.
pub struct Bars {
    bar: Mutex<ProgressBar>,
    visible: bool,
    /// The task under way, for the one-line announcement without a terminal.
    task: Mutex<Option<Task>>,
}

/// A task under way, without a terminal.
struct Task {
    name: String,
    total: u64,
    unit: String,
    start: Instant,
    announced: bool,
}

impl Task {
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
            task: Mutex::new(None),
        }
    }

    fn bar(&self) -> std::sync::MutexGuard<'_, ProgressBar> {
        self.bar.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Progress for Bars {
    fn begin(&self, task: &str, total: u64, unit: &str) {
        if !self.visible {
            let task = Task { name: task.into(), total, unit: unit.into(), start: Instant::now(), announced: false };
            *self.task.lock().unwrap_or_else(|e| e.into_inner()) = Some(task);
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
            let mut task = self.task.lock().unwrap_or_else(|e| e.into_inner());
            if let Some(t) = task.as_mut().filter(|t| !t.announced) {
                if let Some(line) = t.announcement(position, t.start.elapsed().as_secs_f64()) {
                    t.announced = true;
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
        *self.task.lock().unwrap_or_else(|e| e.into_inner()) = None;
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
            announced: false,
        };
        assert_eq!(task.announcement(100, 5.0), None);
        assert_eq!(task.announcement(100, 12.0).unwrap(), "reference: 100 of 400 columns after 12 s, about 36 s to go");
        let spinner = Task { total: 0, unit: String::new(), ..task };
        assert_eq!(spinner.announcement(0, 20.0).unwrap(), "reference after 20 s");
    }
}
