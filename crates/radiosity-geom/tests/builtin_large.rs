//! Tests of the two large built-in scenes, `labyrinth` and `office`: the paper's patch counts
//! and mean reflectivities, determinism, parameters, the maze, and independent geometric checks
//! that no patch is hidden inside a solid or coincides with another.

use radiosity_core::{Channels, Patch, PatchShape, Scene, Vec3};
use radiosity_geom::load_scene;
use radiosity_geom::scenes::labyrinth::passages;
use std::collections::BTreeSet;

fn scene(arg: &str) -> Scene {
    load_scene(arg).unwrap_or_else(|e| panic!("{arg}: {e}")).scene
}

fn error(arg: &str) -> String {
    match load_scene(arg) {
        Ok(_) => panic!("{arg} should be refused"),
        Err(e) => e.to_string(),
    }
}

/// Every patch's vertices and material, for comparing two builds.
fn fingerprint(s: &Scene) -> Vec<(Vec<Vec3>, u32, u32)> {
    s.patches().iter().map(|p| (p.vertices().to_vec(), p.material.0, p.object.0)).collect()
}

/// Fails if two patches share a centroid (within `1e-9` of the scene diagonal) with parallel
/// or anti-parallel normals: a face drawn twice, or two faces pressed together.
fn assert_no_coincident_patches(s: &Scene) {
    let tol = 1e-9 * s.diagonal();
    let mut order: Vec<usize> = (0..s.len()).collect();
    let c = |i: usize| s.patches()[i].centroid();
    order.sort_by(|&a, &b| c(a).x.total_cmp(&c(b).x));
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if c(j).x - c(i).x > tol {
                break;
            }
            let (p, q) = (&s.patches()[i], &s.patches()[j]);
            let parallel = p.normal().dot(q.normal()).abs() > 1.0 - 1e-9;
            assert!(
                !(parallel && (c(i) - c(j)).length() <= tol),
                "patches {i} and {j} coincide at {:?} ({} / {})",
                c(i),
                s.objects()[p.object.0 as usize],
                s.objects()[q.object.0 as usize]
            );
        }
    }
}

/// The distance along the ray `o + t d` to patch `p`, if it hits it at `t > 0`.
fn hit(p: &Patch, o: Vec3, d: Vec3, eps: f64) -> Option<f64> {
    let n = p.normal();
    let along = n.dot(d);
    if along.abs() < 1e-12 {
        return None;
    }
    let t = n.dot(p.centroid() - o) / along;
    if t <= eps {
        return None;
    }
    let h = o + d * t;
    let v = p.vertices();
    let k = v.len();
    (0..k).all(|i| (v[(i + 1) % k] - v[i]).cross(h - v[i]).dot(n) >= -eps * eps).then_some(t)
}

/// Independent check that every patch faces free space: from a point just in front of a
/// patch, rays into its hemisphere must first meet the front of some patch (or nothing, where
/// `closed` is false). A patch inside a solid, or facing into one, would first meet the back of
/// a face. Patches accepted by `blocker` are the only ones rays can meet.
fn assert_faces_free_space(s: &Scene, closed: bool, stride: usize, blocker: impl Fn(usize) -> bool) {
    let diag = s.diagonal();
    let eps = 1e-9 * diag;
    let (lo, hi) = s.bounds();
    let generic =
        [Vec3::new(0.3137, 0.8261, -0.4676), Vec3::new(-0.5923, 0.4431, 0.6722), Vec3::new(0.7213, -0.1234, 0.5519)];
    let blockers: Vec<usize> = (0..s.len()).filter(|&i| blocker(i)).collect();
    for i in (0..s.len()).step_by(stride) {
        let p = &s.patches()[i];
        let n = p.normal();
        let o = p.centroid() + n * (1e-6 * diag);
        if closed {
            assert!(o.cmpgt(lo).all() && o.cmplt(hi).all(), "patch {i} faces out of the room");
        }
        for g in generic {
            let g = g.normalize();
            let d = (n + 0.8 * if g.dot(n) < 0.0 { -g } else { g }).normalize();
            let first = blockers
                .iter()
                .filter_map(|&j| hit(&s.patches()[j], o, d, eps).map(|t| (t, j)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            match first {
                Some((_, j)) => assert!(
                    s.patches()[j].normal().dot(d) < 0.0,
                    "patch {i} of '{}' sees the back of patch {j} of '{}': it lies in a solid",
                    s.objects()[p.object.0 as usize],
                    s.objects()[s.patches()[j].object.0 as usize]
                ),
                None => assert!(!closed, "a ray from patch {i} leaves the closed room"),
            }
        }
    }
}

fn area_where(s: &Scene, keep: impl Fn(&Patch) -> bool) -> f64 {
    s.patches().iter().filter(|p| keep(p)).map(Patch::area).sum()
}

#[test]
fn labyrinth_default_matches_the_paper() {
    let s = scene("labyrinth");
    assert!((3329..=3395).contains(&s.len()), "{} patches", s.len());
    let rho = s.mean_reflectivity();
    assert!((0.585..=0.595).contains(&rho), "mean reflectivity {rho}");
    assert!(!s.emitters().is_empty());
    assert_eq!(s.channels(), Channels::Rgb);
    assert!(s.patches().iter().all(|p| p.shape() == PatchShape::Quad));
}

#[test]
fn office_default_matches_the_paper() {
    let s = scene("office");
    assert!((10881..=11101).contains(&s.len()), "{} patches", s.len());
    let rho = s.mean_reflectivity();
    assert!((0.425..=0.435).contains(&rho), "mean reflectivity {rho}");
    assert!(!s.emitters().is_empty());
    assert_eq!(s.channels(), Channels::Rgb);
    assert!(s.patches().iter().all(|p| p.shape() == PatchShape::Quad));
}

#[test]
fn large_scenes_are_deterministic() {
    for arg in ["labyrinth", "labyrinth:cells=6:seed=42:size=0.4", "office", "office:desks=4:size=0.3"] {
        assert_eq!(fingerprint(&scene(arg)), fingerprint(&scene(arg)), "{arg}");
    }
}

#[test]
fn labyrinth_seed_changes_the_layout_not_the_statistics() {
    let a = scene("labyrinth:seed=1");
    let b = scene("labyrinth:seed=2");
    assert_ne!(fingerprint(&a), fingerprint(&b));
    assert_eq!(a.len(), b.len());
    assert!((a.mean_reflectivity() - b.mean_reflectivity()).abs() < 1e-12);
    assert_ne!(passages(11, 1), passages(11, 2));
}

#[test]
fn bad_parameters_are_refused_naming_the_key() {
    for (arg, key) in [
        ("labyrinth:cells=0", "cells"),
        ("labyrinth:cells=1000", "cells"),
        ("labyrinth:size=0", "size"),
        ("labyrinth:size=-1", "size"),
        ("labyrinth:seed=-3", "seed"),
        ("labyrinth:lights=0", "lights"),
        ("labyrinth:cells=2:lights=5", "lights"),
        ("labyrinth:light=-1", "light"),
        ("labyrinth:walls=3", "walls"),
        ("office:size=-1", "size"),
        ("office:size=abc", "size"),
        ("office:desks=10", "desks"),
        ("office:light=1/2", "light"),
    ] {
        let message = error(arg);
        assert!(message.contains(key), "{arg}: {message}");
    }
}

#[test]
fn mazes_are_perfect() {
    for (n, seed) in [(1, 0), (2, 5), (5, 1), (11, 1998), (20, 7), (37, 123_456_789)] {
        let edges = passages(n, seed);
        assert_eq!(edges.len(), n * n - 1, "{n} cells, seed {seed}");
        let mut parent: Vec<usize> = (0..n * n).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        for [(a, b), (c, d)] in edges {
            assert!(a < n && b < n && c < n && d < n);
            assert_eq!(a.abs_diff(c) + b.abs_diff(d), 1, "passage between non-neighbours");
            let (x, y) = (root(&mut parent, b * n + a), root(&mut parent, d * n + c));
            assert_ne!(x, y, "passage closes a loop");
            parent[x] = y;
        }
        let r = root(&mut parent, 0);
        assert!((0..n * n).all(|i| root(&mut parent, i) == r), "cells not all reachable");
    }
}

#[test]
fn labyrinth_geometry_follows_its_maze() {
    let n = 11;
    let s = scene("labyrinth");
    let maze: BTreeSet<[(usize, usize); 2]> = passages(n, 1998).into_iter().collect();
    // Floor patches on a grid line (x or z a multiple of the 2 m cell) are passage strips;
    // limestone sides away from the posts belong to walls.
    let on_line = |x: f64| (x / 2.0 - (x / 2.0).round()).abs() < 1e-9;
    let near_line = |x: f64| (x - 2.0 * (x / 2.0).round()).abs() <= 0.1 + 1e-9;
    let cell = |x: f64| (x / 2.0).floor() as usize;
    let (mut strips, mut walls) = (BTreeSet::new(), BTreeSet::new());
    for (i, p) in s.patches().iter().enumerate() {
        let (c, nrm) = (p.centroid(), p.normal());
        match s.material_of(i).name.as_str() {
            "sandstone paving" => {
                assert!(c.y == 0.0 && nrm.y > 0.999, "floor patch {i} not at y = 0 facing up");
                if on_line(c.x) {
                    let k = (c.x / 2.0).round() as usize;
                    strips.insert([(k - 1, cell(c.z)), (k, cell(c.z))]);
                } else if on_line(c.z) {
                    let k = (c.z / 2.0).round() as usize;
                    strips.insert([(cell(c.x), k - 1), (cell(c.x), k)]);
                }
            }
            "limestone" if nrm.z.abs() > 0.999 && !near_line(c.x) => {
                walls.insert((0, cell(c.x), (c.z / 2.0).round() as usize));
            }
            "limestone" if nrm.x.abs() > 0.999 && !near_line(c.z) => {
                walls.insert((1, (c.x / 2.0).round() as usize, cell(c.z)));
            }
            "limestone" => {}
            "lamp" => {
                assert!(nrm.y < -0.999 && c.y > 0.0 && c.y < 2.5, "lamp patch {i} must hang facing down");
            }
            other => panic!("unexpected material {other}"),
        }
    }
    assert_eq!(strips, maze);
    // Every grid edge between two cells has a wall exactly when the maze has no passage.
    for a in 0..n {
        for k in 1..n {
            let open_x = maze.contains(&[(k - 1, a), (k, a)]);
            assert_eq!(walls.contains(&(1, k, a)), !open_x, "wall on x = {k}, cell row {a}");
            let open_z = maze.contains(&[(a, k - 1), (a, k)]);
            assert_eq!(walls.contains(&(0, a, k)), !open_z, "wall on z = {k}, cell column {a}");
        }
    }
    // The floor is exactly the cells and the passages: n² squares of 1.8 m, n² − 1 strips.
    let floor = area_where(&s, |p| p.normal().y > 0.999 && p.centroid().y == 0.0);
    let expected = (n * n) as f64 * 1.8 * 1.8 + (n * n - 1) as f64 * 1.8 * 0.2;
    assert!((floor - expected).abs() < 1e-9 * expected, "floor area {floor}, expected {expected}");
}

#[test]
fn labyrinth_has_no_hidden_or_doubled_faces() {
    for arg in ["labyrinth", "labyrinth:cells=4:seed=9:size=0.3:lights=3", "labyrinth:cells=1"] {
        let s = scene(arg);
        assert_no_coincident_patches(&s);
        // The lamps are one-sided panels hanging in the air; rays pass by their backs.
        let lamps: BTreeSet<usize> = s.emitters().into_iter().collect();
        assert_faces_free_space(&s, false, 1, |j| !lamps.contains(&j));
    }
}

#[test]
fn office_has_no_hidden_or_doubled_faces() {
    for (arg, stride) in [("office", 5), ("office:desks=2:size=0.3", 1)] {
        let s = scene(arg);
        let (lo, hi) = s.bounds();
        assert!(lo.abs_diff_eq(Vec3::ZERO, 1e-12) && hi.abs_diff_eq(Vec3::new(7.2, 2.7, 6.0), 1e-12), "{lo} {hi}");
        assert_no_coincident_patches(&s);
        assert_faces_free_space(&s, true, stride, |_| true);
    }
}

#[test]
fn office_lights_are_set_into_the_ceiling() {
    let s = scene("office");
    let emitters = s.emitters();
    for &i in &emitters {
        let p = &s.patches()[i];
        assert!((p.centroid().y - 2.7).abs() < 1e-12 && p.normal().y < -0.999, "light patch {i}");
        assert!(s.objects()[p.object.0 as usize].starts_with("ceiling light "));
    }
    // Lights and ceiling tile the ceiling without overlap: their areas add up to it exactly.
    let ceiling = area_where(&s, |p| (p.centroid().y - 2.7).abs() < 1e-12);
    assert!((ceiling - 7.2 * 6.0).abs() < 1e-9, "ceiling area {ceiling}");
    let lit = emitters.iter().map(|&i| s.patches()[i].area()).sum::<f64>();
    assert!((lit - 8.0 * 0.36).abs() < 1e-9, "light area {lit}");
    for name in ["floor", "ceiling", "back wall", "desk 9", "chair 9", "monitor 1", "bookcase 3", "whiteboard"] {
        assert!(s.objects().iter().any(|o| o == name), "no object '{name}'");
    }
    assert!(scene("office:desks=0").objects().iter().all(|o| !o.starts_with("desk")));
}
