//! [`MpiWorld`]: the MPI processes of `MPI_COMM_WORLD` as a [`Collective`], with sums taken in
//! rank order (crate doc, "Determinism").
//!
//! **The sum.** A vector of `N` values is cut into `K` blocks, block `b` being
//! `b·N/K .. (b+1)·N/K`. `MPI_Alltoallv` hands rank `b` every rank's copy of block `b`; rank `b`
//! adds them in rank order, `((x₀ + x₁) + x₂) + …`; `MPI_Allgatherv` hands every rank the summed
//! blocks. Each rank sends `N` values less its own block, then its block to the `K − 1` others:
//! about `2N` values, as a ring allreduce would, and `2N(K − 1)` over all ranks. The bits depend
//! on the ranks' vectors alone, never on the library's reduction algorithm.
//!
//! **Threads.** [`Collective`] is `Send + Sync`. rsmpi's communicators are not (Open MPI's
//! communicator handle is a pointer), but its [`Universe`] is: an `MpiWorld` keeps the
//! `Universe` and makes the world communicator afresh in each sum, so no `unsafe` is needed. MPI
//! is initialised with at least [`Threading::Serialized`] (any thread may call MPI, one at a
//! time) and each sum holds a lock for its MPI calls, so sums from different threads are
//! serialised. Every rank must still enter its sums in the same order.
//!
//! **Ending.** Dropping the `MpiWorld` finalises MPI; the MPI standard asks that this happen on
//! the thread that initialised it (MPI 3.1, §12.4.3), so drop it where it was made. MPI cannot
//! be initialised again in the same process.

use mpi::Count;
use mpi::Threading;
use mpi::datatype::{Partition, PartitionMut};
use mpi::environment::Universe;
use mpi::topology::SimpleCommunicator;
use mpi::traits::{Communicator, CommunicatorCollectives};
use radiosity_core::collective::{Collective, Traffic};
use radiosity_core::math::Real;
use std::sync::Mutex;
use std::time::Instant;

/// The most values moved in one pair of MPI calls: longer vectors are summed in pieces, which
/// keeps every count and offset within MPI's `int`.
const MAX_PIECE: usize = 1 << 26;

/// Why MPI could not be started.
#[derive(Debug, thiserror::Error)]
pub enum MpiWorldError {
    /// MPI was initialised (or initialised and finalised) before in this process.
    #[error("MPI was already initialised in this process, and can be initialised only once")]
    AlreadyInitialised,
    /// The MPI library cannot let more than one thread call it.
    #[error("the MPI library grants thread level {granted:?}, and radiosity's ranks need Serialized")]
    ThreadingTooLow {
        /// The level the library granted.
        granted: Threading,
    },
}

/// This process's rank of `MPI_COMM_WORLD`, summing in rank order (module doc).
pub struct MpiWorld {
    universe: Universe,
    rank: usize,
    ranks: usize,
    /// Held through each sum's MPI calls, so that they never overlap.
    traffic: Mutex<Traffic>,
}

impl MpiWorld {
    /// Initialises MPI (once per process) for this rank; MPI is finalised when the `MpiWorld`
    /// is dropped. A program not started by an MPI launcher is one rank of one.
    pub fn init() -> Result<MpiWorld, MpiWorldError> {
        let (universe, granted) =
            mpi::initialize_with_threading(Threading::Serialized).ok_or(MpiWorldError::AlreadyInitialised)?;
        if granted < Threading::Serialized {
            return Err(MpiWorldError::ThreadingTooLow { granted });
        }
        let world = universe.world();
        // MPI ranks and sizes are non-negative `int`s.
        let (rank, ranks) = (world.rank().unsigned_abs() as usize, world.size().unsigned_abs() as usize);
        Ok(MpiWorld { universe, rank, ranks, traffic: Mutex::new(Traffic::default()) })
    }

    /// Sums one piece of at most [`MAX_PIECE`] values over the ranks (module doc); returns the
    /// values this rank sent to the others.
    fn sum_piece(&self, world: &SimpleCommunicator, piece: &mut [Real]) -> usize {
        let (n, k) = (piece.len(), self.ranks);
        let starts: Vec<usize> = (0..=k).map(|b| b * n / k).collect();
        let to_count = |v: usize| Count::try_from(v).unwrap_or(Count::MAX);
        let counts: Vec<Count> = starts.windows(2).map(|w| to_count(w[1] - w[0])).collect();
        let displs: Vec<Count> = starts[..k].iter().map(|&s| to_count(s)).collect();
        let mine = starts[self.rank + 1] - starts[self.rank];
        let mut copies = vec![0.0; mine * k];
        let (copy_counts, copy_displs): (Vec<Count>, Vec<Count>) =
            (0..k).map(|r| (to_count(mine), to_count(r * mine))).unzip();
        world.all_to_all_varcount_into(
            &Partition::new(&*piece, &counts[..], &displs[..]),
            &mut PartitionMut::new(&mut copies[..], copy_counts, copy_displs),
        );
        let mut block = copies[..mine].to_vec();
        for r in 1..k {
            let copy = &copies[r * mine..(r + 1) * mine];
            block.iter_mut().zip(copy).for_each(|(sum, x)| *sum += x);
        }
        world.all_gather_varcount_into(&block[..], &mut PartitionMut::new(piece, &counts[..], &displs[..]));
        (n - mine) + mine * (k - 1)
    }
}

impl std::fmt::Debug for MpiWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MpiWorld").field("rank", &self.rank).field("ranks", &self.ranks).finish_non_exhaustive()
    }
}

impl Collective for MpiWorld {
    fn rank(&self) -> usize {
        self.rank
    }

    fn ranks(&self) -> usize {
        self.ranks
    }

    fn sum(&self, values: &mut [Real]) {
        let mut traffic = self.traffic.lock().unwrap_or_else(|e| e.into_inner());
        let start = Instant::now();
        let mut sent = 0;
        if self.ranks > 1 {
            let world = self.universe.world();
            for piece in values.chunks_mut(MAX_PIECE) {
                sent += self.sum_piece(&world, piece);
            }
        }
        traffic.sums += 1;
        traffic.values += values.len() as u64;
        traffic.bytes_sent += (sent * size_of::<Real>()) as u64;
        traffic.seconds += start.elapsed().as_secs_f64();
    }

    fn traffic(&self) -> Traffic {
        *self.traffic.lock().unwrap_or_else(|e| e.into_inner())
    }
}
