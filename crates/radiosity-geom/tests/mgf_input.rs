//! Tests: MGF input. Hand-made fixtures in `test_data/mgf/` check each entity kind, transforms,
//! includes, triangulation and colours against values worked out by hand, and one fixture per
//! bad input checks that the error names the file and line. Files that would make more than a
//! file may (nested arrays, includes that multiply, huge tessellations) are refused at once,
//! with the line and the count. The five real scenes, files written by others, are tested in
//! `third_party_scenes.rs`.

use radiosity_core::{Real, Scene, Vec3};
use radiosity_geom::mgf::colour::Colour;
use radiosity_geom::mgf::{self, limits};
use radiosity_geom::{GeomError, KeyValueParams};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

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

/// Loads MGF held in memory (`name` and the files it includes), which must fail: the error,
/// its message, and how long the load took.
fn refused_in_memory(name: &str, text: &str, includes: &[(&str, String)], params: &[&str]) -> (GeomError, String, f64) {
    let files: BTreeMap<PathBuf, Vec<u8>> =
        includes.iter().map(|(path, text)| (PathBuf::from(path), text.clone().into_bytes())).collect();
    let params = KeyValueParams::parse("test", params.iter().copied(), mgf::PARAMS).unwrap();
    let start = Instant::now();
    let result = mgf::load_slice(text.as_bytes(), Path::new(name), &files, &params);
    let seconds = start.elapsed().as_secs_f64();
    match result {
        Ok(_) => panic!("{name} should be refused"),
        Err(e) => {
            let message = e.to_string();
            (e, message, seconds)
        }
    }
}

/// Three vertices of a unit right triangle, `a b c`, on six lines.
const VERTICES: &str = "v a =\n\tp 0 0 0\nv b =\n\tp 1 0 0\nv c =\n\tp 0 1 0\n";

/// A refusal that must come at once: nothing was instantiated before it.
const QUICK: f64 = 2.0;

#[test]
fn nested_arrays_are_refused_by_the_product_of_their_counts_before_any_copy() {
    // 10^6 x 10^6 at the second array already exceeds the limit of 10^6 instances.
    let start = Instant::now();
    let (e, m) = load_err(&mgf("nested_arrays.mgf"));
    assert!(start.elapsed().as_secs_f64() < QUICK, "{:?}", start.elapsed());
    assert!(matches!(e, GeomError::MgfLimit { line: Some(12), .. }), "{e:?}");
    assert!(
        m.ends_with(
            "nested_arrays.mgf:12: the nested `xf -a` arrays here would make 1000000000000 instances, more than the \
             1000000 a file may create"
        ),
        "{m}"
    );
    assert_eq!(limits::MAX_INSTANCES, 1_000_000);
    // Two counts on one line multiply the same way.
    let (_, m, seconds) = refused_in_memory("one_line.mgf", "xf -a 1000000 -a 1000000\nxf\n", &[], &[]);
    assert!(seconds < QUICK);
    assert!(m.ends_with("one_line.mgf:1: the `xf -a` arrays here would make 1000000000000 instances, more than the 1000000 a file may create"), "{m}");
    // Counts whose product overflows 64 bits are refused the same way, not wrapped around.
    let deep = "xf -a 1000000\n".repeat(4) + "xf\n";
    let (_, m, _) = refused_in_memory("deep.mgf", &deep, &[], &[]);
    assert!(m.ends_with("deep.mgf:2: the nested `xf -a` arrays here would make 1000000000000 instances, more than the 1000000 a file may create"), "{m}");
    let wide = format!("xf{}\nxf\n", " -a 1000000".repeat(4));
    let (_, m, _) = refused_in_memory("wide.mgf", &wide, &[], &[]);
    assert!(m.contains(&format!("would make more than {} instances", u64::MAX)), "{m}");
}

#[test]
fn arrays_inside_includes_multiply_with_the_arrays_around_them() {
    // The part alone makes 1000 x 1000 instances (of a colour), the limit, and one triangle: it loads.
    let part = load(&mgf("include_arrays_part.mgf")).scene;
    assert_eq!(part.len(), 1);
    // A thousand copies of it are 10^9 instances.
    let start = Instant::now();
    let (e, m) = load_err(&mgf("include_arrays.mgf"));
    assert!(start.elapsed().as_secs_f64() < QUICK, "{:?}", start.elapsed());
    assert!(matches!(e, GeomError::MgfLimit { line: Some(3), .. }), "{e:?}");
    assert!(m.contains("include_arrays.mgf:3: the `xf -a` arrays around this include and in "), "{m}");
    assert!(
        m.ends_with("include_arrays_part.mgf would make 1000000000 instances, more than the 1000000 a file may create"),
        "{m}"
    );
}

#[test]
fn include_chains_that_multiply_are_refused_where_the_faces_exceed_the_limit() {
    // c0 defines three vertices and includes c1 ten times, c1 includes c2 ten times, …, c8
    // holds one triangle: 10^8 triangles, with no array. c1's tenth of its total is 10^6 faces per include line, so its
    // includes cross the limit of 2^22 = 4194304 patches at line 5 (5 x 10^6).
    let mut files = Vec::new();
    for k in 1..=8 {
        let text = if k == 8 { "f a b c\n".to_string() } else { format!("i c{}.mgf\n", k + 1).repeat(10) };
        files.push((format!("c{k}.mgf"), text));
    }
    let includes: Vec<(&str, String)> = files.iter().map(|(n, t)| (n.as_str(), t.clone())).collect();
    let (e, m, seconds) =
        refused_in_memory("c0.mgf", &(VERTICES.to_string() + &"i c1.mgf\n".repeat(10)), &includes, &[]);
    assert!(seconds < QUICK, "{seconds} s");
    let per_line = 1_000_000;
    let line = (limits::MAX_PATCHES / per_line + 1) as usize;
    assert!(matches!(e, GeomError::MgfLimit { line: Some(l), .. } if l == line), "{e:?}");
    assert!(
        m.starts_with(&format!(
            "c1.mgf:{line}: the entities up to here, repeated by arrays and includes, would make {} faces",
            line as u64 * per_line
        )),
        "{m}"
    );
    assert!(m.ends_with("more than the 4194304 patches a file may create"), "{m}");
}

#[test]
fn huge_tessellations_are_refused_before_they_are_made() {
    // 1000 spheres of 8 div² facets at div=64.
    let start = Instant::now();
    let (e, m) = load_err(&format!("{}:div=64", mgf("sphere_array.mgf")));
    assert!(start.elapsed().as_secs_f64() < QUICK, "{:?}", start.elapsed());
    assert!(matches!(e, GeomError::MgfLimit { line: Some(6), .. }), "{e:?}");
    assert!(
        m.contains(&format!(
            "sphere_array.mgf:6: the entities up to here, repeated by arrays and includes, would make {} faces",
            1000 * 8 * 64 * 64
        )),
        "{m}"
    );
    // At div=4 the same file is 1000 x 128 patches, and loads.
    assert_eq!(load(&mgf("sphere_array.mgf")).scene.len(), 1000 * 8 * 4 * 4);
    // A unit square cut to 1e-4 of its diagonal √2: ceil(1 / (1e-4 √2)) = 7072 cuts a side.
    let square = "v a =\n\tp 0 0 0\nv b =\n\tp 1 0 0\nv c =\n\tp 1 1 0\nv d =\n\tp 0 1 0\nf a b c d\n";
    let (e, m, seconds) = refused_in_memory("square.mgf", square, &[], &["size=0.0001"]);
    assert!(seconds < QUICK, "{seconds} s");
    assert!(matches!(e, GeomError::MgfLimit { line: None, .. }), "{e:?}");
    assert_eq!(
        m,
        format!(
            "square.mgf: cut to size=0.0001, its faces would make {} patches, more than the 4194304 a file may create",
            7072 * 7072
        )
    );
}

#[test]
fn long_entities_deep_includes_and_deep_objects_are_refused() {
    // A face of 2000 vertices: more words than MGF's reference parser reads.
    let face = format!("f{}\n", " a".repeat(2000));
    let (_, m, _) = refused_in_memory("long.mgf", &face, &[], &[]);
    assert!(
        m.ends_with(
            "long.mgf:1: 'f' has 2000 arguments, more than the 1023 MGF's reference parser reads in one entity"
        ),
        "{m}"
    );
    // A chain of 40 files each including the next: refused at the 33rd.
    let files: Vec<(String, String)> = (1..=40).map(|k| (format!("d{k}.mgf"), format!("i d{}.mgf\n", k + 1))).collect();
    let includes: Vec<(&str, String)> = files.iter().map(|(n, t)| (n.as_str(), t.clone())).collect();
    let (_, m, _) = refused_in_memory("d0.mgf", "i d1.mgf\n", &includes, &[]);
    assert!(
        m.ends_with("d32.mgf:1: including d33.mgf here nests includes 33 deep, more than the 32 a file may"),
        "{m}"
    );
    // An object opened in each of a million copies and never closed: each copy's path is one
    // level longer, and naming them all would take 10^12 bytes. Names are counted as they are
    // made, so the refusal comes after about 11 000 copies (the square root of the work
    // limit), when the names made reach it: not at once, but in bounded time.
    let objects = VERTICES.to_string() + "xf -a 1000000\no x\nf a b c\nxf\n";
    let (e, m, seconds) = refused_in_memory("objects.mgf", &objects, &[], &[]);
    assert!(seconds < 5.0 * QUICK, "{seconds} s");
    assert!(matches!(e, GeomError::MgfLimit { line: Some(8), .. }), "{e:?}");
    assert!(m.contains("objects.mgf:8: the name of the object opened here would take the file's work to "), "{m}");
}

#[test]
fn files_in_memory_load_as_the_same_files_on_disk() {
    let on_disk = load(&mgf("include.mgf")).scene;
    let read = |name: &str| std::fs::read(mgf(name)).unwrap();
    let includes = BTreeMap::from([(PathBuf::from("./scenes/part.mgf"), read("part.mgf"))]);
    let params = KeyValueParams::default();
    let in_memory =
        mgf::load_slice(&read("include.mgf"), Path::new("scenes/include.mgf"), &includes, &params).unwrap().scene;
    assert_eq!(in_memory.len(), on_disk.len());
    for (a, b) in in_memory.patches().iter().zip(on_disk.patches()) {
        assert_eq!(a.vertices(), b.vertices());
    }
    // Nothing is read from the disk: without the map the include is missing.
    let e =
        mgf::load_slice(&read("include.mgf"), Path::new(&mgf("include.mgf")), &BTreeMap::new(), &params).unwrap_err();
    assert!(matches!(e, GeomError::MgfMissingInclude { line: 3, .. }), "{e:?}");
    assert!(e.to_string().contains("no such file among the files given in memory"), "{e}");
}

#[test]
fn iterated_transforms_count_their_matrix_products_as_work() {
    // `xf -i 1000000` is a million matrix products each time it is run; a thousand copies of it
    // are 10^9, past the work limit, refused at the array before any is made.
    let text = "xf -a 1000 -t 0 0 1\nxf -i 1000000 -t 1 0 0\nxf\nxf\n";
    let (e, m, seconds) = refused_in_memory("iterated.mgf", text, &[], &[]);
    assert!(seconds < QUICK, "{seconds} s");
    assert!(matches!(e, GeomError::MgfLimit { line: Some(1), .. }), "{e:?}");
    assert!(
        m.contains("iterated.mgf:1: reading the file up to here, repeated by arrays and includes, would take "),
        "{m}"
    );
    assert!(m.ends_with(&format!("more than the {} a file may take", limits::MAX_WORK)), "{m}");
}

/// Files just under the limits load; how long they take is printed, for docs/scenes.md:
/// `cargo test -p radiosity-geom --test lib mgf_input::files_just_under_the_limits_load --
/// --ignored --nocapture`. Ignored by default: seconds each.
#[test]
#[ignore = "seconds of loading, for the figures in docs/scenes.md"]
fn files_just_under_the_limits_load() {
    let params = KeyValueParams::default();
    // Work: 10 000 copies of 1 600 lines `p 1 2 3` (8 bytes each) are 1.28e8 units, just under
    // 2^27 = 1.34e8.
    let work = VERTICES.to_string() + "f a b c\nv d =\nxf -a 10000\n" + &"p 1 2 3\n".repeat(1600) + "xf\n";
    // Patches: 1 000 copies of 4 000 triangles are 4e6 patches, just under 2^22 = 4.19e6.
    let patches = VERTICES.to_string() + "xf -a 1000\n" + &"f a b c\n".repeat(4000) + "xf\n";
    for (what, text, expected) in [("work", work, 1), ("patches", patches, 4_000_000)] {
        let start = Instant::now();
        let loaded = mgf::load_slice(text.as_bytes(), Path::new("limit.mgf"), &BTreeMap::new(), &params).unwrap();
        eprintln!("{what}: {} patches in {:.2} s", loaded.scene.len(), start.elapsed().as_secs_f64());
        assert_eq!(loaded.scene.len(), expected);
    }
}
