//! A memory-bounded record of each pair's visible fraction, so that a pair traced for one
//! column is not traced again for another.
//!
//! ## Why it is exact
//!
//! The analytic backend's visible fraction `V_ij` ([`crate::pair_visibility`]) is a pure
//! function of the unordered pair: its rays come from a stream keyed by the seed and the
//! pair, its roles from the areas, its ray count from the pair's unoccluded factor. So
//! `V_ij = V_ji` bit for bit, whichever column or row asks and whichever thread computes it,
//! and a recorded value can stand for a computed one without changing a single entry. A
//! solver that shoots patch `j` and later patch `i` computes the pair `{i, j}` twice; a
//! shooting method that shoots a patch again computes its whole column again. With the
//! record, each pair is traced once.
//!
//! ## What is kept
//!
//! The record of a patch `p` holds `V_pk` for every `k`, written when a column or row of `p`
//! is first computed: two bits per patch (not needed, fully visible, fully hidden, partly
//! visible), and the exact `f64` of each partly visible pair in a list sorted by `k`. A
//! later column `j` takes `V_ij` from the record of `j` when there is one (every pair of the
//! column), and otherwise from the record of each receiver `i` that has one.
//!
//! ## Memory
//!
//! A record takes `n / 4` bytes and 16 bytes per partly visible pair, so the records grow
//! with the number of distinct patches whose column or row was computed times `n`, never
//! with `n²` up front. They stop being written once their bytes would pass the budget
//! (`analytic:cache=MIB`, 256 MiB by default); columns computed after that trace their pairs as without a
//! record, with the same values. `n²/4` bytes (every patch recorded, no partly visible
//! pair) is the most a scene could use: 30 MB at 10 990 patches, 2.3 GB at 95 832.

use radiosity_core::Real;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

/// Two bits per pair: nothing recorded (the pair needs no visibility), clear, hidden, partly
/// visible.
const NONE: u64 = 0;
const CLEAR: u64 = 1;
const HIDDEN: u64 = 2;
const PARTIAL: u64 = 3;

/// The recorded visible fractions of every patch whose column or row has been computed.
#[derive(Debug)]
pub struct VisibilityCache {
    records: Vec<OnceLock<Record>>,
    budget: usize,
    bytes: AtomicUsize,
    /// Records not written for want of budget.
    refused: AtomicU64,
    /// Pairs whose visible fraction came from a record.
    reused: AtomicU64,
}

/// What a cache holds and has done.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct CacheFigures {
    /// Patches with a record.
    pub records: usize,
    /// Bytes of the records.
    pub bytes: usize,
    /// The budget.
    pub budget: usize,
    /// Records not written because the budget was reached.
    pub refused: u64,
    /// Pairs whose visible fraction was read instead of traced.
    pub reused: u64,
}

/// The visible fraction of patch `p` with every other patch.
#[derive(Debug)]
pub struct Record {
    /// Two bits per patch, 32 patches to a word.
    codes: Box<[u64]>,
    /// The partly visible pairs `(k, V_pk)`, sorted by `k`.
    partial: Box<[(u32, Real)]>,
    /// Pairs recorded (those that needed visibility).
    pairs: u64,
}

impl Record {
    /// The record of `visible[k] = Some(V_pk)` (`None` where the pair needed no visibility).
    pub fn new(visible: &[Option<Real>]) -> Record {
        let mut codes = vec![0u64; visible.len().div_ceil(32)];
        let mut partial = Vec::new();
        let mut pairs = 0;
        for (k, v) in visible.iter().enumerate() {
            pairs += u64::from(v.is_some());
            let code = match *v {
                None => NONE,
                Some(1.0) => CLEAR,
                Some(0.0) => HIDDEN,
                Some(v) => {
                    partial.push((k as u32, v));
                    PARTIAL
                }
            };
            codes[k / 32] |= code << (2 * (k % 32));
        }
        Record { codes: codes.into(), partial: partial.into(), pairs }
    }

    /// `V_pk`, or `None` when the pair needed no visibility.
    pub fn get(&self, k: usize) -> Option<Real> {
        match (self.codes[k / 32] >> (2 * (k % 32))) & 3 {
            CLEAR => Some(1.0),
            HIDDEN => Some(0.0),
            PARTIAL => {
                let at = self.partial.binary_search_by_key(&(k as u32), |&(i, _)| i).ok()?;
                Some(self.partial[at].1)
            }
            _ => None,
        }
    }

    /// Pairs recorded (those that needed visibility).
    pub fn pairs(&self) -> u64 {
        self.pairs
    }

    /// Bytes the record holds.
    pub fn bytes(&self) -> usize {
        8 * self.codes.len() + size_of::<(u32, Real)>() * self.partial.len()
    }
}

impl VisibilityCache {
    /// An empty cache for `n` patches whose records may take at most `budget` bytes (0: none
    /// is kept).
    pub fn new(n: usize, budget: usize) -> VisibilityCache {
        VisibilityCache {
            records: (0..n).map(|_| OnceLock::new()).collect(),
            budget,
            bytes: AtomicUsize::new(0),
            refused: AtomicU64::new(0),
            reused: AtomicU64::new(0),
        }
    }

    /// The record of patch `p`, if one was written.
    pub fn record(&self, p: usize) -> Option<&Record> {
        self.records[p].get()
    }

    /// Whether a record of `n` patches with no partly visible pair would still fit.
    pub fn has_room(&self, n: usize) -> bool {
        self.bytes.load(Ordering::Relaxed) + 8 * n.div_ceil(32) <= self.budget
    }

    /// Keeps `record` as patch `p`'s when the budget allows and no other thread wrote one
    /// first (it would be the same).
    pub fn insert(&self, p: usize, record: Record) {
        let size = record.bytes();
        let before = self.bytes.fetch_add(size, Ordering::Relaxed);
        if before + size > self.budget {
            self.bytes.fetch_sub(size, Ordering::Relaxed);
            self.refused.fetch_add(1, Ordering::Relaxed);
            return;
        }
        if self.records[p].set(record).is_err() {
            self.bytes.fetch_sub(size, Ordering::Relaxed);
        }
    }

    /// Counts `pairs` visible fractions read from records.
    pub fn count_reused(&self, pairs: u64) {
        if pairs > 0 {
            self.reused.fetch_add(pairs, Ordering::Relaxed);
        }
    }

    /// What the cache holds and has done.
    pub fn figures(&self) -> CacheFigures {
        CacheFigures {
            records: self.records.iter().filter(|r| r.get().is_some()).count(),
            bytes: self.bytes.load(Ordering::Relaxed),
            budget: self.budget,
            refused: self.refused.load(Ordering::Relaxed),
            reused: self.reused.load(Ordering::Relaxed),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_record_gives_back_every_fraction_bit_for_bit() {
        let visible: Vec<Option<Real>> = (0..100)
            .map(|k| match k % 5 {
                0 => None,
                1 => Some(1.0),
                2 => Some(0.0),
                _ => Some(k as Real / 997.0),
            })
            .collect();
        let record = Record::new(&visible);
        for (k, v) in visible.iter().enumerate() {
            assert_eq!(record.get(k).map(Real::to_bits), v.map(Real::to_bits), "patch {k}");
        }
        assert_eq!(record.bytes(), 8 * 4 + 16 * 40);
    }

    #[test]
    fn records_stop_at_the_budget() {
        let record = || Record::new(&[Some(0.5), Some(1.0)]);
        let size = record().bytes();
        let cache = VisibilityCache::new(3, 2 * size);
        cache.insert(0, record());
        cache.insert(0, record());
        cache.insert(1, record());
        cache.insert(2, record());
        let figures = cache.figures();
        assert_eq!((figures.records, figures.bytes, figures.refused), (2, 2 * size, 1));
        assert!(cache.record(2).is_none());
        assert_eq!(VisibilityCache::new(3, 0).figures().records, 0);
    }
}
