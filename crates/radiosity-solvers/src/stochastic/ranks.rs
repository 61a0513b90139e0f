//! How the solvers that sample transport divide their work between the ranks of a problem
//! solved over several ([`crate::Problem::collective`]).
//!
//! **Rays shared** ([`Share`], stochastic Jacobi). Every rank advances every replicate, and
//! casts in each of its iterations the rays of its share of the blocks of patches (of lines,
//! for global lines): block `b` on rank `h(b) mod K` for a fixed hash `h`, the streams keyed
//! by the replicate and the patch, never by the rank, so the rays of all ranks are exactly
//! those one process casts. One sum over the ranks an iteration gives every rank the deposits
//! (`n k` values, summed exactly, [`super::exact_sum`]) and the world's rays, so every rank
//! holds the same state, one process's bits, whatever `K`: the state once, not once a rank,
//! and any number of replicates keeps any number of ranks busy.
//!
//! **Replicates dealt** ([`Deal`], random walks). Replicate `r` is advanced on rank `r mod K`
//! alone, with its own random streams (keyed by the replicate, never by the rank), so its
//! rays are exactly those it casts in one process. After every step each rank hands in the
//! state of its own replicates, zeros for the others', and one sum over the ranks gives every
//! rank every replicate ([`Deal::share`]): the sum of a value and zeros is the value, so
//! every rank holds the same bits, and those of one process, whatever `K`. The rays each rank
//! cast travel in the same sum, so every rank counts the world's
//! ([`crate::Problem::spent_elsewhere`]) and stops at the same step. With `R` replicates,
//! `K ≤ R` ranks share the rays; a rank beyond `R` casts none. A step sends the walks' `R n k`
//! sums.

use crate::run::cost::Unit;
use crate::run::problem::Problem;
use crate::stochastic::sequence::mix;
use radiosity_core::{Collective, Real};

/// Which blocks of rays this rank casts, and the sums that share what they found (module doc).
pub(crate) struct Share<'p> {
    collective: Option<&'p dyn Collective>,
}

impl<'p> Share<'p> {
    /// The share of `problem`'s ranks: every block on this rank in one process.
    pub(crate) fn of(problem: &'p Problem<'_>) -> Share<'p> {
        Share { collective: problem.collective() }
    }

    /// The ranks, when there are several.
    pub(crate) fn collective(&self) -> Option<&'p dyn Collective> {
        self.collective
    }

    /// Whether this rank casts the rays of block `b`: blocks are dealt by a hash of their
    /// index, so that a scene whose bright patches recur with a period (every other block)
    /// does not give them all to one rank.
    pub(crate) fn mine(&self, b: usize) -> bool {
        self.collective.is_none_or(|c| c.deals(mix(b as u64) as usize))
    }

    /// `values` summed over the ranks, in rank order; themselves in one process.
    pub(crate) fn sum(&self, values: &mut [Real]) {
        if let Some(c) = self.collective {
            c.sum(values);
        }
    }

    /// Every rank's `values`, in rank order; this rank's alone in one process.
    pub(crate) fn gathered(&self, values: &[Real]) -> Vec<Vec<Real>> {
        match self.collective {
            Some(c) => c.gather(values),
            None => vec![values.to_vec()],
        }
    }
}

/// Which replicates this rank advances, and the sum that shares them (module doc).
pub(crate) struct Deal<'p> {
    collective: Option<&'p dyn Collective>,
}

impl<'p> Deal<'p> {
    /// The deal of `problem`'s ranks: every replicate on this rank in one process.
    pub(crate) fn of(problem: &'p Problem<'_>) -> Deal<'p> {
        Deal { collective: problem.collective() }
    }

    /// Whether the replicates are dealt to several ranks.
    pub(crate) fn split(&self) -> bool {
        self.collective.is_some()
    }

    /// Whether this rank advances replicate `r`.
    pub(crate) fn mine(&self, r: usize) -> bool {
        self.collective.is_none_or(|c| c.deals(r))
    }

    /// Every replicate's `parts` (indexed by replicate) as its own rank left them, on every
    /// rank, and the `rays_here` this rank cast this step added to `problem`'s count of the
    /// other ranks' rays; nothing to do in one process. Returns the rays every rank cast.
    pub(crate) fn share(&self, problem: &Problem<'_>, parts: &mut [Vec<Real>], rays_here: u64) -> u64 {
        let Some(c) = self.collective else { return rays_here };
        let mut all: Vec<Real> = Vec::with_capacity(parts.iter().map(Vec::len).sum::<usize>() + 1);
        for (r, part) in parts.iter().enumerate() {
            if self.mine(r) {
                all.extend_from_slice(part);
            } else {
                all.extend(std::iter::repeat_n(0.0, part.len()));
            }
        }
        all.push(rays_here as Real);
        c.sum(&mut all);
        let mut at = 0;
        for part in parts.iter_mut() {
            let len = part.len();
            part.copy_from_slice(&all[at..at + len]);
            at += len;
        }
        let world = all[at] as u64;
        problem.spent_elsewhere(Unit::Rays, world.saturating_sub(rays_here));
        world
    }
}
