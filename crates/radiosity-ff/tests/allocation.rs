//! Computing a pair of the analytic backend allocates nothing, whatever its number of shadow
//! rays: the quadrature, the probe, the grid, the Sobol net and the Latin hypercubes all live
//! on the stack, so a column's cost is its arithmetic and its rays.
//!
//! `allocation-counter` makes the test binary's allocator count the allocations of each
//! thread; every other test of the binary allocates through it unchanged. The hierarchical
//! operator's own count of the bytes it holds is checked against it too.

use radiosity_core::{MaterialId, ObjectId, Patch, Real, Vec3};
use radiosity_ff::pair_visibility::{RayBudget, visible_fraction};
use radiosity_ff::{AnalyticColumns, AnalyticParams, BackendSpec};
use radiosity_geom::{SceneAnalysis, Visibility, load_scene};
use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

/// The allocations `f` makes on this thread, and its value.
fn allocations_of<T>(f: impl FnOnce() -> T) -> (u64, T) {
    let mut value = None;
    let info = allocation_counter::measure(|| value = Some(f()));
    (info.count_total, value.expect("measured"))
}

#[test]
fn the_counter_counts() {
    // Without it, a zero below could mean a counter that was never installed.
    let (allocated, v) = allocations_of(|| std::hint::black_box(vec![1u8; 10]));
    assert_eq!((allocated, v.len()), (1, 10));
}

#[test]
fn visible_fractions_allocate_nothing_at_any_ray_count() {
    // A floor and a wall sharing an edge, half of the floor hidden, so that the probes of
    // large budgets disagree and the estimate takes all of its rays, from 1 to 2^20.
    let (m, o) = (MaterialId(0), ObjectId(0));
    let quad = |v: [[Real; 3]; 4]| Patch::quad(v.map(Vec3::from), m, o).unwrap();
    let floor = quad([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 0.0, 0.0]]);
    let wall = quad([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]);
    for rays in [1, 2, 15, 16, 17, 255, 256, 1000, 4096, 65_536, 1 << 20] {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(rays as u64);
        let mut traced = 0usize;
        let mut half = |x: Vec3, _: usize, _: Vec3, _: usize| {
            traced += 1;
            x.z <= 0.5
        };
        let budget = RayBudget { rays, per_unit: 0 };
        let (allocated, v) =
            allocations_of(|| visible_fraction((&floor, 0), (&wall, 1), 0.2, budget, 1e-12, &mut rng, &mut half));
        assert_eq!(allocated, 0, "{rays} rays allocated {allocated} times");
        assert!((0.0..=1.0).contains(&v), "{rays} rays: {v}");
        if rays >= 256 {
            // The probe disagreed, and every ray of the budget was drawn.
            assert!(v > 0.0 && v < 1.0, "{rays} rays: {v}");
            assert!(traced >= rays, "{rays} rays, {traced} traced");
        }
    }
}

#[test]
fn analytic_pairs_allocate_nothing_on_an_occluded_scene() {
    // Every pair of a few columns of multi-cubes at four times the default budget: distant
    // pairs with one ray, neighbours with thousands, touching pairs graded into panels, and
    // pairs cut by each other's planes.
    let scene = load_scene("multi-cubes").unwrap().scene;
    let vis = Visibility::new(&scene);
    let analysis = SceneAnalysis::new(&scene, &vis);
    assert!(analysis.occlusion.value);
    let params = *BackendSpec::parse("analytic:budget=98304").unwrap().params::<AnalyticParams>().expect("analytic");
    let f = AnalyticColumns::new(&scene, &vis, &analysis, params);
    let n = scene.len();
    let mut nonzero = 0;
    for j in (0..n).step_by(n / 7) {
        for i in 0..n {
            let (allocated, value) = allocations_of(|| f.pair(i, j));
            assert_eq!(allocated, 0, "pair ({i}, {j}) allocated {allocated} times");
            nonzero += usize::from(value > 0.0);
        }
    }
    assert!(nonzero > n, "{nonzero} non-zero pairs");
}

#[test]
fn the_hierarchical_operator_counts_the_bytes_it_holds() {
    // The bytes the operator says it holds (`scenes --explain` and `solve --verbose` print them
    // part by part) against the bytes the allocator still holds for it once built: within 10%.
    // The build runs on this thread alone, where the counter counts.
    let p = radiosity_geom::PreparedScene::load("office:size=0.5").unwrap();
    let params = radiosity_ff::HierarchicalParams::default();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).use_current_thread().build().unwrap();
    let mut built = None;
    let info = pool.install(|| {
        allocation_counter::measure(|| {
            built =
                Some(radiosity_ff::HierarchicalColumns::new(p.scene(), &p.visibility().unwrap(), &p.analysis, params));
        })
    });
    let operator = built.unwrap();
    let figures = operator.figures();
    assert_eq!(figures.bytes, figures.held.total());
    let held = info.bytes_current as f64;
    let counted = figures.bytes as f64;
    assert!(
        (counted - held).abs() <= 0.1 * held,
        "counted {counted} bytes, the allocator holds {held} for the operator ({:?})",
        figures.held
    );
    drop(operator);
}

#[test]
fn shooting_from_the_hierarchys_nodes_reads_and_writes_its_buffers_in_place() {
    // A node shooter's charges, a shot and its push, a channel at a time: the operator works
    // in the solver's own buffers, allocating a vector over the patches at most, not a copy
    // of every node's moments or forms (96 bytes a node, 2 GB a channel at ten million
    // patches).
    use radiosity_core::LinkSource;
    let p = radiosity_geom::PreparedScene::load("office:size=0.5").unwrap();
    let operator =
        radiosity_ff::HierarchicalColumns::new(p.scene(), &p.visibility().unwrap(), &p.analysis, Default::default());
    let (n, nodes) = (p.scene().len(), operator.parents().len());
    let x: Vec<Real> = (0..n).map(|i| 1.0 + (i % 7) as Real).collect();
    let mut charges = vec![0.0; nodes * operator.charge_len()];
    let mut fields = vec![0.0; nodes * operator.field_len()];
    let mut out = vec![0.0; n];
    let sending = vec![true; nodes];
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).use_current_thread().build().unwrap();
    let info = pool.install(|| {
        allocation_counter::measure(|| {
            operator.charges(&x, 1, &mut charges);
            operator.shoot(&charges, &sending, 1, &mut fields);
            operator.evaluate(&mut fields, 1, &mut out);
            operator.clear(&sending, 1, &mut charges);
        })
    });
    let most = (n * size_of::<Real>()) as u64 + 4096;
    assert!(info.bytes_max <= most, "{} bytes at most, {most} allowed, {nodes} nodes", info.bytes_max);
    // Every node sent what it held: the push gives the product, and the charges are clear.
    let mut product = vec![0.0; n];
    radiosity_core::ColumnSource::multiply(&operator, &x, 1, &mut product);
    for (a, b) in out.iter().zip(&product) {
        assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-300), "{a} against {b}");
    }
    assert!(charges.iter().all(|c| *c == 0.0));
}
