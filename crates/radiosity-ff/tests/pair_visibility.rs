//! Tests of the pair visibility estimator against kernel-weighted visible fractions known
//! independently: a floor and a wall sharing an edge, with every segment from the far half of
//! the floor blocked (the exact fraction is Howell's factor from the near half over the factor
//! from the whole floor, far above the half an area-weighted estimate gives) or all but a thin
//! strip along the edge; and a slot of the MGF classroom, a wall seeing a desk top through a
//! 2 cm gap, against cosine-weighted rays cast from the wall.

use super::closed_forms::perpendicular;
use radiosity_core::math::cosine_direction;
use radiosity_core::{Material, MaterialId, ObjectId, Patch, Real, Scene, Spectrum, Vec3};
use radiosity_ff::ff_point_polygon::point_to_polygon;
use radiosity_ff::pair_visibility::{RayBudget, visible_fraction};
use radiosity_ff::quadrature::gauss_legendre;
use radiosity_ff::{AnalyticColumns, AnalyticParams, BackendSpec};
use radiosity_geom::{SceneAnalysis, SceneBuilder, Visibility};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// The floor (`y = 0`, `z ∈ [0, 1]`, facing +y) and the wall (`z = 0`, facing +z), sharing
/// the edge along x.
fn floor_and_wall() -> (Patch, Patch) {
    let (m, o) = (MaterialId(0), ObjectId(0));
    let floor = Patch::quad(
        [Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0)],
        m,
        o,
    )
    .unwrap();
    let wall = Patch::quad(
        [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
        m,
        o,
    )
    .unwrap();
    assert!(floor.normal().y > 0.9 && wall.normal().z > 0.9);
    (floor, wall)
}

/// The exact kernel-weighted fraction of floor-to-wall segments that start on the floor's
/// strip of width `w` along the shared edge.
fn exact_strip(w: Real) -> Real {
    w * perpendicular(1.0, w, 1.0) / perpendicular(1.0, 1.0, 1.0)
}

/// The exact kernel-weighted fraction of floor-to-wall segments that start on the near half.
fn exact() -> Real {
    exact_strip(0.5)
}

/// The estimate when only segments from the floor's strip of width `w` along the shared edge
/// are clear.
fn estimate_strip(w: Real, budget: RayBudget, seed: u64) -> Real {
    let (floor, wall) = floor_and_wall();
    let u = perpendicular(1.0, 1.0, 1.0);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut blocked_beyond = |x: Vec3, from: usize, _: Vec3, to: usize| {
        assert_eq!((from, to), (0, 1));
        x.z <= w
    };
    visible_fraction((&floor, 0), (&wall, 1), u, budget, 1e-12, &mut rng, &mut blocked_beyond)
}

fn estimate(budget: RayBudget, seed: u64) -> Real {
    estimate_strip(0.5, budget, seed)
}

/// The floor-to-wall estimate with `rays` rays, `u` taken as their factor, each segment clear
/// when `clear` says so of its point on the floor; with the number of segments traced.
fn floor_to_wall(u: Real, rays: usize, seed: u64, mut clear: impl FnMut(Vec3) -> bool) -> (Real, usize) {
    let (floor, wall) = floor_and_wall();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut traced = 0;
    let mut trace = |x: Vec3, _: usize, _: Vec3, _: usize| {
        traced += 1;
        clear(x)
    };
    let v = visible_fraction((&floor, 0), (&wall, 1), u, RayBudget { rays, per_unit: 0 }, 1e-12, &mut rng, &mut trace);
    (v, traced)
}

/// The mean of `values` and its standard error.
fn mean_and_error(values: &[Real]) -> (Real, Real) {
    let n = values.len() as Real;
    let mean = values.iter().sum::<Real>() / n;
    let spread = (values.iter().map(|v| (v - mean).powi(2)).sum::<Real>() / (n - 1.0)).sqrt();
    (mean, spread / n.sqrt())
}

#[test]
fn the_exact_fraction_is_well_above_the_area_fraction() {
    // What the test can tell apart: about 0.72 against 0.5.
    assert!(exact() > 0.65, "{}", exact());
}

#[test]
fn many_rays_converge_to_the_kernel_weighted_fraction() {
    let v = estimate(RayBudget { rays: 16384, per_unit: 0 }, 1);
    assert!((v - exact()).abs() < 5e-3, "{v} against {}", exact());
}

#[test]
fn few_rays_are_unbiased() {
    // One, two and eight rays, averaged over many independent pairs: within four standard
    // errors of the exact fraction, for the plain estimator and the probed one.
    for rays in [1, 2, 8] {
        let trials = 20_000 / rays;
        let mean =
            (0..trials as u64).map(|s| estimate(RayBudget { rays, per_unit: 0 }, s)).sum::<Real>() / trials as Real;
        let v = exact();
        let standard_error = (v * (1.0 - v) / (trials * rays) as Real).sqrt();
        assert!((mean - v).abs() < 4.0 * standard_error, "{rays} rays: {mean} against {v} ± {standard_error}");
    }
}

#[test]
fn a_probed_pair_is_unbiased() {
    // 64 rays: a probe of 8 decides, and either 8 or 64 fresh rays estimate.
    let trials = 400;
    let values: Vec<Real> = (0..trials).map(|s| estimate(RayBudget { rays: 64, per_unit: 0 }, s)).collect();
    let (mean, standard_error) = mean_and_error(&values);
    assert!((mean - exact()).abs() < 4.0 * standard_error + 2e-3, "{mean} against {} ± {standard_error}", exact());
}

#[test]
fn a_probed_pair_with_many_rays_is_unbiased() {
    // 1024 rays and only a strip of 1% of the floor's width visible: the probe of 32 finds
    // every segment blocked in some trials, and the estimate is then drawn from 64 fresh
    // segments (a sixteenth of the rays), otherwise from 1024.
    let (w, trials) = (0.01, 400);
    let u = perpendicular(1.0, 1.0, 1.0);
    let (mut values, mut agreed) = (Vec::new(), 0);
    for seed in 0..trials {
        let (v, traced) = floor_to_wall(u, 1024, seed, |x| x.z <= w);
        values.push(v);
        agreed += usize::from(traced == 32 + 64);
    }
    let (mean, standard_error) = mean_and_error(&values);
    let v = exact_strip(w);
    assert!(agreed >= trials as usize / 20, "the probe agreed in {agreed} of {trials} trials");
    assert!((mean - v).abs() < 4.0 * standard_error, "{mean} against {v} ± {standard_error}");
}

#[test]
fn an_agreed_pair_is_estimated_from_a_sixteenth_of_its_rays_from_256_on() {
    // A fully visible pair: the probe of ⌈√k⌉ agrees, and the estimate takes
    // max(⌈√k⌉, ⌈k / 16⌉) fresh segments.
    for (rays, segments) in [(16, 4 + 4), (100, 10 + 10), (256, 16 + 16), (1024, 32 + 64), (4096, 64 + 256)] {
        assert_eq!(floor_to_wall(0.2, rays, 5, |_| true), (1.0, segments), "{rays} rays");
    }
}

#[test]
fn fully_visible_and_hidden_pairs_are_exact() {
    for rays in [1, 16, 300] {
        for (answer, expected) in [(true, 1.0), (false, 0.0)] {
            assert_eq!(floor_to_wall(0.2, rays, 3, |_| answer).0, expected, "{rays} rays");
        }
    }
}

#[test]
fn few_rays_near_a_shared_edge_are_unbiased() {
    // Only the floor's strip of width 0.05 along the edge is visible, where the kernel is
    // largest. Points are drawn on the floor by rejection, bounded by F(dA_x → wall) at the
    // floor's corners and edge midpoints; taken on the edge itself, where the wall is cut a
    // tolerance away, that gave 0.35 instead of 0.5 just inside, and the estimate came out
    // 5% low (6 standard errors here).
    for rays in [1, 4] {
        let trials = 100_000 / rays;
        let mean = (0..trials as u64).map(|s| estimate_strip(0.05, RayBudget { rays, per_unit: 0 }, s)).sum::<Real>()
            / trials as Real;
        let v = exact_strip(0.05);
        let standard_error = (v * (1.0 - v) / (trials * rays) as Real).sqrt();
        assert!((mean - v).abs() < 4.0 * standard_error, "{rays} rays: {mean} against {v} ± {standard_error}");
    }
}

/// Patches 722, 742 and 1103 of `salon/classroom.mgf` (with its hidden patches left out), in
/// that order: the two walls of a 2 cm slot 7 cm deep and 1.13 m long (0 facing +y, 2 facing
/// −y), and the underside of a desk top (1) in the plane of the slot's upper edge, reaching
/// 5 mm into its opening. The wall 2 sees the desk top past wall 0 only through that 5 mm
/// strip and past the slot's ends.
fn slot() -> Scene {
    let mut b = SceneBuilder::new("classroom slot");
    let m = b.material(Material::new("grey", Spectrum::grey(0.5), Spectrum::ZERO)).unwrap();
    let o = b.object("slot");
    let p = Vec3::new;
    for quad in [
        [p(3.865, 2.49, 0.69), p(2.735, 2.49, 0.69), p(2.735, 2.49, 0.76), p(3.865, 2.49, 0.76)],
        [p(2.705, 2.495, 0.76), p(3.895, 2.495, 0.76), p(3.895, 1.905, 0.76), p(2.705, 1.905, 0.76)],
        [p(2.735, 2.51, 0.69), p(3.865, 2.51, 0.69), p(3.865, 2.51, 0.76), p(2.735, 2.51, 0.76)],
    ] {
        b.polygon(&quad, m, o).unwrap();
    }
    b.build().unwrap()
}

/// Row `i` of the occluded form factors by brute force: `rays` cosine-weighted rays from
/// uniform points of patch `i`, each counted for the patch it hits first (from the front).
fn cast_row(scene: &Scene, vis: &Visibility, i: usize, rays: usize) -> Vec<Real> {
    let patch = &scene.patches()[i];
    let v = patch.vertices();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let mut hits = vec![0usize; scene.len()];
    for _ in 0..rays {
        let (s, t): (Real, Real) = (rng.random(), rng.random());
        let x = v[0].lerp(v[1], s).lerp(v[3].lerp(v[2], s), t);
        let d = cosine_direction(patch.normal(), rng.random(), rng.random());
        if let Some(hit) = vis.first_hit(x, d, Some(i)).filter(|h| h.front) {
            hits[hit.patch] += 1;
        }
    }
    hits.iter().map(|&h| h as Real / rays as Real).collect()
}

#[test]
fn a_wall_seeing_a_desk_top_through_a_slot() {
    // The classroom's worst row: the wall's factor to the desk top came out 0.109 against
    // 0.027, and its row summed to 1.076. The estimate drew its points on the desk top (the
    // lower index) and joined each to 64 cells of the wall, so only 91 points carried its
    // 5 866 segments, and about one of them fell on the 5 mm strip that sees the wall: an
    // unbiased estimate, spread like a coin toss. With a point per segment, drawn where the
    // kernel is, it is within a few thousandths for every seed, whichever patch the points
    // are drawn on.
    let scene = slot();
    let vis = Visibility::new(&scene);
    let analysis = SceneAnalysis::new(&scene, &vis);
    let rays = 200_000;
    let truth = cast_row(&scene, &vis, 2, rays);
    // About 0.744 and 0.028.
    let standard_error = truth.iter().map(|&p| (p * (1.0 - p) / rays as Real).sqrt()).collect::<Vec<_>>();
    assert!((truth[1] - 0.028).abs() < 0.002, "{truth:?}");
    let parse = |arg: &str| *BackendSpec::parse(arg).unwrap().params::<AnalyticParams>().expect("analytic");
    // The estimate's own spread is about 0.001 for the desk top; the quadrature's error for
    // the opposite wall about 1e-4.
    let allowed = |j: usize| 4.0 * standard_error[j] + 0.005;
    for seed in 0..8 {
        let f = AnalyticColumns::new(&scene, &vis, &analysis, parse(&format!("analytic:seed={seed}")));
        assert!(f.traces_shadow_rays());
        for j in [0, 1] {
            let got = f.pair(2, j);
            assert!(
                (got - truth[j]).abs() < allowed(j),
                "seed {seed}: F[2][{j}] = {got} against {} ± {}",
                truth[j],
                standard_error[j]
            );
        }
    }
    // The analytic backend draws the points on the wall, the smaller patch; drawn on the desk
    // top, where the kernel crowds into the 5 mm strip, they do as well.
    let mut open = analysis.clone();
    open.occlusion.value = false;
    let unoccluded = AnalyticColumns::new(&scene, &vis, &open, parse("analytic")).pair(2, 1);
    let (wall, desk) = (&scene.patches()[2], &scene.patches()[1]);
    for seed in 0..8 {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let budget = RayBudget { rays: 1, per_unit: 16384 };
        let v = visible_fraction((desk, 1), (wall, 2), unoccluded, budget, 1e-9, &mut rng, &mut |x, a, y, b| {
            vis.unoccluded_between(x, a, y, b)
        });
        let got = unoccluded * v;
        assert!((got - truth[1]).abs() < allowed(1), "seed {seed}: {got} against {} ± {}", truth[1], standard_error[1]);
    }
}

#[test]
fn stiff_scenes_get_rays_in_proportion_to_their_amplification_squared() {
    use radiosity_ff::pair_visibility::stiffness_factor;
    // ((1 − 0.8) / (1 − ρ̄))², rounded up, between 1 and 64.
    for (rho, factor) in [(0.0, 1), (0.5, 1), (0.8, 1), (0.9, 4), (0.95, 16), (0.975, 64), (0.99, 64), (1.0, 64)] {
        assert_eq!(stiffness_factor(rho), factor, "ρ̄ = {rho}");
    }
    assert_eq!(stiffness_factor(Real::NAN), 1);
}

/// A unit square at `z = 0` facing up, and one at `z = 10`, five units aside, facing down:
/// small against their distance, so their few segments are drawn jointly by rejection from
/// uniform points of both.
fn distant_squares() -> (Patch, Patch) {
    let (m, o) = (MaterialId(0), ObjectId(0));
    let square = |x: Real, z: Real, up: bool| {
        let mut v =
            [Vec3::new(x, 0.0, z), Vec3::new(x + 1.0, 0.0, z), Vec3::new(x + 1.0, 1.0, z), Vec3::new(x, 1.0, z)];
        if !up {
            v.reverse();
        }
        Patch::quad(v, m, o).unwrap()
    };
    let (a, b) = (square(0.0, 0.0, true), square(5.0, 10.0, false));
    assert!(a.normal().z > 0.9 && b.normal().z < -0.9);
    (a, b)
}

#[test]
fn few_rays_between_distant_patches_are_unbiased() {
    // Only segments from the half of the lower square nearer the upper one are clear. The
    // exact kernel-weighted fraction, from Lambert's formula integrated over each half, is
    // above the area fraction 0.5 because the nearer half sees more of the upper square.
    let (a, b) = distant_squares();
    let nodes = gauss_legendre(16);
    let half = |from: Real| {
        let mut sum = 0.0;
        for &(s, ws) in &nodes {
            for &(t, wt) in &nodes {
                let x = Vec3::new(from + 0.5 * s, t, 0.0);
                sum += ws * wt * point_to_polygon(x, a.normal(), b.vertices());
            }
        }
        sum
    };
    let exact = half(0.5) / (half(0.0) + half(0.5));
    let trials = 100_000;
    let clear = (0..trials as u64)
        .map(|seed| {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
            let mut nearer_half = |x: Vec3, _: usize, _: Vec3, _: usize| x.x > 0.5;
            visible_fraction(
                (&a, 0),
                (&b, 1),
                1e-3,
                RayBudget { rays: 1, per_unit: 0 },
                1e-12,
                &mut rng,
                &mut nearer_half,
            )
        })
        .sum::<Real>();
    let mean = clear / trials as Real;
    let standard_error = (exact * (1.0 - exact) / trials as Real).sqrt();
    assert!(exact - 0.5 > 10.0 * standard_error, "the case cannot tell the kernel from the area: {exact}");
    assert!((mean - exact).abs() < 4.0 * standard_error, "{mean} against {exact} ± {standard_error}");
}
