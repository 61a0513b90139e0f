//! [`launch`]: runs a program as `K` MPI ranks on this machine, through the system's MPI
//! launcher, and reports a rank that failed in one sentence.
//!
//! The ranks' standard output passes straight through. Their standard error, and the
//! launcher's, is forwarded line by line as it comes and also kept, so that a failed run can say
//! which rank ended it (module `failure`): "rank 1 of 3 ended with exit status 3 before the
//! distributed run finished". The launcher's own boxed reports (Open MPI frames them between
//! lines of dashes) are kept but not forwarded: that sentence says what they say.

use crate::failure::{Ending, first_failure};
use crate::launcher::Launcher;
use std::ffi::OsString;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Why a distributed run did not finish.
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    /// No MPI launcher on this machine.
    #[error(
        "no MPI launcher was found (neither $MPIRUN, mpirun nor mpiexec on PATH): install Open MPI (openmpi-bin, libopenmpi-dev) or MPICH"
    )]
    NoLauncher,
    /// A run of no ranks was asked for.
    #[error("a distributed run needs at least one rank")]
    NoRanks,
    /// The launcher could not be started.
    #[error("the MPI launcher {} could not be started: {source}", launcher.display())]
    Start {
        /// The launcher's executable.
        launcher: PathBuf,
        /// Why it could not be started.
        source: std::io::Error,
    },
    /// A known rank ended the run.
    #[error("rank {rank} of {ranks} ended with {ending} before the distributed run finished")]
    RankEnded {
        /// The rank that ended first.
        rank: usize,
        /// The number of ranks.
        ranks: usize,
        /// How it ended: "exit status 3", "signal 9 (Killed)".
        ending: String,
    },
    /// A rank, which the launcher did not name, ended the run.
    #[error("a rank ended with {ending} before the distributed run finished")]
    SomeRankEnded {
        /// How it ended, or the launcher's own exit status where nothing more is known.
        ending: String,
    },
}

/// Runs `program args` as `ranks` MPI ranks on this machine and waits for them (module doc).
pub fn launch(ranks: usize, program: &Path, args: &[OsString]) -> Result<(), LaunchError> {
    if ranks == 0 {
        return Err(LaunchError::NoRanks);
    }
    let launcher = Launcher::find().ok_or(LaunchError::NoLauncher)?;
    let start_error = |source| LaunchError::Start { launcher: launcher.path.clone(), source };
    let mut child = Command::new(&launcher.path)
        .args(launcher.arguments(ranks, program, args))
        .stdin(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(start_error)?;
    let mut kept = Vec::new();
    if let Some(stderr) = child.stderr.take() {
        forward_lines(BufReader::new(stderr), &mut kept);
    }
    let status = child.wait().map_err(start_error)?;
    if status.success() {
        return Ok(());
    }
    let launcher_ending = match (status.code(), std::os::unix::process::ExitStatusExt::signal(&status)) {
        (Some(code), _) => Ending::Status(code),
        (None, Some(signal)) => Ending::Signal(signal, None),
        (None, None) => Ending::Improperly,
    };
    Err(match first_failure(&String::from_utf8_lossy(&kept)) {
        Some((Some(rank), ending)) if rank < ranks => {
            LaunchError::RankEnded { rank, ranks, ending: ending.to_string() }
        }
        Some((_, ending)) => LaunchError::SomeRankEnded { ending: ending.to_string() },
        None => LaunchError::SomeRankEnded { ending: launcher_ending.to_string() },
    })
}

/// Copies `from` to this process's standard error a line at a time, as the lines come, but for
/// the launcher's boxed reports (module doc), keeping a copy of every line in `kept`; ends at
/// the end of `from` or when it cannot be read.
fn forward_lines(mut from: impl BufRead, kept: &mut Vec<u8>) {
    let mut line = Vec::new();
    // Within one of the launcher's boxed reports.
    let mut boxed = false;
    loop {
        line.clear();
        match from.read_until(b'\n', &mut line) {
            Ok(0) | Err(_) => break,
            Ok(_) => {
                let frame = line.len() > 20 && line.trim_ascii().iter().all(|&b| b == b'-');
                boxed ^= frame;
                if !(frame || boxed) {
                    // Our own standard error failing (closed) must not stop the ranks' run.
                    let _ = std::io::stderr().lock().write_all(&line);
                }
                kept.extend_from_slice(&line);
            }
        }
    }
}
