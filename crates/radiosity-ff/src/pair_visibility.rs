//! The visible fraction of a pair of patches, weighted by the form-factor kernel, estimated
//! with stratified shadow rays and refined adaptively where the first rays disagree.
//!
//! ## The quantity
//!
//! For patches `a`, `b` the analytic backend computes the unoccluded `U_ab` exactly and
//! multiplies it by
//!
//! `V_ab = ∫_a ∫_b K(x, y) v(x, y) dy dx / ∫_a ∫_b K(x, y) dy dx`,
//!
//! `K = cos θ_x cos θ_y / (π r²)` the kernel and `v ∈ {0, 1}` the segment's visibility, so
//! that `U_ab V_ab` is the occluded form factor (Cohen & Wallace 1993, §4.9; Sillion & Puech
//! 1994, §3.3). `K` is zero unless `x` is in front of `b`'s plane and `y` in front of `a`'s,
//! so both integrals run over `L × H`: `a` cut by `b`'s plane and `b` cut by `a`'s, convex
//! polygons.
//!
//! ## How many rays
//!
//! A pair gets `k = max(rays, ⌈budget · u⌉)` segments, `u` its larger unoccluded form factor
//! (the one of its smaller patch). A row's error is `Σ_j U_ij (V̂_ij − V_ij)`; with the
//! variance of `V̂` falling like `1/k`, giving each pair rays in proportion to `U` makes a row's
//! variance at most `σ² Σ_j U_ij / budget`, whatever the sizes of its pairs, and a row's
//! rays at most `budget · Σ_j U_ij` on top of one per pair. The many distant pairs of a large
//! scene get one ray each, the few near ones hundreds.
//!
//! ## Few rays: both ends drawn by the kernel
//!
//! With `k < 16`, each segment's ends are drawn in proportion to the kernel, so that each
//! segment is clear with probability exactly `V` and the estimate, the clear fraction, is
//! unbiased for any `k`: `x` on `L` in proportion to `F(dA_x → H)` by rejection from uniform
//! points (bounded by the largest value at `L`'s corners, edge midpoints and centre, with a
//! margin of 1.25;
//! such pairs are small against their distance, where `F(dA_x → H)` varies little), and
//! `y` on `H` in proportion to `cos θ_x cos θ_y / r²` from `x`: a direction uniform in `H`'s
//! solid angle at `x` (Arvo 1995, [`crate::solid_angle`]) is kept with probability
//! `cos θ_x / max cos θ_x`, the cosine at `y` and `1/r²` being the solid angle's own measure.
//! The one-ray estimator this replaces drew both ends uniformly by area, which weights
//! visibility by area rather than by the kernel (0.5% low in the row sums of a box with a
//! block), and drew them on the whole patches: a segment to the part of `b` behind `a`'s
//! plane enters `a`'s own solid and is blocked.
//!
//! ## Many rays: stratified, weighted exactly
//!
//! With `k ≥ 16`, `H` is cut into strata `S` (cells of `b`'s parameter square cut by `a`'s
//! plane, `s² = min(⌊k^{1/4}⌋, 8)²` of them), `k / s²` points `x` are stratified on `L` (a
//! Latin hypercube, mapped to `L` by area), each point is joined to a point `y` drawn in
//! every stratum in proportion to the kernel (as above), and
//!
//! `V̂ = Σ_x Σ_S F(dA_x → S) v(x, y_S) / Σ_x Σ_S F(dA_x → S)`,
//!
//! with `F(dA_x → S)` Lambert's exact point-to-polygon factor. Each point's strata carry its
//! kernel exactly (`Σ_S F(dA_x → S) = F(dA_x → H)`), a fully visible pair gives exactly 1 and
//! a hidden one exactly 0, and the one bias left, of the ratio over the points `x`, falls
//! like `1/k`. Two other weights were measured and dropped: the point-to-point kernel of each
//! segment, and a stratum's factor seen from an independent point; both give a few segments
//! near a shared edge weights thousands of times the typical one.
//!
//! ## Probes
//!
//! Most pairs of a scene are fully visible or fully hidden, and need no refinement. A pair
//! given `k ≥ 16` rays is first probed with `k / 16` segments stratified over both patches.
//! When they agree (all clear or all blocked) the pair is estimated from `k / 16` fresh
//! segments, otherwise from `k` fresh ones. The estimate never reuses the probe: an estimate
//! from the very segments that decided to stop is biased (a pair 20% visible whose few probes
//! all happen to be blocked would count as hidden, and nothing would make up for it; on
//! `multi-cubes`, whose partly visible pairs are mostly hidden, that put the mean row sum
//! 1.5% low). With the decision and the estimate independent, the estimate's expectation is
//! `V` whichever way the probe decided, and a fully visible or hidden pair still comes out
//! exactly 1 or 0. This is the visibility classification of hierarchical radiosity
//! (Hanrahan, Salzman & Aupperle 1991), with rays instead of shafts.
//!
//! The samples come from the caller's random stream, keyed by the unordered pair, so `V_ab =
//! V_ba` exactly and a pair's value does not depend on the thread or column that computes it.

use crate::ff_point_polygon::{MAX_CLIPPED, clip_above, point_to_polygon};
use crate::quadrature::parametrisation;
use crate::solid_angle::{SphericalPolygon, pick_fan_triangle};
use radiosity_core::{Patch, Real, Vec3};
use rand::Rng;
use rand::seq::SliceRandom;

/// Pairs given fewer rays than this are sampled without a probe.
const PROBED: usize = 16;
/// A probe traces this fraction of the pair's rays (at least 2).
const PROBE_SHARE: usize = 16;
/// The most strata along each side of `b`'s parameter square (64 strata).
const MAX_SIDE: usize = 8;
/// Points per sampling round kept on the stack.
const STACK_POINTS: usize = 64;

/// A convex polygon of at most [`MAX_CLIPPED`] vertices with its fan triangles' cumulative
/// areas, to draw points uniformly by area.
#[derive(Clone, Copy)]
struct Region {
    vertices: [Vec3; MAX_CLIPPED],
    count: usize,
    /// `cumulative[t]`: the area of fan triangles `0..=t` (triangle `t` is `0, t+1, t+2`).
    cumulative: [Real; MAX_CLIPPED - 2],
}

impl Region {
    const EMPTY: Region = Region { vertices: [Vec3::ZERO; MAX_CLIPPED], count: 0, cumulative: [0.0; MAX_CLIPPED - 2] };

    /// `polygon` cut to the closed half-space `n · (y − o) ≥ 0`.
    fn clipped(polygon: &[Vec3], o: Vec3, n: Vec3) -> Region {
        let mut region = Region::EMPTY;
        region.count = clip_above(o, n, polygon, &mut region.vertices);
        let mut area = 0.0;
        for t in 0..region.count.saturating_sub(2) {
            let v = &region.vertices;
            area += 0.5 * (v[t + 1] - v[0]).cross(v[t + 2] - v[0]).length();
            region.cumulative[t] = area;
        }
        region
    }

    fn area(&self) -> Real {
        if self.count < 3 { 0.0 } else { self.cumulative[self.count - 3] }
    }

    fn polygon(&self) -> &[Vec3] {
        &self.vertices[..self.count]
    }

    /// The point at `(u, v) ∈ [0, 1)²`, uniform by area when `(u, v)` is uniform: `u` picks
    /// the fan triangle and is rescaled within it, then Shirley's square-to-triangle warp.
    /// Stratified `(u, v)` stay spread out.
    fn point_at(&self, u: Real, v: Real) -> Vec3 {
        let (t, s, _) = pick_fan_triangle(&self.cumulative[..self.count - 2], u);
        let r = s.sqrt();
        let w = &self.vertices;
        w[0] * (1.0 - r) + w[t + 1] * (r * (1.0 - v)) + w[t + 2] * (r * v)
    }
}

/// The running sums of one pair's estimate.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    /// `Σ F(dA_x → S) v`.
    visible: Real,
    /// `Σ F(dA_x → S)`.
    total: Real,
}

/// How many shadow rays a pair gets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayBudget {
    /// The fewest rays of a pair.
    pub rays: usize,
    /// The rays of a pair whose larger unoccluded form factor is 1; a pair gets this times
    /// its larger unoccluded form factor.
    pub per_unit: usize,
}

impl RayBudget {
    /// The rays of a partially visible pair whose larger unoccluded form factor is `u`:
    /// `per_unit · u` rounded up, at least `rays`.
    pub fn rays(&self, u: Real) -> usize {
        self.rays.max(scaled(self.per_unit, u))
    }
}

/// `⌈count · u⌉` for `u ∈ [0, 1]`.
fn scaled(count: usize, u: Real) -> usize {
    (count as Real * u.clamp(0.0, 1.0)).ceil() as usize
}

/// The kernel-weighted visible fraction of the pair `(a, b)` (module documentation), whose
/// larger unoccluded form factor is `u`, with the rays `budget` gives it. `tolerance` is the
/// distance below which a point counts as on a plane. `trace(x, ia, y, ib)` answers whether
/// the segment from `x` on `a` (index `ia`) to `y` on `b` (index `ib`) is clear.
pub fn visible_fraction(
    (a, ia): (&Patch, usize),
    (b, ib): (&Patch, usize),
    u: Real,
    budget: RayBudget,
    tolerance: Real,
    rng: &mut impl Rng,
    trace: &mut impl FnMut(Vec3, usize, Vec3, usize) -> bool,
) -> Real {
    // L: a in front of b's plane; H: b in front of a's plane (a hair forward, so points on a
    // plane count as behind it).
    let (na, nb) = (a.normal(), b.normal());
    let lower = Region::clipped(a.vertices(), b.vertices()[0] + nb * tolerance, nb);
    let upper = Region::clipped(b.vertices(), a.vertices()[0] + na * tolerance, na);
    if lower.area() <= 0.0 || upper.area() <= 0.0 {
        return 1.0;
    }
    let pair = Pair { lower, upper, b, na, oa: a.vertices()[0], tolerance, ia, ib };
    let mut sums = Sums::default();
    let k = budget.rays(u);
    if k < PROBED {
        pair.sample(k, rng, trace, &mut sums);
    } else {
        // Decide with the probe, estimate with fresh segments: the estimate's expectation is
        // then V whatever the probe decided (module documentation, "Adaptive refinement").
        let probe = (k / PROBE_SHARE).max(2);
        let clear = pair.probe(probe, rng, trace);
        let agreed = clear == 0 || clear == probe;
        pair.sample(if agreed { probe } else { k }, rng, trace, &mut sums);
    }
    if sums.total > 0.0 { sums.visible / sums.total } else { 1.0 }
}

/// What sampling one pair needs.
struct Pair<'p> {
    /// `a` cut by `b`'s plane.
    lower: Region,
    /// `b` cut by `a`'s plane.
    upper: Region,
    /// The patch the strata cut.
    b: &'p Patch,
    /// `a`'s normal.
    na: Vec3,
    /// A point of `a`'s plane.
    oa: Vec3,
    tolerance: Real,
    ia: usize,
    ib: usize,
}

impl Pair<'_> {
    /// Traces `k` segments whose ends are stratified over both `L` and `H` (a Latin hypercube
    /// on each, paired at random) and returns how many are clear. Only whether they agree is
    /// used, so they spread over the pair as far as `k` segments can.
    fn probe(&self, k: usize, rng: &mut impl Rng, trace: &mut impl FnMut(Vec3, usize, Vec3, usize) -> bool) -> usize {
        let mut clear = 0;
        latin_hypercube(k, rng, |_, [x, y]| {
            let x = self.lower.point_at(x.0, x.1);
            let y = self.upper.point_at(y.0, y.1);
            clear += usize::from(trace(x, self.ia, y, self.ib));
        });
        clear
    }

    /// Adds `k < 16` segments to `sums`, each with both ends drawn in proportion to the
    /// kernel (module documentation), so that each one's visibility has expectation `V`:
    /// `x` on `L` in proportion to `F(dA_x → H)` by rejection, `y` on `H` from `x` by
    /// [`kernel_point`]. Each segment weighs the same.
    fn sample_few(
        &self,
        k: usize,
        rng: &mut impl Rng,
        trace: &mut impl FnMut(Vec3, usize, Vec3, usize) -> bool,
        sums: &mut Sums,
    ) {
        let seen_from = |x: Vec3| point_to_polygon(x, self.na, self.upper.polygon());
        // F(dA_x → H) at the corners, edge midpoints and centre of L, with a margin, bounds it
        // on L: a pair given this few rays is small against its distance, where F varies
        // little (module documentation).
        let lower = self.lower.polygon();
        let centre = lower.iter().copied().sum::<Vec3>() / lower.len() as Real;
        let midpoints = (0..lower.len()).map(|e| 0.5 * (lower[e] + lower[(e + 1) % lower.len()]));
        let largest = lower.iter().copied().chain(midpoints).chain([centre]).map(seen_from).fold(0.0, Real::max);
        let bound = (FEW_MARGIN * largest).min(1.0);
        if bound <= 0.0 {
            return;
        }
        for _ in 0..k {
            let mut x = centre;
            for _ in 0..MAX_TRIES {
                x = self.lower.point_at(rng.random(), rng.random());
                if rng.random::<Real>() * bound <= seen_from(x) {
                    break;
                }
            }
            let Some(y) = kernel_point(x, self.na, self.upper.polygon(), rng) else { continue };
            let clear = trace(x, self.ia, y, self.ib);
            sums.total += 1.0;
            if clear {
                sums.visible += 1.0;
            }
        }
    }

    /// Adds about `k` segments to `sums`: `side²` strata of `b` cut by `a`'s plane, and
    /// `k / side²` Latin-hypercube points on `L`, each joined to every stratum.
    fn sample(
        &self,
        k: usize,
        rng: &mut impl Rng,
        trace: &mut impl FnMut(Vec3, usize, Vec3, usize) -> bool,
        sums: &mut Sums,
    ) {
        let side = ((k as Real).powf(0.25).floor() as usize).clamp(1, MAX_SIDE);
        if side == 1 {
            return self.sample_few(k, rng, trace, sums);
        }
        let points = (k / (side * side)).max(1);
        let cell = 1.0 / side as Real;
        let mut strata = [Region::EMPTY; MAX_SIDE * MAX_SIDE];
        let origin = self.oa + self.na * self.tolerance;
        for (c, stratum) in strata.iter_mut().enumerate().take(side * side) {
            let (s0, t0) = ((c % side) as Real * cell, (c / side) as Real * cell);
            let corners = [(s0, t0), (s0 + cell, t0), (s0 + cell, t0 + cell), (s0, t0 + cell)]
                .map(|(s, t)| parametrisation(self.b, s, t).0);
            *stratum = Region::clipped(&corners, origin, self.na);
        }
        let strata = &strata[..side * side];
        latin_hypercube(points, rng, |rng, [(u, v)]| {
            let x = self.lower.point_at(u, v);
            for stratum in strata {
                if stratum.area() <= 0.0 {
                    continue;
                }
                let weight = point_to_polygon(x, self.na, stratum.polygon());
                if weight <= 0.0 {
                    continue;
                }
                let Some(y) = kernel_point(x, self.na, stratum.polygon(), rng) else { continue };
                let clear = trace(x, self.ia, y, self.ib);
                sums.total += weight;
                if clear {
                    sums.visible += weight;
                }
            }
        });
    }
}

/// Draws tried by a rejection before taking the last one (module documentation).
const MAX_TRIES: usize = 64;
/// The margin on the largest `F(dA_x → H)` found at the corners and centre of `L`, for
/// drawing `x` by rejection.
const FEW_MARGIN: Real = 1.25;

/// A point `y` of `polygon` drawn with density in proportion to the kernel from `x` (normal
/// `n`): a direction uniform in the polygon's solid angle (Arvo), kept with probability
/// `cos θ_x` over its largest value on the polygon. `None` when the polygon subtends nothing.
fn kernel_point(x: Vec3, n: Vec3, polygon: &[Vec3], rng: &mut impl Rng) -> Option<Vec3> {
    let seen = SphericalPolygon::new(x, polygon);
    let bound = seen.max_cosine(n);
    if bound <= 0.0 {
        return None;
    }
    let mut last = None;
    for _ in 0..MAX_TRIES {
        let y = seen.point_at(x, rng.random(), rng.random())?;
        if rng.random::<Real>() * bound <= n.dot((y - x).normalize_or_zero()) {
            return Some(y);
        }
        last = Some(y);
    }
    last
}

/// Calls `f` with `k` points of the unit square for each of `N ≤ 2` squares: on each square a
/// Latin hypercube (every row and every column of the `k × k` grid holds one point,
/// jittered within its cell), and the squares' points paired at random. `f` gets the random
/// stream back. The permutations stay on the stack for the usual counts, so that a pair
/// allocates nothing.
fn latin_hypercube<R: Rng, const N: usize>(k: usize, rng: &mut R, mut f: impl FnMut(&mut R, [(Real, Real); N])) {
    let mut stack = [0u32; 4 * STACK_POINTS];
    let mut heap = Vec::new();
    let orders: &mut [u32] = if 2 * N * k <= stack.len() {
        &mut stack[..2 * N * k]
    } else {
        heap.resize(2 * N * k, 0u32);
        &mut heap
    };
    for order in orders.chunks_mut(k) {
        order.iter_mut().enumerate().for_each(|(p, slot)| *slot = p as u32);
        order.shuffle(rng);
    }
    let scale = 1.0 / k as Real;
    for p in 0..k {
        let points = std::array::from_fn(|d| {
            let u = (orders[2 * d * k + p] as Real + rng.random::<Real>()) * scale;
            let v = (orders[(2 * d + 1) * k + p] as Real + rng.random::<Real>()) * scale;
            (u, v)
        });
        f(rng, points);
    }
}
