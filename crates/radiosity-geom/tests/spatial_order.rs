//! Tests of the spatially coherent patch order: a permutation whose consecutive patches lie
//! nearer each other than in a shuffled order.

use radiosity_core::{Real, Scene};
use radiosity_geom::{load_scene, spatial_order};

/// The mean distance between the centroids of patches consecutive in `order`.
fn mean_step(scene: &Scene, order: &[usize]) -> Real {
    let c = |i: usize| scene.patches()[i].centroid();
    let total: Real = order.windows(2).map(|w| c(w[0]).distance(c(w[1]))).sum();
    total / (order.len() - 1) as Real
}

fn is_permutation(order: &[usize], n: usize) -> bool {
    let mut sorted = order.to_vec();
    sorted.sort_unstable();
    sorted == (0..n).collect::<Vec<_>>()
}

#[test]
fn the_spatial_order_is_a_coherent_permutation() {
    // Measured mean steps (Morton, index order, shuffled): multi-cubes 0.54, 0.83, 3.1;
    // cornell:res=2 219, 261, 412; the furnace with its block 0.48, 0.65, 0.65.
    for arg in ["multi-cubes", "cornell:res=2", "furnace:res=2:block=true"] {
        let scene = load_scene(arg).unwrap().scene;
        let n = scene.len();
        let order = spatial_order(&scene);
        assert!(is_permutation(&order, n), "{arg}: {order:?}");
        // A deterministic shuffle: 7919 is prime and divides none of these n.
        let shuffled: Vec<usize> = (0..n).map(|i| i * 7919 % n).collect();
        assert!(is_permutation(&shuffled, n), "{arg}: 7919 shares a factor with n = {n}");
        let (coherent, scattered) = (mean_step(&scene, &order), mean_step(&scene, &shuffled));
        assert!(coherent < scattered, "{arg}: mean step {coherent} in Morton order, {scattered} shuffled");
    }
    // In the paper's scene the order is much more coherent than a shuffle, and more than the
    // meshers' own order (object by object).
    let scene = load_scene("multi-cubes").unwrap().scene;
    let n = scene.len();
    let coherent = mean_step(&scene, &spatial_order(&scene));
    let scattered = mean_step(&scene, &(0..n).map(|i| i * 7919 % n).collect::<Vec<_>>());
    let by_index = mean_step(&scene, &(0..n).collect::<Vec<_>>());
    assert!(coherent < 0.5 * scattered && coherent < by_index, "{coherent}, {scattered} shuffled, {by_index} by index");
}

#[test]
fn the_spatial_order_is_deterministic() {
    let scene = load_scene("multi-cubes").unwrap().scene;
    assert_eq!(spatial_order(&scene), spatial_order(&scene));
}
