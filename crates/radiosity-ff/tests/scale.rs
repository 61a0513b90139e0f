//! Scale invariance: form factors and radiosities must not depend on the coordinate scale.
//!
//! Form factors are dimensionless, so multiplying every coordinate by `s` must leave `F`, and
//! so `B`, unchanged. Every tolerance of the pipeline is meant to be relative (ARCHITECTURE,
//! "No tolerance is absolute"); these tests check it end to end on `inner-box:res=2`, where the
//! inner box occludes and shadow rays are traced, and on `furnace` with its block.
//!
//! The scales `1e-4` and `1e4` are not powers of two, so scaled coordinates are rounded
//! differently and bitwise equality is not to be expected. What is expected is that every
//! discrete decision is the same at every scale: every shadow ray, hemicube pixel and Monte
//! Carlo ray hits the same patch. One flipped decision would move an entry by a whole ray's
//! or pixel's weight (1e-4 for 10000 Monte Carlo rays, 8e-5 for a hemicube pixel at res 128,
//! all of an entry for one analytic shadow ray), so the tolerance of `1e-12` of the largest
//! entry proves that none flipped, and leaves the rounding of the coordinates, which was
//! measured at:
//!
//! | backend | max difference / largest entry (1e-4 and 1e4 against 1) |
//! |---|---|
//! | analytic (defaults, and `rays=16`) | 5.5e-16 |
//! | hemicube (defaults, res 128) | 2.9e-16 |
//! | montecarlo (defaults, 10000 rays) | 1.4e-16 (hit counts identical) |
//! | radiosity by dense LU, every backend | 1.5e-15 relative |
//!
//! (`furnace:res=2:block=true`, analytic, 1e-4 against 1e4: 5.6e-16 on F, 3.3e-16 on B.)
//!
//! The Monte Carlo check found a scale bug in how scenes applied `scale`: they meshed at the
//! target scale, and bilinear subdivision computes a coordinate that all corners of a face
//! share as `x (1 − s) + x s`, exactly `x` for some `x` and an ulp off for others. At
//! `inner-box:res=3:scale=1e-4` the wall at `x = 1e-4` leaned by 2e-16 where the wall at
//! `x = 1` is flat; the sign of that lean flips the z component of the normal, which turns
//! the tangent frame Monte Carlo samples directions in by 180°, so every ray of that wall
//! went elsewhere and entries moved by up to a tenth of the largest entry. Scenes now mesh
//! at scale 1 and multiply the vertices afterwards (`scenes::scaled` in radiosity-geom).

use radiosity_core::dense_lu::lu_solve;
use radiosity_core::{ColumnSource, LinearSystem, Real, Scene};
use radiosity_ff::{
    AnalyticColumns, AnalyticParams, BackendSpec, FormFactorInput, MonteCarloColumns, MonteCarloParams,
};
use radiosity_geom::{SceneAnalysis, Visibility, load_scene};

/// The tolerance on form factors, relative to the largest entry (see the module doc).
const F_TOLERANCE: Real = 1e-12;
/// The tolerance on radiosities, relative to the largest.
const B_TOLERANCE: Real = 1e-10;

/// A scene with its full form-factor matrix (row-major) from one backend.
struct Computed {
    scene: Scene,
    f: Vec<Real>,
}

fn compute(scene_arg: &str, ff_arg: &str) -> Computed {
    let scene = load_scene(scene_arg).unwrap_or_else(|e| panic!("{scene_arg}: {e}")).scene;
    let visibility = Visibility::new(&scene);
    let analysis = SceneAnalysis::new(&scene, &visibility);
    assert!(analysis.occlusion.value, "{scene_arg}: the inner box should occlude");
    let input = FormFactorInput { scene: &scene, visibility: visibility.clone(), analysis: &analysis };
    let spec = BackendSpec::parse(ff_arg).unwrap();
    if let Some(&params) = spec.params::<AnalyticParams>() {
        assert!(AnalyticColumns::new(&scene, &visibility, &analysis, params).traces_shadow_rays(), "{scene_arg}");
    }
    let backend = spec.build(input).unwrap();
    let n = backend.patch_count();
    let mut f = vec![0.0; n * n];
    let mut column = vec![0.0; n];
    for j in 0..n {
        backend.fill_column(j, &mut column);
        for (i, &v) in column.iter().enumerate() {
            f[i * n + j] = v;
        }
    }
    drop(backend);
    Computed { scene, f }
}

/// `max |a − b| / max |a|`.
fn relative_difference(a: &[Real], b: &[Real]) -> Real {
    assert_eq!(a.len(), b.len());
    let largest = a.iter().fold(0.0, |m: Real, v| m.max(v.abs()));
    assert!(largest > 0.0);
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, Real::max) / largest
}

/// `B = E + ρ F B` solved by dense LU in every channel, patch-major.
fn radiosity(c: &Computed) -> Vec<Real> {
    let system = LinearSystem::from_scene(&c.scene);
    let (n, k) = (system.len(), system.channels().count());
    let mut b = vec![0.0; n * k];
    for ch in 0..k {
        let x = lu_solve(n, false, |i, j| Real::from(i == j) - system.rho(i, ch) * c.f[i * n + j], |i| system.e(i, ch))
            .expect("a regular system");
        for (i, v) in x.into_iter().enumerate() {
            b[i * k + ch] = v;
        }
    }
    b
}

/// Compares `F` and `B` of `base` at every scale of `scales` against scale 1.
fn check(base: &str, ff: &str, scales: &[&str], f_tolerance: Real) {
    let one = compute(base, ff);
    let b_one = radiosity(&one);
    for s in scales {
        let arg = format!("{base}:scale={s}");
        let other = compute(&arg, ff);
        let df = relative_difference(&one.f, &other.f);
        assert!(df <= f_tolerance, "{arg} {ff}: F differs from scale 1 by {df:.2e} of its largest entry");
        let db = relative_difference(&b_one, &radiosity(&other));
        assert!(db <= B_TOLERANCE, "{arg} {ff}: B differs from scale 1 by {db:.2e}");
    }
}

#[test]
fn form_factors_and_radiosities_of_inner_box_do_not_depend_on_the_scale() {
    for ff in ["analytic", "analytic:rays=16", "hemicube", "montecarlo"] {
        check("inner-box:res=2", ff, &["1e-4", "1e4"], F_TOLERANCE);
        // A coloured variant, with only the inner box emitting, solves three channels.
        let coloured = "inner-box:res=2:rho=0.9/0.5/0.1:emission=0:inner-emission=5/1/0";
        check(coloured, ff, &["1e-4", "1e4"], F_TOLERANCE);
    }
}

#[test]
fn monte_carlo_rays_hit_the_same_patches_at_every_scale() {
    let tallies = |s: &str| {
        let scene = load_scene(&format!("inner-box:res=3:scale={s}")).unwrap().scene;
        let vis = Visibility::new(&scene);
        let mc = MonteCarloColumns::new(&scene, &vis, MonteCarloParams { rays: 2000, seed: 1 });
        (0..scene.len()).map(|j| mc.tally(j)).collect::<Vec<_>>()
    };
    let one = tallies("1");
    // When scenes meshed at the target scale, the wall at x = 1e-4 leaned by 2e-16 and its
    // rays left in other directions (res=2 did not show it: halves subdivide exactly).
    for s in ["1e-4", "1e4", "1e-8", "1e8"] {
        assert_eq!(tallies(s), one, "scale {s}");
    }
}

#[test]
fn furnace_with_a_block_has_the_same_analytic_form_factors_at_both_extreme_scales() {
    let small = compute("furnace:res=2:block=true:scale=1e-4", "analytic");
    let large = compute("furnace:res=2:block=true:scale=1e4", "analytic");
    let d = relative_difference(&small.f, &large.f);
    assert!(d <= F_TOLERANCE, "furnace F differs between scales 1e-4 and 1e4 by {d:.2e}");
    let db = relative_difference(&radiosity(&small), &radiosity(&large));
    assert!(db <= B_TOLERANCE, "furnace B differs by {db:.2e}");
}

#[test]
fn extreme_cases_of_the_suite_do_not_depend_on_the_scale() {
    // Measured worst differences over these cases: 3.9e-15 of the largest entry (analytic,
    // the box on the floor at scale 1e4), except the thin slab under the hemicube, below.
    let scales = ["1e-8", "1e-4", "1e4", "1e8"];
    for base in [
        // The suite's own scale cases are the default layout, res=3, at 1e-4 and 1e4.
        "inner-box",
        "inner-box:res=2:size=5e-4:height=5e-4",
        "inner-box:res=2:gap=0",
        "inner-box:res=2:gap=1e-6",
        "inner-box:res=2:size=0.8:height=1e-4:gap=0.45",
    ] {
        check(base, "analytic", &scales, F_TOLERANCE);
        check(base, "montecarlo:rays=2000", &scales, F_TOLERANCE);
        // The slab's sides are 1e-4 high between y = 0.45 and 0.4501, so their height, and
        // area, is known only to ulp(0.45) / 1e-4 ≈ 5.6e-13 relative, rounded differently at
        // each scale. The hemicube divides its row entries by the receiver's area, which
        // carries that error into F (measured 4.1e-13 of the largest entry); the analytic
        // backend integrates over the same area it divides by, and it cancels.
        let hemicube_tolerance = if base.contains("height=1e-4") { 2e-12 } else { F_TOLERANCE };
        check(base, "hemicube:res=64", &scales, hemicube_tolerance);
    }
}
