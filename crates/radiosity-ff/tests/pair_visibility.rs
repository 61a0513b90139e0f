//! Tests of the pair visibility estimator against a kernel-weighted visible fraction known in
//! closed form: a floor and a wall sharing an edge, with every segment from the far half of
//! the floor blocked. The exact fraction is Howell's factor from the near half over the
//! factor from the whole floor, far above the half an area-weighted estimate gives.

use super::closed_forms::perpendicular;
use radiosity_core::{MaterialId, ObjectId, Patch, Real, Vec3};
use radiosity_ff::pair_visibility::{RayBudget, visible_fraction};
use rand::SeedableRng;
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

/// The exact kernel-weighted fraction of floor-to-wall segments that start on the near half.
fn exact() -> Real {
    0.5 * perpendicular(1.0, 0.5, 1.0) / perpendicular(1.0, 1.0, 1.0)
}

fn estimate(budget: RayBudget, seed: u64) -> Real {
    let (floor, wall) = floor_and_wall();
    let u = perpendicular(1.0, 1.0, 1.0);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut blocked_far_half = |x: Vec3, from: usize, _: Vec3, to: usize| {
        assert_eq!((from, to), (0, 1));
        x.z <= 0.5
    };
    visible_fraction((&floor, 0), (&wall, 1), u, budget, 1e-12, &mut rng, &mut blocked_far_half)
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
    // 64 rays: a probe of 4 decides, and either 4 or 64 fresh rays estimate.
    let trials = 400;
    let values: Vec<Real> = (0..trials).map(|s| estimate(RayBudget { rays: 64, per_unit: 0 }, s)).collect();
    let mean = values.iter().sum::<Real>() / trials as Real;
    let spread = (values.iter().map(|v| (v - mean).powi(2)).sum::<Real>() / (trials - 1) as Real).sqrt();
    let standard_error = spread / (trials as Real).sqrt();
    assert!((mean - exact()).abs() < 4.0 * standard_error + 2e-3, "{mean} against {} ± {standard_error}", exact());
}

#[test]
fn fully_visible_and_hidden_pairs_are_exact() {
    let (floor, wall) = floor_and_wall();
    for rays in [1, 16, 300] {
        for (answer, expected) in [(true, 1.0), (false, 0.0)] {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
            let v = visible_fraction(
                (&floor, 0),
                (&wall, 1),
                0.2,
                RayBudget { rays, per_unit: 0 },
                1e-12,
                &mut rng,
                &mut |_, _, _, _| answer,
            );
            assert_eq!(v, expected, "{rays} rays");
        }
    }
}
