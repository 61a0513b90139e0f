//! The operator's link lists in compressed sparse row form: for each node or patch, the other
//! ends of its links and their values, ordered by the other end, so that a product reads its
//! vector in order. The other ends are packed as differences ([`Packed`]), a byte or so each.
//!
//! A near link or far pair ([`Adjacency`]) is held once, with its `A_i F_ij` in `f32`
//! ([`Transfer`]), in the list of its lower end; its higher end's list holds the lower end and
//! the link's place in the lower end's list. So it costs 4 bytes for its value and a few for
//! its two entries, not the 16 of a link in both its ends' lists with its value twice, and
//! both ends read the same value, which keeps reciprocity exact.
//!
//! A far link ([`FarLists`]) is in both its nodes' lists: a product works out its geometry
//! from both ends, and a search for it at one end would cost more than that arithmetic. It is
//! the other node and its rays' tally, coded as its place in a table ordered by how often
//! each tally occurs, so that the common ones take a byte. Its direction, length and `g` are
//! worked out again from the nodes' centres wherever it is used, to the same bits.
//!
//! Lists are built on every thread from the refinement's links as they were gathered, in
//! parts ([`Gathered`]): each end's place claimed by an atomic count, each list then sorted by
//! itself and packed, so the lists are the same whatever the number of threads.

use super::packed::Packed;
use radiosity_core::Real;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU8, AtomicU16, AtomicU32, AtomicUsize, Ordering};

/// Links by the node or patch at either end: for each of `len` keys, the other ends and the
/// links' values, ordered by the other end (so that a product reads its vector in order).
#[derive(Debug)]
pub(super) struct Adjacency {
    /// Where each key's values start in `value` (`len + 1`): the links to its higher ends.
    pub(super) start: Vec<usize>,
    /// Each link once, in its lower end's list: the higher ends,
    higher: Packed,
    /// and the values, in the same order.
    pub(super) value: Vec<Transfer>,
    /// Each link again, in its higher end's list: the lower end and the link's place in the
    /// lower end's list.
    lower: Packed,
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
        let slots: Vec<AtomicU32> = bytemuck::zeroed_vec(other.len());
        let places: Vec<AtomicU32> = bytemuck::zeroed_vec(other.len());
        start.par_windows(2).enumerate().for_each(|(k, at)| {
            for (place, &o) in other[at[0]..at[1]].iter().enumerate() {
                let slot = next[o as usize].fetch_add(1, Ordering::Relaxed);
                slots[slot].store(k as u32, Ordering::Relaxed);
                places[slot].store(place as u32, Ordering::Relaxed);
            }
        });
        drop(next);
        let mut lower: Vec<u32> = slots.into_iter().map(AtomicU32::into_inner).collect();
        let mut places: Vec<u32> = places.into_iter().map(AtomicU32::into_inner).collect();
        sorted_by_other(&lower_start, &mut lower, &mut places);
        let lower = Packed::new(&lower_start, &lower, Some(&|e| places[e]));
        let higher = Packed::new(&start, &other, None);
        Adjacency { start, higher, value, lower }
    }

    /// The list of `k`: the other ends, in increasing order, and the values.
    pub(super) fn of(&self, k: usize) -> impl Iterator<Item = (u32, Transfer)> + '_ {
        let lower = self.lower.of(k).map(|(o, place)| (o, self.value[self.start[o as usize] + place as usize]));
        let higher = self.start[k]..self.start[k + 1];
        lower.chain(self.higher.of(k).map(|(o, _)| o).zip(self.value[higher].iter().copied()))
    }

    /// The number of links in the list of `k`.
    pub(super) fn degree(&self, k: usize) -> usize {
        self.start[k + 1] - self.start[k] + self.lower.degree(k)
    }

    /// Each link once: its ends, the lower first, in increasing order of the ends.
    pub(super) fn ends(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        (0..self.higher.keys()).flat_map(move |k| self.higher.of(k).map(move |(o, _)| (k as u32, o)))
    }

    /// The number of links.
    pub(super) fn len(&self) -> usize {
        self.value.len()
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

    /// The bytes the links' entries hold: each link's value and its two packed entries, not
    /// the offsets every key has.
    pub(super) fn entry_bytes(&self) -> usize {
        self.value.len() * size_of::<Transfer>() + self.higher.entry_bytes() + self.lower.entry_bytes()
    }

    /// The bytes the lists hold.
    pub(super) fn bytes(&self) -> usize {
        self.start.len() * size_of::<usize>()
            + self.value.len() * size_of::<Transfer>()
            + self.higher.bytes()
            + self.lower.bytes()
    }
}

/// Far links by node, each in the lists of both its nodes: the other node and the code of the
/// link's rays' tally (`[clear, count]`), its place in `tallies` (module doc).
#[derive(Debug)]
pub(super) struct FarLists {
    /// The other nodes, each with its link's code.
    lists: Packed,
    /// The distinct tallies, the most frequent first (ties in increasing order).
    tallies: Vec<[u16; 2]>,
    /// The number of links.
    links: usize,
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
        let count = links.len();
        // Neighbouring links mostly share a tally: counted in runs.
        let counted: BTreeMap<[u16; 2], usize> = (links.0.par_iter())
            .map(|part| {
                let mut counts = BTreeMap::new();
                let mut run: Option<([u16; 2], usize)> = None;
                for l in part {
                    let t = ends(l).2;
                    match &mut run {
                        Some((last, n)) if *last == t => *n += 1,
                        _ => {
                            if let Some((last, n)) = run.replace((t, 1)) {
                                *counts.entry(last).or_insert(0) += n;
                            }
                        }
                    }
                }
                if let Some((last, n)) = run {
                    *counts.entry(last).or_insert(0) += n;
                }
                counts
            })
            .reduce(BTreeMap::new, |mut a, b| {
                for (t, n) in b {
                    *a.entry(t).or_insert(0) += n;
                }
                a
            });
        let mut tallies: Vec<([u16; 2], usize)> = counted.into_iter().collect();
        tallies.sort_by_key(|&(t, n)| (std::cmp::Reverse(n), t));
        // A tally is `[c, c]` for c up to `rays`, or `[c, probe]`, each with or without the
        // zeroth-order bit: at most 2 · (4096 + 1024) of them.
        let mut by_tally: Vec<([u16; 2], u16)> = (tallies.iter().enumerate())
            .map(|(code, &(t, _))| (t, u16::try_from(code).expect("at most 65,536 distinct tallies")))
            .collect();
        by_tally.sort_unstable();
        let code =
            |t: [u16; 2]| by_tally[by_tally.binary_search_by_key(&t, |e| e.0).expect("every tally is in the table")].1;
        let lists = if tallies.len() <= 256 {
            packed_far::<_, AtomicU8>(len, links, |l| {
                let (a, b, t) = ends(l);
                (a, b, code(t) as u8)
            })
        } else {
            packed_far::<_, AtomicU16>(len, links, |l| {
                let (a, b, t) = ends(l);
                (a, b, code(t))
            })
        };
        FarLists { lists, tallies: tallies.into_iter().map(|(t, _)| t).collect(), links: count }
    }

    /// The list of node `k`: the other nodes, in increasing order, and the links' tallies.
    pub(super) fn of(&self, k: usize) -> impl Iterator<Item = (u32, [u16; 2])> + '_ {
        self.lists.of(k).map(|(o, code)| (o, self.tallies[code as usize]))
    }

    /// The number of links in the list of `k`.
    pub(super) fn degree(&self, k: usize) -> usize {
        self.lists.degree(k)
    }

    /// Each link once: its ends, the lower first, and its tally, in increasing order of the
    /// ends.
    pub(super) fn links(&self) -> impl Iterator<Item = (u32, u32, [u16; 2])> + '_ {
        (0..self.lists.keys())
            .flat_map(move |k| self.of(k).filter(move |&(o, _)| o as usize > k).map(move |(o, t)| (k as u32, o, t)))
    }

    /// Each link once: its ends, the lower first.
    pub(super) fn ends(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.links().map(|(a, b, _)| (a, b))
    }

    /// The number of links.
    pub(super) fn len(&self) -> usize {
        self.links
    }

    /// The bytes the links' entries hold (with the table of tallies), not the offsets every
    /// node has.
    pub(super) fn entry_bytes(&self) -> usize {
        self.lists.entry_bytes() + self.tallies.len() * size_of::<[u16; 2]>()
    }

    /// The bytes the lists hold.
    pub(super) fn bytes(&self) -> usize {
        self.lists.bytes() + self.tallies.len() * size_of::<[u16; 2]>()
    }
}

/// The far lists of `links`, each link at both ends with its code, packed.
fn packed_far<L: Send + Sync, S: Slot>(
    len: usize,
    links: Gathered<L>,
    ends: impl Fn(&L) -> (u32, u32, S::Value) + Sync,
) -> Packed
where
    S::Value: Into<u32>,
{
    let (start, other, codes) = scattered::<_, S>(len, links, true, ends);
    Packed::new(&start, &other, Some(&|e| codes[e].into()))
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
    sorted_by_other(&start, &mut other, &mut payload);
    (start, other, payload)
}

/// Each list that `start` cuts `other` and `payload` into, sorted by its other ends: the slots
/// were claimed in any order.
fn sorted_by_other<T: Copy + Send + Sync>(start: &[usize], other: &mut [u32], payload: &mut [T]) {
    let lists = lists_of(start, other).into_iter().zip(lists_of(start, payload));
    lists.collect::<Vec<_>>().into_par_iter().for_each_init(Vec::new, |entries, (o, x)| {
        entries.clear();
        entries.extend(o.iter().copied().zip(x.iter().copied()));
        entries.sort_unstable_by_key(|e: &(u32, T)| e.0);
        for (k, &(q, y)) in entries.iter().enumerate() {
            (o[k], x[k]) = (q, y);
        }
    });
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
            (again.start, again.higher, again.lower),
            (adjacency.start.clone(), adjacency.higher.clone(), adjacency.lower.clone())
        );
        assert_eq!(again.value, adjacency.value);
        // Each link is held once with its value, its two ends packed: fewer than the 12 bytes
        // of a `u32` at each end and the value, and at least the value and a byte an end.
        let bytes = adjacency.entry_bytes();
        assert!(bytes < 12 * scrambled_len && bytes >= 6 * scrambled_len, "{bytes} for {scrambled_len}");
    }

    #[test]
    fn lists_with_a_lower_end_a_repeat_or_an_end_out_of_range_are_refused() {
        let adjacency = Adjacency::new(5, vec![(0, 3, 1.0), (1, 2, 2.0), (4, 1, 3.0)].into(), |&l| l);
        let (start, other) = (adjacency.start.clone(), adjacency.ends().map(|(_, o)| o).collect::<Vec<u32>>());
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
            // Each entry is its other end, a byte among 60 nodes, and its code, a byte below
            // 128 and two above; each list starts with its length, a byte; and the table.
            let entries = lists.entry_bytes() - 4 * lists.tallies.len();
            let widest = if distinct <= 128 { 1 } else { 2 };
            let links = 2 * scrambled.len();
            assert!(entries >= 2 * links + len as usize && entries <= (1 + widest) * links + len as usize, "{entries}");
        }
    }
}
