//! Tests: MGF input. Hand-made fixtures in `test_data/mgf/` check each entity kind, transforms,
//! includes, triangulation and colours against values worked out by hand, and one fixture per
//! bad input checks that the error names the file and line. The five real scenes, files
//! written by others, are tested in `third_party_scenes.rs`.

use radiosity_core::{Real, Scene, Vec3};
use radiosity_geom::GeomError;
use radiosity_geom::mgf::colour::Colour;
use std::collections::BTreeMap;

use crate::{fixture, load, load_err};

/// A fixture in `test_data/mgf/`.
fn mgf(name: &str) -> String {
    fixture(&format!("mgf/{name}"))
}

/// Patch count and area per object name.
fn per_object(scene: &Scene) -> BTreeMap<String, (usize, Real)> {
    let mut out = BTreeMap::new();
    for p in scene.patches() {
        let e = out.entry(scene.objects()[p.object.0 as usize].clone()).or_insert((0, 0.0));
        e.0 += 1;
        e.1 += p.area();
    }
    out
}

fn close(a: Real, b: Real, tol: Real) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn materials_colours_objects_and_continuation_lines() {
    let loaded = load(&mgf("basic.mgf"));
    let scene = &loaded.scene;
    assert_eq!(scene.len(), 2);
    let objects = per_object(scene);
    assert_eq!(objects.keys().collect::<Vec<_>>(), ["room/floor", "room/lamp"]);
    let floor = &scene.patches()[0];
    assert_eq!(floor.vertices().len(), 4, "the quad is one patch");
    assert!(close(floor.area(), 1.0, 1e-12));
    assert!((floor.normal() - Vec3::Z).length() < 1e-12, "counter-clockwise seen from +z faces +z");
    let grey = scene.reflectivity(0);
    for c in grey.0 {
        assert!(close(c, 0.5, 1e-3), "cxy 1/3 1/3 with rd 0.5 is grey 0.5: {grey:?}");
    }
    assert_eq!(scene.emission(0).0, [0.0; 3]);
    // cxy 0.64 0.33 is the sRGB red primary: all emission is in the red channel.
    let e = scene.emission(1).0;
    assert!(e[0] > 1.0 && e[1] < 1e-2 && e[2] < 1e-2, "red emission: {e:?}");
    assert_eq!(scene.emitters(), vec![1]);
    // `v t2 = t1` copies t1, then `p` moves the copy only.
    let lamp = &scene.patches()[1];
    assert!(lamp.vertices().contains(&Vec3::new(0.0, 0.0, 1.0)) && lamp.vertices().contains(&Vec3::new(0.0, 1.0, 1.0)));
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(loaded.warnings[0].contains("rs ×1") && loaded.warnings[0].contains("sides ×1"), "{:?}", loaded.warnings);
}

#[test]
fn includes_carry_their_own_transforms_and_arrays() {
    let scene = load(&mgf("include.mgf")).scene;
    assert_eq!(scene.len(), 4);
    let has = |p: Vec3| scene.patches().iter().any(|q| q.vertices().iter().any(|v| (*v - p).length() < 1e-12));
    // -rz 90 then -t 10 0 0: (1, 0, 0) -> (0, 1, 0) -> (10, 1, 0); (0, 1, 0) -> (-1, 0, 0) -> (9, 0, 0).
    assert!(has(Vec3::new(10.0, 1.0, 0.0)) && has(Vec3::new(9.0, 0.0, 0.0)));
    for z in [0.0, 5.0, 10.0] {
        assert!(has(Vec3::new(1.0, 0.0, z)), "array element at z = {z}");
    }
    assert_eq!(per_object(&scene).keys().collect::<Vec<_>>(), ["part"]);
}

#[test]
fn nested_arrays_and_mirrors_keep_the_front_side() {
    let scene = load(&mgf("array.mgf")).scene;
    assert_eq!(scene.len(), 2 * 3 + 1);
    for p in scene.patches() {
        assert!((p.normal() - Vec3::Z).length() < 1e-12, "mirroring reverses the winding: {:?}", p.normal());
    }
    let corners: Vec<Vec3> = scene.patches().iter().map(|p| p.vertices()[0]).collect();
    for x in [0.0, 10.0] {
        for y in [0.0, 10.0, 20.0] {
            assert!(corners.contains(&Vec3::new(x, y, 0.0)), "instance at ({x}, {y})");
        }
    }
    let mirrored = scene.patches().last().unwrap();
    assert!(mirrored.vertices().contains(&Vec3::new(-1.0, 0.0, -20.0)));
}

#[test]
fn faces_with_holes_are_triangulated_to_the_right_area() {
    let scene = load(&mgf("hole.mgf")).scene;
    let objects = per_object(&scene);
    for name in ["seam", "fh"] {
        let (count, area) = objects[name];
        assert!(close(area, 16.0 - 4.0, 1e-9), "{name}: outer minus inner area, got {area} in {count} patches");
    }
    for p in scene.patches() {
        assert!((p.normal() - Vec3::Z).length() < 1e-9);
    }
}

#[test]
fn non_convex_faces_are_ear_clipped() {
    let scene = load(&mgf("concave.mgf")).scene;
    assert_eq!(scene.len(), 4, "a hexagon gives 4 triangles");
    assert!(close(scene.total_area(), 3.0, 1e-12));
}

#[test]
fn curved_primitives_follow_renderpark_divisions() {
    let scene = load(&format!("{}:div=2", mgf("shapes.mgf"))).scene;
    let counts: BTreeMap<String, usize> = per_object(&scene).into_iter().map(|(k, (n, _))| (k, n)).collect();
    let expected =
        [("annulus", 8), ("cone", 8), ("cyl", 8), ("disc", 8), ("prism", 6), ("sph", 2 * 2 * 8), ("torus", 16 * 4)];
    assert_eq!(counts, expected.iter().map(|(k, n)| (k.to_string(), *n)).collect());
    let objects = per_object(&scene);
    // An 8-gon of radius 1 has perimeter 16 sin(pi/8); the cylinder is 2 high.
    let octagon = 16.0 * (std::f64::consts::PI / 8.0).sin();
    assert!(close(objects["cyl"].1, 2.0 * octagon, 1e-9));
    assert!(close(objects["prism"].1, 6.0, 1e-12), "a unit cube");
    assert!(close(objects["disc"].1, 8.0 * 0.5 * (std::f64::consts::PI / 4.0).sin(), 1e-12));
    // Closed solids face outwards.
    for (name, centre) in [("sph", Vec3::new(10.0, 0.0, 0.0)), ("prism", Vec3::new(20.5, 0.5, 0.5))] {
        for p in scene.patches().iter().filter(|p| scene.objects()[p.object.0 as usize] == name) {
            assert!(p.normal().dot(p.centroid() - centre) > 0.0, "{name} faces outwards");
        }
    }
    // Rings face along the centre vertex's normal.
    for p in scene.patches().iter().filter(|p| scene.objects()[p.object.0 as usize] == "disc") {
        assert!((p.normal() - Vec3::Z).length() < 1e-9);
    }
    let default = load(&mgf("shapes.mgf")).scene;
    assert_eq!(per_object(&default)["cyl"].0, 16, "div defaults to 4");
}

#[test]
fn size_subdivides_and_keeps_the_area() {
    let coarse = load(&mgf("basic.mgf")).scene;
    let fine = load(&format!("{}:size=0.1", mgf("basic.mgf"))).scene;
    assert!(fine.len() > 10 * coarse.len());
    assert!(close(fine.total_area(), coarse.total_area(), 1e-9));
    let (_, message) = load_err(&format!("{}:div=0", mgf("basic.mgf")));
    assert!(message.contains("div=0"), "{message}");
}

#[test]
fn zero_area_faces_are_dropped_with_one_warning() {
    let loaded = load(&mgf("degenerate.mgf"));
    assert_eq!(loaded.scene.len(), 1);
    assert_eq!(loaded.warnings.len(), 1);
    assert!(loaded.warnings[0].contains("dropped 1 degenerate face (zero area) of 2"), "{:?}", loaded.warnings);
}

#[test]
fn bad_inputs_name_file_and_line() {
    // A line that is not an entity is skipped; with nothing else, the file has no faces.
    let (e, m) = load_err(&mgf("not_a_name.mgf"));
    assert!(matches!(e, GeomError::EmptyFile { .. }), "{e:?}");
    assert!(m.contains("contains no usable triangles; it has no faces; skipped 1 line whose first"), "{m}");
    assert!(m.ends_with("not_a_name.mgf:3)"), "{m}");

    let (e, m) = load_err(&mgf("undefined_vertex.mgf"));
    assert!(matches!(e, GeomError::MgfUndefined { line: 5, kind: "vertex", .. }), "{e:?}");
    assert!(m.ends_with("undefined_vertex.mgf:5: undefined vertex 'v12'"), "{m}");

    let (e, m) = load_err(&mgf("undefined_material.mgf"));
    assert!(matches!(e, GeomError::MgfUndefined { line: 2, kind: "material", .. }), "{e:?}");
    assert!(m.contains("undefined material 'nowhere'"), "{m}");

    let (e, m) = load_err(&mgf("cycle_a.mgf"));
    assert!(matches!(e, GeomError::MgfIncludeCycle { line: 3, .. }), "{e:?}");
    assert!(m.contains("cycle_b.mgf:3: including") && m.contains("cycle_a.mgf makes an include cycle"), "{m}");

    let (e, m) = load_err(&mgf("missing_include.mgf"));
    assert!(matches!(e, GeomError::MgfMissingInclude { line: 3, .. }), "{e:?}");
    assert!(m.contains("missing_include.mgf:3: cannot read included file") && m.contains("no_such_file.mgf"), "{m}");

    // A face of two vertices is skipped; with nothing else, the file has no faces.
    let (e, m) = load_err(&mgf("two_vertices.mgf"));
    assert!(matches!(e, GeomError::EmptyFile { .. }), "{e:?}");
    assert!(m.contains("it has no faces; skipped 1 face or hole with fewer than 3 vertices"), "{m}");
    assert!(m.ends_with("two_vertices.mgf:5)"), "{m}");

    // Binary data is no MGF: one sentence naming the first binary byte.
    let dir = std::env::temp_dir().join(format!("radiosity-mgf-binary-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes, offset) in [("nul.mgf", &b"v a =\n\0\x01\x02"[..], 6), ("latin1.mgf", &b"# caf\xe9\n"[..], 5)] {
        let file = dir.join(name);
        std::fs::write(&file, bytes).unwrap();
        let (e, m) = load_err(file.to_str().unwrap());
        assert!(matches!(e, GeomError::NotText { .. }), "{e:?}");
        assert!(m.ends_with(&format!("{name} is not a text file: byte {offset} is binary data")), "{m}");
    }
    // An included file that is binary is refused the same way.
    std::fs::write(dir.join("includes_binary.mgf"), "i nul.mgf\n").unwrap();
    let (e, m) = load_err(dir.join("includes_binary.mgf").to_str().unwrap());
    assert!(matches!(e, GeomError::NotText { offset: 6, .. }), "{e:?}");
    assert!(m.contains("nul.mgf is not a text file"), "{m}");
    std::fs::remove_dir_all(&dir).unwrap();

    let (e, _) = load_err(&mgf("no_such_scene.mgf"));
    assert!(matches!(e, GeomError::Io { .. }), "{e:?}");
}

#[test]
fn colour_conversion() {
    // 0.333 is not quite 1/3: z = 0.334 instead of 0.3333 lifts blue by 0.35% (measured
    // 0.99876, 1.00013, 1.00349), which is the conversion's exact answer, not an error.
    let grey = Colour::from_xy(0.333, 0.333).unwrap().rgb(1.0).0;
    for c in grey {
        assert!(close(c, 1.0, 4e-3), "{grey:?}");
    }
    let exact = Colour::from_xy(1.0 / 3.0, 1.0 / 3.0).unwrap().rgb(0.7).0;
    for c in exact {
        assert!(close(c, 0.7, 1e-12), "{exact:?}");
    }
    // The sRGB green primary: only green (white-balanced by E's green channel, 0.948).
    let green = Colour::from_xy(0.30, 0.60).unwrap().rgb(1.0).0;
    assert!(green[0] < 1e-3 && green[2] < 1e-3 && green[1] > 1.0, "{green:?}");
    // A flat spectrum is the equal-energy white, up to the fit of the matching functions.
    let flat = Colour::from_samples(380.0, 780.0, &[0.5; 41]).unwrap();
    let (x, y) = flat.xy();
    assert!(close(x, 1.0 / 3.0, 5e-3) && close(y, 1.0 / 3.0, 5e-3), "({x}, {y})");
    // Black bodies: warm is red, hot is blue; 6504 K is close to D65 (0.3127, 0.3290).
    let warm = Colour::black_body(2800.0).unwrap().rgb(1.0).0;
    let hot = Colour::black_body(12000.0).unwrap().rgb(1.0).0;
    assert!(warm[0] > warm[2] && hot[2] > hot[0], "{warm:?} {hot:?}");
    let (x, y) = Colour::black_body(6504.0).unwrap().xy();
    assert!(close(x, 0.3135, 5e-3) && close(y, 0.3235, 5e-3), "({x}, {y})");
    // cmix weights are luminances: equal parts of two colours sit between them.
    let red = Colour::from_xy(0.64, 0.33).unwrap();
    let white = Colour::default();
    let (x, _) = Colour::mix(&[(1.0, red), (1.0, white)]).unwrap().xy();
    assert!(x > 1.0 / 3.0 && x < 0.64, "{x}");
}

#[test]
fn unknown_entities_are_ignored_with_one_warning_and_vertices_default_to_the_origin() {
    let loaded = load(&mgf("unknown.mgf"));
    assert_eq!(loaded.scene.len(), 1);
    let patch = &loaded.scene.patches()[0];
    assert!((patch.area() - 0.5).abs() < 1e-12, "{}", patch.area());
    assert!(patch.vertices().contains(&Vec3::ZERO), "{:?}", patch.vertices());
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    let w = &loaded.warnings[0];
    assert!(w.contains("ignored 3 unknown entities ('bogus' ×2, 'glow' ×1; the first at "), "{w}");
    assert!(w.ends_with("unknown.mgf:5), as MGF's reference parser does"), "{w}");
}

#[test]
fn lines_the_reference_parser_passes_over_are_skipped_with_one_warning_each() {
    // Two lines that are not entities (a vertex line without its `p`, a stray path), a
    // colour with y = 0, faces and a hole of two vertices or none, and an `o` closing nothing:
    // the scene is the one without them, its black material reflecting nothing.
    let lenient = load(&mgf("lenient.mgf"));
    let clean = load(&mgf("lenient_clean.mgf"));
    assert!(clean.warnings.is_empty(), "{:?}", clean.warnings);
    assert_eq!(lenient.scene.len(), clean.scene.len());
    assert_eq!(lenient.scene.len(), 2);
    assert!(close(lenient.scene.total_area(), clean.scene.total_area(), 1e-12));
    for (a, b) in lenient.scene.patches().iter().zip(clean.scene.patches()) {
        let (ma, mb) =
            (&lenient.scene.materials()[a.material.0 as usize], &clean.scene.materials()[b.material.0 as usize]);
        assert_eq!(ma.reflectivity, mb.reflectivity);
    }
    let w = &lenient.warnings;
    assert_eq!(w.len(), 4, "{w:?}");
    assert!(w[0].contains("skipped 2 lines whose first word is not an entity name (the first at "), "{w:?}");
    assert!(w[0].ends_with("lenient.mgf:13), as MGF's reference parser does"), "{w:?}");
    assert!(w[1].contains("took 1 chromaticity with y ≤ 0 as black (the first at "), "{w:?}");
    assert!(w[1].ends_with("lenient.mgf:7), as RenderPark does"), "{w:?}");
    assert!(w[2].contains("skipped 4 faces or holes with fewer than 3 vertices (the first at "), "{w:?}");
    assert!(w[2].ends_with("lenient.mgf:27), as RenderPark does"), "{w:?}");
    assert!(w[3].contains("ignored 1 'o' line closing an object when none is open (the first at "), "{w:?}");
    assert!(w[3].ends_with("lenient.mgf:28), since it changes no geometry"), "{w:?}");
    // A negative x is still no chromaticity: an error of one sentence naming the line.
    let dir = std::env::temp_dir().join(format!("radiosity-mgf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad_colour.mgf");
    std::fs::write(&bad, "c red =\n\tcxy -0.2 0.3\n").unwrap();
    let (_, m) = load_err(bad.to_str().unwrap());
    assert!(m.ends_with("bad_colour.mgf:2: 'cxy -0.2 0.3' is not a chromaticity"), "{m}");
    std::fs::remove_dir_all(&dir).unwrap();
}
