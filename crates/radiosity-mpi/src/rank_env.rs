//! [`rank_from_env`]: whether this process is a rank started by an MPI launcher, read from the
//! environment the launcher sets, without initialising MPI.
//!
//! Open MPI sets `OMPI_COMM_WORLD_RANK` and `OMPI_COMM_WORLD_SIZE`; MPICH's Hydra launcher (and
//! others speaking PMI) sets `PMI_RANK` and `PMI_SIZE`.

/// This process's rank and the number of ranks, `(rank, ranks)`, when it was started by
/// `mpirun`/`mpiexec` (Open MPI or MPICH); `None` otherwise, or when the variables do not
/// describe a rank (not numbers, or a rank not below the size).
pub fn rank_from_env() -> Option<(usize, usize)> {
    let read = |name: &str| std::env::var(name).ok()?.trim().parse::<usize>().ok();
    [("OMPI_COMM_WORLD_RANK", "OMPI_COMM_WORLD_SIZE"), ("PMI_RANK", "PMI_SIZE")]
        .into_iter()
        .find_map(|(rank, size)| Some((read(rank)?, read(size)?)))
        .filter(|&(rank, ranks)| rank < ranks)
}
