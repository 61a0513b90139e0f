//! Distributed runs: this process as one of several MPI ranks (built with `--features mpi`
//! and started by `mpirun`), and `--ranks K`, which starts `mpirun` on this program.
//!
//! Under `mpirun -np K`, every rank runs the same command (SPMD): it loads the scene, builds
//! its part of the hierarchical operator (`BackendRegistry::builtin_split`) and runs the same
//! solvers, meeting the other ranks in the operator's sums; the solvers that sample transport
//! deal their replicates to the ranks instead (`Lab::over_ranks`). Rank 0 alone prints and writes:
//! the other ranks' standard output and error go to `/dev/null`, except a panic's message.
//! Only `solve` and `compare` run distributed; the other commands refuse a world of several
//! ranks instead of running K times.

use anyhow::{Result, bail};
use radiosity_core::Collective;
use radiosity_ff::{BackendRegistry, BackendSpec};
use std::sync::Arc;

/// `--ranks K`, for the commands that run distributed.
#[derive(Debug, clap::Args)]
pub struct RanksArg {
    /// Runs as K MPI ranks on this machine, starting mpirun itself (an xtask built with
    /// --features mpi: cargo xtask-mpi); each rank builds its part of the hierarchical
    /// operator, and rank 0 reports.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub ranks: Option<u32>,
}

/// The ranks this process is one of, made by `main` and handed to the command that runs
/// distributed; a single process holds none. MPI is finalised when the last reference to the
/// world is dropped, which is this value's, at the end of `main`.
#[derive(Clone, Default)]
pub struct Ranks {
    world: Option<Arc<dyn Collective>>,
}

impl Ranks {
    /// Starts MPI when this process is one of several ranks (`distributed`: whether the
    /// command runs distributed); refuses a world of several ranks for a command that does
    /// not, or for a build without MPI.
    pub fn start(command: &str, distributed: bool) -> Result<Ranks> {
        let Some((rank, ranks)) = radiosity_mpi::rank_from_env().filter(|&(_, k)| k > 1) else {
            return Ok(Ranks::default());
        };
        if !distributed {
            bail!(
                "`cargo xtask {command}` runs in one process, and this is rank {rank} of {ranks}: only solve and compare run distributed under mpirun"
            );
        }
        Ok(Ranks { world: Some(start_mpi(rank, ranks)?) })
    }

    /// The ranks this process is one of, when it is one of several.
    pub fn world(&self) -> Option<Arc<dyn Collective>> {
        self.world.clone()
    }

    /// Whether this process prints and writes: rank 0, or a single process.
    pub fn reports(&self) -> bool {
        self.world.as_ref().is_none_or(|w| w.rank() == 0)
    }

    /// The backend `arg` names: over several ranks, `hierarchical` is this rank's part of the
    /// operator split over them ([`BackendRegistry::for_ranks`]).
    pub fn backend(&self, arg: &str) -> Result<BackendSpec> {
        Ok(BackendRegistry::for_ranks(self.world.clone()).parse(arg)?)
    }
}

/// Initialises MPI as rank `rank` of `ranks`, silencing the ranks above 0.
#[cfg(feature = "mpi")]
fn start_mpi(rank: usize, ranks: usize) -> Result<Arc<dyn Collective>> {
    let world = radiosity_mpi::MpiWorld::init()?;
    anyhow::ensure!(
        (world.rank(), world.ranks()) == (rank, ranks),
        "MPI says this is rank {} of {}, the launcher's environment rank {rank} of {ranks}",
        world.rank(),
        world.ranks()
    );
    if rank != 0 {
        silence(rank)?;
    }
    Ok(Arc::new(world))
}

/// Refuses to run as a rank of several without MPI.
#[cfg(not(feature = "mpi"))]
fn start_mpi(rank: usize, ranks: usize) -> Result<Arc<dyn Collective>> {
    bail!(
        "this is rank {rank} of {ranks} under mpirun, but this xtask was built without MPI, so each rank would solve \
         alone: build it with --features mpi (cargo xtask-mpi)"
    )
}

/// Sends this rank's standard output and error to `/dev/null`, keeping the error stream for
/// a panic's message, prefixed with the rank.
#[cfg(feature = "mpi")]
fn silence(rank: usize) -> Result<()> {
    use std::io::Write;
    let stderr = std::fs::File::from(nix::unistd::dup(std::io::stderr())?);
    let null = std::fs::OpenOptions::new().write(true).open("/dev/null")?;
    nix::unistd::dup2_stdout(&null)?;
    nix::unistd::dup2_stderr(&null)?;
    let stderr = std::sync::Mutex::new(stderr);
    std::panic::set_hook(Box::new(move |info| {
        let mut out = stderr.lock().unwrap_or_else(|e| e.into_inner());
        let _ = writeln!(out, "rank {rank}: {info}");
    }));
    Ok(())
}

/// Whether `e`, from [`launch`], is rank 0 ending as a failed command ends (exit status 1),
/// after printing its error: nothing is left to say.
pub fn reported(e: &anyhow::Error) -> bool {
    matches!(e.downcast_ref(), Some(radiosity_mpi::LaunchError::RankEnded { rank: 0, ending, .. }) if ending == "exit status 1")
}

/// `--ranks K`: runs this very command as `K` ranks under `mpirun` and returns `true`, or
/// returns `false` when this process is already one of the ranks (then `K` must be their
/// number).
pub fn launch(ranks: u32) -> Result<bool> {
    if let Some((_, size)) = radiosity_mpi::rank_from_env() {
        if size != ranks as usize {
            bail!("--ranks {ranks}, but mpirun started {size} ranks: give one or the other");
        }
        return Ok(false);
    }
    if !cfg!(feature = "mpi") {
        bail!(
            "--ranks needs an xtask built with MPI: cargo xtask-mpi (cargo run --release -p xtask --features mpi --)"
        );
    }
    let program = std::env::current_exe()?;
    let args: Vec<_> = std::env::args_os().skip(1).collect();
    radiosity_mpi::launch(ranks as usize, &program, &args)?;
    Ok(true)
}
