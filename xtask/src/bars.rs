//! Progress bars on stderr for the library's long calls ([`radiosity_eval::Progress`]). When
//! stderr is not a terminal there are no bars, so logs and tests see only results and
//! warnings, and the library's [`Lines`] says what a long task does every 30 s.

use indicatif::{ProgressBar, ProgressStyle};
use radiosity_eval::{Lines, Progress};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::Duration;

/// One bar at a time, replaced at each task; lines without a terminal.
pub struct Bars {
    bar: Mutex<ProgressBar>,
    /// `None` on a terminal.
    lines: Option<Lines>,
}

impl Bars {
    /// Bars on stderr when it is a terminal, lines otherwise.
    pub fn new() -> Bars {
        Bars { bar: Mutex::new(ProgressBar::hidden()), lines: (!std::io::stderr().is_terminal()).then(Lines::new) }
    }

    fn bar(&self) -> std::sync::MutexGuard<'_, ProgressBar> {
        self.bar.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Progress for Bars {
    fn begin(&self, task: &str, total: u64, unit: &str) {
        if let Some(lines) = &self.lines {
            return lines.begin(task, total, unit);
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
        if let Some(lines) = &self.lines {
            return lines.advance(position, message);
        }
        let bar = self.bar();
        bar.set_position(position);
        if !message.is_empty() {
            bar.set_message(message.to_string());
        }
    }

    fn end(&self) {
        if let Some(lines) = &self.lines {
            lines.end();
        }
        self.bar().finish_and_clear();
    }

    fn warn(&self, message: &str) {
        self.bar().suspend(|| eprintln!("warning: {message}"));
    }
}
