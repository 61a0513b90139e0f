//! Lists of node or patch numbers packed as variable-length differences, the way the link
//! lists hold their other ends.
//!
//! A list's other ends are in increasing order, and the tree's pre-order puts a node's
//! neighbours in space close to it in number. So each end is written as its difference from
//! the previous one (the first as its signed difference from the list's key) in LEB128: seven
//! bits a byte, the high bit saying that more follow. On `office:size=0.05` an end takes
//! 1.2 to 1.3 bytes, not the 4 of a `u32`. Each entry may carry a small number of its own
//! (a far link's tally code, a near link's place in its lower end's list), packed the same
//! way. A list starts with its length, so a key's degree is one read.
//!
//! The lists are read in order only, as a product reads them; a list of a few dozen entries
//! is searched by reading it.

use rayon::prelude::*;

/// The keys a task packs at once.
const CHUNK: usize = 4096;

/// Lists of `u32` other ends, each with an optional `u32` of its own, packed (module doc).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Packed {
    /// Where each key's list starts in `bytes` (`len + 1`).
    at: Vec<usize>,
    bytes: Vec<u8>,
    /// Whether each entry carries a number of its own.
    extra: bool,
}

/// The bytes LEB128 takes for `v`.
fn width(v: u64) -> usize {
    (64 - (v | 1).leading_zeros() as usize).div_ceil(7)
}

/// Writes `v` at the start of `out`, returning the rest.
fn put(out: &mut [u8], mut v: u64) -> &mut [u8] {
    let mut i = 0;
    while v >= 0x80 {
        out[i] = (v as u8) | 0x80;
        v >>= 7;
        i += 1;
    }
    out[i] = v as u8;
    &mut out[i + 1..]
}

/// Reads a number at `*pos`, moving past it.
#[inline]
fn get(bytes: &[u8], pos: &mut usize) -> u64 {
    let (mut v, mut shift) = (0u64, 0);
    loop {
        let b = bytes[*pos];
        *pos += 1;
        v |= u64::from(b & 0x7f) << shift;
        if b < 0x80 {
            return v;
        }
        shift += 7;
    }
}

/// Reads a number at the start of `bytes`, moving past it: a byte at once when it is the last.
#[inline(always)]
fn read(bytes: &mut &[u8]) -> u64 {
    match bytes.split_first() {
        Some((&b, rest)) if b < 0x80 => {
            *bytes = rest;
            u64::from(b)
        }
        _ => {
            let mut pos = 0;
            let v = get(bytes, &mut pos);
            *bytes = &bytes[pos..];
            v
        }
    }
}

/// The entries of one packed list, in order ([`Packed::of`]).
pub(super) struct Entries<'a> {
    /// The list's bytes after `next`'s difference.
    bytes: &'a [u8],
    /// The entries not yet given.
    left: usize,
    /// The next other end, already read.
    next: u32,
    extra: bool,
}

impl Iterator for Entries<'_> {
    type Item = (u32, u32);

    #[inline]
    fn next(&mut self) -> Option<(u32, u32)> {
        if self.left == 0 {
            return None;
        }
        let o = self.next;
        let x = if self.extra { read(&mut self.bytes) as u32 } else { 0 };
        self.left -= 1;
        if self.left > 0 {
            self.next = o + read(&mut self.bytes) as u32;
        }
        Some((o, x))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.left, Some(self.left))
    }
}

impl ExactSizeIterator for Entries<'_> {}

/// The first end's difference from the key, signed, folded so that small either way is small.
fn zigzag(first: u32, key: usize) -> u64 {
    let d = i64::from(first) - key as i64;
    ((d << 1) ^ (d >> 63)) as u64
}

fn unzigzag(z: u64, key: usize) -> u32 {
    let d = ((z >> 1) as i64) ^ -((z & 1) as i64);
    (key as i64 + d) as u32
}

impl Packed {
    /// The lists `start` cuts `other` into (each increasing), entry `e` carrying `extra(e)`
    /// when `extra` is given. Packed on every thread, the same bytes whatever their number.
    pub(super) fn new(start: &[usize], other: &[u32], extra: Option<&(dyn Fn(usize) -> u32 + Sync)>) -> Packed {
        let keys = start.len() - 1;
        // Entry `e`'s difference in the list of `k`.
        let delta = |k: usize, e: usize| {
            if e == start[k] { zigzag(other[e], k) } else { u64::from(other[e] - other[e - 1]) }
        };
        let list_width = |k: usize| {
            let list = start[k]..start[k + 1];
            let mut w = width(list.len() as u64);
            for e in list {
                w += width(delta(k, e)) + extra.map_or(0, |x| width(u64::from(x(e))));
            }
            w
        };
        let widths: Vec<usize> = (0..keys).into_par_iter().map(list_width).collect();
        let mut at = Vec::with_capacity(keys + 1);
        at.push(0);
        let mut total = 0;
        for w in widths {
            total += w;
            at.push(total);
        }
        let mut bytes = vec![0u8; total];
        // Each chunk of keys writes its own slice of the bytes.
        let mut slices = Vec::with_capacity(keys.div_ceil(CHUNK));
        let mut rest = bytes.as_mut_slice();
        for first in (0..keys).step_by(CHUNK) {
            let last = (first + CHUNK).min(keys);
            let (slice, tail) = rest.split_at_mut(at[last] - at[first]);
            slices.push((first..last, slice));
            rest = tail;
        }
        slices.into_par_iter().for_each(|(keys, mut out)| {
            for k in keys {
                let list = start[k]..start[k + 1];
                out = put(out, list.len() as u64);
                for e in list {
                    out = put(out, delta(k, e));
                    if let Some(x) = extra {
                        out = put(out, u64::from(x(e)));
                    }
                }
            }
        });
        Packed { at, bytes, extra: extra.is_some() }
    }

    /// The list of `k`: its other ends in increasing order, each with its own number (0 when
    /// the lists carry none).
    #[inline]
    pub(super) fn of(&self, k: usize) -> Entries<'_> {
        let mut bytes = &self.bytes[self.at[k]..self.at[k + 1]];
        let left = read(&mut bytes) as usize;
        let next = if left > 0 { unzigzag(read(&mut bytes), k) } else { 0 };
        Entries { bytes, left, next, extra: self.extra }
    }

    /// The length of the list of `k`.
    pub(super) fn degree(&self, k: usize) -> usize {
        let mut pos = self.at[k];
        get(&self.bytes, &mut pos) as usize
    }

    /// The number of keys.
    pub(super) fn keys(&self) -> usize {
        self.at.len() - 1
    }

    /// The bytes of the packed lists, not their offsets.
    pub(super) fn entry_bytes(&self) -> usize {
        self.bytes.len()
    }

    /// The bytes held, offsets included.
    pub(super) fn bytes(&self) -> usize {
        self.bytes.len() + self.at.len() * size_of::<usize>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_of_every_width_read_back_as_written() {
        for v in [0, 1, 127, 128, 16_383, 16_384, u64::from(u32::MAX), u64::MAX] {
            let mut buf = [0u8; 10];
            let rest = put(&mut buf, v).len();
            assert_eq!(10 - rest, width(v), "{v}");
            let mut pos = 0;
            assert_eq!(get(&buf, &mut pos), v);
            assert_eq!(pos, width(v));
        }
    }

    #[test]
    fn lists_read_back_with_their_numbers_over_any_gap_and_when_empty() {
        // Keys with empty lists, ends below and above the key, gaps up to the largest u32.
        let lists: Vec<Vec<u32>> = vec![
            vec![],
            vec![0, 2, 3, 1_000, 70_000, u32::MAX - 1],
            vec![],
            vec![5],
            vec![0, 1],
            (0..300).map(|i| i * 7 + 1).collect(),
            vec![],
        ];
        let mut start = vec![0];
        let mut other = Vec::new();
        for list in &lists {
            other.extend(list);
            start.push(other.len());
        }
        let extra = |e: usize| (e as u32).wrapping_mul(2_654_435_761) >> (e % 32);
        let with = Packed::new(&start, &other, Some(&extra));
        let without = Packed::new(&start, &other, None);
        assert_eq!(with.keys(), lists.len());
        for (k, list) in lists.iter().enumerate() {
            let expected: Vec<(u32, u32)> = list.iter().enumerate().map(|(i, &o)| (o, extra(start[k] + i))).collect();
            assert_eq!(with.of(k).collect::<Vec<_>>(), expected, "key {k}");
            assert_eq!(without.of(k).map(|(o, _)| o).collect::<Vec<_>>(), *list, "key {k}");
            assert_eq!((with.degree(k), without.degree(k)), (list.len(), list.len()));
        }
        // Close ends take a byte: the 300 ends seven apart, a byte each and two for the count.
        assert_eq!(without.at[6] - without.at[5], 2 + 300);
    }
}
