//! Tests of the `office` scene's `floors` parameter: each storey is the first one moved up by
//! the 3 m storey height (same patches, order and materials, names prefixed `storey N `), the
//! storeys are closed rooms that cannot see each other, and the build is deterministic.

use crate::{load, load_err};
use radiosity_core::{Scene, Vec3};
use radiosity_geom::Visibility;
use rand::{Rng, SeedableRng};

/// The storey height the scene documents: a 2.7 m room plus a 0.3 m slab.
const STOREY: f64 = 3.0;

fn scene(arg: &str) -> Scene {
    load(arg).scene
}

/// Every patch's vertices, material and object name, for comparing two builds.
fn fingerprint(s: &Scene) -> Vec<(Vec<Vec3>, u32, String)> {
    s.patches()
        .iter()
        .enumerate()
        .map(|(i, p)| (p.vertices().to_vec(), p.material.0, s.object_of(i).to_string()))
        .collect()
}

#[test]
fn one_floor_is_the_single_room() {
    for (plain, one) in [("office", "office:floors=1"), ("office:desks=4:size=0.3", "office:desks=4:size=0.3:floors=1")]
    {
        let (a, b) = (scene(plain), scene(one));
        assert_eq!(fingerprint(&a), fingerprint(&b), "{one}");
        assert_eq!(a.objects(), b.objects(), "{one}");
        assert!(b.objects().iter().all(|o| !o.starts_with("storey")), "{one}");
    }
}

#[test]
fn each_storey_is_the_first_moved_up_by_the_storey_height() {
    let one = scene("office");
    let n = one.len();
    for floors in [2, 3] {
        let many = scene(&format!("office:floors={floors}"));
        // The slab faces are the storeys' own floors and ceilings: no patch is added.
        assert_eq!(many.len(), floors * n, "floors={floors}");
        assert_eq!(many.emitters().len(), floors * one.emitters().len(), "floors={floors}");
        assert_eq!(many.materials(), one.materials());
        let (lo, hi) = many.bounds();
        let top = (floors - 1) as f64 * STOREY + 2.7;
        assert!(lo.abs_diff_eq(Vec3::ZERO, 1e-12) && hi.abs_diff_eq(Vec3::new(7.2, top, 6.0), 1e-12), "{lo} {hi}");
        for storey in 0..floors {
            let lift = Vec3::new(0.0, storey as f64 * STOREY, 0.0);
            for (i, p) in one.patches().iter().enumerate() {
                let j = storey * n + i;
                let q = &many.patches()[j];
                // Cut in the storey's frame, then moved by a whole number of metres: the
                // vertices are exactly the first storey's plus the lift.
                let moved: Vec<Vec3> = p.vertices().iter().map(|&v| v + lift).collect();
                assert_eq!(q.vertices(), &moved[..], "storey {} patch {i}", storey + 1);
                assert!(q.normal().abs_diff_eq(p.normal(), 1e-12), "storey {} patch {i}", storey + 1);
                assert!((q.area() - p.area()).abs() <= 1e-12 * p.area(), "storey {} patch {i}", storey + 1);
                assert_eq!(q.material, p.material, "storey {} patch {i}", storey + 1);
                let name = one.object_of(i);
                let expected = if storey == 0 { name.to_string() } else { format!("storey {} {name}", storey + 1) };
                assert_eq!(many.object_of(j), expected);
            }
        }
        // Each storey's objects come after all of the storey below's.
        let per_storey = one.objects().len();
        assert_eq!(many.objects().len(), floors * per_storey);
        assert_eq!(many.objects()[per_storey], "storey 2 floor");
    }
}

#[test]
fn storeys_do_not_see_each_other() {
    let s = scene("office:floors=2:size=0.4");
    let n = s.len() / 2;
    let vis = Visibility::new(&s);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    // Upward rays from storey 1 and downward rays from storey 2, from random points of
    // random patches that face at least partly that way.
    for (storey, up) in [(0, 1.0), (1, -1.0)] {
        let mut cast = 0;
        while cast < 400 {
            let i = storey * n + rng.random_range(0..n);
            let p = &s.patches()[i];
            if p.normal().y * up < -0.5 {
                continue;
            }
            let d = Vec3::new(rng.random::<f64>() - 0.5, up * rng.random::<f64>(), rng.random::<f64>() - 0.5);
            if d.dot(p.normal()) <= 0.0 || d.y * up <= 0.0 {
                continue;
            }
            cast += 1;
            let origin = p.point_at(rng.random(), rng.random());
            let hit = vis
                .first_hit(origin, d, Some(i))
                .unwrap_or_else(|| panic!("a ray from patch {i} ({}) leaves its storey", s.object_of(i)));
            assert!(hit.front, "a ray from patch {i} ({}) meets the back of patch {}", s.object_of(i), hit.patch);
            assert_eq!(
                hit.patch / n,
                storey,
                "a ray from patch {i} ({}) reaches patch {} ({}) of the other storey",
                s.object_of(i),
                hit.patch,
                s.object_of(hit.patch)
            );
        }
    }
}

#[test]
fn storeys_are_deterministic_and_bounded() {
    let arg = "office:floors=3:desks=2:size=0.6";
    assert_eq!(fingerprint(&scene(arg)), fingerprint(&scene(arg)));
    assert_eq!(scene(arg).objects(), scene(arg).objects());
    for bad in ["office:floors=0", "office:floors=65", "office:floors=two", "office:floors=-1"] {
        let (_, message) = load_err(bad);
        assert!(message.contains("floors"), "{bad}: {message}");
    }
}
