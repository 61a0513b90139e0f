//! Tests of the montecarlo backend: Howell's closed forms within the reported standard
//! deviation, unbiasedness across seeds, exact ray accounting in closed boxes, back faces,
//! uniform sampling of any patch shape, and determinism.

use super::closed_forms::*;
use radiosity_core::{ColumnSource, Material, Real, Scene, Spectrum, Vec3};
use radiosity_ff::ff_point_polygon::point_to_polygon;
use radiosity_ff::montecarlo::MAX_BATCH;
use radiosity_ff::{MonteCarloColumns, MonteCarloParams};
use radiosity_geom::mesh::{BoxFace, Facing};
use radiosity_geom::{SceneBuilder, Visibility, load_scene};

fn params(rays: usize, seed: u64) -> MonteCarloParams {
    MonteCarloParams { rays, seed }
}

/// Column `j` and its reported variance.
fn column(source: &MonteCarloColumns<'_>, j: usize) -> (Vec<Real>, Vec<Real>) {
    let n = source.patch_count();
    let (mut column, mut variance) = (vec![0.0; n], vec![0.0; n]);
    source.column_with_variance(j, &mut column, &mut variance);
    (column, variance)
}

/// All columns of `source`, computed on a rayon pool of `threads` threads.
fn mean_and_sample_variance(values: &[Real]) -> (Real, Real) {
    let k = values.len() as Real;
    let mean = values.iter().sum::<Real>() / k;
    (mean, values.iter().map(|v| (v - mean).powi(2)).sum::<Real>() / (k - 1.0))
}

#[test]
fn howells_values_lie_within_four_reported_sigmas() {
    // One patch per rectangle: F_12 aggregated is column 1's entry 0. Measured with 10^5
    // rays, seed 0: σ = 1.26e-3 for both, errors -1.7σ (opposed) and -0.34σ (corner).
    let rays = 100_000;
    for (scene, exact) in
        [(opposed_squares(1), parallel(1.0, 1.0, 1.0)), (corner(1.0, 1.0, 1.0, 1), perpendicular(1.0, 1.0, 1.0))]
    {
        let vis = Visibility::new(&scene);
        let mc = MonteCarloColumns::new(&scene, &vis, params(rays, 0));
        let estimate = aggregate(&scene, &mc, 1);
        let (col, variance) = column(&mc, 1);
        assert_eq!(col[0], estimate);
        let sigma = variance[0].sqrt();
        // The plug-in bound is the multinomial variance times B/(B - 1) ≈ 1.
        let multinomial = (estimate * (1.0 - estimate) / rays as Real).sqrt();
        assert!(sigma >= multinomial && sigma < 1.001 * multinomial, "{sigma} vs {multinomial}");
        assert!((estimate - exact).abs() < 4.0 * sigma, "{estimate} vs {exact} (σ {sigma})");
        assert_eq!((col[1], variance[1]), (0.0, 0.0));
        assert_eq!(mc.clamped(), 0);
    }
}

#[test]
fn the_estimate_is_unbiased_across_seeds_and_the_variance_conservative() {
    // 20 seeds × 10^4 rays. Measured: the mean is within 1σ/√20 of Howell's value, and the
    // spread across seeds is about 0.8 of the reported σ (Latin hypercube sampling removes
    // a little variance; the reported bound does not count on it).
    let (rays, seeds) = (10_000, 20);
    for (scene, exact) in
        [(opposed_squares(1), parallel(1.0, 1.0, 1.0)), (corner(1.0, 1.0, 1.0, 1), perpendicular(1.0, 1.0, 1.0))]
    {
        let vis = Visibility::new(&scene);
        let (mut estimates, mut variances) = (Vec::new(), Vec::new());
        for seed in 0..seeds {
            let (col, variance) = column(&MonteCarloColumns::new(&scene, &vis, params(rays, seed)), 1);
            estimates.push(col[0]);
            variances.push(variance[0]);
        }
        let (mean, spread) = mean_and_sample_variance(&estimates);
        let reported = variances.iter().sum::<Real>() / seeds as Real;
        let sigma_of_mean = (reported / seeds as Real).sqrt();
        assert!((mean - exact).abs() < 4.0 * sigma_of_mean, "{mean} vs {exact} (σ/√k {sigma_of_mean})");
        // With 20 draws the sample variance is within a factor 2 of the true one with
        // probability > 0.99, so this fails only if the reported variance is too small.
        assert!(spread < 2.0 * reported, "spread {spread:e} vs reported {reported:e}");
        // Seeds give different estimates.
        assert!(estimates.windows(2).any(|w| w[0] != w[1]));
    }
}

/// Every patch's tally in `scene`: no ray escapes, and front and back hits account for every
/// ray. Returns the back hits of every shooter.
fn closed_box_tallies(scene: &Scene, rays: usize) -> Vec<u64> {
    let vis = Visibility::new(scene);
    let mc = MonteCarloColumns::new(scene, &vis, params(rays, 3));
    (0..scene.len())
        .map(|j| {
            let tally = mc.tally(j);
            assert_eq!(tally.rays, rays as u64);
            assert_eq!(tally.escaped, 0, "shooter {j}");
            assert_eq!(tally.front.iter().sum::<u64>() + tally.back, tally.rays, "shooter {j}");
            assert_eq!(tally.front[j], 0, "shooter {j} hit itself");
            tally.back
        })
        .collect()
}

#[test]
fn rows_sum_to_one_in_a_closed_furnace() {
    let rays = 4_000;
    for arg in ["furnace:res=2", "furnace:res=2:block=true"] {
        let scene = load_scene(arg).unwrap().scene;
        // Every ray hits the front of some patch: the shooter's row sums to exactly 1.
        assert!(closed_box_tallies(&scene, rays).iter().all(|&b| b == 0));
        let vis = Visibility::new(&scene);
        let mc = MonteCarloColumns::new(&scene, &vis, params(rays, 3));
        let n = scene.len();
        let area: Vec<Real> = scene.patches().iter().map(|p| p.area()).collect();
        let (mut rows, mut row_variance) = (vec![0.0; n], vec![0.0; n]);
        for j in 0..n {
            let (col, variance) = column(&mc, j);
            let shooter: Real = (0..n).map(|i| area[i] * col[i] / area[j]).sum();
            assert!((shooter - 1.0).abs() < 1e-12, "{arg}: shooter {j}: {shooter}");
            for i in 0..n {
                rows[i] += col[i];
                row_variance[i] += variance[i];
            }
        }
        // An assembled row Σ_j F_ij gathers independent estimates from every shooter; it is
        // unbiased for the true closure 1, with variance Σ_j Var(F_ij).
        for i in 0..n {
            let sigma = row_variance[i].sqrt();
            assert!((rows[i] - 1.0).abs() < 4.0 * sigma, "{arg}: row {i}: {} (σ {sigma})", rows[i]);
        }
    }
}

/// The unit box facing inwards with a block `[0.3, 0.7]³` whose faces point into it: the
/// walls see the block's back.
pub(super) fn box_with_inverted_block() -> Scene {
    let mut b = SceneBuilder::new("inverted block");
    let grey = b.material(Material::new("grey", Spectrum::grey(0.5), Spectrum::grey(1.0))).unwrap();
    let walls = b.object("walls");
    b.axis_box([Vec3::ZERO, Vec3::ONE], &BoxFace::ALL, Facing::Inward, 0.5, grey, walls).unwrap();
    let block = b.object("block");
    b.axis_box([Vec3::splat(0.3), Vec3::splat(0.7)], &BoxFace::ALL, Facing::Inward, 0.5, grey, block).unwrap();
    b.build().unwrap()
}

#[test]
fn back_faces_receive_nothing_and_every_ray_is_accounted_for() {
    // Closed, so no ray escapes: the front-hit fractions sum to exactly 1 minus the
    // back-hit fraction. The walls' rays that meet the block land on its back; the block's
    // own patches face into it and see only its other faces' fronts.
    let scene = box_with_inverted_block();
    let walls = 24;
    let backs = closed_box_tallies(&scene, 2_000);
    assert!(backs[..walls].iter().all(|&b| b > 0));
    assert!(backs[walls..].iter().all(|&b| b == 0));
    let vis = Visibility::new(&scene);
    let mc = MonteCarloColumns::new(&scene, &vis, params(2_000, 3));
    let mut col = vec![0.0; scene.len()];
    for j in 0..walls {
        mc.fill_column(j, &mut col);
        assert!(col[walls..].iter().all(|&f| f == 0.0), "a wall's light reached the block");
    }

    // Opposed squares turned away from each other: no front is hit, every ray escapes or
    // lands on the other's back.
    let flipped = two_rectangles([Vec3::ZERO, Vec3::X, Vec3::Y], [Vec3::new(0.0, 0.0, 1.0), Vec3::X, Vec3::Y], 1);
    let vis = Visibility::new(&flipped);
    let mc = MonteCarloColumns::new(&flipped, &vis, params(5_000, 0));
    let tally = mc.tally(0);
    assert_eq!(tally.front, vec![0, 0]);
    assert!(tally.back > 0);
    assert_eq!(tally.back + tally.escaped, 5_000);
    assert_eq!(all_columns(&mc, 1), vec![vec![0.0; 2]; 2]);
}

/// A shooter at z = 0 facing up (`shape`, counter-clockwise from above) and a unit square at
/// z = 0.5 facing down over its narrow end.
fn shooter_and_square(shape: &[Vec3]) -> Scene {
    let mut b = SceneBuilder::new("shapes");
    let grey = b.material(Material::new("grey", Spectrum::grey(0.5), Spectrum::grey(1.0))).unwrap();
    let object = b.object("shapes");
    b.polygon(shape, grey, object).unwrap();
    let p = |x: Real, y: Real| Vec3::new(x, y, 0.5);
    b.polygon(&[p(1.0, -0.5), p(1.0, 0.5), p(2.0, 0.5), p(2.0, -0.5)], grey, object).unwrap();
    b.build().unwrap()
}

#[test]
fn points_are_uniform_by_area_on_any_patch_shape() {
    // F_10 = (1/A_1) ∫_{A_1} F(dA_x → P_0) dA_x by a 200 × 200 midpoint rule on the square,
    // against the rays from the shooter P_0 (a trapezoid, which a bilinear map would sample
    // far too densely at its narrow end, and a triangle).
    let p = |x: Real, y: Real| Vec3::new(x, y, 0.0);
    let trapezoid = [p(0.0, -1.0), p(2.0, -0.2), p(2.0, 0.2), p(0.0, 1.0)];
    let triangle = [p(0.0, -1.0), p(2.0, 0.0), p(0.0, 1.0)];
    for shape in [&trapezoid[..], &triangle[..]] {
        let scene = shooter_and_square(shape);
        let (shooter, square) = (&scene.patches()[0], &scene.patches()[1]);
        let k = 200;
        let mut exact = 0.0;
        for a in 0..k {
            for b in 0..k {
                let x = square.point_at((a as Real + 0.5) / k as Real, (b as Real + 0.5) / k as Real);
                exact += point_to_polygon(x, square.normal(), shooter.vertices());
            }
        }
        exact /= (k * k) as Real;
        let vis = Visibility::new(&scene);
        let (col, variance) = column(&MonteCarloColumns::new(&scene, &vis, params(200_000, 0)), 0);
        let sigma = variance[1].sqrt();
        assert!((col[1] - exact).abs() < 4.0 * sigma, "{} vs {exact} (σ {sigma})", col[1]);
    }
}

#[test]
fn columns_are_deterministic_whatever_the_threads() {
    // More rays than one batch, so batches are traced in parallel.
    let rays = 2 * MAX_BATCH + 17;
    let scene = opposed_squares(3);
    let vis = Visibility::new(&scene);
    let a = MonteCarloColumns::new(&scene, &vis, params(rays, 5));
    let b = MonteCarloColumns::new(&scene, &vis, params(rays, 5));
    let one = assert_thread_independent(&a);
    assert_eq!(one, all_columns(&b, 1));
    // fill_column and column_with_variance agree.
    for (j, expected) in one.iter().enumerate() {
        assert_eq!(&column(&a, j).0, expected);
    }
    let other = MonteCarloColumns::new(&scene, &vis, params(rays, 6));
    assert_ne!(one, all_columns(&other, 1));
}

#[test]
fn odd_inputs_do_not_panic() {
    let scene = opposed_squares(1);
    let vis = Visibility::new(&scene);
    let none = MonteCarloColumns::new(&scene, &vis, params(0, 0));
    assert_eq!(column(&none, 1), (vec![0.0; 2], vec![0.0; 2]));
    assert_eq!(none.tally(1).rays, 0);
    let one = MonteCarloColumns::new(&scene, &vis, params(1, 0));
    assert_eq!(one.variance_factor(), 1.0);
    let (col, _) = column(&one, 1);
    assert!(col[0] == 0.0 || col[0] == 1.0);
    let mc = MonteCarloColumns::new(&scene, &vis, params(100, 0));
    let (col, variance) = column(&mc, 7);
    assert_eq!((col, variance), (vec![0.0; 2], vec![0.0; 2]));
    assert_eq!(mc.tally(7).rays, 0);
    mc.fill_column(1, &mut [0.0; 1]);
    mc.fill_column(1, &mut [0.0; 5]);
    mc.column_with_variance(1, &mut [0.0; 2], &mut [0.0; 1]);
}
