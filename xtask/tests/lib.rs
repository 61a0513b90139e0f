//! Command-line tests of `cargo xtask`: the `scenes` figures the project promises, and one
//! clear sentence with a non-zero exit code for every kind of bad input.

use assert_cmd::Command;
use serde_json::Value;

fn xtask(args: &[&str]) -> assert_cmd::assert::Assert {
    Command::cargo_bin("xtask").unwrap().args(args).env("RUST_BACKTRACE", "1").assert()
}

fn stdout_json(args: &[&str]) -> Value {
    let out = xtask(args).success().get_output().stdout.clone();
    serde_json::from_slice(&out).unwrap()
}

/// Runs a command that must fail, and checks the failure is one clean sentence.
fn failure(args: &[&str]) -> String {
    let out = xtask(args).failure().code(1).get_output().clone();
    let stderr = String::from_utf8(out.stderr).unwrap();
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{args:?} printed more than one line: {stderr}");
    assert!(lines[0].starts_with("error: "), "{stderr}");
    assert!(!stderr.contains("panicked") && !stderr.contains("backtrace"), "{stderr}");
    assert!(out.stdout.is_empty());
    stderr
}

#[test]
fn scenes_lists_the_paper_figures() {
    let list = stdout_json(&["scenes", "--json"]);
    let scenes = list.as_array().unwrap();
    let get = |name: &str| scenes.iter().find(|s| s["scene"] == name).unwrap_or_else(|| panic!("{name} missing"));
    // (name, patches, relative tolerance on patches, mean reflectivity) from the paper, §5.
    for (name, patches, tol, rho) in
        [("multi-cubes", 480.0, 0.0, 0.44), ("labyrinth", 3362.0, 0.01, 0.59), ("office", 10991.0, 0.01, 0.43)]
    {
        let s = get(name);
        let n = s["patches"].as_f64().unwrap();
        assert!((n - patches).abs() <= tol * patches, "{name}: {n} patches");
        let mean = s["mean_reflectivity"].as_f64().unwrap();
        assert!((mean - rho).abs() <= 0.005, "{name}: mean reflectivity {mean}");
        assert!(s["emitters"].as_u64().unwrap() > 0, "{name}");
    }
    let furnace = get("furnace");
    assert_eq!(furnace["channels"], 1);
    assert_eq!(furnace["left_out"].as_array().unwrap().len(), 2);
    assert_eq!(get("cornell")["channels"], 3);
    assert_eq!(scenes.len(), 5);
}

#[test]
fn scenes_text_lists_names_and_parameters() {
    let out = xtask(&["scenes"]).success().get_output().stdout.clone();
    let text = String::from_utf8(out).unwrap();
    for name in ["multi-cubes", "labyrinth", "office", "cornell", "furnace", "res=4", "rho=0.5", "left out"] {
        assert!(text.contains(name), "missing {name} in\n{text}");
    }
}

#[test]
fn explain_gives_a_reason_for_every_decision() {
    let out = xtask(&["scenes", "--explain", "furnace:block=true"]).success().get_output().stdout.clone();
    let text = String::from_utf8(out).unwrap();
    assert_eq!(text.matches("because").count(), 4, "{text}");
    assert!(text.contains("shadow rays traced") && text.contains("grey, one channel"), "{text}");
    let r = stdout_json(&["scenes", "--explain", "furnace", "--json"]);
    assert_eq!(r["patches"], 96);
    assert_eq!(r["occlusion"]["value"], "no shadow rays");
    assert_eq!(r["closure"]["value"], "closed");
    assert!(r["closure"]["reason"].as_str().unwrap().contains("384 sampled rays"));
    let r = stdout_json(&["scenes", "--explain", "cornell:res=2", "--json"]);
    assert!(r["closure"]["value"].as_str().unwrap().starts_with("open"));
}

#[test]
fn compare_says_what_it_does_not_do_yet() {
    let out = xtask(&["compare"]).success().get_output().stdout.clone();
    let text = String::from_utf8(out).unwrap();
    assert!(text.contains("multi-cubes: 480 patches"), "{text}");
    assert!(text.contains("not implemented yet"), "{text}");
}

#[test]
fn bad_scene_arguments_fail_cleanly() {
    let e = failure(&["scenes", "--explain", "multicubes"]);
    assert!(e.contains("unknown scene 'multicubes'") && e.contains("furnace"), "{e}");
    let e = failure(&["scenes", "--explain", "furnace:res=-1"]);
    assert!(e.contains("res=-1"), "{e}");
    let e = failure(&["scenes", "--explain", "furnace:rho=1"]);
    assert!(e.contains("rho=1") && e.contains("[0, 1)"), "{e}");
    let e = failure(&["scenes", "--explain", "office:colour=red"]);
    assert!(e.contains("no parameter 'colour'"), "{e}");
    let e = failure(&["compare", "--scene", "cornell:res"]);
    assert!(e.contains("key=value"), "{e}");
    let e = failure(&["scenes", "--explain", "no/such/file.gltf"]);
    assert!(e.contains("no/such/file.gltf"), "{e}");
    let e = failure(&["scenes", "--explain", "no/such/file.mgf"]);
    assert!(e.contains("no/such/file.mgf"), "{e}");
}

fn fixture(name: &str) -> String {
    format!("{}/../crates/radiosity-geom/test_data/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn bad_gltf_files_fail_cleanly() {
    // (fixture, words the one-line error must contain)
    let cases = [
        ("white.gltf", vec!["white.gltf", "material 'snow'", "reflectivity 1"]),
        ("no_material.gltf", vec!["no material", "default material"]),
        ("nan.gltf", vec!["nan.gltf", "mesh 'broken'", "NaN or infinite"]),
        ("no_position.gltf", vec!["no POSITION attribute"]),
        ("lines.gltf", vec!["mode LINES"]),
        ("empty_scene.gltf", vec!["no usable triangles"]),
        ("all_degenerate.gltf", vec!["degenerate"]),
        ("required_ext.gltf", vec!["KHR_draco_mesh_compression"]),
        ("garbage.gltf", vec!["not glTF JSON"]),
        ("truncated.gltf", vec!["truncated"]),
        ("truncated.glb", vec!["truncated"]),
        ("short_buffer.gltf", vec!["buffer 0 is truncated"]),
    ];
    for (file, words) in cases {
        let e = failure(&["scenes", "--explain", &fixture(file)]);
        for w in words {
            assert!(e.contains(w), "{file}: expected '{w}' in {e}");
        }
        // The reason is said once, not repeated by the error chain.
        let first = e.split(": ").nth(2).unwrap_or_default();
        assert!(first.is_empty() || e.matches(first).count() == 1, "{file}: repeated message {e}");
    }
}

#[test]
fn real_cornell_export_loads_upright() {
    let path = format!("{}/../../shared/scenes/cornell-box-toy-ray-tracer.gltf", env!("CARGO_MANIFEST_DIR"));
    let r = stdout_json(&["scenes", "--explain", &path, "--json"]);
    assert_eq!(r["patches"], 32);
    assert_eq!(r["emitters"], 2);
    // Upright: y runs from the floor at 0 to the ceiling at 1.99.
    assert!((r["bounds"][0][1].as_f64().unwrap()).abs() < 1e-6);
    assert!((r["bounds"][1][1].as_f64().unwrap() - 1.99).abs() < 1e-6);
    let degenerate = stdout_json(&["scenes", "--explain", &fixture("degenerate.gltf"), "--json"]);
    assert_eq!(degenerate["warnings"].as_array().unwrap().len(), 1);
}
