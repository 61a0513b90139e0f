//! The `montecarlo` backend: cosine-weighted rays from points spread over the shooter count
//! the fraction of its power each patch receives, giving the shooter's row; reciprocity
//! turns the row into the column.
//!
//! ## Rule
//!
//! From patch `j`, `N = rays` rays leave points `x_r` uniformly distributed over `j`'s area,
//! in directions `ω_r` distributed as `cos θ / π` about `j`'s normal. With `h_i` the number
//! of rays whose first hit is the **front** side of patch `i`,
//!
//! `F̂_ji = h_i / N`,  and the column entry  `F̂_ij = F̂_ji A_j / A_i`
//!
//! (reciprocity, docs/design.md §3.3); when `A_j > A_i` noise alone can push `F̂_ij` above 1,
//! and the guard clamps and counts it ([`crate::guard`]). Because `F_ji = (1/A_j) ∫_{A_j} ∫ [ray (x, ω) first hits the
//! front of i] cos θ / π dω dA`, the hit indicator has mean `F_ji` under this sampling and
//! `F̂_ji` is unbiased (Bekaert 1999, ch. 4). Rays arriving on a patch's back carry light into
//! the inside of an object or behind a one-sided surface: they reach no receiver and count
//! for nothing, as in the hemicube backend. Rays that hit nothing leave the scene. So
//! `Σ_i h_i + back + escaped = N` exactly ([`RayTally`]), and a closed scene facing inwards
//! has rows summing to exactly 1.
//!
//! ## Sampling
//!
//! The four coordinates of a ray are drawn by Latin hypercube sampling (McKay, Beckman &
//! Conover 1979): each of `s, t` (the point) and `u₁, u₂` (the direction) is cut into `N`
//! equal strata, and a random permutation per coordinate pairs the strata, with a uniform
//! jitter inside each. Every ray is still marginally uniform, so the estimator stays
//! unbiased; the strata only remove variance. The coordinates are mapped, preserving
//! measure:
//!
//! - point: `s` picks one of the patch's fan triangles in proportion to its area, and is
//!   rescaled inside that choice; `(s', t)` maps onto the triangle by
//!   `(1 − √s') v₀ + √s' (1 − t) v₁ + √s' t v₂` (Turk 1990), uniform by area on any convex
//!   quad or triangle (the bilinear map of a non-parallelogram quad would not be);
//! - direction: Malley's method, a uniform point `(√u₁ cos 2πu₂, √u₁ sin 2πu₂)` of the unit
//!   disc lifted to the hemisphere, `z = √(1 − u₁)`, which is cosine-distributed.
//!
//! Rays go in batches of at most [`MAX_BATCH`] (`N` is split into nearly equal batches), each
//! an independent Latin hypercube, so memory stays bounded for any `N`. Batch `k` of shooter
//! `j` draws from a ChaCha8 stream keyed by the seed and `j`, at word offset `k · 2³²`; the
//! batches are traced in parallel (rayon) and the counts are integers, so a column is the
//! same bit for bit whatever the thread count or the order in which columns are asked.
//!
//! ## Variance
//!
//! With independent rays, `h_i` would be one cell of a multinomial count and
//! `Var(F̂_ji) = F_ji (1 − F_ji) / N`. A Latin hypercube sample of `B ≥ 2` points is a
//! scrambled `(0, 1, s)`-net in base `B`, whose variance never exceeds `B / (B − 1)` times
//! that of `B` independent points (Owen 1997); over independent batches of at least `B`
//! rays the same factor bounds the whole estimate. The reported variance is therefore the
//! **plug-in** bound
//!
//! `Var(F̂_ji) ≤ c · F̂_ji (1 − F̂_ji) / N`,  `c = B_min / (B_min − 1)` (`c = 1` when `N = 1`),
//!
//! estimated from the sample itself (the unknown `F_ji` replaced by `F̂_ji`), and for the
//! column entry `Var(F̂_ij) = (A_j / A_i)² Var(F̂_ji)`. It is conservative: the tests measure
//! the actual spread across seeds well below it. An entry with no hit reports variance 0,
//! which says only that the sample saw nothing there.
//!
//! ## References
//!
//! - P. Bekaert, *Hierarchical and Stochastic Algorithms for Radiosity*, PhD thesis,
//!   KU Leuven, 1999 (stochastic form factors by local lines).
//! - T. J. V. Malley, *A Shading Method for Computer Generated Images*, MSc thesis,
//!   University of Utah, 1988 (cosine-weighted directions from the unit disc).
//! - G. Turk, "Generating random points in triangles", *Graphics Gems*, 1990.
//! - M. D. McKay, R. J. Beckman, W. J. Conover, "A comparison of three methods for selecting
//!   values of input variables in the analysis of output from a computer code",
//!   Technometrics 21(2), 1979.
//! - A. B. Owen, "Monte Carlo variance of scrambled net quadrature", SIAM J. Numer. Anal.
//!   34(5), 1997.

use crate::backend::FormFactorBackend;
use crate::guard::ClampCounter;
use radiosity_core::math::cosine_direction;
use radiosity_core::{ColumnSource, Patch, Real, Scene, Vec3};
use radiosity_geom::{ParamDoc, Visibility};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Parameters of the Monte Carlo backend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MonteCarloParams {
    /// Cosine-weighted rays shot from each patch.
    pub rays: usize,
    /// Seed of the rays.
    pub seed: u64,
}

/// Parameters of `montecarlo`.
pub const MONTECARLO_PARAMS: &[ParamDoc] = &[
    ParamDoc { key: "rays", default: "10000", doc: "cosine-weighted rays per shooting patch, 1 to 10^9" },
    ParamDoc { key: "seed", default: "0", doc: "seed of the rays" },
];

/// The largest Latin hypercube batch, in rays.
pub const MAX_BATCH: usize = 4096;
/// Batches traced together before their hits are counted (bounds memory for huge `N`).
const BATCHES_PER_ROUND: usize = 64;

/// Monte Carlo form-factor columns of one scene.
#[derive(Debug)]
pub struct MonteCarloColumns<'a> {
    scene: &'a Scene,
    visibility: Visibility,
    params: MonteCarloParams,
    clamped: ClampCounter,
}

/// What the rays of one shooter did.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct RayTally {
    /// Rays shot (`N`; 0 for a patch index out of range).
    pub rays: u64,
    /// `front[i]`: rays whose first hit is the front side of patch `i` (`h_i`).
    pub front: Vec<u64>,
    /// Rays whose first hit is the back side of a patch.
    pub back: u64,
    /// Rays that hit nothing.
    pub escaped: u64,
}

/// What one ray did.
#[derive(Clone, Copy, Debug)]
enum Outcome {
    Front(usize),
    Back,
    Escaped,
}

/// Uniform sampling by area over a patch's fan triangles (also the scene sampler's origins,
/// [`crate::scene_transport`]).
#[derive(Clone, Debug)]
pub(crate) struct AreaSampler {
    triangles: [[Vec3; 3]; 2],
    /// The fraction of the area in the first triangle (1 for a triangle patch).
    split: Real,
}

impl AreaSampler {
    pub(crate) fn new(patch: &Patch) -> AreaSampler {
        let mut triangles = [[Vec3::ZERO; 3]; 2];
        let mut areas = [0.0; 2];
        for (k, tri) in patch.triangles().take(2).enumerate() {
            triangles[k] = tri;
            areas[k] = (tri[1] - tri[0]).cross(tri[2] - tri[0]).length();
        }
        let total = areas[0] + areas[1];
        let split = if total > 0.0 && areas[1] > 0.0 { areas[0] / total } else { 1.0 };
        AreaSampler { triangles, split }
    }

    /// The point at `(s, t)` in the unit square; uniform `(s, t)` give points uniform by area.
    pub(crate) fn point(&self, s: Real, t: Real) -> Vec3 {
        let (tri, s) = if s < self.split || self.split >= 1.0 {
            (&self.triangles[0], s / self.split)
        } else {
            (&self.triangles[1], ((s - self.split) / (1.0 - self.split)).min(1.0))
        };
        let r = s.sqrt();
        tri[0] * (1.0 - r) + tri[1] * (r * (1.0 - t)) + tri[2] * (r * t)
    }
}

/// The sizes of the batches `n` rays are split into: nearly equal, none above [`MAX_BATCH`].
pub(crate) fn batch_sizes(n: usize) -> (usize, usize, usize) {
    let count = n.div_ceil(MAX_BATCH);
    if count == 0 {
        return (0, 0, 0);
    }
    (count, n / count, n % count)
}

/// The rays `(origin, direction)` of batch `k` of shooter `j` (patch `patch`): `size` rays,
/// one Latin hypercube over origin and direction, drawn from the stream of `j` at the batch's
/// own position, so every batch is the same whichever thread draws it. [`crate::traced`]
/// lists the same rays for benchmarks.
pub(crate) fn batch_rays(
    seed: u64,
    j: usize,
    patch: &Patch,
    k: usize,
    size: usize,
) -> impl Iterator<Item = (Vec3, Vec3)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(j as u64);
    rng.set_word_pos((k as u128) << 32);
    let mut strata: [Vec<u32>; 4] = std::array::from_fn(|_| (0..size as u32).collect());
    for s in &mut strata {
        s.shuffle(&mut rng);
    }
    let n = patch.normal();
    let sampler = AreaSampler::new(patch);
    let jitter = move |stratum: u32, rng: &mut ChaCha8Rng| (stratum as Real + rng.random::<Real>()) / size as Real;
    (0..size).map(move |r| {
        let origin = sampler.point(jitter(strata[0][r], &mut rng), jitter(strata[1][r], &mut rng));
        let (u1, u2) = (jitter(strata[2][r], &mut rng), jitter(strata[3][r], &mut rng));
        (origin, cosine_direction(n, u1, u2))
    })
}

impl<'a> MonteCarloColumns<'a> {
    /// Prepares the backend.
    pub fn new(scene: &'a Scene, visibility: &Visibility, params: MonteCarloParams) -> MonteCarloColumns<'a> {
        MonteCarloColumns { scene, visibility: visibility.clone(), params, clamped: ClampCounter::default() }
    }

    /// Entries clamped into `[0, 1]` so far.
    pub fn clamped(&self) -> u64 {
        self.clamped.count()
    }

    /// The factor `c ≥ 1` by which the reported variance inflates the multinomial one to
    /// bound the Latin hypercube batches' variance: `B / (B − 1)` for the smallest batch `B`.
    pub fn variance_factor(&self) -> Real {
        let (_, smallest, _) = batch_sizes(self.params.rays);
        if smallest >= 2 { smallest as Real / (smallest - 1) as Real } else { 1.0 }
    }

    /// Shoots the rays of patch `j` and counts what they hit. A `j` out of range shoots
    /// nothing.
    pub fn tally(&self, j: usize) -> RayTally {
        let n = self.scene.len();
        let mut tally = RayTally { rays: 0, front: vec![0; n], back: 0, escaped: 0 };
        let Some(patch) = self.scene.patches().get(j) else {
            return tally;
        };
        let (count, base, extra) = batch_sizes(self.params.rays);
        let mut outcomes: Vec<Vec<Outcome>> = Vec::new();
        for first in (0..count).step_by(BATCHES_PER_ROUND) {
            (first..(first + BATCHES_PER_ROUND).min(count))
                .into_par_iter()
                .map(|k| self.batch(j, patch, k, base + usize::from(k < extra)))
                .collect_into_vec(&mut outcomes);
            for outcome in outcomes.iter().flatten() {
                match *outcome {
                    Outcome::Front(i) => tally.front[i] += 1,
                    Outcome::Back => tally.back += 1,
                    Outcome::Escaped => tally.escaped += 1,
                }
            }
        }
        tally.rays = self.params.rays as u64;
        tally
    }

    /// Batch `k` of shooter `j`: `size` rays, one Latin hypercube.
    fn batch(&self, j: usize, patch: &Patch, k: usize, size: usize) -> Vec<Outcome> {
        batch_rays(self.params.seed, j, patch, k, size)
            .map(|(origin, direction)| match self.visibility.first_hit(origin, direction, Some(j)) {
                Some(hit) if hit.front => Outcome::Front(hit.patch),
                Some(_) => Outcome::Back,
                None => Outcome::Escaped,
            })
            .collect()
    }

    /// Column `j` (`column[i] = F̂_ij`, clamped like [`ColumnSource::fill_column`]'s, which
    /// gives the same values) and, for every `i`, the plug-in variance bound of that entry
    /// (see the module documentation). Entries beyond the scene's patches are set to 0.
    pub fn column_with_variance(&self, j: usize, column: &mut [Real], variance: &mut [Real]) {
        column.fill(0.0);
        variance.fill(0.0);
        let tally = self.tally(j);
        let patches = self.scene.patches();
        if let (Some(shooter), true) = (patches.get(j), tally.rays > 0) {
            let rays = tally.rays as Real;
            let factor = self.variance_factor();
            for (i, (&hits, receiver)) in tally.front.iter().zip(patches).enumerate() {
                let fji = hits as Real / rays;
                let ratio = shooter.area() / receiver.area();
                if let Some(f) = column.get_mut(i) {
                    *f = fji * ratio;
                }
                if let Some(v) = variance.get_mut(i) {
                    *v = ratio * ratio * factor * fji * (1.0 - fji) / rays;
                }
            }
        }
        self.clamped.clamp(column);
    }
}

impl ColumnSource for MonteCarloColumns<'_> {
    fn patch_count(&self) -> usize {
        self.scene.len()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        self.column_with_variance(j, column, &mut [])
    }
}

/// Monte Carlo columns are not reciprocal: a row of the matrix they assemble would need every
/// column.
impl FormFactorBackend for MonteCarloColumns<'_> {
    fn clamped(&self) -> u64 {
        MonteCarloColumns::clamped(self)
    }
}
