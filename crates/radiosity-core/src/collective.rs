//! [`Collective`]: the seam between a computation split over ranks and whatever carries its
//! messages (MPI in `radiosity-mpi`, threads in [`InProcessRanks`]).
//!
//! A distributed computation here is SPMD: every rank runs the same program on the same
//! replicated data (the scene, the cluster tree, the solver's vectors) and holds its own share
//! of the expensive part (the hierarchical operator's links). The ranks meet in one operation,
//! a sum of vectors, which every rank enters in the same order with the same length.
//!
//! **Same bits everywhere.** A sum is taken in rank order, `((x₀ + x₁) + x₂) + …`, and every
//! rank receives the same bits. So the ranks' replicated state never drifts apart (a solver's
//! stop decision, taken on every rank, is the same decision), and a given number of ranks gives
//! the same numbers on every run, whatever the transport's own reduction algorithm would do.
//! Against one process the result differs only by the order of summation.
//!
//! **Decisions that read a clock** (a `time=` stop rule) differ between ranks, so they are
//! taken on rank 0 and shared ([`Collective::agree`]).

use crate::math::Real;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Instant;

/// What a rank has sent and waited for in collective sums.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Traffic {
    /// Collective sums entered.
    pub sums: u64,
    /// Values summed, over all the sums (each rank's vector length, added up).
    pub values: u64,
    /// Bytes this rank sent to other ranks (0 where the ranks share memory).
    pub bytes_sent: u64,
    /// Seconds spent in the sums, waiting for the other ranks included.
    pub seconds: f64,
}

/// Ranks that sum vectors together (module doc).
pub trait Collective: Send + Sync {
    /// This rank, in `0..ranks()`.
    fn rank(&self) -> usize;

    /// The number of ranks.
    fn ranks(&self) -> usize;

    /// Replaces `values` on every rank by the sum over the ranks of their `values`, taken in
    /// rank order, the same bits on every rank. Every rank calls it, in the same order, with
    /// the same length.
    fn sum(&self, values: &mut [Real]);

    /// What this rank has sent and waited for so far.
    fn traffic(&self) -> Traffic;

    /// Whether item `i` of a list dealt round-robin between the ranks (item `i` to rank
    /// `i mod K`) is this rank's: how the analysis's probes and a sampling solver's replicates
    /// are dealt.
    fn deals(&self, i: usize) -> bool {
        i % self.ranks() == self.rank()
    }

    /// Rank 0's `flag`, on every rank: for decisions that may differ between ranks, such as
    /// one that reads a clock.
    fn agree(&self, flag: bool) -> bool {
        let mut flags = [flag];
        self.agree_all(&mut flags);
        flags[0]
    }

    /// Rank 0's `flags`, on every rank, in one sum ([`Collective::agree`]).
    fn agree_all(&self, flags: &mut [bool]) {
        let mut v: Vec<Real> = flags.iter().map(|&f| if self.rank() == 0 && f { 1.0 } else { 0.0 }).collect();
        self.sum(&mut v);
        flags.iter_mut().zip(v).for_each(|(f, v)| *f = v > 0.0);
    }

    /// Every rank's `values` (the same length on each), in rank order, on every rank.
    fn gather(&self, values: &[Real]) -> Vec<Vec<Real>> {
        let (m, k) = (values.len(), self.ranks());
        let mut all = vec![0.0; m * k];
        all[self.rank() * m..(self.rank() + 1) * m].copy_from_slice(values);
        self.sum(&mut all);
        (0..k).map(|r| all[r * m..(r + 1) * m].to_vec()).collect()
    }
}

impl<C: Collective + ?Sized> Collective for Arc<C> {
    fn rank(&self) -> usize {
        (**self).rank()
    }

    fn ranks(&self) -> usize {
        (**self).ranks()
    }

    fn sum(&self, values: &mut [Real]) {
        (**self).sum(values)
    }

    fn traffic(&self) -> Traffic {
        (**self).traffic()
    }

    fn agree(&self, flag: bool) -> bool {
        (**self).agree(flag)
    }

    fn agree_all(&self, flags: &mut [bool]) {
        (**self).agree_all(flags)
    }

    fn gather(&self, values: &[Real]) -> Vec<Vec<Real>> {
        (**self).gather(values)
    }
}

/// `K` ranks as threads of one process: a distributed computation tried, and tested, without
/// MPI. Each rank's sum waits for the others; a rank that panics makes the others panic at
/// their next sum instead of waiting forever.
#[derive(Debug)]
pub struct InProcessRanks {
    rank: usize,
    shared: Arc<Meeting>,
    traffic: Mutex<Traffic>,
}

/// Where the ranks' threads meet: each rank's vector of the current sum, and a count of the
/// ranks that have arrived.
#[derive(Debug)]
struct Meeting {
    ranks: usize,
    state: Mutex<Round>,
    changed: Condvar,
}

#[derive(Debug, Default)]
struct Round {
    slots: Vec<Vec<Real>>,
    arrived: usize,
    generation: u64,
    /// The first rank that ended (returned or panicked), if one did.
    abandoned: Option<usize>,
}

impl InProcessRanks {
    /// Runs `f` on `ranks` threads, each with its rank's [`Collective`], and returns what each
    /// returned, in rank order. Panics (on every thread) when one of them panics. A rank ends
    /// when the last clone of its `Arc` is dropped: a sum another rank enters after that
    /// panics.
    pub fn run<T: Send>(ranks: usize, f: impl Fn(Arc<InProcessRanks>) -> T + Sync) -> Vec<T> {
        assert!(ranks >= 1, "a distributed computation needs at least one rank");
        let shared = Arc::new(Meeting {
            ranks,
            state: Mutex::new(Round { slots: vec![Vec::new(); ranks], ..Round::default() }),
            changed: Condvar::new(),
        });
        std::thread::scope(|scope| {
            let handles: Vec<_> = (0..ranks)
                .map(|rank| {
                    let me = InProcessRanks { rank, shared: shared.clone(), traffic: Mutex::new(Traffic::default()) };
                    let f = &f;
                    scope.spawn(move || f(Arc::new(me)))
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
        })
    }
}

impl InProcessRanks {
    /// Arrives at the current round and waits until every rank has: the last to arrive starts
    /// the next round.
    fn meet<'a>(&self, mut round: MutexGuard<'a, Round>) -> MutexGuard<'a, Round> {
        let meeting = &self.shared;
        round.arrived += 1;
        let generation = round.generation;
        if round.arrived == meeting.ranks {
            round.arrived = 0;
            round.generation += 1;
            meeting.changed.notify_all();
        }
        while round.generation == generation {
            round = meeting.changed.wait(round).unwrap_or_else(|e| e.into_inner());
            if round.generation == generation {
                self.check_others(&round);
            }
        }
        round
    }

    /// Panics when another rank has ended: the round can never be complete.
    fn check_others(&self, round: &Round) {
        if let Some(rank) = round.abandoned {
            panic!("rank {rank} ended before a collective sum that rank {} waits in", self.rank);
        }
    }
}

impl Drop for InProcessRanks {
    /// A rank that ends, by returning or by panicking, enters no further sum: a rank waiting
    /// in one, or entering one later, would wait forever, so it panics instead.
    fn drop(&mut self) {
        let mut round = self.shared.state.lock().unwrap_or_else(|e| e.into_inner());
        round.abandoned.get_or_insert(self.rank);
        self.shared.changed.notify_all();
    }
}

impl Collective for InProcessRanks {
    fn rank(&self) -> usize {
        self.rank
    }

    fn ranks(&self) -> usize {
        self.shared.ranks
    }

    fn sum(&self, values: &mut [Real]) {
        let start = Instant::now();
        // Phase one: every rank leaves its vector, and waits for the others'.
        let mut round = self.shared.state.lock().unwrap_or_else(|e| e.into_inner());
        self.check_others(&round);
        round.slots[self.rank] = values.to_vec();
        let round = self.meet(round);
        // Every rank sums the slots in rank order: the same bits on each.
        values.copy_from_slice(&round.slots[0]);
        for slot in &round.slots[1..] {
            values.iter_mut().zip(slot).for_each(|(v, s)| *v += s);
        }
        // Phase two: no rank leaves a vector for the next sum before every rank has read this one.
        drop(self.meet(round));
        let mut traffic = self.traffic.lock().unwrap_or_else(|e| e.into_inner());
        traffic.sums += 1;
        traffic.values += values.len() as u64;
        traffic.seconds += start.elapsed().as_secs_f64();
    }

    fn traffic(&self) -> Traffic {
        *self.traffic.lock().unwrap_or_else(|e| e.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_are_taken_in_rank_order_and_agree_on_every_rank() {
        // 1e16 + 1 + (−1e16) is 0 or 1 depending on the order: rank order gives
        // (1e16 + 1) − 1e16 = 0 in f64 (1e16 + 1 rounds to 1e16).
        let parts = [1e16, 1.0, -1e16];
        let sums = InProcessRanks::run(3, |r| {
            let mut v = [parts[r.rank()], r.rank() as Real];
            r.sum(&mut v);
            v
        });
        for v in &sums {
            assert_eq!(v, &[0.0, 3.0]);
        }
        let ordered = (parts[0] + parts[1]) + parts[2];
        assert_eq!(sums[0][0], ordered);
    }

    #[test]
    fn gather_and_agree_see_every_rank() {
        let seen = InProcessRanks::run(3, |r| {
            let all = r.gather(&[r.rank() as Real, 10.0 * r.rank() as Real]);
            let agreed = r.agree(r.rank() == 0);
            let disagreed = r.agree(r.rank() != 0);
            (all, agreed, disagreed, r.traffic().sums)
        });
        for (all, agreed, disagreed, sums) in seen {
            assert_eq!(all, vec![vec![0.0, 0.0], vec![1.0, 10.0], vec![2.0, 20.0]]);
            assert!(agreed && !disagreed);
            assert_eq!(sums, 3);
        }
    }

    #[test]
    fn a_rank_that_panics_stops_the_others_instead_of_hanging_them() {
        let outcome = std::panic::catch_unwind(|| {
            InProcessRanks::run(3, |r| {
                if r.rank() == 1 {
                    panic!("rank 1 fails");
                }
                let mut v = [1.0];
                r.sum(&mut v);
                r.sum(&mut v);
            })
        });
        assert!(outcome.is_err());
    }
}
