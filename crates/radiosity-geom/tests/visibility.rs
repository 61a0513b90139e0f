//! Tests of visibility on hand-built cases: blocked, unblocked, grazing, touching patches,
//! huge and tiny coordinates, self-intersection and queries from many threads.

use radiosity_core::{Material, Scene, Spectrum, Vec3};
use radiosity_geom::{SceneBuilder, Visibility};

fn v(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x, y, z)
}

/// A floor [0,1]² at y = 0 facing up, a ceiling at y = 2 facing down, and optionally a
/// blocker square [0.25, 0.75]² at y = 1; everything scaled by `s` and moved by `offset`.
fn sandwich(blocker: bool, s: f64, offset: Vec3) -> Scene {
    let mut b = SceneBuilder::new("sandwich");
    let m = b.material(Material::new("m", Spectrum::grey(0.5), Spectrum::ZERO)).unwrap();
    let o = b.object("o");
    let t = |p: Vec3| p * s + offset;
    b.polygon(&[t(v(0., 0., 0.)), t(v(0., 0., 1.)), t(v(1., 0., 1.)), t(v(1., 0., 0.))], m, o).unwrap();
    b.polygon(&[t(v(0., 2., 0.)), t(v(1., 2., 0.)), t(v(1., 2., 1.)), t(v(0., 2., 1.))], m, o).unwrap();
    if blocker {
        b.polygon(&[t(v(0.25, 1., 0.25)), t(v(0.25, 1., 0.75)), t(v(0.75, 1., 0.75)), t(v(0.75, 1., 0.25))], m, o)
            .unwrap();
    }
    b.build().unwrap()
}

#[test]
fn blocked_and_unblocked_segments() {
    let vis = Visibility::new(&sandwich(true, 1.0, Vec3::ZERO));
    assert_eq!(vis.triangle_count(), 6);
    // Straight through the blocker's middle, and through a point just inside its edge.
    assert!(!vis.unoccluded_between(v(0.5, 0., 0.5), 0, v(0.5, 2., 0.5), 1));
    assert!(!vis.unoccluded_between(v(0.26, 0., 0.5), 0, v(0.26, 2., 0.5), 1));
    // Beside the blocker, and diagonally past its edge.
    assert!(vis.unoccluded_between(v(0.1, 0., 0.5), 0, v(0.1, 2., 0.5), 1));
    assert!(vis.unoccluded_between(v(0.0, 0., 0.0), 0, v(0.4, 2., 0.0), 1));
    // Without the blocker everything is visible.
    let open = Visibility::new(&sandwich(false, 1.0, Vec3::ZERO));
    assert!(open.unoccluded_between(v(0.5, 0., 0.5), 0, v(0.5, 2., 0.5), 1));
}

#[test]
fn grazing_segments() {
    let vis = Visibility::new(&sandwich(true, 1.0, Vec3::ZERO));
    // Exactly through the blocker's edge counts as blocked (edges are inclusive) ...
    assert!(!vis.unoccluded(v(0.25, 0.5, 0.5), v(0.25, 1.5, 0.5)));
    // ... through its corner too, and a hair outside it does not.
    assert!(!vis.unoccluded(v(0.75, 0.5, 0.75), v(0.75, 1.5, 0.75)));
    assert!(vis.unoccluded(v(0.75 + 1e-9, 0.5, 0.5), v(0.75 + 1e-9, 1.5, 0.5)));
    // A segment lying in the blocker's plane grazes it and is not blocked by it.
    assert!(vis.unoccluded(v(-0.5, 1.0, 0.5), v(1.5, 1.0, 0.5)));
}

#[test]
fn points_on_patches_do_not_shadow_themselves() {
    let vis = Visibility::new(&sandwich(false, 1.0, Vec3::ZERO));
    // Free points lying exactly on the floor and the ceiling.
    assert!(vis.unoccluded(v(0.3, 0., 0.3), v(0.9, 2., 0.1)));
    // Grazing departures from the floor, with the patches known.
    assert!(vis.unoccluded_between(v(0.0, 0., 0.0), 0, v(1.0, 2., 1.0), 1));
    assert!(vis.unoccluded_between(v(1e-12, 0., 0.5), 0, v(1.0 - 1e-12, 2., 0.5), 1));
}

/// Two patches meeting along an edge (a floor and a wall), and a third, wall-high, patch that
/// touches the floor's far edge.
fn corner() -> Scene {
    let mut b = SceneBuilder::new("corner");
    let m = b.material(Material::new("m", Spectrum::grey(0.5), Spectrum::ZERO)).unwrap();
    let o = b.object("o");
    b.polygon(&[v(0., 0., 0.), v(0., 0., 1.), v(1., 0., 1.), v(1., 0., 0.)], m, o).unwrap(); // floor, up
    b.polygon(&[v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)], m, o).unwrap(); // wall x = 0, +x
    b.polygon(&[v(1., 0., 0.), v(1., 0., 1.), v(1., 1., 1.), v(1., 1., 0.)], m, o).unwrap(); // wall x = 1, -x
    b.build().unwrap()
}

#[test]
fn touching_patches_see_each_other_up_to_the_shared_edge() {
    let vis = Visibility::new(&corner());
    for d in [0.5, 1e-3, 1e-6, 1e-9, 1e-12] {
        assert!(vis.unoccluded_between(v(d, 0., 0.5), 0, v(0., d, 0.5), 1), "distance {d}");
        assert!(vis.unoccluded_between(v(1.0 - d, 0., 0.5), 0, v(1., d, 0.5), 2), "distance {d}");
    }
    // The two walls face each other across the floor.
    assert!(vis.unoccluded_between(v(0., 0.5, 0.5), 1, v(1., 0.5, 0.5), 2));
    assert!(vis.unoccluded_between(v(0., 1e-9, 0.5), 1, v(1., 1e-9, 0.5), 2));
}

#[test]
fn answers_do_not_depend_on_scale_or_position() {
    let queries = [
        (v(0.5, 0., 0.5), v(0.5, 2., 0.5), false),
        (v(0.26, 0., 0.5), v(0.26, 2., 0.5), false),
        (v(0.1, 0., 0.5), v(0.1, 2., 0.5), true),
        (v(0.74, 0., 0.74), v(0.74, 2., 0.74), false),
        (v(0.76, 0., 0.74), v(0.76, 2., 0.74), true),
        (v(0.0, 0., 0.0), v(0.4, 2., 0.0), true),
    ];
    for s in [1e-4, 1.0, 1e4] {
        for offset in [Vec3::ZERO, v(1e4, -3e4, 5e3), v(-1e-3, 2e-3, 7e-4)] {
            let vis = Visibility::new(&sandwich(true, s, offset));
            for (p, q, visible) in queries {
                let (p, q) = (p * s + offset, q * s + offset);
                assert_eq!(vis.unoccluded_between(p, 0, q, 1), visible, "scale {s}, offset {offset}, {p} -> {q}");
                let first = vis.first_hit(p, q - p, Some(0)).unwrap();
                assert_eq!(first.patch, if visible { 1 } else { 2 });
                // The ceiling faces down (front), the blocker faces up (back).
                assert_eq!(first.front, visible);
            }
        }
    }
}

#[test]
fn first_hit_and_escape() {
    let vis = Visibility::new(&sandwich(true, 1.0, Vec3::ZERO));
    let hit = vis.first_hit(v(0.5, 0., 0.5), Vec3::Y, Some(0)).unwrap();
    assert_eq!(hit.patch, 2);
    assert!((hit.t - 1.0).abs() < 1e-12);
    // From above the ceiling, looking down: the back of the ceiling.
    let back = vis.first_hit(v(0.1, 3., 0.1), Vec3::NEG_Y, None).unwrap();
    assert_eq!((back.patch, back.front), (1, false));
    let front = vis.first_hit(v(0.1, 1., 0.1), Vec3::Y, None).unwrap();
    assert_eq!((front.patch, front.front), (1, true));
    assert!(vis.escapes(v(0.5, 0., 0.5), Vec3::X, Some(0)));
    assert!(!vis.escapes(v(0.5, 0., 0.5), v(0.1, 1., 0.0), Some(0)));
    assert!(vis.first_hit(v(0.5, 0., 0.5), Vec3::NEG_Y, Some(0)).is_none());
}

#[test]
fn queries_from_many_threads_agree() {
    let scene = radiosity_geom::load_scene("multi-cubes").unwrap().scene;
    let vis = Visibility::new(&scene);
    let pairs: Vec<(usize, usize)> = (0..400).map(|k| ((k * 37) % 480, (k * 91 + 11) % 480)).collect();
    let query = |&(i, j): &(usize, usize)| {
        let (a, b) = (&scene.patches()[i], &scene.patches()[j]);
        vis.unoccluded_between(a.centroid(), i, b.centroid(), j)
    };
    let serial: Vec<bool> = pairs.iter().map(query).collect();
    // Some pairs are hidden and some are not, or the comparison would prove nothing.
    assert!(serial.iter().any(|&x| x) && serial.iter().any(|&x| !x));
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..4).map(|_| s.spawn(|| pairs.iter().map(query).collect::<Vec<bool>>())).collect();
        for h in handles {
            assert_eq!(h.join().unwrap(), serial);
        }
    });
}

#[test]
fn occluders_right_next_to_the_origin_are_found() {
    // obvhs skips BVH nodes nearer than 1e-4 ray units; occluders far nearer must still count.
    for s in [1e-4, 1.0, 1e4] {
        let vis = Visibility::new(&sandwich(true, s, Vec3::ZERO));
        for gap in [1e-3, 1e-6, 1e-8] {
            let p = v(0.5, 1.0 - gap, 0.5) * s;
            assert!(!vis.unoccluded(p, v(0.5, 2.0, 0.5) * s), "scale {s}, gap {gap}");
            assert!(!vis.unoccluded(v(0.5, 0.0, 0.5) * s, v(0.5, 1.0 + gap, 0.5) * s), "scale {s}, gap {gap}");
            let hit = vis.first_hit(p, Vec3::Y, None).unwrap();
            assert_eq!(hit.patch, 2);
            assert!((hit.t - gap * s).abs() <= 1e-9 * s, "scale {s}, gap {gap}, t {}", hit.t);
        }
    }
}

#[test]
fn bvh_hits_agree_with_brute_force() {
    use rand::{Rng, SeedableRng};
    for arg in ["multi-cubes", "furnace:block=true", "cornell:res=4"] {
        let scene = radiosity_geom::load_scene(arg).unwrap().scene;
        let vis = Visibility::new(&scene);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut near_wall = 0;
        for k in 0..3000 {
            let i = rng.random_range(0..scene.len());
            let patch = &scene.patches()[i];
            // Half the origins hug the patch's edges, where neighbouring walls are closest.
            let (a, b) = if k % 2 == 0 {
                (rng.random::<f64>(), rng.random::<f64>())
            } else {
                near_wall += 1;
                (1e-5 * rng.random::<f64>(), rng.random::<f64>())
            };
            let origin = patch.point_at(a, b);
            let d = Vec3::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5);
            let d = if d.dot(patch.normal()) < 0.0 { -d } else { d };
            let fast = vis.first_hit(origin, d, Some(i));
            let slow = vis.first_hit_brute_force(origin, d, Some(i));
            assert_eq!(fast.map(|h| h.patch), slow.map(|h| h.patch), "{arg}: ray {k} from patch {i}");
            assert_eq!(vis.escapes(origin, d, Some(i)), slow.is_none(), "{arg}: ray {k}");
        }
        assert!(near_wall > 1000);
    }
}

#[test]
fn rays_along_axes_with_negative_zero_components_hit() {
    // `-Vec3::Y` is (−0, −1, −0): obvhs reads a ray's octant from the sign bits, so such rays
    // once missed the floor of every room. Every axis direction, both signs of zero, must agree
    // with the brute-force answer.
    let scene = radiosity_geom::load_scene("furnace:block=true").unwrap().scene;
    let vis = Visibility::new(&scene);
    let origin = v(0.31, 0.37, 0.29);
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        for d in [axis, -axis, axis * -1.0, Vec3::ZERO - axis] {
            let fast = vis.first_hit(origin, d, None).map(|h| h.patch);
            assert!(fast.is_some(), "{d:?} escapes a closed box");
            assert_eq!(fast, vis.first_hit_brute_force(origin, d, None).map(|h| h.patch), "{d:?}");
            assert!(!vis.escapes(origin, d, None), "{d:?}");
        }
    }
}
