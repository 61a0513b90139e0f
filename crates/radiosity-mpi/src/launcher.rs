//! Which MPI launcher starts the ranks, and the arguments it needs on this machine.
//!
//! The launcher is `$MPIRUN` when set, else `mpirun`, else `mpiexec`, found on `PATH`. Open MPI
//! (told by `--version` naming "Open MPI" or its runtime "OpenRTE") refuses to start more ranks
//! than cores without `--oversubscribe`, and any rank as root without `--allow-run-as-root`; MPICH
//! needs neither.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// An MPI launcher found on this machine.
#[derive(Clone, Debug)]
pub(crate) struct Launcher {
    /// The launcher's executable.
    pub(crate) path: PathBuf,
    /// Whether it is Open MPI's.
    open_mpi: bool,
}

impl Launcher {
    /// `$MPIRUN`, else `mpirun` or `mpiexec` on `PATH`; `None` when there is none.
    pub(crate) fn find() -> Option<Launcher> {
        let path = match std::env::var_os("MPIRUN").filter(|v| !v.is_empty()) {
            Some(named) => on_path(Path::new(&named))?,
            None => ["mpirun", "mpiexec"].into_iter().find_map(|name| on_path(Path::new(name)))?,
        };
        let open_mpi = Command::new(&path)
            .arg("--version")
            .stdin(Stdio::null())
            .output()
            .map(|out| {
                let text = [out.stdout, out.stderr].concat();
                let text = String::from_utf8_lossy(&text);
                text.contains("Open MPI") || text.contains("OpenRTE")
            })
            .unwrap_or(false);
        Some(Launcher { path, open_mpi })
    }

    /// The launcher's arguments that run `program args` as `ranks` ranks.
    pub(crate) fn arguments(&self, ranks: usize, program: &Path, args: &[OsString]) -> Vec<OsString> {
        let mut all: Vec<OsString> = Vec::new();
        if self.open_mpi {
            all.push("--oversubscribe".into());
            if effective_uid() == Some(0) {
                all.push("--allow-run-as-root".into());
            }
        }
        all.extend(["-np".into(), ranks.to_string().into(), program.into()]);
        all.extend(args.iter().cloned());
        all
    }
}

/// `name` itself when it names a path (it holds a `/`), else the first file of that name in a
/// directory of `PATH`.
fn on_path(name: &Path) -> Option<PathBuf> {
    if name.components().count() > 1 || name.is_absolute() {
        return name.is_file().then(|| name.to_path_buf());
    }
    let dirs = std::env::var_os("PATH")?;
    std::env::split_paths(&dirs).map(|dir| dir.join(name)).find(|candidate| candidate.is_file())
}

/// This process's effective user id, read from `/proc/self/status` (its `Uid:` line holds the
/// real, effective, saved and file-system ids); `None` where there is no such file.
fn effective_uid() -> Option<u32> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find_map(|line| line.strip_prefix("Uid:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn open_mpi_gets_oversubscribe_and_the_rank_count_before_the_program() {
        let launcher = Launcher { path: "mpirun".into(), open_mpi: true };
        let args = launcher.arguments(3, Path::new("/bin/prog"), &["--flag".into()]);
        let root = effective_uid() == Some(0);
        let mut expected: Vec<OsString> = vec!["--oversubscribe".into()];
        if root {
            expected.push("--allow-run-as-root".into());
        }
        expected.extend(["-np", "3", "/bin/prog", "--flag"].map(OsString::from));
        assert_eq!(args, expected);
    }

    #[test]
    fn other_launchers_get_only_the_rank_count() {
        let launcher = Launcher { path: "mpiexec".into(), open_mpi: false };
        let args = launcher.arguments(2, Path::new("prog"), &[]);
        assert_eq!(args, ["-np", "2", "prog"].map(OsString::from));
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn the_effective_uid_is_read_where_proc_exists() {
        if Path::new("/proc/self/status").exists() {
            // The owner of a file this process creates is its effective uid (Linux).
            let probe = std::env::temp_dir().join(format!("radiosity-mpi-uid-{}", std::process::id()));
            std::fs::write(&probe, b"").unwrap();
            let owner = std::os::unix::fs::MetadataExt::uid(&std::fs::metadata(&probe).unwrap());
            std::fs::remove_file(&probe).unwrap();
            assert_eq!(effective_uid(), Some(owner));
        }
    }
}
