//! The operator's link lists in compressed sparse row form: for each node or patch, the other
//! ends of its links and their values, ordered by the other end, so that a product reads its
//! vector in order; each link is in the lists of both its ends.
//!
//! A far link is stored as its two nodes and its rays' tally, 8 bytes an end; its direction,
//! length and `g` are worked out again from the nodes' centres wherever it is used, to the
//! same bits. A near link or far pair is its other end and its `A_i F_ij` in `f32`
//! ([`Transfer`]), 8 bytes an end.

use radiosity_core::Real;
use rayon::prelude::*;

/// Links by the node or patch at either end: for each of `len` keys, the other end and the
/// link's value, ordered by the other end (so that a product reads its vector in order).
#[derive(Debug)]
pub(super) struct Adjacency<T> {
    pub(super) start: Vec<usize>,
    pub(super) other: Vec<u32>,
    pub(super) value: Vec<T>,
}

impl<T: Copy + Default + Send> Adjacency<T> {
    /// The lists of `links` `(a, b, value)`, each in `a`'s list and in `b`'s. A pair is linked
    /// once, so the order within a list is total.
    pub(super) fn new<L>(len: usize, links: &[L], ends: impl Fn(&L) -> (u32, u32, T)) -> Adjacency<T> {
        let mut start = vec![0usize; len + 1];
        for (a, b, _) in links.iter().map(&ends) {
            start[a as usize + 1] += 1;
            start[b as usize + 1] += 1;
        }
        for k in 0..len {
            start[k + 1] += start[k];
        }
        let mut next = start.clone();
        let (mut other, mut value) = (vec![0u32; start[len]], vec![T::default(); start[len]]);
        for (a, b, v) in links.iter().map(&ends) {
            for (p, q) in [(a, b), (b, a)] {
                (other[next[p as usize]], value[next[p as usize]]) = (q, v);
                next[p as usize] += 1;
            }
        }
        let (mut rest_other, mut rest_value) = (other.as_mut_slice(), value.as_mut_slice());
        let mut lists = Vec::with_capacity(len);
        for k in 0..len {
            let count = start[k + 1] - start[k];
            let (o, tail_o) = rest_other.split_at_mut(count);
            let (v, tail_v) = rest_value.split_at_mut(count);
            lists.push((o, v));
            (rest_other, rest_value) = (tail_o, tail_v);
        }
        lists.into_par_iter().for_each_init(Vec::new, |entries, (o, v)| {
            entries.clear();
            entries.extend(o.iter().copied().zip(v.iter().copied()));
            entries.sort_unstable_by_key(|e: &(u32, T)| e.0);
            for (k, &(q, x)) in entries.iter().enumerate() {
                (o[k], v[k]) = (q, x);
            }
        });
        Adjacency { start, other, value }
    }

    /// The list of `k`: the other ends and the values.
    pub(super) fn of(&self, k: usize) -> impl Iterator<Item = (&u32, &T)> {
        let at = self.start[k]..self.start[k + 1];
        self.other[at.clone()].iter().zip(&self.value[at])
    }

    /// The number of links in the list of `k`.
    pub(super) fn degree(&self, k: usize) -> usize {
        self.start[k + 1] - self.start[k]
    }

    /// Each link once: its ends, the lower first.
    pub(super) fn ends(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        (0..self.start.len() - 1).flat_map(move |k| {
            self.other[self.start[k]..self.start[k + 1]]
                .iter()
                .filter(move |&&o| o as usize > k)
                .map(move |&o| (k as u32, o))
        })
    }

    /// The bytes the links' entries hold: their other ends and values, not the offsets every
    /// key has.
    pub(super) fn entry_bytes(&self) -> usize {
        self.other.len() * (size_of::<u32>() + size_of::<T>())
    }

    /// The bytes the lists hold.
    pub(super) fn bytes(&self) -> usize {
        self.start.len() * size_of::<usize>() + self.other.len() * (size_of::<u32>() + size_of::<T>())
    }
}

/// A near link's or far pair's `A_i F_ij` as stored: `f32`, half an `f64`'s bytes. One
/// number serves both directions, so reciprocity stays exact; the rounding moves a product by
/// less than `1e-7` of its size (tested against the `f64` entries).
pub(crate) type Transfer = f32;

/// The link lists of an operator and its closure weights.
pub(super) struct Lists {
    pub(super) far: Adjacency<[u16; 2]>,
    pub(super) near: Adjacency<Transfer>,
    pub(super) pairs: Adjacency<Transfer>,
    pub(super) weights: Vec<Real>,
}
