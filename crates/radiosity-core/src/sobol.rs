//! Owen-scrambled Sobol points in four dimensions: the joint stratification of a shadow
//! segment's two ends (`radiosity-ff`), and of a ray's origin and direction (the stochastic
//! solvers).
//!
//! Sobol's sequence (1967) in base 2 with Joe & Kuo's direction numbers (2008, "Constructing
//! Sobol sequences with better two-dimensional projections", SIAM J. Sci. Comput. 30(5),
//! the table `new-joe-kuo-6.21201`, dimensions 1 to 4): point `p` has in dimension `d` the
//! XOR of the direction numbers `v_{d,b}` over the set bits `b` of `p`. Each dimension is
//! then scrambled by nested uniform (Owen 1995) scrambling, drawn per call from the random
//! stream by Burley's hash (2020, "Practical hash-based Owen scrambling", JCGT 9(4), §4):
//! the bits are reversed, permuted by the Laine–Karras hash, and reversed back, so that every
//! elementary interval in base 2 goes to one of the same size with all its points. Every
//! block of `2^m` consecutive points starting at a multiple of `2^m` is a `(3, m, 4)`-net
//! (`t = 0 + 0 + 1 + 2` for these dimensions) whatever the scramble, so the first `k` points
//! are a union of nets, one per binary digit of `k`; each scramble makes the estimate
//! unbiased.
//!
//! Against a Latin hypercube in each of two squares paired at random, the net also
//! stratifies the squares jointly, which is what a visibility boundary that moves with both
//! ends of a segment needs: for the indicator of a set with a smooth boundary, the variance
//! of a scrambled net falls faster than `1/k` (He & Wang 2015, "On the convergence rate of
//! randomized quasi-Monte Carlo for discontinuous functions", SIAM J. Numer. Anal. 53(5)).

use crate::math::Real;

/// Bits of each coordinate.
const BITS: usize = 32;

/// Joe & Kuo's `(s, a, m_1 … m_s)` for dimensions 2 to 4 (dimension 1 is van der Corput's).
const PRIMITIVES: [(usize, u32, [u32; 3]); 3] = [(1, 0, [1, 0, 0]), (2, 1, [1, 3, 0]), (3, 1, [1, 3, 1])];

/// The direction numbers `v_{d, b}`, each left-aligned in 32 bits.
const DIRECTIONS: [[u32; BITS]; 4] = directions();

const fn directions() -> [[u32; BITS]; 4] {
    let mut v = [[0u32; BITS]; 4];
    let mut b = 0;
    while b < BITS {
        v[0][b] = 1 << (BITS - 1 - b);
        b += 1;
    }
    let mut d = 0;
    while d < PRIMITIVES.len() {
        let (s, a, m) = PRIMITIVES[d];
        let row = &mut v[d + 1];
        let mut b = 0;
        while b < s {
            row[b] = m[b] << (BITS - 1 - b);
            b += 1;
        }
        while b < BITS {
            let mut x = row[b - s] ^ (row[b - s] >> s);
            let mut k = 1;
            while k < s {
                if (a >> (s - 1 - k)) & 1 == 1 {
                    x ^= row[b - k];
                }
                k += 1;
            }
            row[b] = x;
            b += 1;
        }
        d += 1;
    }
    v
}

/// Coordinate `d` of point `index` of the unscrambled sequence, as 32 bits.
fn coordinate(index: u32, d: usize) -> u32 {
    let mut x = 0;
    let mut rest = index;
    let mut b = 0;
    while rest != 0 {
        if rest & 1 == 1 {
            x ^= DIRECTIONS[d][b];
        }
        rest >>= 1;
        b += 1;
    }
    x
}

/// Nested uniform scrambling of `x` keyed by `seed` (Burley 2020, Listing 2 with the hash of
/// §4): a permutation of the bits below each prefix, chosen by the prefix.
fn owen_scramble(x: u32, seed: u32) -> u32 {
    let mut x = x.reverse_bits();
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x.reverse_bits()
}

/// Point `index` of the four-dimensional Sobol sequence, dimension `d` Owen-scrambled with
/// `seeds[d]`; coordinates lie in `(0, 1)`.
pub fn scrambled_point(index: u32, seeds: [u32; 4]) -> [Real; 4] {
    let unit = |x: u32| (Real::from(x) + 0.5) / 4_294_967_296.0;
    std::array::from_fn(|d| unit(owen_scramble(coordinate(index, d), seeds[d])))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(k: usize, seed: u64) -> Vec<[Real; 4]> {
        // Distinct, arbitrary seeds per dimension.
        let seeds: [u32; 4] = std::array::from_fn(|d| {
            (seed as u32).wrapping_mul(0x9e37_79b9).wrapping_add((d as u32).wrapping_mul(0x85eb_ca6b))
        });
        (0..k as u32).map(|p| scrambled_point(p, seeds)).collect()
    }

    #[test]
    fn the_unscrambled_sequence_follows_its_direction_numbers() {
        // In natural order point 2^b is the direction numbers v_{·, b}: from the table, point
        // 1 is (1/2)⁴ and point 2 is (1/4, 3/4, 3/4, 3/4); point 3 is their XOR.
        let at = |p: u32| [0, 1, 2, 3].map(|d| Real::from(coordinate(p, d)) / 4_294_967_296.0);
        assert_eq!(at(0), [0.0; 4]);
        assert_eq!(at(1), [0.5; 4]);
        assert_eq!(at(2), [0.25, 0.75, 0.75, 0.75]);
        assert_eq!(at(3), [0.75, 0.25, 0.25, 0.25]);
    }

    #[test]
    fn scrambled_points_stay_a_net() {
        // The first four dimensions have t = 0 + 0 + 1 + 2 = 3, so 2^8 points are a
        // (3, 8, 4)-net: every box of 2^{d_1} × … × 2^{d_4} cells with Σ d = 5 holds 8.
        for seed in 0..4 {
            let p = points(256, seed);
            for shape in 0..6u32.pow(4) {
                let d: [u32; 4] = std::array::from_fn(|i| shape / 6u32.pow(i as u32) % 6);
                if d.iter().sum::<u32>() != 5 {
                    continue;
                }
                let mut counts = [0usize; 32];
                for q in &p {
                    let cell = (0..4).fold(0, |c, i| (c << d[i]) | (q[i] * Real::from(1u32 << d[i])) as usize);
                    counts[cell] += 1;
                }
                assert!(counts.iter().all(|&c| c == 8), "seed {seed}, shape {d:?}: {counts:?}");
            }
            // One dimension alone: one point in each of 256 intervals.
            for d in 0..4 {
                let mut seen = [false; 256];
                for q in &p {
                    seen[(q[d] * 256.0) as usize] = true;
                }
                assert!(seen.iter().all(|&s| s), "seed {seed}, dimension {d}");
            }
        }
    }

    #[test]
    fn scrambles_differ_by_seed() {
        assert_ne!(points(4, 0), points(4, 1));
        assert_eq!(points(4, 7), points(4, 7));
    }
}
