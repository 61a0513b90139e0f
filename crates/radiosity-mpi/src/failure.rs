//! Which rank ended a distributed run, and how, read from the launcher's error output.
//!
//! Open MPI 4.1's `mpirun` reports the first rank to fail in one of these forms (the rank is the
//! last number of a process name `[[job,1],rank]`):
//!
//! ```text
//! mpirun noticed that process rank 2 with PID 0 on node vm exited on signal 9 (Killed).
//! mpirun detected that one or more processes exited with non-zero status, ...
//!   Process name: [[11449,1],1]
//!   Exit code:    3
//! mpirun has exited due to process rank 1 with PID 0 on node vm exiting improperly. ...
//! MPI_ABORT was invoked on rank 1 in communicator MPI_COMM_WORLD
//! with errorcode 3.
//! ```
//!
//! An ending read from none of them is reported by the launcher's own exit status.

/// How a rank ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Ending {
    /// It exited with this status (or called `MPI_Abort` with this error code).
    Status(i32),
    /// A signal ended it: its number and, where the launcher names it, its name.
    Signal(i32, Option<String>),
    /// It exited without finalising MPI (its status unknown).
    Improperly,
}

impl std::fmt::Display for Ending {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Ending::Status(status) => write!(f, "exit status {status}"),
            Ending::Signal(signal, Some(name)) => write!(f, "signal {signal} ({name})"),
            Ending::Signal(signal, None) => write!(f, "signal {signal}"),
            Ending::Improperly => write!(f, "an exit that did not finalise MPI"),
        }
    }
}

/// The rank that failed first and how it ended, where the launcher's error output says so; the
/// rank is `None` where the output names an ending but not the rank.
pub(crate) fn first_failure(stderr: &str) -> Option<(Option<usize>, Ending)> {
    let lines: Vec<&str> = stderr.lines().map(str::trim).collect();
    for (i, line) in lines.iter().enumerate() {
        if let Some(rest) = after(line, "process rank ") {
            let rank = leading_number(rest).and_then(|r| usize::try_from(r).ok());
            if let Some(signal) = after(rest, "exited on signal ") {
                let name = signal.split_once('(').and_then(|(_, n)| n.split_once(')')).map(|(n, _)| n.to_string());
                return Some((rank, Ending::Signal(leading_number(signal)?, name)));
            }
            if rest.contains("exiting improperly") {
                return Some((rank, Ending::Improperly));
            }
            if let Some(status) = after(rest, "exited with status ") {
                return Some((rank, Ending::Status(leading_number(status)?)));
            }
        }
        if let Some(name) = after(line, "Process name:") {
            let rank = name.rsplit(',').next().and_then(leading_number).and_then(|r| usize::try_from(r).ok());
            let code = lines[i + 1..].iter().take(3).find_map(|l| after(l, "Exit code:")).and_then(leading_number);
            if let Some(code) = code {
                return Some((rank, Ending::Status(code)));
            }
        }
        if let Some(rest) = after(line, "MPI_ABORT was invoked on rank ") {
            let rank = leading_number(rest).and_then(|r| usize::try_from(r).ok());
            let tail = lines[i..].iter().take(3).copied().collect::<Vec<_>>().join(" ");
            if let Some(code) = after(&tail, "errorcode ").and_then(leading_number) {
                return Some((rank, Ending::Status(code)));
            }
        }
    }
    None
}

/// What follows the first `marker` in `text`.
fn after<'a>(text: &'a str, marker: &str) -> Option<&'a str> {
    text.find(marker).map(|at| &text[at + marker.len()..])
}

/// The (possibly negative) whole number that `text` opens with, after blanks.
fn leading_number(text: &str) -> Option<i32> {
    let text = text.trim_start();
    let digits = text
        .char_indices()
        .find(|&(i, c)| !(c.is_ascii_digit() || (i == 0 && c == '-')))
        .map_or(text.len(), |(i, _)| i);
    text[..digits].parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    // The texts below are what Open MPI 4.1.4's mpirun printed for ranks that failed.

    #[test]
    fn a_non_zero_exit_names_the_rank_of_the_process_name() {
        let text = "--------------------------------------------------------------------------
Primary job  terminated normally, but 1 process returned
a non-zero exit code. Per user-direction, the job has been aborted.
--------------------------------------------------------------------------
--------------------------------------------------------------------------
mpirun detected that one or more processes exited with non-zero status, thus causing
the job to be terminated. The first process to do so was:

  Process name: [[11449,1],1]
  Exit code:    3
--------------------------------------------------------------------------
";
        assert_eq!(first_failure(text), Some((Some(1), Ending::Status(3))));
    }

    #[test]
    fn a_signal_names_the_rank_and_the_signal() {
        let text = "mpirun noticed that process rank 2 with PID 0 on node vm exited on signal 9 (Killed).\n";
        assert_eq!(first_failure(text), Some((Some(2), Ending::Signal(9, Some("Killed".into())))));
        assert_eq!(Ending::Signal(9, Some("Killed".into())).to_string(), "signal 9 (Killed)");
    }

    #[test]
    fn an_abort_names_the_rank_and_its_error_code() {
        let text = "MPI_ABORT was invoked on rank 1 in communicator MPI_COMM_WORLD\nwith errorcode 7.\n";
        assert_eq!(first_failure(text), Some((Some(1), Ending::Status(7))));
    }

    #[test]
    fn output_without_a_report_names_nothing() {
        assert_eq!(first_failure("rank 0 prints a warning\n"), None);
        assert_eq!(leading_number(" -12x"), Some(-12));
        assert_eq!(leading_number("x"), None);
    }
}
