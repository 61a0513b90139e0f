//! The visible fraction of a pair of patches, weighted by the form-factor kernel, estimated with
//! stratified shadow rays and refined adaptively where the first rays disagree.
//!
//! For patches `a`, `b` the analytic backend computes the unoccluded `U_ab` exactly and multiplies
//! it by `V_ab = ∫_a ∫_b K(x, y) v(x, y) dy dx / ∫_a ∫_b K(x, y) dy dx`, with
//! `K = cos θ_x cos θ_y / (π r²)` the kernel and `v ∈ {0, 1}` the segment's visibility, so that
//! `U_ab V_ab` is the occluded form factor (Cohen & Wallace 1993, §4.9; Sillion & Puech 1994,
//! §3.3). `K` is zero unless `x` is in front of `b`'s plane and `y` in front of `a`'s, so both
//! integrals run over `L × H`: `a` cut by `b`'s plane and `b` cut by `a`'s, convex polygons. The
//! design's history and its measurements are in `docs/visibility-estimator.md`.
//!
//! ## How many rays
//!
//! A pair gets `k = max(rays, ⌈budget · u⌉)` segments ([`RayBudget`]), `u` its larger unoccluded
//! form factor. With `V̂`'s variance at most about `σ² / k`, a row's error
//! `Σ_j U_ij (V̂_ij − V_ij)` has variance at most about `σ² Σ_j U_ij / budget` whatever its pairs'
//! sizes; `σ²` is `V (1 − V) ≤ 1/4`, or about `0.37` after a chance agreement ("Probes").
//!
//! ## Stiff scenes
//!
//! An error `δ` in the area-weighted mean row sum (its noise falls like `1/√budget`) moves a closed
//! scene's solution by about `δ ρ̄ / (1 − ρ̄)` (docs/design.md §3.2). So where the most
//! reflective channel's area-weighted mean `ρ̄` exceeds 0.8, the budget is multiplied by
//! `((1 − 0.8) / (1 − ρ̄))²`, rounded up, at most 64 ([`stiffness_factor`]): as noisy as at
//! `ρ̄ = 0.8` up to `ρ̄ = 0.975`.
//!
//! ## Which patch is which
//!
//! The points `x` are drawn on `a`, the smaller patch by the caller's quadrature rule (areas, then
//! the lower index), so `(i, j)` and `(j, i)` agree. On `a`, `F(dA_x → H) ≤ 1` averages `u`: no
//! point weighs more than `1/u` times the mean.
//!
//! ## Few rays: both ends drawn by the kernel
//!
//! With `k < 16` both ends of a segment are drawn in proportion to the kernel: the clear fraction
//! is unbiased. Where `K̂`, a bound on the kernel over `L × H`, is at most twice the kernel between
//! the centres, they are drawn jointly: points uniform on `L × H`, kept with probability
//! `K(x, y) / K̂`. Otherwise `x` is drawn on `L` in proportion to `F(dA_x → H)` by rejection,
//! bounded by 1.25 times its largest value at `L`'s centre, corners and edge midpoints (a hair
//! inside); then a direction uniform in `H`'s solid angle (Arvo 1995, [`crate::solid_angle`]) is
//! kept with probability `cos θ_x / max cos θ_x`. First proposals come from a Latin hypercube.
//!
//! ## Many rays: a point per segment, both ends stratified together
//!
//! With `k ≥ 16` each segment takes `x` and its direction to `y` from one point of a
//! four-dimensional Sobol net, Owen-scrambled (Owen 1995, [`crate::sobol`]). Two coordinates map to
//! `L` through a density `p` constant on the cells of a grid over `L`'s parameter square
//! (`⌊√k / 4⌋ ∈ [4, 16]` a side; one cell where `F(dA_x → H)` varies by less than a factor 2), in
//! proportion to the largest `F(dA_x → H)` at each cell's corners and at least `10⁻³` of the
//! largest cell's. Two give the first direction tried in Arvo's map, kept by the cosine test (a
//! rejected one is redrawn outside the net). Then `V̂ = Σ w(x) v(x, y) / Σ w(x)`,
//! `w(x) = F(dA_x → H) / p(x)`: fully visible and hidden pairs give exactly 1 and 0, the ratio's
//! bias falls like `1/k`, and for a boundary that moves with both ends the variance falls faster
//! than `1/k` (He & Wang 2015).
//!
//! ## Probes
//!
//! A pair given `k ≥ 16` rays is first probed with `m = ⌈√k⌉` segments drawn from its grid: if all
//! agree, it is estimated from `f = max(m, ⌈k / 16⌉)` fresh segments, otherwise from `k`. The
//! estimate never reuses the probe, so it is independent of the decision and its expectation is
//! `V` either way: hierarchical radiosity's visibility classification (Hanrahan, Salzman &
//! Aupperle 1991), with rays for shafts. A chance agreement costs variance at most about
//! `e^{−1} / (m f)`: `0.37 / k` up to `k = 256`, and `5.9 / k^{3/2}` beyond. The pairs of
//! `k > 256` are those with the largest unoccluded factors, where a chance agreement moves a row
//! the most (`U` times the error), and the larger estimates add at most a sixteenth of the
//! segments those pairs are given. The random stream is keyed by the
//! unordered pair, so `V_ab = V_ba` exactly.
//!
//! ## References
//!
//! - M. F. Cohen, J. R. Wallace, *Radiosity and Realistic Image Synthesis*, Academic Press 1993.
//! - F. X. Sillion, C. Puech, *Radiosity and Global Illumination*, Morgan Kaufmann 1994.
//! - J. Arvo, "Stratified sampling of spherical triangles", SIGGRAPH 1995, 437–438.
//! - A. B. Owen, "Randomly permuted (t,m,s)-nets and (t,s)-sequences", Springer 1995, 299–317.
//! - Z. He, X. Wang, "On the convergence rate of randomized quasi-Monte Carlo for discontinuous
//!   functions", SIAM J. Numer. Anal. 53(5), 2015.
//! - P. Hanrahan, D. Salzman, L. Aupperle, "A rapid hierarchical radiosity algorithm", SIGGRAPH
//!   1991 (Computer Graphics 25(4)), 197–206.

use crate::ff_point_polygon::{MAX_CLIPPED, clip_above, point_to_polygon, point_to_polygon_each, point_to_polygon_x4};
use crate::sobol::scrambled_sobol;
use crate::solid_angle::{SphericalPolygon, pick_fan_triangle};
use radiosity_core::{Patch, Real, Vec3};
use rand::Rng;
use rand::seq::SliceRandom;

/// Pairs given fewer rays than this are sampled without a probe.
const PROBED: usize = 16;
/// From this many segments on, `x` is stratified and weighed rather than drawn by rejection.
const MANY: usize = 16;
/// Latin-hypercube points whose permutations are kept on the stack: the few segments of a
/// pair (fewer than [`PROBED`] and [`MANY`]). The array is zeroed for every pair, so it is
/// kept no larger (four times larger, it took 4% of a column's time).
const STACK_POINTS: usize = 16;

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
    /// `Σ w v`, `w` each segment's weight.
    visible: Real,
    /// `Σ w`.
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

/// Mean reflectivity up to which a scene gets the budget as given.
const STIFF_FROM: Real = 0.8;
/// The largest stiffness factor.
const MAX_STIFFNESS: usize = 64;

/// The factor on the ray budget of a scene whose most reflective channel has area-weighted
/// mean reflectivity `rho` (module documentation, "Stiff scenes"): `((1 − 0.8) / (1 − ρ̄))²`,
/// rounded up, between 1 and 64.
pub fn stiffness_factor(rho: Real) -> usize {
    // NaN and ρ̄ ≤ 0.8 both take the plain budget.
    if rho.is_nan() || rho <= STIFF_FROM {
        return 1;
    }
    let factor = ((1.0 - STIFF_FROM) / (1.0 - rho.min(1.0 - Real::EPSILON))).powi(2);
    (factor.ceil() as usize).clamp(1, MAX_STIFFNESS)
}

/// `⌈count · u⌉` for `u ∈ [0, 1]`.
fn scaled(count: usize, u: Real) -> usize {
    (count as Real * u.clamp(0.0, 1.0)).ceil() as usize
}

/// The kernel-weighted visible fraction of the pair `(a, b)` (module documentation), whose
/// larger unoccluded form factor is `u`, with the rays `budget` gives it. `a` should be the
/// smaller patch, whose factor `u` is: its points are the ones stratified and weighed
/// (module documentation, "Which patch is which"). `tolerance` is the distance below which a
/// point counts as on a plane. `trace(x, ia, y, ib)` answers whether the segment from `x` on
/// `a` (index `ia`) to `y` on `b` (index `ib`) is clear.
pub fn visible_fraction(
    (a, ia): (&Patch, usize),
    (b, ib): (&Patch, usize),
    u: Real,
    budget: RayBudget,
    tolerance: Real,
    rng: &mut impl Rng,
    trace: &mut impl FnMut(Vec3, usize, Vec3, usize) -> bool,
) -> Real {
    let Some((lower, upper)) = facing_parts(a, b, tolerance) else { return 1.0 };
    let (na, nb) = (a.normal(), b.normal());
    let mut sums = Sums::default();
    let k = budget.rays(u);
    let joint = Joint::new(&lower, &upper, na, nb);
    let path = path_for(k, joint.is_some());
    if let (SamplingPath::Joint, Some(joint)) = (path, &joint) {
        // A pair small against its distance, with few rays: no bound by Lambert's formula,
        // no grid (module documentation, "Few rays").
        joint.sample(k, rng, &mut |x, y| trace(x, ia, y, ib), &mut sums);
        return if sums.total > 0.0 { sums.visible / sums.total } else { 1.0 };
    }
    let pair = Pair::new(lower, upper, na, ia, ib);
    if path == SamplingPath::Kernel {
        pair.sample_few(k, rng, trace, &mut sums);
    } else {
        // Decide with the probe, estimate with fresh segments: the estimate's expectation is
        // then V whatever the probe decided (module documentation, "Probes").
        let grid = pair.grid(k);
        let probe = probe_size(k);
        let agreed = pair.probe(&grid, probe, rng, trace);
        let fresh = if agreed { agreed_estimate_size(k) } else { k };
        if let (true, Some(joint)) = (fresh < MANY, &joint) {
            joint.sample(fresh, rng, &mut |x, y| trace(x, ia, y, ib), &mut sums);
        } else if fresh < MANY {
            pair.sample_few(fresh, rng, trace, &mut sums);
        } else {
            pair.sample_many(&grid, fresh, rng, trace, &mut sums);
        }
    }
    if sums.total > 0.0 { sums.visible / sums.total } else { 1.0 }
}

/// `L` and `H` of the pair `(a, b)`: `a` in front of `b`'s plane and `b` in front of `a`'s, each
/// plane moved a hair (`tolerance`) forward so that points on it count as behind; `None` when
/// either is empty, and no segment is drawn.
fn facing_parts(a: &Patch, b: &Patch, tolerance: Real) -> Option<(Region, Region)> {
    let (na, nb) = (a.normal(), b.normal());
    let lower = Region::clipped(a.vertices(), b.vertices()[0] + nb * tolerance, nb);
    let upper = Region::clipped(b.vertices(), a.vertices()[0] + na * tolerance, na);
    (lower.area() > 0.0 && upper.area() > 0.0).then_some((lower, upper))
}

/// How [`visible_fraction`] samples a pair (module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SamplingPath {
    /// Fewer than 16 rays, both ends drawn together by rejection against a bound on the kernel
    /// ("Few rays", pairs small against their distance).
    Joint,
    /// Fewer than 16 rays, `x` by rejection against Lambert's formula and `y` by Arvo's map
    /// ("Few rays", the other pairs).
    Kernel,
    /// 16 rays or more: a probe from the grid, then fresh segments ("Many rays", "Probes").
    Probed,
}

impl SamplingPath {
    /// Every path, in the order above.
    pub const ALL: [SamplingPath; 3] = [SamplingPath::Joint, SamplingPath::Kernel, SamplingPath::Probed];

    /// A short name for reports.
    pub fn name(self) -> &'static str {
        match self {
            SamplingPath::Joint => "few rays, both ends jointly",
            SamplingPath::Kernel => "few rays, Lambert and Arvo",
            SamplingPath::Probed => "16 rays or more, probed",
        }
    }
}

/// The path [`visible_fraction`] takes for the same arguments, without drawing anything; `None`
/// when it draws no segment (`L` or `H` empty).
pub fn sampling_path(a: &Patch, b: &Patch, u: Real, budget: RayBudget, tolerance: Real) -> Option<SamplingPath> {
    let (lower, upper) = facing_parts(a, b, tolerance)?;
    Some(path_for(budget.rays(u), Joint::new(&lower, &upper, a.normal(), b.normal()).is_some()))
}

/// The path of a pair given `k` rays, `joint` when both its ends may be drawn together: the one
/// decision [`visible_fraction`] and [`sampling_path`] share.
fn path_for(k: usize, joint: bool) -> SamplingPath {
    match (k < PROBED, joint) {
        (true, true) => SamplingPath::Joint,
        (true, false) => SamplingPath::Kernel,
        (false, _) => SamplingPath::Probed,
    }
}

/// The segments of the probe of a pair given `k ≥ 16` rays: `⌈√k⌉` (module documentation,
/// "Probes").
fn probe_size(k: usize) -> usize {
    (k as Real).sqrt().ceil() as usize
}

/// The fresh segments that estimate a pair given `k ≥ 16` rays whose probe agreed: `⌈√k⌉`, or
/// `⌈k / 16⌉` from `k = 256` on (module documentation, "Probes").
fn agreed_estimate_size(k: usize) -> usize {
    probe_size(k).max(k.div_ceil(AGREED_SHARE))
}

/// An agreed pair's estimate takes at least `1 / AGREED_SHARE` of its rays (module
/// documentation, "Probes").
const AGREED_SHARE: usize = 16;

/// The largest ratio of the kernel's bound over `L × H` to its value between the centres for
/// which a pair's few segments are drawn jointly ([`Joint`]): about half the proposals or
/// more are kept.
const JOINT_SPREAD: Real = 2.0;

/// A pair whose few segments have both ends drawn together in proportion to the kernel, by
/// rejection from points uniform by area on `L × H` (module documentation, "Few rays").
struct Joint<'r> {
    lower: &'r Region,
    upper: &'r Region,
    na: Vec3,
    nb: Vec3,
    /// An upper bound of `cos θ_x cos θ_y / r²` (without the `1/π`) over `L × H`.
    bound: Real,
}

impl<'r> Joint<'r> {
    /// The pair `(L, H)` with normals `na`, `nb`, when it is small enough against its distance
    /// that the bound on the kernel is within [`JOINT_SPREAD`] of its value between the
    /// centres of `L` and `H`: `n_a · (y − x) ≤ max_H n_a · y − min_L n_a · x` and the same
    /// for `n_b`, both linear, so their maxima are at vertices; `r ≥ |c_L − c_H| − ρ_L − ρ_H`,
    /// `ρ` the largest distance from a centre to its polygon's vertices.
    fn new(lower: &'r Region, upper: &'r Region, na: Vec3, nb: Vec3) -> Option<Joint<'r>> {
        let (l, h) = (lower.polygon(), upper.polygon());
        let centre = |p: &[Vec3]| p.iter().copied().sum::<Vec3>() / p.len() as Real;
        let (cl, ch) = (centre(l), centre(h));
        let reach = |p: &[Vec3], c: Vec3| p.iter().map(|v| (*v - c).length()).fold(0.0, Real::max);
        let nearest = (ch - cl).length() - reach(l, cl) - reach(h, ch);
        if nearest <= 0.0 {
            return None;
        }
        let range = |p: &[Vec3], n: Vec3| {
            p.iter().map(|v| n.dot(*v)).fold((Real::INFINITY, Real::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)))
        };
        let towards_h = range(h, na).1 - range(l, na).0;
        let towards_l = range(l, nb).1 - range(h, nb).0;
        let squared = nearest * nearest;
        let bound = towards_h * towards_l / (squared * squared);
        let centres = kernel(cl, na, ch, nb);
        (centres > 0.0 && bound <= JOINT_SPREAD * centres).then_some(Joint { lower, upper, na, nb, bound })
    }

    /// Adds `k` segments drawn in proportion to the kernel over `L × H` to `sums`, each
    /// weighing the same, `trace(x, y)` telling whether each is clear: a proposal uniform by
    /// area on both, kept with probability `K(x, y) / bound`. The first proposal of each
    /// segment comes from a Latin hypercube over both squares, so that the segments spread
    /// out; a rejected one is redrawn freely, the last of [`MAX_TRIES`] kept.
    fn sample(&self, k: usize, rng: &mut impl Rng, trace: &mut impl FnMut(Vec3, Vec3) -> bool, sums: &mut Sums) {
        latin_hypercube(k, rng, |rng, [(u, v), (s, t)]| {
            let (mut x, mut y) = (self.lower.point_at(u, v), self.upper.point_at(s, t));
            for _ in 1..MAX_TRIES {
                if rng.random::<Real>() * self.bound <= kernel(x, self.na, y, self.nb) {
                    break;
                }
                x = self.lower.point_at(rng.random(), rng.random());
                y = self.upper.point_at(rng.random(), rng.random());
            }
            sums.total += 1.0;
            if trace(x, y) {
                sums.visible += 1.0;
            }
        });
    }
}

/// The point-to-point kernel `cos θ_x cos θ_y / r²` without its `1/π`, from `x` (normal
/// `na`) to `y` (normal `nb`): zero unless each point is in front of the other's normal.
fn kernel(x: Vec3, na: Vec3, y: Vec3, nb: Vec3) -> Real {
    let d = y - x;
    let (at_x, at_y) = (na.dot(d), -nb.dot(d));
    if at_x <= 0.0 || at_y <= 0.0 {
        return 0.0;
    }
    let r2 = d.length_squared();
    at_x * at_y / (r2 * r2)
}

/// What sampling one pair needs.
struct Pair {
    /// `a` cut by `b`'s plane.
    lower: Region,
    /// `b` cut by `a`'s plane.
    upper: Region,
    /// `a`'s normal.
    na: Vec3,
    /// The bound on `F(dA_x → H)` over `L` for drawing `x` by rejection.
    bound: Real,
    /// Whether `F(dA_x → H)` varies over `L` by more than [`GRID_SPREAD`].
    varies: bool,
    ia: usize,
    ib: usize,
}

impl Pair {
    /// The pair `(L, H)` with the bound for drawing points of `L` by rejection: `F(dA_x → H)`
    /// at the corners, edge midpoints and centre of `L`, with a margin (module documentation,
    /// "Few rays"). The corners and midpoints are taken a hair inside `L`: on `L`'s boundary,
    /// where `b`'s plane cuts `a`, `H` is cut a tolerance away as well, and `F` there falls
    /// short of its value just inside (0.35 against 0.5 at the shared edge of a floor and a
    /// wall), which left the bound below the largest value and drew too few points near the
    /// edge.
    fn new(lower: Region, upper: Region, na: Vec3, ia: usize, ib: usize) -> Pair {
        let mut pair = Pair { lower, upper, na, bound: 0.0, varies: false, ia, ib };
        let corners = pair.lower.polygon();
        let centre = corners.iter().copied().sum::<Vec3>() / corners.len() as Real;
        let midpoints = (0..corners.len()).map(|e| 0.5 * (corners[e] + corners[(e + 1) % corners.len()]));
        let inside = |p: Vec3| p + (centre - p) * INSIDE;
        // Corners and midpoints, four at a time on SIMD lanes, then the centre.
        let mut points = [centre; 2 * MAX_CLIPPED + 1];
        let count = 2 * corners.len();
        for (slot, p) in points.iter_mut().zip(corners.iter().copied().chain(midpoints)) {
            *slot = inside(p);
        }
        let mut values = [0.0; 2 * MAX_CLIPPED + 1];
        points[count] = centre;
        point_to_polygon_each(&points[..=count], pair.na, pair.upper.polygon(), &mut values[..=count]);
        let (smallest, largest) =
            values[..=count].iter().fold((Real::INFINITY, 0.0), |(lo, hi): (Real, Real), &f| (lo.min(f), hi.max(f)));
        pair.bound = (FEW_MARGIN * largest).min(1.0);
        pair.varies = largest > GRID_SPREAD * smallest;
        pair
    }

    /// `F(dA_x → H)`.
    fn seen_from(&self, x: Vec3) -> Real {
        point_to_polygon(x, self.na, self.upper.polygon())
    }

    /// `F(dA_x → H)` at four points at once, each lane bit for bit [`Pair::seen_from`].
    fn seen_from_x4(&self, x: [Vec3; 4]) -> [Real; 4] {
        point_to_polygon_x4(x, self.na, self.upper.polygon())
    }

    /// Calls `f(x, y)` for `k` segments with both ends drawn in proportion to the kernel
    /// (module documentation, "Few rays"), so that each one is clear with probability `V`: `x`
    /// on `L` in proportion to `F(dA_x → H)` by rejection, `y` on `H` from `x` by
    /// [`kernel_point`]. The first point tried for `x` and the first direction tried for `y`
    /// come from a Latin hypercube over both squares, so that the segments spread out.
    fn kernel_segments(&self, k: usize, rng: &mut impl Rng, mut f: impl FnMut(Vec3, Vec3)) {
        if self.bound <= 0.0 {
            return;
        }
        latin_hypercube(k, rng, |rng, [(mut u, mut v), direction]| {
            let mut x = self.lower.point_at(u, v);
            for _ in 1..MAX_TRIES {
                if rng.random::<Real>() * self.bound <= self.seen_from(x) {
                    break;
                }
                (u, v) = (rng.random(), rng.random());
                x = self.lower.point_at(u, v);
            }
            if let Some(y) = kernel_point(x, self.na, self.upper.polygon(), direction, rng) {
                f(x, y);
            }
        });
    }

    /// The grid that [`Pair::sample_many`] and [`Pair::probe`] draw `x` from for a pair given
    /// `k` rays.
    fn grid(&self, k: usize) -> Grid {
        Grid::new(grid_side(k, self.varies), |corners| {
            self.seen_from_x4(corners.map(|(u, v)| self.lower.point_at(u, v)))
        })
    }

    /// Calls `f(x, y, w)` for `k` segments, each with its own `x` and its own direction to
    /// `y`, from one scrambled Sobol point in four dimensions: `x` on `L` with the density `p`
    /// of `grid`, `y` on `H` in proportion to the kernel from `x` by [`kernel_point`] (its
    /// first direction tried from the point), and `w = F(dA_x → H) / p(x)` (module
    /// documentation, "Many rays").
    ///
    /// The points are taken four at a time, so that `F(dA_x → H)` is evaluated on four lanes
    /// ([`Pair::seen_from_x4`]); the directions are then drawn in the points' order, so the
    /// random stream is read as with one point at a time.
    fn grid_segments<R: Rng>(&self, grid: &Grid, k: usize, rng: &mut R, mut f: impl FnMut(Vec3, Vec3, Real)) {
        let upper = self.upper.polygon();
        let mut batch = [(Vec3::ZERO, 0.0, (0.0, 0.0)); 4];
        let mut filled = 0;
        let mut flush = |batch: &[(Vec3, Real, (Real, Real))], rng: &mut R| {
            let mut weights = [0.0; 4];
            let points: [Vec3; 4] = std::array::from_fn(|l| batch.get(l).map_or(Vec3::ZERO, |b| b.0));
            point_to_polygon_each(&points[..batch.len()], self.na, upper, &mut weights[..batch.len()]);
            for (&(x, density, direction), seen) in batch.iter().zip(weights) {
                let weight = seen / density;
                if weight <= 0.0 {
                    continue;
                }
                if let Some(y) = kernel_point(x, self.na, upper, direction, rng) {
                    f(x, y, weight);
                }
            }
        };
        scrambled_sobol(k, rng, |rng, [su, sv, du, dv]| {
            let ((u, v), density) = grid.point_at((su, sv));
            batch[filled] = (self.lower.point_at(u, v), density, (du, dv));
            filled += 1;
            if filled == 4 {
                flush(&batch, rng);
                filled = 0;
            }
        });
        flush(&batch[..filled], rng);
    }

    /// Traces `k` segments drawn from `grid` ([`Pair::grid_segments`]), so nearly as the
    /// kernel weighs them, and says whether they agree (all clear or all blocked). Only that
    /// is used, so that the estimate is independent of the decision (module documentation,
    /// "Probes").
    fn probe(
        &self,
        grid: &Grid,
        k: usize,
        rng: &mut impl Rng,
        trace: &mut impl FnMut(Vec3, usize, Vec3, usize) -> bool,
    ) -> bool {
        let (mut clear, mut traced) = (0, 0);
        self.grid_segments(grid, k, rng, |x, y, _| {
            traced += 1;
            clear += usize::from(trace(x, self.ia, y, self.ib));
        });
        clear == 0 || clear == traced
    }

    /// Adds `k < 16` segments drawn by the kernel ([`Pair::kernel_segments`]) to `sums`, each
    /// weighing the same.
    fn sample_few(
        &self,
        k: usize,
        rng: &mut impl Rng,
        trace: &mut impl FnMut(Vec3, usize, Vec3, usize) -> bool,
        sums: &mut Sums,
    ) {
        self.kernel_segments(k, rng, |x, y| {
            sums.total += 1.0;
            if trace(x, self.ia, y, self.ib) {
                sums.visible += 1.0;
            }
        });
    }

    /// Adds `k ≥ 16` segments drawn from `grid` ([`Pair::grid_segments`]) to `sums`, each
    /// weighing `F(dA_x → H) / p(x)` (module documentation, "Many rays").
    fn sample_many(
        &self,
        grid: &Grid,
        k: usize,
        rng: &mut impl Rng,
        trace: &mut impl FnMut(Vec3, usize, Vec3, usize) -> bool,
        sums: &mut Sums,
    ) {
        self.grid_segments(grid, k, rng, |x, y, weight| {
            sums.total += weight;
            if trace(x, self.ia, y, self.ib) {
                sums.visible += weight;
            }
        });
    }
}

/// The fewest cells along each side of the grid [`Pair::sample_many`] draws `x` from, when
/// `F(dA_x → H)` varies over `L`.
const MIN_GRID: usize = 4;
/// The most cells along each side of that grid.
const MAX_GRID: usize = 16;
/// `F(dA_x → H)` varies over `L` when its largest value at the points the rejection bound is
/// taken from is more than this times its smallest.
const GRID_SPREAD: Real = 2.0;
/// A cell's density is at least this fraction of the largest cell's, so that no part of `L`
/// goes unsampled.
const GRID_FLOOR: Real = 1e-3;

/// Cells along each side of the grid for `k` segments: `⌊√k / 4⌋`, between [`MIN_GRID`] and
/// [`MAX_GRID`], so that its `4 side²` evaluations of `F(dA_x → H)` stay below `k / 4` for
/// `k ≥ 256`; one cell when `F(dA_x → H)` hardly varies over `L` (`varies` false).
fn grid_side(k: usize, varies: bool) -> usize {
    if varies { (((k as Real).sqrt() / 4.0) as usize).clamp(MIN_GRID, MAX_GRID) } else { 1 }
}

/// A piecewise-constant density on the unit square, `side × side` cells, each in proportion
/// to the largest of a function at its corners, taken a hair inside the cell (the map from
/// the square to `L` jumps between fan triangles along some cell edges, and `L`'s boundary
/// is where `F(dA_x → H)` falls short, see [`INSIDE`]).
struct Grid {
    side: usize,
    /// `cumulative[c]`: the weights of cells `0..=c`, row by row.
    cumulative: [Real; MAX_GRID * MAX_GRID],
}

impl Grid {
    /// `f` gives the function at four points of the square at once.
    fn new(side: usize, f: impl Fn([(Real, Real); 4]) -> [Real; 4]) -> Grid {
        let mut cumulative = [0.0; MAX_GRID * MAX_GRID];
        if side == 1 {
            cumulative[0] = 1.0;
            return Grid { side, cumulative };
        }
        let width = 1.0 / side as Real;
        let (near, far) = (INSIDE * width, (1.0 - INSIDE) * width);
        let mut weights = [0.0; MAX_GRID * MAX_GRID];
        for (c, weight) in weights.iter_mut().enumerate().take(side * side) {
            let (u, v) = ((c % side) as Real * width, (c / side) as Real * width);
            *weight = f([(near, near), (far, near), (near, far), (far, far)].map(|(du, dv)| (u + du, v + dv)))
                .into_iter()
                .fold(0.0, Real::max);
        }
        let largest = weights.iter().copied().fold(0.0, Real::max);
        let floor = if largest > 0.0 { GRID_FLOOR * largest } else { 1.0 };
        let mut total = 0.0;
        for (sum, weight) in cumulative.iter_mut().zip(weights).take(side * side) {
            total += weight.max(floor);
            *sum = total;
        }
        Grid { side, cumulative }
    }

    /// The point of the square at `(u, v) ∈ [0, 1)²` under the density (`u` picks the cell in
    /// proportion to its weight and is rescaled within it), and the density there.
    fn point_at(&self, (u, v): (Real, Real)) -> ((Real, Real), Real) {
        let cells = self.side * self.side;
        let (c, s, width) = pick_fan_triangle(&self.cumulative[..cells], u);
        let total = self.cumulative[cells - 1];
        let side = self.side as Real;
        let (i, j) = ((c % self.side) as Real, (c / self.side) as Real);
        (((i + s) / side, (j + v) / side), width / total * side * side)
    }
}

/// Draws tried by a rejection before taking the last one (module documentation).
const MAX_TRIES: usize = 64;
/// The margin on the largest `F(dA_x → H)` found at the corners and centre of `L`, for
/// drawing `x` by rejection.
const FEW_MARGIN: Real = 1.25;
/// How far towards `L`'s centre, as a fraction of the way, the corners and edge midpoints
/// where `F(dA_x → H)` bounds the rejection are moved, and how far into its cell, as a
/// fraction of the cell, each corner where [`Grid`] takes it: far more than the plane
/// tolerance (`1e-9` of the scene), too little to change the value much. Lambert's formula
/// loses digits in proportion to the inverse distance to an edge of `H`, and at `1e-6` the
/// grid's weights moved with the rounding of the coordinates: `inner-box:res=2:gap=0` at
/// scale `1e-8` differed from scale 1 by 2.2e-12 of the largest entry.
const INSIDE: Real = 1e-3;

/// A point `y` of `polygon` drawn with density in proportion to the kernel from `x` (normal
/// `n`): a direction uniform in the polygon's solid angle (Arvo), kept with probability
/// `cos θ_x` over its largest value on the polygon. The first direction tried is the one at
/// `first ∈ [0, 1)²` (a stratified draw stays stratified when it is kept), the others are
/// fresh. `None` when the polygon subtends nothing.
fn kernel_point(x: Vec3, n: Vec3, polygon: &[Vec3], first: (Real, Real), rng: &mut impl Rng) -> Option<Vec3> {
    let seen = SphericalPolygon::new(x, polygon);
    let bound = seen.max_cosine(n);
    if bound <= 0.0 {
        return None;
    }
    let mut last = None;
    let (mut u, mut v) = first;
    for _ in 0..MAX_TRIES {
        let y = seen.point_at(x, u, v)?;
        if rng.random::<Real>() * bound <= n.dot((y - x).normalize_or_zero()) {
            return Some(y);
        }
        last = Some(y);
        (u, v) = (rng.random(), rng.random());
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
