//! The random numbers of the solvers that sample transport: points of `[0, 1)^4`, one per ray,
//! from a pseudo-random or a quasi-random sequence ([`Sequence`]), in streams keyed by what
//! they are for, so that the same seed gives the same rays whatever the thread count.
//!
//! A stream ([`Sequence::stream`]) is keyed by the run's seed and up to three integers (the
//! replicate, the iteration, the patch): streams of different keys are independent.
//!
//! - `random`: SplitMix64 (Steele, Lea & Flood 2014) seeded by a hash of the key: four 53-bit
//!   numbers a point.
//! - `sobol`: the four-dimensional Sobol sequence, Owen-scrambled per stream
//!   ([`radiosity_core::sobol`]): every block of `2^m` points of a stream is a `(3, m, 4)`-net,
//!   and every point is uniform, so estimates stay unbiased.
//! - `halton`: Halton's sequence in bases 2, 3, 5, 7, each digit shifted at random per stream
//!   and digit position (a random digit scrambling, Matoušek 1998): every point is uniform
//!   and the sequence keeps its stratification.
//!
//! ## References
//!
//! - Steele, Lea & Flood 2014, "Fast splittable pseudorandom number generators", OOPSLA.
//! - Owen 1995, "Randomly permuted (t, m, s)-nets and (t, s)-sequences", in *Monte Carlo and
//!   Quasi-Monte Carlo Methods in Scientific Computing*.
//! - Matoušek 1998, "On the L2-discrepancy for anchored boxes", J. Complexity 14(4).
//! - Keller 1996, "Quasi-Monte Carlo radiosity", Eurographics Rendering Workshop.

use radiosity_core::Real;
use radiosity_core::sobol::scrambled_point;

/// Which sequence a solver draws its rays from (module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Sequence {
    /// Pseudo-random (the default).
    #[default]
    Random,
    /// Owen-scrambled Sobol.
    Sobol,
    /// Halton with random digit shifts.
    Halton,
}

impl Sequence {
    /// The name as written in a solver's parameters.
    pub fn name(self) -> &'static str {
        match self {
            Sequence::Random => "random",
            Sequence::Sobol => "sobol",
            Sequence::Halton => "halton",
        }
    }

    /// The sequence named `name`, if any.
    pub fn parse(name: &str) -> Option<Sequence> {
        [Sequence::Random, Sequence::Sobol, Sequence::Halton].into_iter().find(|s| s.name() == name)
    }

    /// The stream of `seed` and `key` (module doc), from its first point.
    pub fn stream(self, seed: u64, key: [u64; 3]) -> PointStream {
        let mut hash = SplitMix(mix(seed ^ mix(key[0] ^ mix(key[1] ^ mix(key[2])))));
        let scramble = match self {
            Sequence::Random => Scramble::None,
            Sequence::Sobol => Scramble::Sobol(std::array::from_fn(|_| hash.next() as u32)),
            Sequence::Halton => {
                Scramble::Halton(Box::new(std::array::from_fn(|_| std::array::from_fn(|_| hash.next()))))
            }
        };
        PointStream { random: hash, scramble, index: 0 }
    }
}

/// Digits of each Halton coordinate that are shifted (enough for 2^32 points in base 2).
const HALTON_DIGITS: usize = 32;

/// The bases of the Halton coordinates.
const HALTON_BASES: [u64; 4] = [2, 3, 5, 7];

/// How a stream's points are made.
#[derive(Clone, Debug)]
enum Scramble {
    None,
    Sobol([u32; 4]),
    /// A random number per coordinate and digit position, its shift modulo the base.
    Halton(Box<[[u64; HALTON_DIGITS]; 4]>),
}

/// A stream of points of `[0, 1)^4` ([`Sequence::stream`]).
#[derive(Clone, Debug)]
pub struct PointStream {
    random: SplitMix,
    scramble: Scramble,
    index: u64,
}

impl PointStream {
    /// The next point.
    pub fn next_point(&mut self) -> [Real; 4] {
        let index = self.index;
        self.index += 1;
        match &self.scramble {
            Scramble::None => std::array::from_fn(|_| self.random.unit()),
            Scramble::Sobol(seeds) => scrambled_point(index as u32, *seeds),
            Scramble::Halton(shifts) => std::array::from_fn(|d| halton(index, HALTON_BASES[d], &shifts[d])),
        }
    }

    /// The stream from its point `index` on: for the quasi-random sequences, the same points
    /// as after drawing `index` of them, so that streams drawn one after another continue one
    /// low-discrepancy sequence; for `random`, an independent stream keyed by `index` too.
    pub fn from_index(mut self, index: u64) -> PointStream {
        match self.scramble {
            Scramble::None => self.random = SplitMix(mix(self.random.0 ^ mix(index))),
            _ => self.index = index,
        }
        self
    }

    /// The stream `count` points further on: the points it would give after drawing `count`
    /// more, without drawing them (a patch's rays cast in parts, each part from its own place).
    pub fn skipped(mut self, count: u64) -> PointStream {
        match self.scramble {
            // A random point takes a number of each coordinate.
            Scramble::None => self.random.0 = self.random.0.wrapping_add(GAMMA.wrapping_mul(4 * count)),
            _ => self.index += count,
        }
        self
    }

    /// The stream with its pseudo-random part ([`PointStream::uniform`], and the points of
    /// `random`) keyed by `key` too, its quasi-random points unchanged.
    pub fn rekeyed(mut self, key: u64) -> PointStream {
        self.random = SplitMix(mix(self.random.0 ^ mix(key.wrapping_add(0x5851_f42d_4c95_7f2d))));
        self
    }

    /// A uniform number in `[0, 1)` from the stream's pseudo-random part, whatever the sequence
    /// (for choices beside the rays: rounding a ray count).
    pub fn uniform(&mut self) -> Real {
        self.random.unit()
    }
}

/// The radical inverse of `index` in `base`, each digit position `k` shifted by
/// `shifts[k] mod base`; in `[0, 1)`.
fn halton(index: u64, base: u64, shifts: &[u64; HALTON_DIGITS]) -> Real {
    let (mut rest, mut scale, mut x) = (index, 1.0 / base as Real, 0.0);
    for &shift in shifts {
        // Digits beyond the index's are zero, shifted too: the point is uniform.
        let digit = (rest % base + shift % base) % base;
        x += digit as Real * scale;
        rest /= base;
        scale /= base as Real;
        if scale < 1e-17 {
            break;
        }
    }
    x.min(1.0 - Real::EPSILON / 2.0)
}

/// SplitMix64's finaliser: a bijective mix of 64 bits.
pub(crate) fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// SplitMix64 (module doc).
#[derive(Clone, Debug)]
struct SplitMix(u64);

/// SplitMix64's step: its state advances by this at each number.
const GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GAMMA);
        mix(self.0)
    }

    /// A uniform number in `[0, 1)` of 53 bits.
    fn unit(&mut self) -> Real {
        (self.next() >> 11) as Real / (1u64 << 53) as Real
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mean_and_spread(sequence: Sequence, points: usize, streams: u64) -> (Real, Real) {
        // The integral of x y z w over the cube is 1/16: the spread of its estimate over
        // independent streams.
        let estimates: Vec<Real> = (0..streams)
            .map(|s| {
                let mut stream = sequence.stream(7, [s, 0, 0]);
                (0..points).map(|_| stream.next_point().iter().product::<Real>()).sum::<Real>() / points as Real
            })
            .collect();
        let mean = estimates.iter().sum::<Real>() / streams as Real;
        let var = estimates.iter().map(|e| (e - mean).powi(2)).sum::<Real>() / (streams - 1) as Real;
        (mean, var.sqrt())
    }

    #[test]
    fn every_sequence_is_unbiased_and_the_quasi_random_ones_spread_less() {
        let (_, random) = mean_and_spread(Sequence::Random, 1024, 64);
        for sequence in [Sequence::Random, Sequence::Sobol, Sequence::Halton] {
            let (mean, spread) = mean_and_spread(sequence, 1024, 64);
            // Within 4 standard errors of the mean of 64 streams.
            assert!((mean - 1.0 / 16.0).abs() < 4.0 * spread / 8.0 + 1e-12, "{sequence:?}: {mean}");
            if sequence != Sequence::Random {
                assert!(spread < random / 4.0, "{sequence:?}: {spread} against {random}");
            }
        }
    }

    #[test]
    fn streams_are_keyed_and_repeatable() {
        for sequence in [Sequence::Random, Sequence::Sobol, Sequence::Halton] {
            let a: Vec<_> = (0..4)
                .map({
                    let mut s = sequence.stream(1, [2, 3, 4]);
                    move |_| s.next_point()
                })
                .collect();
            let b: Vec<_> = (0..4)
                .map({
                    let mut s = sequence.stream(1, [2, 3, 4]);
                    move |_| s.next_point()
                })
                .collect();
            let c: Vec<_> = (0..4)
                .map({
                    let mut s = sequence.stream(1, [2, 3, 5]);
                    move |_| s.next_point()
                })
                .collect();
            assert_eq!(a, b);
            assert_ne!(a, c);
            assert!(a.iter().flatten().all(|&x| (0.0..1.0).contains(&x)));
            // Skipping points gives the points drawing them would have left next.
            let mut drawn = sequence.stream(1, [2, 3, 4]);
            drawn.uniform();
            let mut skipped = drawn.clone().skipped(2);
            drawn.next_point();
            drawn.next_point();
            assert_eq!(skipped.next_point(), drawn.next_point(), "{sequence:?}");
        }
    }
}
