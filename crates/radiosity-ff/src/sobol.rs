//! Owen-scrambled Sobol points in four dimensions, drawn from a random stream: the joint
//! stratification of a shadow segment's two ends. The sequence and its scrambling are
//! [`radiosity_core::sobol`]'s.

use radiosity_core::Real;
use radiosity_core::sobol::scrambled_point;
use rand::Rng;

/// Calls `f` with the first `k` points of the four-dimensional Sobol sequence, each dimension
/// Owen-scrambled with a seed drawn from `rng`; coordinates lie in `(0, 1)`.
pub fn scrambled_sobol<R: Rng>(k: usize, rng: &mut R, mut f: impl FnMut(&mut R, [Real; 4])) {
    let seeds: [u32; 4] = std::array::from_fn(|_| rng.random());
    for p in 0..k.min(u32::MAX as usize) as u32 {
        f(rng, scrambled_point(p, seeds));
    }
}
