//! The operator's link lists in compressed sparse row form: for each node or patch, the other
//! ends of its links and their values, ordered by the other end, so that a product reads its
//! vector in order.
//!
//! A near link or far pair ([`Adjacency`]) is held once, with its `A_i F_ij` in `f32`
//! ([`Transfer`]), in the list of its lower end; its higher end's list holds only the lower
//! end, and finds the value by a binary search in the lower end's list (a few dozen entries).
//! So it costs 12 bytes, not the 16 of a link in both its ends' lists with its value twice,
//! and both ends read the same value, which keeps reciprocity exact.
//!
//! A far link ([`FarLists`]) is in both its nodes' lists: a product works out its geometry
//! from both ends, and a search for it at one end would cost more than that arithmetic. It is
//! the other node and its rays' tally, coded in a byte (two when the operator has more than
//! 256 distinct tallies): 10 bytes a link. Its direction, length and `g` are worked out again
//! from the nodes' centres wherever it is used, to the same bits.
//!
//! Lists are built on every thread from the refinement's links as they were gathered, in
//! parts ([`Gathered`]): each end's place claimed by an atomic count, each list then sorted by
//! itself, so the lists are the same whatever the number of threads.

use radiosity_core::Real;
use rayon::prelude::*;
use std::collections::BTreeSet;
use std::sync::atomic::{AtomicU8, AtomicU16, AtomicU32, AtomicUsize, Ordering};

/// Links by the node or patch at either end: for each of `len` keys, the other ends and the
/// links' values, ordered by the other end (so that a product reads its vector in order).
#[derive(Debug)]
pub(super) struct Adjacency {
    /// Where each key's list of higher ends starts in `other` and `value` (`len + 1`).
    pub(super) start: Vec<usize>,
    /// Each link once, in its lower end's list: the higher end,
    pub(super) other: Vec<u32>,
    /// and the value.
    pub(super) value: Vec<Transfer>,
    /// Where each key's list of lower ends starts in `lower` (`len + 1`).
    lower_start: Vec<usize>,
    /// Each link again, in its higher end's list: the lower end alone.
    lower: Vec<u32>,
}

impl Adjacency {
    /// The lists of `links` `(a, b, value)`, each in `a`'s list and in `b`'s. A pair is linked
    /// once, so the order within a list is total and the lists are the same whatever the
    /// order of `links` and the number of threads.
    pub(super) fn new<L: Send + Sync>(
        len: usize,
        links: Gathered<L>,
        ends: impl Fn(&L) -> (u32, u32, Transfer) + Sync,
    ) -> Adjacency {
        let (start, other, value) = scattered::<_, AtomicU32>(len, links, false, |l| {
            let (a, b, v) = ends(l);
            (a, b, v.to_bits())
        });
        Adjacency::from_higher(start, other, value.into_par_iter().map(Transfer::from_bits).collect())
    }

    /// The lists whose higher ends and values are `other` and `value`, `start` giving where
    /// each key's list starts, each list ordered and above its key (as
    /// [`Adjacency::is_ordered`] checks); the lower ends' lists are worked out from them.
    pub(super) fn from_higher(start: Vec<usize>, other: Vec<u32>, value: Vec<Transfer>) -> Adjacency {
        let len = start.len() - 1;
        let counts: Vec<AtomicU32> = (0..len).into_par_iter().map(|_| AtomicU32::new(0)).collect();
        other.par_iter().for_each(|&o| {
            counts[o as usize].fetch_add(1, Ordering::Relaxed);
        });
        let lower_start = offsets(counts);
        let next: Vec<AtomicUsize> = lower_start[..len].par_iter().map(|&s| AtomicUsize::new(s)).collect();
        let slots: Vec<AtomicU32> = (0..other.len()).into_par_iter().map(|_| AtomicU32::new(0)).collect();
        start.par_windows(2).enumerate().for_each(|(k, at)| {
            for &o in &other[at[0]..at[1]] {
                let slot = next[o as usize].fetch_add(1, Ordering::Relaxed);
                slots[slot].store(k as u32, Ordering::Relaxed);
            }
        });
        let mut lower: Vec<u32> = slots.into_iter().map(AtomicU32::into_inner).collect();
        // The slots were claimed in any order: each list sorted by itself.
        lists_of(&lower_start, &mut lower).into_par_iter().for_each(|list| list.sort_unstable());
        Adjacency { start, other, value, lower_start, lower }
    }

    /// The value of the link between `lo` and `hi > lo`, from `lo`'s list.
    fn between(&self, lo: u32, hi: u32) -> Transfer {
        let at = self.start[lo as usize]..self.start[lo as usize + 1];
        let place = self.other[at.clone()].partition_point(|&o| o < hi);
        debug_assert_eq!(self.other[at.start + place], hi);
        self.value[at.start + place]
    }

    /// The list of `k`: the other ends, in increasing order, and the values.
    pub(super) fn of(&self, k: usize) -> impl Iterator<Item = (u32, Transfer)> + '_ {
        let lower = &self.lower[self.lower_start[k]..self.lower_start[k + 1]];
        let higher = self.start[k]..self.start[k + 1];
        (lower.iter().map(move |&o| (o, self.between(o, k as u32))))
            .chain(self.other[higher.clone()].iter().copied().zip(self.value[higher].iter().copied()))
    }

    /// The number of links in the list of `k`.
    pub(super) fn degree(&self, k: usize) -> usize {
        self.start[k + 1] - self.start[k] + self.lower_start[k + 1] - self.lower_start[k]
    }

    /// Each link once: its ends, the lower first.
    pub(super) fn ends(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.start
            .windows(2)
            .enumerate()
            .flat_map(move |(k, at)| self.other[at[0]..at[1]].iter().map(move |&o| (k as u32, o)))
    }

    /// The number of links.
    pub(super) fn len(&self) -> usize {
        self.other.len()
    }

    /// Whether `start`, over `keys` keys and `entries` links, runs from 0 to `entries` without
    /// decreasing, and each key's higher ends, `other`, are above it, below `keys` and
    /// increasing: lists that [`Adjacency::from_higher`] takes.
    pub(super) fn is_ordered(keys: usize, entries: usize, start: &[usize], other: &[u32]) -> bool {
        start.len() == keys + 1
            && start.first() == Some(&0)
            && start.last() == Some(&entries)
            && other.len() == entries
            && start.windows(2).all(|w| w[0] <= w[1])
            && start.par_windows(2).enumerate().all(|(k, at)| {
                let list = &other[at[0]..at[1]];
                list.first().is_none_or(|&o| o as usize > k)
                    && list.last().is_none_or(|&o| (o as usize) < keys)
                    && list.windows(2).all(|w| w[0] < w[1])
            })
    }

    /// The bytes the links' entries hold: each link's two ends and its value, not the offsets
    /// every key has.
    pub(super) fn entry_bytes(&self) -> usize {
        self.other.len() * (size_of::<u32>() + size_of::<Transfer>()) + self.lower.len() * size_of::<u32>()
    }

    /// The bytes the lists hold.
    pub(super) fn bytes(&self) -> usize {
        (self.start.len() + self.lower_start.len()) * size_of::<usize>() + self.entry_bytes()
    }
}

/// Far links by node, each in the lists of both its nodes: the other node and the code of the
/// link's rays' tally (`[clear, count]`) in `tallies` (module doc).
#[derive(Debug)]
pub(super) struct FarLists {
    /// Where each node's list starts (`len + 1`).
    start: Vec<usize>,
    /// The other nodes.
    other: Vec<u32>,
    /// The links' tallies, as places in `tallies`.
    codes: Codes,
    /// The distinct tallies, in increasing order.
    tallies: Vec<[u16; 2]>,
}

/// Places in a table of at most 256 entries, or of more.
#[derive(Debug)]
enum Codes {
    Narrow(Vec<u8>),
    Wide(Vec<u16>),
}

impl Codes {
    fn at(&self, e: usize) -> usize {
        match self {
            Codes::Narrow(c) => c[e] as usize,
            Codes::Wide(c) => c[e] as usize,
        }
    }

    fn bytes(&self) -> usize {
        match self {
            Codes::Narrow(c) => c.len(),
            Codes::Wide(c) => 2 * c.len(),
        }
    }
}

impl FarLists {
    /// The lists of `links` `(a, b, [clear, count])` over `len` nodes, each link in `a`'s list
    /// and in `b`'s. A pair is linked once, so the order within a list is total and the lists
    /// are the same whatever the order of `links` and the number of threads.
    pub(super) fn new<L: Send + Sync>(
        len: usize,
        links: Gathered<L>,
        ends: impl Fn(&L) -> (u32, u32, [u16; 2]) + Sync,
    ) -> FarLists {
        // Neighbouring links mostly share a tally: the set is searched only when it changes.
        let tallies: Vec<[u16; 2]> = (links.0.par_iter())
            .map(|part| {
                let (mut set, mut last) = (BTreeSet::new(), None);
                for l in part {
                    let t = ends(l).2;
                    if last != Some(t) {
                        set.insert(t);
                        last = Some(t);
                    }
                }
                set
            })
            .reduce(BTreeSet::new, |mut a, mut b| {
                a.append(&mut b);
                a
            })
            .into_iter()
            .collect();
        // A tally is `[c, c]` for c up to `rays`, or `[c, probe]`, each with or without the
        // zeroth-order bit: at most 2 · (4096 + 1024) of them.
        let code = |t: [u16; 2]| tallies.binary_search(&t).expect("every tally is in the table");
        let (start, other, codes) = if tallies.len() <= 256 {
            let (start, other, codes) = scattered::<_, AtomicU8>(len, links, true, |l| {
                let (a, b, t) = ends(l);
                (a, b, code(t) as u8)
            });
            (start, other, Codes::Narrow(codes))
        } else {
            let (start, other, codes) = scattered::<_, AtomicU16>(len, links, true, |l| {
                let (a, b, t) = ends(l);
                (a, b, u16::try_from(code(t)).expect("at most 65,536 distinct tallies"))
            });
            (start, other, Codes::Wide(codes))
        };
        FarLists { start, other, codes, tallies }
    }

    /// The list of node `k`: the other nodes, in increasing order, and the links' tallies.
    pub(super) fn of(&self, k: usize) -> impl Iterator<Item = (u32, [u16; 2])> + '_ {
        (self.start[k]..self.start[k + 1]).map(move |e| (self.other[e], self.tallies[self.codes.at(e)]))
    }

    /// The number of links in the list of `k`.
    pub(super) fn degree(&self, k: usize) -> usize {
        self.start[k + 1] - self.start[k]
    }

    /// Each link once: its ends, the lower first, and its tally, in increasing order of the
    /// ends.
    pub(super) fn links(&self) -> impl Iterator<Item = (u32, u32, [u16; 2])> + '_ {
        (0..self.start.len() - 1)
            .flat_map(move |k| self.of(k).filter(move |&(o, _)| o as usize > k).map(move |(o, t)| (k as u32, o, t)))
    }

    /// Each link once: its ends, the lower first.
    pub(super) fn ends(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.links().map(|(a, b, _)| (a, b))
    }

    /// The number of links.
    pub(super) fn len(&self) -> usize {
        self.other.len() / 2
    }

    /// The bytes the links' entries hold (with the table of tallies), not the offsets every
    /// node has.
    pub(super) fn entry_bytes(&self) -> usize {
        self.other.len() * size_of::<u32>() + self.codes.bytes() + self.tallies.len() * size_of::<[u16; 2]>()
    }

    /// The bytes the lists hold.
    pub(super) fn bytes(&self) -> usize {
        self.start.len() * size_of::<usize>() + self.entry_bytes()
    }
}

/// Lists by key of the links' other ends and payloads, `ends` giving a link's ends and
/// payload: each link in its lower end's list, and with `mirrored` in its higher end's too.
/// Each entry's slot is claimed by an atomic count, on every thread, and each list is then
/// sorted by its other ends: the same lists whatever the order of `links` and the number of
/// threads (a pair is linked once). Returns where each key's list starts, the other ends and
/// the payloads.
///
/// The lists' pages are zero until written, so the system gives them as they fill, and each
/// part of `links` is freed once its links are placed: where the allocator hands freed parts
/// back, the build holds not much more than the larger of the two, not both.
fn scattered<L: Send + Sync, S: Slot>(
    len: usize,
    links: Gathered<L>,
    mirrored: bool,
    ends: impl Fn(&L) -> (u32, u32, S::Value) + Sync,
) -> (Vec<usize>, Vec<u32>, Vec<S::Value>) {
    let each = |l: &L, f: &mut dyn FnMut(u32, u32, S::Value)| {
        let (a, b, x) = ends(l);
        if mirrored {
            f(a, b, x);
            f(b, a, x);
        } else {
            f(a.min(b), a.max(b), x);
        }
    };
    let counts: Vec<AtomicU32> = bytemuck::zeroed_vec(len);
    links.par_iter().for_each(|l| {
        each(l, &mut |key, _, _| {
            counts[key as usize].fetch_add(1, Ordering::Relaxed);
        })
    });
    let start = offsets(counts);
    let next: Vec<AtomicUsize> = start[..len].par_iter().map(|&s| AtomicUsize::new(s)).collect();
    let entries = start[len];
    let other: Vec<AtomicU32> = bytemuck::zeroed_vec(entries);
    let payload: Vec<S> = bytemuck::zeroed_vec(entries);
    links.0.into_par_iter().for_each(|part| {
        for l in &part {
            each(l, &mut |key, o, x| {
                let slot = next[key as usize].fetch_add(1, Ordering::Relaxed);
                other[slot].store(o, Ordering::Relaxed);
                payload[slot].put(x);
            })
        }
    });
    drop(next);
    let mut other: Vec<u32> = other.into_iter().map(AtomicU32::into_inner).collect();
    let mut payload: Vec<S::Value> = payload.into_iter().map(S::value).collect();
    // The slots were claimed in any order: each list sorted by itself.
    let lists = lists_of(&start, &mut other).into_iter().zip(lists_of(&start, &mut payload));
    lists.collect::<Vec<_>>().into_par_iter().for_each_init(Vec::new, |entries, (o, x)| {
        entries.clear();
        entries.extend(o.iter().copied().zip(x.iter().copied()));
        entries.sort_unstable_by_key(|e: &(u32, S::Value)| e.0);
        for (k, &(q, y)) in entries.iter().enumerate() {
            (o[k], x[k]) = (q, y);
        }
    });
    (start, other, payload)
}

/// An atomic slot of a list's payload, as wide as its value, so that the lists' build holds
/// no more than the lists.
trait Slot: bytemuck::Zeroable + Send + Sync {
    type Value: Copy + Send + Sync;
    fn put(&self, value: Self::Value);
    fn value(self) -> Self::Value;
}

macro_rules! slot {
    ($atomic:ty, $value:ty) => {
        impl Slot for $atomic {
            type Value = $value;
            fn put(&self, value: $value) {
                self.store(value, Ordering::Relaxed);
            }
            fn value(self) -> $value {
                self.into_inner()
            }
        }
    };
}
slot!(AtomicU8, u8);
slot!(AtomicU16, u16);
slot!(AtomicU32, u32);

/// `all` cut into each key's list, `start` giving where each starts.
fn lists_of<'a, T>(start: &[usize], all: &'a mut [T]) -> Vec<&'a mut [T]> {
    let mut rest = all;
    let mut lists = Vec::with_capacity(start.len().saturating_sub(1));
    for at in start.windows(2) {
        let (list, tail) = rest.split_at_mut(at[1] - at[0]);
        lists.push(list);
        rest = tail;
    }
    lists
}

/// Links gathered by the refinement's tasks, in parts of [`PART`] links (the last part may
/// hold fewer): a task's full parts are joined to another's without a copy and read in place
/// by the lists built from them, so that the build never holds a kind of link twice, and a
/// part's spare capacity is at most its own size.
#[derive(Clone, Debug)]
pub(crate) struct Gathered<T>(Vec<Vec<T>>);

/// The links of a full part of [`Gathered`].
const PART: usize = 1 << 16;

impl<T> Default for Gathered<T> {
    fn default() -> Gathered<T> {
        Gathered(Vec::new())
    }
}

impl<T> From<Vec<T>> for Gathered<T> {
    fn from(links: Vec<T>) -> Gathered<T> {
        Gathered(vec![links])
    }
}

impl<T> Gathered<T> {
    pub fn push(&mut self, link: T) {
        match self.0.last_mut() {
            Some(last) if last.len() < PART => last.push(link),
            _ => self.0.push(vec![link]),
        }
    }

    /// The last part, taken out when it is not full.
    fn partial(&mut self) -> Option<Vec<T>> {
        if self.0.last().is_some_and(|last| last.len() < PART) { self.0.pop() } else { None }
    }

    /// Moves `other`'s full parts after these without copying them, then the links of both
    /// last parts, when not full.
    pub fn append(&mut self, other: &mut Gathered<T>) {
        let (mine, theirs) = (self.partial(), other.partial());
        self.0.append(&mut other.0);
        for part in [mine, theirs].into_iter().flatten() {
            for link in part {
                self.push(link);
            }
        }
    }

    /// Puts `front`'s links before these.
    pub fn prepend(&mut self, mut front: Gathered<T>) {
        front.0.append(&mut self.0);
        self.0 = front.0;
    }

    pub fn len(&self) -> usize {
        self.0.iter().map(Vec::len).sum()
    }

    pub fn iter(&self) -> impl Iterator<Item = &T> {
        self.0.iter().flatten()
    }

    #[cfg(test)]
    pub fn is_empty(&self) -> bool {
        self.0.iter().all(Vec::is_empty)
    }
}

impl<T: Sync> Gathered<T> {
    /// The links, on rayon's threads.
    pub fn par_iter(&self) -> impl ParallelIterator<Item = &T> {
        self.0.par_iter().flat_map_iter(|part| part.iter())
    }
}

/// Where each key's list starts, from the lists' lengths: `counts.len() + 1` offsets.
fn offsets(counts: Vec<AtomicU32>) -> Vec<usize> {
    let mut start = Vec::with_capacity(counts.len() + 1);
    start.push(0);
    let mut total = 0;
    for c in counts {
        total += c.into_inner() as usize;
        start.push(total);
    }
    start
}

/// A near link's or far pair's `A_i F_ij` as stored: `f32`, half an `f64`'s bytes. One
/// number serves both directions, so reciprocity stays exact; the rounding moves a product by
/// less than `1e-7` of its size (tested against the `f64` entries).
pub(crate) type Transfer = f32;

/// The link lists of an operator and its closure weights.
pub(super) struct Lists {
    pub(super) far: FarLists,
    pub(super) near: Adjacency,
    pub(super) pairs: Adjacency,
    pub(super) weights: Vec<Real>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Links `(a, b, value)` between distinct keys below `len`, each pair once, in a scrambled
    /// order with either end first.
    fn links(len: u32) -> Vec<(u32, u32, f32)> {
        let mut links = Vec::new();
        for a in 0..len {
            for b in a + 1..len {
                if (a * 31 + b * 17) % 7 < 3 {
                    let (x, y) = if (a + b) % 2 == 0 { (a, b) } else { (b, a) };
                    links.push((x, y, (a * 1000 + b) as f32));
                }
            }
        }
        links.sort_by_key(|&(a, b, _)| (a * 7919 + b * 104_729) % 65_521);
        links
    }

    #[test]
    fn each_list_holds_every_link_of_its_key_in_order_of_the_other_end_whatever_the_input_order() {
        let len = 60;
        let mut scrambled = links(len);
        let adjacency = Adjacency::new(len as usize, scrambled.clone().into(), |&l| l);
        for k in 0..len {
            let mut expected: Vec<(u32, f32)> = scrambled
                .iter()
                .filter_map(|&(a, b, v)| (a == k).then_some((b, v)).or((b == k).then_some((a, v))))
                .collect();
            expected.sort_by_key(|e| e.0);
            let listed: Vec<(u32, f32)> = adjacency.of(k as usize).collect();
            assert_eq!(listed, expected, "key {k}");
            assert_eq!(adjacency.degree(k as usize), expected.len());
        }
        assert_eq!(adjacency.len(), scrambled.len());
        assert_eq!(adjacency.ends().count(), scrambled.len());
        // The same lists from the links in another order, gathered in two parts.
        scrambled.reverse();
        let tail = scrambled.split_off(scrambled.len() / 3);
        let mut parts = Gathered::from(scrambled);
        parts.append(&mut Gathered::from(tail));
        let scrambled_len = parts.len();
        let again = Adjacency::new(len as usize, parts, |&l| l);
        assert_eq!(
            (again.start, again.other, again.lower_start, again.lower),
            (adjacency.start.clone(), adjacency.other.clone(), adjacency.lower_start.clone(), adjacency.lower.clone())
        );
        assert_eq!(again.value, adjacency.value);
        // Each link is held once with its value: 12 bytes, not 16.
        assert_eq!(adjacency.entry_bytes(), 12 * scrambled_len);
    }

    #[test]
    fn lists_with_a_lower_end_a_repeat_or_an_end_out_of_range_are_refused() {
        let adjacency = Adjacency::new(5, vec![(0, 3, 1.0), (1, 2, 2.0), (4, 1, 3.0)].into(), |&l| l);
        let (start, other) = (adjacency.start.clone(), adjacency.other.clone());
        assert!(Adjacency::is_ordered(5, 3, &start, &other));
        assert!(!Adjacency::is_ordered(4, 3, &start[..4], &other), "an end out of range");
        // Key 1's list is [2, 4]: a lower end, a repeat, an end beyond the keys.
        for bad in [[3, 0, 4], [3, 2, 2], [3, 2, 5]] {
            assert!(!Adjacency::is_ordered(5, 3, &start, &bad), "{bad:?}");
        }
    }

    #[test]
    fn far_lists_hold_every_link_at_both_ends_with_its_tally_in_a_byte_or_two() {
        let len = 60;
        for distinct in [3, 1000] {
            // Tallies `[c, c]` for c below `distinct`: one byte a code for 3, two for 1000.
            let scrambled: Vec<(u32, u32, [u16; 2])> = links(len)
                .iter()
                .enumerate()
                .map(|(e, &(a, b, _))| (a, b, [(e % distinct) as u16, (e % distinct) as u16]))
                .collect();
            let lists = FarLists::new(len as usize, scrambled.clone().into(), |&l| l);
            for k in 0..len {
                let mut expected: Vec<(u32, [u16; 2])> = scrambled
                    .iter()
                    .filter_map(|&(a, b, t)| (a == k).then_some((b, t)).or((b == k).then_some((a, t))))
                    .collect();
                expected.sort_by_key(|e| e.0);
                assert_eq!(lists.of(k as usize).collect::<Vec<_>>(), expected, "node {k}");
                assert_eq!(lists.degree(k as usize), expected.len());
            }
            let mut once: Vec<(u32, u32, [u16; 2])> =
                scrambled.iter().map(|&(a, b, t)| (a.min(b), a.max(b), t)).collect();
            once.sort();
            assert_eq!(lists.links().collect::<Vec<_>>(), once);
            assert_eq!(lists.len(), scrambled.len());
            assert_eq!(lists.tallies.len(), distinct.min(scrambled.len()));
            let code = if distinct <= 256 { 1 } else { 2 };
            assert_eq!(lists.entry_bytes(), (8 + 2 * code) * scrambled.len() + 4 * lists.tallies.len());
        }
    }
}
