//! Tests of the small built-in scenes and of scene arguments: counts, statistics, emitters,
//! orientation and parameter errors, against figures derived independently of the generators.

use approx::assert_relative_eq;
use radiosity_core::{Channels, Scene, Vec3};
use radiosity_geom::{builtin_scenes, load_scene};

fn scene(arg: &str) -> Scene {
    load_scene(arg).unwrap_or_else(|e| panic!("{arg}: {e}")).scene
}

fn object_area(scene: &Scene, name: &str) -> f64 {
    let id = scene.objects().iter().position(|o| o == name).unwrap_or_else(|| panic!("no object {name}"));
    scene.patches().iter().filter(|p| p.object.0 as usize == id).map(|p| p.area()).sum()
}

#[test]
fn multi_cubes_matches_the_paper() {
    let s = scene("multi-cubes");
    assert_eq!(s.len(), 480);
    assert!((s.mean_reflectivity() - 0.44).abs() <= 0.005, "{}", s.mean_reflectivity());
    assert_eq!(s.channels(), Channels::Rgb);
    assert_eq!(s.objects().len(), 65);
    // Four emitters, in the ceiling (y = 4), facing down, in its central quarter.
    let emitters = s.emitters();
    assert_eq!(emitters.len(), 4);
    for &i in &emitters {
        let p = &s.patches()[i];
        assert_relative_eq!(p.centroid().y, 4.0);
        assert_relative_eq!(p.normal(), Vec3::NEG_Y);
        assert!((p.centroid().x - 2.0).abs() < 1.0 && (p.centroid().z - 2.0).abs() < 1.0);
    }
    // Outer faces look into the cube, small-cube faces look out of their cube.
    let centre = Vec3::splat(2.0);
    for p in &s.patches()[..96] {
        assert!(p.normal().dot(centre - p.centroid()) > 0.0);
    }
    for p in &s.patches()[96..] {
        let cell = (p.centroid() - p.normal() * 0.25).floor() + Vec3::splat(0.5);
        assert!(p.normal().dot(p.centroid() - cell) > 0.0);
        assert_relative_eq!(p.area(), 0.25);
    }
    assert_eq!(scene("multi-cubes:divisions=6").len(), 6 * 36 + 384);
}

#[test]
fn furnace_is_a_closed_uniform_box() {
    let s = scene("furnace");
    assert_eq!(s.len(), 96);
    assert_eq!(s.materials().len(), 1);
    assert_eq!(s.channels(), Channels::Grey);
    assert_eq!(s.emitters().len(), 96);
    assert_relative_eq!(s.total_area(), 6.0, max_relative = 1e-13);
    assert_relative_eq!(s.mean_reflectivity(), 0.5);
    for p in s.patches() {
        assert!(p.normal().dot(Vec3::splat(0.5) - p.centroid()) > 0.0);
    }
    // Block side 0.4 at patch size 1/4: ceil(1.6) = 2 per edge, 24 more patches.
    let b = scene("furnace:block=true");
    assert_eq!(b.len(), 96 + 24);
    assert_relative_eq!(b.total_area(), 6.0 + 6.0 * 0.16, max_relative = 1e-13);
    let rgb = scene("furnace:res=2:rho=0.9/0.5/0:emission=2");
    assert_eq!(rgb.len(), 24);
    assert_eq!(rgb.channels(), Channels::Rgb);
    assert_eq!(rgb.reflectivity(0).0, [0.9, 0.5, 0.0]);
    assert_eq!(rgb.emission(0).0, [2.0; 3]);
}

#[test]
fn cornell_keeps_the_published_geometry() {
    let s = scene("cornell");
    assert_eq!(s.channels(), Channels::Rgb);
    // Areas from the published coordinates, by hand: the floor is a trapezoid with parallel
    // sides 552.8 and 549.6 over a depth of 559.2; the back wall one with 549.6 and 556.0 over
    // a height of 548.8; the green wall a 559.2 × 548.8 rectangle; the ceiling 556 × 559.2 less
    // the 130 × 105 light.
    assert_relative_eq!(object_area(&s, "floor"), (552.8 + 549.6) / 2.0 * 559.2, max_relative = 1e-12);
    assert_relative_eq!(object_area(&s, "back wall"), (549.6 + 556.0) / 2.0 * 548.8, max_relative = 1e-12);
    assert_relative_eq!(object_area(&s, "green wall"), 559.2 * 548.8, max_relative = 1e-12);
    assert_relative_eq!(object_area(&s, "ceiling"), 556.0 * 559.2 - 130.0 * 105.0, max_relative = 1e-12);
    assert_relative_eq!(object_area(&s, "light"), 130.0 * 105.0, max_relative = 1e-12);
    // Short block: top quad by the shoelace formula in (x, z), plus four 165-high sides.
    let top = [(130.0, 65.0), (82.0, 225.0), (240.0, 272.0), (290.0, 114.0)];
    let shoelace: f64 =
        (0..4).map(|i| top[i].0 * top[(i + 1) % 4].1 - top[(i + 1) % 4].0 * top[i].1).sum::<f64>().abs() / 2.0;
    let perimeter: f64 = (0..4)
        .map(|i| ((top[i].0 - top[(i + 1) % 4].0).powi(2) + (top[i].1 - top[(i + 1) % 4].1).powi(2)).sqrt())
        .sum();
    assert_relative_eq!(object_area(&s, "short block"), shoelace + 165.0 * perimeter, max_relative = 1e-12);
    // The light: the only emitter, at the ceiling's height, facing down, inside its rectangle.
    let emitters = s.emitters();
    assert!(!emitters.is_empty());
    for &i in &emitters {
        let p = &s.patches()[i];
        assert_relative_eq!(p.centroid().y, 548.8);
        assert_relative_eq!(p.normal(), Vec3::NEG_Y, epsilon = 1e-12);
        assert!((213.0..=343.0).contains(&p.centroid().x) && (227.0..=332.0).contains(&p.centroid().z));
    }
    // Room surfaces face the inside.
    let inside = Vec3::new(278.0, 274.4, 279.6);
    for (i, p) in s.patches().iter().enumerate() {
        let object = &s.objects()[p.object.0 as usize];
        if !object.contains("block") {
            assert!(p.normal().dot(inside - p.centroid()) > 0.0, "patch {i} of {object}");
        }
    }
    // Resolution: patches no longer than 559.2 / res.
    let fine = scene("cornell:res=16");
    assert!(fine.len() > 3 * s.len());
    for p in fine.patches() {
        let v = p.vertices();
        assert!((0..v.len()).all(|k| (v[(k + 1) % v.len()] - v[k]).length() <= 559.2 / 16.0 * 2f64.sqrt() + 1e-9));
    }
    let closed = scene("cornell:front=true");
    assert_relative_eq!(closed.total_area() - s.total_area(), object_area(&closed, "front wall"), max_relative = 1e-12);
}

#[test]
fn every_builtin_scene_loads_with_defaults_and_documents_its_parameters() {
    for b in builtin_scenes() {
        let s = scene(b.name);
        assert!(!s.is_empty(), "{}", b.name);
        assert!(!s.emitters().is_empty(), "{} has no light", b.name);
        assert!(!b.summary.is_empty());
        for p in b.params {
            assert!(!p.doc.is_empty());
            // Every documented default is accepted when given explicitly.
            let explicit = format!("{}:{}={}", b.name, p.key, p.default);
            assert_eq!(scene(&explicit).len(), s.len(), "{explicit}");
        }
    }
}

#[test]
fn bad_scene_arguments_are_clear_errors() {
    let err = |arg: &str| load_scene(arg).unwrap_err().to_string();
    let e = err("multi-cube");
    assert!(
        e.contains("unknown scene 'multi-cube'") && e.contains("multi-cubes, labyrinth, office, cornell, furnace"),
        "{e}"
    );
    let e = err("furnace:rez=4");
    assert!(e.contains("no parameter 'rez'") && e.contains("res, rho, emission, block"), "{e}");
    let e = err("furnace:res=-2");
    assert!(e.contains("res=-2") && e.contains("integer from 1"), "{e}");
    let e = err("furnace:res=0");
    assert!(e.contains("res=0"), "{e}");
    let e = err("furnace:rho=1");
    assert!(e.contains("rho=1") && e.contains("[0, 1)"), "{e}");
    let e = err("furnace:rho=0.5/0.2");
    assert!(e.contains("three separated by '/'"), "{e}");
    let e = err("furnace:emission=-1");
    assert!(e.contains("emission=-1"), "{e}");
    let e = err("furnace:block=maybe");
    assert!(e.contains("true or false"), "{e}");
    let e = err("furnace:res");
    assert!(e.contains("not of the form key=value"), "{e}");
    let e = err("multi-cubes:cube=1.5");
    assert!(e.contains("cube=1.5"), "{e}");
    let e = err("nowhere/scene.gltf");
    assert!(e.contains("nowhere/scene.gltf"), "{e}");
}

/// The inner box's patches of an `inner-box` scene (object "inner box").
fn inner_patches(s: &Scene) -> Vec<&radiosity_core::Patch> {
    let id = s.objects().iter().position(|o| o == "inner box").expect("an inner box");
    s.patches().iter().filter(|p| p.object.0 as usize == id).collect()
}

#[test]
fn inner_box_counts_and_areas_of_every_suite_case() {
    // (argument, wall patches, inner patches, inner box (size, height), scale), the counts
    // worked out by hand from ceil(edge · res): at res=3 an edge of 0.4 takes 2 patches and one
    // of 0.8 takes 3; at res=2 an edge of 5e-4 takes 1.
    let cases = [
        ("inner-box", 54, 24, (0.4, 0.4), 1.0),
        ("inner-box:res=2:size=5e-4:height=5e-4", 24, 6, (5e-4, 5e-4), 1.0),
        ("inner-box:res=2:size=5e-4:height=5e-4:emission=0:inner-emission=1e6", 24, 6, (5e-4, 5e-4), 1.0),
        ("inner-box:gap=0", 54, 24, (0.4, 0.4), 1.0),
        ("inner-box:gap=1e-6", 54, 24, (0.4, 0.4), 1.0),
        // Top and bottom 3 × 3, each side 3 strips of 0.8/3 by 1e-4.
        ("inner-box:size=0.8:height=1e-4:gap=0.45", 54, 18 + 12, (0.8, 1e-4), 1.0),
        ("inner-box:scale=1e-4", 54, 24, (0.4, 0.4), 1e-4),
        ("inner-box:scale=1e4", 54, 24, (0.4, 0.4), 1e4),
    ];
    for (arg, walls, inner, (size, height), scale) in cases {
        let s = scene(arg);
        assert_eq!(s.len(), walls + inner, "{arg}");
        assert_eq!(inner_patches(&s).len(), inner, "{arg}");
        let inner_area = (2.0 * size * size + 4.0 * size * height) * scale * scale;
        assert_relative_eq!(object_area(&s, "box"), 6.0 * scale * scale, max_relative = 1e-13);
        assert_relative_eq!(object_area(&s, "inner box"), inner_area, max_relative = 1e-12);
        assert_relative_eq!(s.total_area(), 6.0 * scale * scale + inner_area, max_relative = 1e-13);
        // Walls are res × res per face, all the same size.
        let wall_patch = 6.0 * scale * scale / walls as f64;
        for p in &s.patches()[..walls] {
            assert_relative_eq!(p.area(), wall_patch, max_relative = 1e-12);
        }
    }
    // Area ratio 1e6: wall patch 0.25, inner face 2.5e-7.
    let s = scene("inner-box:res=2:size=5e-4:height=5e-4");
    let (largest, smallest) =
        s.patches().iter().fold((0.0f64, f64::INFINITY), |(hi, lo), p| (hi.max(p.area()), lo.min(p.area())));
    assert_relative_eq!(largest, 0.25, max_relative = 1e-13);
    assert_relative_eq!(smallest, 2.5e-7, max_relative = 1e-9);
    assert_relative_eq!(largest / smallest, 1e6, max_relative = 1e-9);
    // The tiny bright emitter: only the six inner faces emit.
    let s = scene("inner-box:res=2:size=5e-4:height=5e-4:emission=0:inner-emission=1e6");
    assert_eq!(s.emitters(), (24..30).collect::<Vec<_>>());
    assert_eq!(s.emission(24).0, [1e6; 3]);
    assert_eq!(s.emission(0).0, [0.0; 3]);
    // Thin slab: its sides are strips 1e-4 high.
    let s = scene("inner-box:size=0.8:height=1e-4:gap=0.45");
    let strips = inner_patches(&s).into_iter().filter(|p| p.normal().y.abs() < 1e-12).count();
    assert_eq!(strips, 12);
    // Touching: at gap=0 the bottom face lies on the floor, facing it, and the sides end on it.
    let s = scene("inner-box:gap=0");
    let bottom: Vec<_> = inner_patches(&s).into_iter().filter(|p| p.normal().y < -0.5).collect();
    assert_eq!(bottom.len(), 4);
    assert!(bottom.iter().all(|p| p.vertices().iter().all(|v| v.y == 0.0)));
}

#[test]
fn inner_box_defaults_are_uniform_and_its_inner_faces_face_outward() {
    let s = scene("inner-box");
    assert_eq!(s.channels(), Channels::Grey);
    assert_eq!(s.emitters().len(), s.len());
    assert!((0..s.len()).all(|i| s.emission(i).0 == [1.0; 3] && s.reflectivity(i).0 == [0.5; 3]));
    let walls_centre = Vec3::splat(0.5);
    for arg in ["inner-box", "inner-box:gap=0", "inner-box:size=0.8:height=1e-4:gap=0.45", "inner-box:scale=1e4"] {
        let s = scene(arg);
        let inner = inner_patches(&s);
        // The inner box's centre, from its own patches' extent.
        let (lo, hi) = inner
            .iter()
            .flat_map(|p| p.vertices().iter())
            .fold((Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)), |(lo, hi), v| (lo.min(*v), hi.max(*v)));
        let centre = (lo + hi) * 0.5;
        for p in &inner {
            assert!(p.normal().dot(p.centroid() - centre) > 0.0, "{arg}: inner patch faces inward");
        }
        let scale = if arg.ends_with("1e4") { 1e4 } else { 1.0 };
        let id = s.objects().iter().position(|o| o == "box").unwrap();
        for p in s.patches().iter().filter(|p| p.object.0 as usize == id) {
            assert!(p.normal().dot(walls_centre * scale - p.centroid()) > 0.0, "{arg}: wall faces outward");
        }
    }
    // Another inner emission and colours.
    let s = scene("inner-box:res=2:rho=0.9/0.5/0:emission=0:inner-emission=2/1/0");
    assert_eq!(s.channels(), Channels::Rgb);
    assert_eq!(s.emitters().len(), 6);
    assert_eq!(s.emission(29).0, [2.0, 1.0, 0.0]);
    assert_eq!(s.reflectivity(0).0, [0.9, 0.5, 0.0]);
}

#[test]
fn scale_multiplies_coordinates_exactly() {
    for (one, arg) in [
        ("inner-box", "inner-box:scale=1e4"),
        ("inner-box", "inner-box:scale=1e-4"),
        ("inner-box:size=0.8:height=1e-4:gap=0.45", "inner-box:size=0.8:height=1e-4:gap=0.45:scale=1e4"),
        ("furnace:block=true", "furnace:block=true:scale=1e4"),
        ("furnace:block=true", "furnace:block=true:scale=1e-4"),
    ] {
        let factor: f64 = arg.rsplit('=').next().unwrap().parse().unwrap();
        let (a, b) = (scene(one), scene(arg));
        assert_eq!(a.len(), b.len(), "{arg}");
        for (p, q) in a.patches().iter().zip(b.patches()) {
            let expected = p.centroid() * factor;
            let error = (q.centroid() - expected).length();
            assert!(error <= 1e-12 * expected.length(), "{arg}: {} against {expected}", q.centroid());
            assert_eq!(p.vertices().len(), q.vertices().len());
            // The scene is meshed at scale 1 and scaled: each vertex is the product, rounded
            // once, so the same faces are flat (or tilted by an ulp) at every scale.
            for (v, w) in p.vertices().iter().zip(q.vertices()) {
                assert_eq!(*w, *v * factor, "{arg}");
            }
            assert_relative_eq!(q.area(), p.area() * factor * factor, max_relative = 1e-12);
            assert!((p.normal() - q.normal()).length() <= 1e-14, "{arg}: {} against {}", p.normal(), q.normal());
            if p.normal().to_array().iter().filter(|c| **c == 0.0).count() == 2 {
                assert_eq!(p.normal(), q.normal(), "{arg}: a flat face stays flat");
            }
        }
    }
    // furnace's total area scales with the square.
    assert_relative_eq!(scene("furnace:scale=1e-8").total_area(), 6e-16, max_relative = 1e-13);
    assert_relative_eq!(scene("furnace:scale=1e8").total_area(), 6e16, max_relative = 1e-13);
}

#[test]
fn bad_inner_box_parameters_name_the_key() {
    let err = |arg: &str| load_scene(arg).unwrap_err().to_string();
    let e = err("inner-box:gap=0.6");
    assert!(e.contains("gap=0.6") && e.contains("gap + height < 1"), "{e}");
    let e = err("inner-box:gap=0.5:height=0.5");
    assert!(e.contains("gap=0.5") && e.contains("gap + height < 1"), "{e}");
    let e = err("inner-box:height=0.7");
    assert!(e.contains("height=0.7") && e.contains("gap + height < 1"), "{e}");
    let e = err("inner-box:gap=-0.1");
    assert!(e.contains("gap=-0.1") && e.contains(">= 0"), "{e}");
    for size in ["0", "1", "-0.5", "nan"] {
        let e = err(&format!("inner-box:size={size}"));
        assert!(e.contains(&format!("size={size}")) && e.contains("(0, 1)"), "{e}");
    }
    let e = err("inner-box:height=0");
    assert!(e.contains("height=0") && e.contains("(0, 1)"), "{e}");
    let e = err("inner-box:rho=1");
    assert!(e.contains("rho=1") && e.contains("[0, 1)"), "{e}");
    let e = err("inner-box:inner-emission=-1");
    assert!(e.contains("inner-emission=-1") && e.contains(">= 0"), "{e}");
    let e = err("inner-box:res=0");
    assert!(e.contains("res=0") && e.contains("integer from 1 to 1000"), "{e}");
    for scale in ["0", "-1", "1e-9", "1e9", "inf"] {
        for name in ["inner-box", "furnace"] {
            let e = err(&format!("{name}:scale={scale}"));
            assert!(e.contains(&format!("scale={scale}")) && e.contains("[1e-8, 1e8]"), "{e}");
        }
    }
    let e = err("inner-box:sise=0.3");
    assert!(e.contains("no parameter 'sise'") && e.contains("res, size, height, gap"), "{e}");
}
