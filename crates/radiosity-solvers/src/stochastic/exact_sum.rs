//! Sums whose bits do not depend on the order of their terms: the deposits of an iteration's
//! rays, added on every thread and then over the ranks.
//!
//! A floating-point sum depends on the order of its terms, so deposits summed by several
//! threads, or by several ranks each over its share of the rays, would differ in their last
//! bits from one process's, and a run's rays would depend on them (a patch's number of rays
//! is rounded from its power). Here every term is rounded once to a multiple of `2^(e − 124)`,
//! `e` the exponent of a bound on every sum, and the integers are added: integer addition is
//! associative, so the sum is the same whatever the threads, the ranks or the order. A term is
//! rounded (towards zero) by at most `2^(e − 124)`, 2^-71 of the bound below `f64`'s own
//! rounding of it, which is what the sum loses against an exact one.
//!
//! A term that is not finite is not rounded: it makes every sum NaN (on every rank), so that
//! the caller's check of its result finds it.
//!
//! On a thread, an entry is an `i128` held as two atomic words, added without a lock: the low
//! word's carry goes to the high word, so the sum is exact modulo `2^128`, and the bound keeps
//! it below `2^124`. Over the ranks, each entry travels as three limbs of at most 43 bits in
//! the [`Collective`]'s `f64` sum, exact for up to 1024 ranks; when every rank has few entries
//! that are not zero (an iteration with fewer rays than patches), only those travel, each with
//! its place, and each rank adds the others' to its own.

use radiosity_core::{Collective, Real};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};

/// The bits below the bound's exponent that a term keeps.
const FRACTION: i32 = 124;

/// The bits of the two lower limbs of an entry sent over the ranks.
const LIMB: u32 = 42;

/// Entries summed over the ranks in one call: a chunk's limbs take 6 MiB.
const CHUNK: usize = 1 << 18;

/// Sums of terms added in any order, the same bits for any order (module doc).
pub(crate) struct ExactSum {
    low: Vec<AtomicU64>,
    high: Vec<AtomicU64>,
    /// Whether a term was not finite (on any rank, once summed over them): every sum is then
    /// written as NaN, so that the caller's check finds it rather than a term silently lost.
    broken: AtomicBool,
    /// `2^(FRACTION − e)`: a term to its multiple of the quantum.
    to_fixed: Real,
    /// `2^(e − FRACTION)`.
    to_real: Real,
}

/// `2^p`, exactly, for `p` within the normal range.
fn power_of_two(p: i32) -> Real {
    Real::from_bits(((p + 1023).clamp(1, 2046) as u64) << 52)
}

impl ExactSum {
    /// `len` sums, each of whose terms' absolute values add to at most `bound` (over every
    /// rank). The bound must be the same on every rank and for every number of ranks.
    pub fn new(len: usize, bound: Real) -> ExactSum {
        // 2^e > bound; a zero or non-finite bound gives e = 0 (nothing to add, or a term that
        // is not finite, found by the caller's check on the result).
        let e = if bound > 0.0 && bound.is_finite() { ((bound.to_bits() >> 52) as i32 - 1023) + 1 } else { 0 };
        let e = e.clamp(-890, 890);
        ExactSum {
            low: (0..len).into_par_iter().map(|_| AtomicU64::new(0)).collect(),
            high: (0..len).into_par_iter().map(|_| AtomicU64::new(0)).collect(),
            broken: AtomicBool::new(false),
            to_fixed: power_of_two(FRACTION - e),
            to_real: power_of_two(e - FRACTION),
        }
    }

    /// Adds `x` to sum `at`, from any thread.
    pub fn add(&self, at: usize, x: Real) {
        if !x.is_finite() {
            self.broken.store(true, Relaxed);
            return;
        }
        // Scaling by a power of two is exact; `as` rounds towards zero.
        let v = (x * self.to_fixed) as i128;
        self.add_fixed(at, v);
    }

    fn add_fixed(&self, at: usize, v: i128) {
        let (low, high) = (v as u64, (v >> 64) as u64);
        let before = self.low[at].fetch_add(low, Relaxed);
        let carry = u64::from(before.overflowing_add(low).1);
        self.high[at].fetch_add(high.wrapping_add(carry), Relaxed);
    }

    fn fixed(&self, at: usize) -> i128 {
        (((self.high[at].load(Relaxed) as u128) << 64) | self.low[at].load(Relaxed) as u128) as i128
    }

    /// Replaces every sum by its sum over the ranks of `collective` (each rank calls it, in
    /// the same order); nothing in one process. Where every rank's sums that are not zero
    /// are few (an iteration with fewer rays than patches), only those travel, each with its
    /// place; otherwise every sum does.
    pub fn sum_over(&mut self, collective: Option<&dyn Collective>) {
        let Some(c) = collective else { return };
        let len = self.low.len();
        let used = |at: &usize| self.low[*at].load(Relaxed) != 0 || self.high[*at].load(Relaxed) != 0;
        let count = (0..len).into_par_iter().filter(used).count();
        let counts = c.gather(&[count as Real, Real::from(u8::from(self.broken.load(Relaxed)))]);
        let most = counts.iter().map(|v| v[0] as usize).max().unwrap_or(0);
        if counts.iter().any(|v| v[1] > 0.0) {
            self.broken.store(true, Relaxed);
            return;
        }
        // An entry sent sparse takes its place and three limbs, a dense one three limbs; sent
        // sparse, every rank's entries travel at once, so no more than a chunk's worth.
        let sparse = c.ranks() * most * 4;
        if sparse < 3 * len && sparse <= 3 * CHUNK {
            let nonzero: Vec<usize> = (0..len).into_par_iter().filter(used).collect();
            self.sum_sparse(c, &nonzero, most);
        } else {
            self.sum_dense(c);
        }
    }

    /// The three limbs of sum `at` (module doc), each below `2^43` in magnitude, so converted
    /// through `i64` (one instruction, where `i128` takes a routine).
    fn limbs(&self, at: usize) -> [Real; 3] {
        let (v, mask) = (self.fixed(at), (1i128 << LIMB) - 1);
        [(v & mask) as i64 as Real, ((v >> LIMB) & mask) as i64 as Real, (v >> (2 * LIMB)) as i64 as Real]
    }

    /// The value of three limbs.
    fn of_limbs(l: &[Real]) -> i128 {
        i128::from(l[0] as i64) + (i128::from(l[1] as i64) << LIMB) + (i128::from(l[2] as i64) << (2 * LIMB))
    }

    /// Every rank's sums that are not zero (`nonzero` here, at most `most` on any rank), each
    /// with its place, added to this rank's: integer sums, so the order does not matter.
    fn sum_sparse(&mut self, c: &dyn Collective, nonzero: &[usize], most: usize) {
        // Rank r's entries in its own slot, zeros in the others' (`Collective::gather`, without
        // a copy a rank): the sum hands every rank every slot. A place is stored plus one, so
        // that an unused entry reads 0.
        let (me, slot) = (c.rank(), 4 * most);
        let mut all = vec![0.0; c.ranks() * slot];
        for (entry, &at) in all[me * slot..(me + 1) * slot].chunks_mut(4).zip(nonzero) {
            entry[0] = (at + 1) as Real;
            entry[1..].copy_from_slice(&self.limbs(at));
        }
        c.sum(&mut all);
        for (_, part) in all.chunks(slot.max(1)).enumerate().filter(|(rank, _)| *rank != me) {
            for entry in part.chunks(4).take_while(|e| e[0] > 0.0) {
                self.add_fixed(entry[0] as usize - 1, Self::of_limbs(&entry[1..]));
            }
        }
    }

    /// Every sum through the ranks' `f64` sum, as three limbs, in chunks.
    fn sum_dense(&mut self, c: &dyn Collective) {
        let len = self.low.len();
        for start in (0..len).step_by(CHUNK) {
            let end = (start + CHUNK).min(len);
            let mut limbs = vec![0.0; 3 * (end - start)];
            limbs.par_chunks_mut(3 * 4096).enumerate().for_each(|(b, out)| {
                for (i, l) in out.chunks_mut(3).enumerate() {
                    l.copy_from_slice(&self.limbs(start + b * 4096 + i));
                }
            });
            c.sum(&mut limbs);
            (start..end).into_par_iter().zip(limbs.par_chunks(3)).for_each(|(at, l)| {
                let v = Self::of_limbs(l);
                self.low[at].store(v as u64, Relaxed);
                self.high[at].store((v >> 64) as u64, Relaxed);
            });
        }
    }

    /// The sums, rounded to the nearest `f64`, into `out`.
    pub fn write(&self, out: &mut [Real]) {
        if self.broken.load(Relaxed) {
            out.fill(Real::NAN);
            return;
        }
        out.par_iter_mut().enumerate().for_each(|(at, o)| *o = self.fixed(at) as Real * self.to_real);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use radiosity_core::InProcessRanks;

    /// Terms of every size and sign, in a fixed order.
    fn terms(count: usize) -> Vec<Real> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        (0..count)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let unit = (state >> 11) as Real / (1u64 << 53) as Real;
                (unit - 0.3) * power_of_two((state % 40) as i32 - 30)
            })
            .collect()
    }

    #[test]
    fn a_sum_is_the_same_bits_in_any_order_on_any_threads_and_ranks_and_within_its_quantum_of_the_exact() {
        let t = terms(20_000);
        let bound: Real = t.iter().map(|x| x.abs()).sum();
        let one = |order: &mut dyn Iterator<Item = usize>| {
            let s = ExactSum::new(1, bound);
            order.for_each(|i| s.add(0, t[i]));
            let mut out = [0.0];
            s.write(&mut out);
            out[0]
        };
        let forwards = one(&mut (0..t.len()));
        assert_eq!(forwards, one(&mut (0..t.len()).rev()));
        assert_eq!(forwards, one(&mut (0..t.len()).map(|i| (i * 7919) % t.len())));
        // On every thread, in whatever order they take.
        let s = ExactSum::new(1, bound);
        t.par_iter().for_each(|&x| s.add(0, x));
        let mut out = [0.0];
        s.write(&mut out);
        assert_eq!(out[0], forwards);
        // Over 3 ranks, each with a third of the terms: every rank ends with the same bits.
        let ranks = InProcessRanks::run(3, |c| {
            let mut s = ExactSum::new(1, bound);
            t.iter().enumerate().filter(|(i, _)| c.deals(*i)).for_each(|(_, &x)| s.add(0, x));
            s.sum_over(Some(&*c));
            let mut out = [0.0];
            s.write(&mut out);
            out[0]
        });
        assert!(ranks.iter().all(|&r| r == forwards), "{ranks:?} against {forwards}");
        // Against the exact sum (the terms in 128-bit fixed point at a finer quantum): within
        // a quantum a term, and f64's rounding of the result.
        let exact: i128 = t.iter().map(|&x| (x * power_of_two(100)) as i128).sum();
        let exact = exact as Real / power_of_two(100);
        let quantum = power_of_two(((bound.to_bits() >> 52) as i32 - 1023) + 1 - FRACTION);
        assert!((forwards - exact).abs() <= t.len() as Real * quantum + exact.abs() * Real::EPSILON);
    }

    #[test]
    fn sums_over_ranks_are_one_process_bits_whether_few_or_many_are_not_zero() {
        // 3 ranks, 3000 sums: 20 terms (few sums not zero: sent with their places) or 20,000
        // (most not zero: every sum sent), each term on the rank of its index.
        let t = terms(20_000);
        let bound: Real = t.iter().map(|x| x.abs()).sum();
        let len = 3000;
        for count in [20, 20_000] {
            let place = |i: usize| (i * 7919) % len;
            let one = ExactSum::new(len, bound);
            (0..count).for_each(|i| one.add(place(i), t[i]));
            let mut expected = vec![0.0; len];
            one.write(&mut expected);
            let ranks = InProcessRanks::run(3, |c| {
                let mut s = ExactSum::new(len, bound);
                (0..count).filter(|i| c.deals(*i)).for_each(|i| s.add(place(i), t[i]));
                s.sum_over(Some(&*c));
                let mut out = vec![0.0; len];
                s.write(&mut out);
                (out, c.traffic().values)
            });
            for (out, values) in &ranks {
                assert_eq!(out, &expected, "{count} terms");
                // Sparse: a count, then 4 values a sum not zero of each rank; dense: 3 a sum.
                let dense = count > len;
                assert_eq!(*values > 3 * len as u64, dense, "{count} terms: {values} values sent");
            }
        }
    }

    #[test]
    fn a_term_that_is_not_finite_makes_every_sum_nan_on_every_rank() {
        let one = ExactSum::new(3, 10.0);
        one.add(0, 1.0);
        one.add(2, Real::INFINITY);
        let mut out = [0.0; 3];
        one.write(&mut out);
        assert!(out.iter().all(|x| x.is_nan()), "{out:?}");
        // Over two ranks, rank 1's NaN reaches rank 0.
        let ranks = InProcessRanks::run(2, |c| {
            let mut s = ExactSum::new(3, 10.0);
            s.add(c.rank(), if c.rank() == 1 { Real::NAN } else { 1.0 });
            s.sum_over(Some(&*c));
            let mut out = [0.0; 3];
            s.write(&mut out);
            out
        });
        assert!(ranks.iter().flatten().all(|x| x.is_nan()), "{ranks:?}");
    }

    #[test]
    fn a_sum_that_cancels_keeps_the_small_terms_a_float_sum_would_lose() {
        // 1e16 + 1 − 1e16: f64 gives 0 in that order and 1 in another; the fixed point, 1.
        let s = ExactSum::new(1, 2.0e16 + 1.0);
        for x in [1e16, 1.0, -1e16] {
            s.add(0, x);
        }
        let mut out = [0.0];
        s.write(&mut out);
        assert_eq!(out[0], 1.0);
    }
}
