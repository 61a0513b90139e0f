//! MPI ranks for the radiosity solvers: [`launch`] starts a program as `K` MPI ranks on this
//! machine, and, with the crate feature `mpi`, `MpiWorld` is a
//! [`radiosity_core::Collective`] whose ranks are MPI processes.
//!
//! A distributed run is SPMD (the module doc of `radiosity_core::collective`): every rank runs
//! the same program, and the ranks meet only in collective sums.
//!
//! **Installing MPI.** Without the feature `mpi` the crate needs no MPI and holds only the
//! launcher and [`rank_from_env`]. The feature builds rsmpi, the Rust binding, against the
//! system's MPI: its build script finds MPI through `mpicc` (or pkg-config) and generates the
//! bindings with bindgen, which needs libclang. On Debian or Ubuntu:
//!
//! ```text
//! apt-get install libopenmpi-dev openmpi-bin libclang-dev
//! cargo test -p radiosity-mpi --features mpi
//! ```
//!
//! Only Open MPI is tested (CI installs it); MPICH's launcher and its rank variables are
//! recognised, but no test runs under MPICH. Running as root, Open MPI's `mpirun` refuses to start
//! without `--allow-run-as-root`; [`launch`] adds it, and `--oversubscribe` so that more ranks
//! than cores may run (the ranks of a test on a small machine).
//!
//! **Determinism.** [`MpiWorld::sum`](radiosity_core::Collective::sum) sums in rank order,
//! `((x₀ + x₁) + x₂) + …`, element by element, and every rank receives the same bits; a given
//! number of ranks gives the same bits on every run. `MPI_Allreduce` promises neither: the standard
//! only advises implementors that a reduction give the same result whenever it is applied to
//! the same arguments in the same order (MPI 3.1, §5.9.1), and the order of summation is the
//! library's choice, which may depend on the message sizes and the machine. So the sum is built
//! from `MPI_Alltoallv` and `MPI_Allgatherv` instead (module `world`, with the feature).
//!
//! References: rsmpi, <https://docs.rs/mpi/0.8> and <https://github.com/rsmpi/rsmpi>; the MPI
//! standard, version 3.1 (the version rsmpi's documentation cites),
//! <https://www.mpi-forum.org/docs/> (§5.7 gather-to-all, §5.8 all-to-all, §5.9.1 reduction
//! order, §12.4.3 threading levels); Open MPI's `mpirun(1)` manual.

mod failure;
mod launch;
mod launcher;
pub mod projection;
mod rank_env;
#[cfg(feature = "mpi")]
pub mod world;

pub use launch::{LaunchError, launch};
pub use rank_env::rank_from_env;
#[cfg(feature = "mpi")]
pub use world::{MpiWorld, MpiWorldError};
