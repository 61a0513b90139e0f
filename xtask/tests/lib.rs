//! Command-line tests of `cargo xtask`: the `scenes` figures the project promises, and one
//! clear sentence with a non-zero exit code for every kind of bad input.

use assert_cmd::Command;
use serde_json::Value;

mod bad_input;
mod bench;
mod distributed;
mod export;
mod readme;
mod render;
mod sampled;
mod stress;
mod watch;

/// The cache every test run shares: its own folder, so that tests never read what an
/// earlier build cached.
fn cache_dir() -> std::path::PathBuf {
    std::env::temp_dir().join(format!("radiosity-test-cache-{}", std::process::id()))
}

/// Analytic form factors with a small shadow-ray budget, for tests of the command line on
/// `multi-cubes`, whose occluded pairs make the default budget cost about 30 ms a column:
/// what these tests check does not depend on the budget, and the default one is checked
/// against Howell and the path tracer in `radiosity-ff` and `radiosity-eval`.
const QUICK_FF: &str = "analytic:budget=1024";

/// `solve --json` of `pr` on `multi-cubes` with [`QUICK_FF`] until `rules`.
fn quick_pr(rules: &str) -> Value {
    stdout_json(&["solve", "--scene", "multi-cubes", "--ff", QUICK_FF, "--solver", "pr", "--until", rules, "--json"])
}

fn xtask(args: &[&str]) -> assert_cmd::assert::Assert {
    Command::cargo_bin("xtask")
        .unwrap()
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .env("RADIOSITY_CACHE_DIR", cache_dir())
        .assert()
}

/// As [`xtask`], with the environment variable `key` set to `value`.
fn xtask_in_env(args: &[&str], key: &str, value: &str) -> assert_cmd::assert::Assert {
    Command::cargo_bin("xtask")
        .unwrap()
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .env("RADIOSITY_CACHE_DIR", cache_dir())
        .env(key, value)
        .assert()
}

fn stdout_json(args: &[&str]) -> Value {
    let out = xtask(args).success().get_output().stdout.clone();
    serde_json::from_slice(&out).unwrap()
}

/// Runs a command that must fail, and checks the failure is one clean sentence.
pub(crate) fn failure(args: &[&str]) -> String {
    let out = xtask(args).failure().code(1).get_output().clone();
    let stderr = String::from_utf8(out.stderr).unwrap();
    // One error: a sentence, long lists wrapped onto continuation lines indented by two spaces.
    let lines: Vec<&str> = stderr.lines().collect();
    assert!(
        !lines.is_empty() && lines[1..].iter().all(|l| l.starts_with("  ")),
        "{args:?} printed more than one error: {stderr}"
    );
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
    assert_eq!(scenes.len(), 6);
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
    assert_eq!(text.matches("because").count(), 5, "{text}");
    assert!(text.contains("geometry    0 hidden") && text.contains("no patch is hidden"), "{text}");
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
fn explain_names_the_hidden_patches_it_left_out() {
    // The Cornell blocks have no bottoms: the floor wholly under them faces their insides.
    let out = xtask(&["scenes", "--explain", "cornell"]).success().get_output().stdout.clone();
    let text = String::from_utf8(out).unwrap();
    assert!(text.contains("6 hidden (0 pressed, 6 enclosed"), "{text}");
    assert!(text.contains("hidden: patch 20 of 'floor' faces the inside of a closed solid"), "{text}");
    assert!(text.contains("6 hidden patches (pressed against other surfaces or inside closed solids)"), "{text}");
    let r = stdout_json(&["scenes", "--explain", "cornell", "--json"]);
    assert_eq!(r["geometry"]["hidden"], 6);
    assert_eq!(r["patches"], 554, "the six are left out of the system");
}

#[test]
fn compare_writes_the_table_the_report_and_the_plots() {
    let dir = std::env::temp_dir().join(format!("radiosity-compare-{}", std::process::id()));
    let dir_arg = dir.to_str().unwrap();
    let args = ["compare", "--scene", "cornell:res=2", "--solvers", "pr,xu-g8-m16:f=4", "--out", dir_arg];
    let out = xtask(&args).success().get_output().stdout.clone();
    let summary = String::from_utf8(out).unwrap();
    assert!(summary.contains("pr") && summary.contains("xu-g8-m16:f=4") && summary.contains("e_rms @n"), "{summary}");
    // Every output names the clock of its seconds: by default, columns computed.
    assert!(summary.lines().next().unwrap().ends_with("seconds (measured)"), "{summary}");
    assert!(summary.contains("\nseconds (measured): form factors and solving timed"), "{summary}");
    let csv = std::fs::read_to_string(dir.join("convergence.csv")).unwrap();
    assert!(csv.starts_with("solver,step,columns,seconds,ff_seconds,clock,e_rms,e_max,residual,bound\n"), "{csv}");
    assert!(csv.lines().any(|l| l.starts_with("xu-g8-m16:f=4,")), "{csv}");
    assert!(csv.lines().skip(1).all(|l| l.contains(",measured,")), "{csv}");
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for section in [
        "n/4",
        "1e-2",
        "1e-3",
        "Where the time went",
        "Left out",
        "dense LU",
        "e_rms-seconds.png",
        "Seconds (measured): form factors and solving timed",
        "measured seconds to reach",
        "form factors (measured)",
    ] {
        assert!(report.contains(section), "missing {section} in\n{report}");
    }
    assert!(std::fs::read_to_string(dir.join("e_rms-seconds.svg")).unwrap().contains("measured seconds"));
    for plot in ["e_rms-steps", "e_rms-columns", "e_rms-seconds"] {
        let svg = std::fs::read_to_string(dir.join(format!("{plot}.svg"))).unwrap();
        assert!(svg.contains("<svg") && svg.contains("xu-g8-m16:f=4"), "{plot}");
        let png = std::fs::read(dir.join(format!("{plot}.png"))).unwrap();
        assert!(png.starts_with(b"\x89PNG"), "{plot}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
    // Columns charged: charged seconds, and the same numbers.
    let charged = [&args[..], &["--columns", "charged"]].concat();
    let out = xtask(&charged).success().get_output().stdout.clone();
    let charged = String::from_utf8(out).unwrap();
    assert!(charged.lines().next().unwrap().ends_with("seconds (charged)"), "{charged}");
    assert!(charged.contains("\nseconds (charged): solving timed, columns read from the stored matrix"), "{charged}");
    let without_seconds = |table: &str| -> Vec<Vec<String>> {
        let rows = table.lines().skip(1).take_while(|l| !l.starts_with("seconds"));
        rows.map(|l| {
            let fields: Vec<String> = l.split_whitespace().map(str::to_string).collect();
            fields[..fields.len() - 1].to_vec()
        })
        .collect()
    };
    assert_eq!(without_seconds(&summary), without_seconds(&charged));
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(
        report.contains("Seconds (charged): solving timed") && report.contains("form factors (charged)"),
        "{report}"
    );
    assert!(std::fs::read_to_string(dir.join("convergence.csv")).unwrap().contains(",charged,"));
    std::fs::remove_dir_all(&dir).unwrap();
    let e = failure(&["compare", "--columns", "free"]);
    assert!(e.contains("it must be computed or charged"), "{e}");
    let e = failure(&["compare", "--solvers", "pr,magic"]);
    assert!(e.contains("unknown solver 'magic'") && e.contains("solve --help"), "{e}");
    let e = failure(&["compare", "--solvers", " , "]);
    assert!(e.contains("no solver"), "{e}");
    let e = failure(&["compare", "--until", "colums=2n"]);
    assert!(e.contains("unknown rule"), "{e}");
}

#[test]
fn paper_sets_each_claim_beside_the_measurement() {
    let dir = std::env::temp_dir().join(format!("radiosity-paper-{}", std::process::id()));
    xtask(&["paper", "--scenes", "multi-cubes", "--ff", QUICK_FF, "--out", dir.to_str().unwrap()]).success();
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for text in
        ["Fig. 1", "n = 480", "`xu-g30-m480` beats `xu-g30` at n steps", "multi-cubes/e_rms-steps.png", "budget=1024"]
    {
        assert!(report.contains(text), "missing {text} in\n{report}");
    }
    // Each claim row ends with its verdict.
    let verdicts = report.lines().filter(|l| l.ends_with("| yes |") || l.ends_with("| **no** |")).count();
    assert_eq!(verdicts, 5, "{report}");
    assert!(dir.join("multi-cubes").join("e_rms-steps.svg").exists());
    std::fs::remove_dir_all(&dir).unwrap();

    // By default the columns come from the assembled matrix, charged: every seconds figure says
    // so. Computed columns put them on the measured clock, and the claims, in steps, read the
    // same figures either way.
    assert!(report.contains("Seconds on the `charged` clock") && report.contains("to 1e-2 (columns / charged s)"));
    let out = dir.to_str().unwrap();
    xtask(&["paper", "--scenes", "multi-cubes", "--ff", QUICK_FF, "--columns", "computed", "--out", out]).success();
    let computed = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(computed.contains("Seconds on the `measured` clock") && !computed.contains("charged"), "{computed}");
    let claims = |r: &str| -> Vec<String> {
        r.lines().filter(|l| l.ends_with("| yes |") || l.ends_with("| **no** |")).map(String::from).collect()
    };
    assert_eq!(claims(&report), claims(&computed));
    std::fs::remove_dir_all(&dir).unwrap();
    let e = failure(&["paper", "--scenes", "cornell"]);
    assert!(e.contains("'cornell' is not one of the paper's scenes"), "{e}");
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
    // A relative path found nowhere names the scenes folder it was also looked for in.
    let out = xtask_in_env(&["scenes", "--explain", "mgf/no-such.mgf"], "RADIOSITY_SCENES", "/no/scenes/here")
        .failure()
        .code(1)
        .get_output()
        .stderr
        .clone();
    let e = String::from_utf8(out).unwrap();
    assert!(e.contains("mgf/no-such.mgf") && e.contains("/no/scenes/here (from RADIOSITY_SCENES)"), "{e}");
}

#[test]
fn bad_mgf_fails_cleanly() {
    for (name, words) in [
        ("mgf/not_a_name.mgf", "whose first word is not an entity name"),
        ("mgf/undefined_vertex.mgf", "undefined vertex 'v12'"),
        ("mgf/undefined_material.mgf", "undefined material 'nowhere'"),
        ("mgf/cycle_a.mgf", "include cycle"),
        ("mgf/missing_include.mgf", "cannot read included file"),
    ] {
        let e = failure(&["scenes", "--explain", &fixture(name)]);
        assert!(e.contains(".mgf:") && e.contains(words), "{name}: {e}");
    }
    // Entities this loader does not know load with one warning, as MGF's reference parser does.
    let out = xtask(&["scenes", "--explain", &fixture("mgf/unknown.mgf")]).success().get_output().clone();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("warning: ") && stderr.contains("ignored 3 unknown entities"), "{stderr}");
    assert!(String::from_utf8(out.stdout).unwrap().contains("patches     1 "));
}

pub(crate) fn fixture(name: &str) -> String {
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
fn a_warning_is_one_line_and_degenerate_triangles_warn() {
    let degenerate = stdout_json(&["scenes", "--explain", &fixture("degenerate.gltf"), "--json"]);
    assert_eq!(degenerate["warnings"].as_array().unwrap().len(), 1);
}

fn ff_json(args: &[&str]) -> Value {
    let mut all = vec!["ff"];
    all.extend_from_slice(args);
    all.push("--json");
    stdout_json(&all)
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

#[test]
fn ff_out_writes_the_printed_matrix_for_other_programs() {
    let dir = std::env::temp_dir().join(format!("radiosity-ff-out-{}", std::process::id()));
    let mtx = dir.join("F.mtx");
    let r = ff_json(&["--scene", "furnace:res=2", "--out", mtx.to_str().unwrap()]);
    let f: Vec<Vec<f64>> = r["F"].as_array().unwrap().iter().map(numbers).collect();
    // Matrix Market: a banner, comments, `n n nnz`, then 1-based `i j F_ij`, every non-zero
    // entry of the printed matrix, read back to the same f32.
    let text = std::fs::read_to_string(&mtx).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('%'));
    assert!(text.starts_with("%%MatrixMarket matrix coordinate real general\n"), "{text}");
    let size: Vec<usize> = lines.next().unwrap().split(' ').map(|v| v.parse().unwrap()).collect();
    let nonzeros = f.iter().flatten().filter(|v| **v != 0.0).count();
    assert_eq!(size, [24, 24, nonzeros]);
    for line in lines {
        let v: Vec<&str> = line.split(' ').collect();
        let (i, j, value): (usize, usize, f64) = (v[0].parse().unwrap(), v[1].parse().unwrap(), v[2].parse().unwrap());
        assert_eq!(value as f32, f[i - 1][j - 1] as f32, "F[{i}][{j}]");
    }
    // The patches beside it: area, then emission and reflectivity (one channel), column-major.
    let patches = std::fs::read_to_string(dir.join("F.patches.mtx")).unwrap();
    let values: Vec<f64> =
        patches.lines().filter(|l| !l.starts_with('%')).skip(1).map(|l| l.parse().unwrap()).collect();
    assert!(patches.contains("% columns: area emission[0] reflectivity[0]\n"), "{patches}");
    assert_eq!(values.len(), 24 * 3);
    for (i, p) in r["patches"].as_array().unwrap().iter().enumerate() {
        assert_eq!(values[i], p["area"].as_f64().unwrap());
        // The furnace emits 1 and reflects 0.5 everywhere.
        assert_eq!((values[24 + i], values[48 + i]), (1.0, 0.5));
    }
    // NumPy: a zip archive holding scipy.sparse's keys and the patches' arrays.
    let npz = dir.join("system.npz");
    xtask(&["ff", "--scene", "furnace:res=2", "--out", npz.to_str().unwrap()]).success();
    let bytes = std::fs::read(&npz).unwrap();
    assert!(bytes.starts_with(b"PK\x03\x04"));
    for name in ["format", "shape", "data", "indices", "indptr", "area", "emission", "reflectivity"] {
        let entry = format!("{name}.npy");
        assert!(bytes.windows(entry.len()).any(|w| w == entry.as_bytes()), "no {entry}");
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failure(&["ff", "--scene", "furnace:res=2", "--out", "F.csv"]).contains(".mtx (Matrix Market) or .npz"));
}

#[test]
fn ff_json_has_the_promised_keys_and_a_closed_furnace_sums_to_one() {
    let r = ff_json(&["--scene", "furnace:res=2"]);
    for key in ["patches", "F", "row_sums", "max_reciprocity_error"] {
        assert!(r.get(key).is_some(), "missing {key}");
    }
    assert!(r["backend"].as_str().unwrap().starts_with("analytic:"), "{}", r["backend"]);
    let patches = r["patches"].as_array().unwrap();
    assert_eq!(patches.len(), 24);
    for (i, p) in patches.iter().enumerate() {
        assert_eq!(p["id"], i);
        assert!((p["area"].as_f64().unwrap() - 0.25).abs() < 1e-12);
        assert_eq!(p["centroid"].as_array().unwrap().len(), 3);
    }
    let f: Vec<Vec<f64>> = r["F"].as_array().unwrap().iter().map(numbers).collect();
    assert_eq!(f.len(), 24);
    let sums = numbers(&r["row_sums"]);
    for (i, row) in f.iter().enumerate() {
        assert_eq!(row.len(), 24);
        assert_eq!(row[i], 0.0, "a flat patch does not see itself");
        let sum: f64 = row.iter().sum();
        assert!((sum - sums[i]).abs() < 1e-6, "row {i}: {sum} against {}", sums[i]);
        // The furnace is a closed, convex cube: nothing occludes, every row sums to 1.
        assert!((sums[i] - 1.0).abs() < 1e-3, "row {i} sums to {}", sums[i]);
    }
    // The reported reciprocity error is that of the printed matrix (equal areas here), up to
    // the f32 rounding of the printed entries; the default analytic backend keeps it small.
    let mut worst: f64 = 0.0;
    for (i, row) in f.iter().enumerate() {
        for (j, &fij) in row.iter().enumerate() {
            let scale = fij.max(f[j][i]);
            if scale > 0.0 {
                worst = worst.max((fij - f[j][i]).abs() / scale);
            }
        }
    }
    let reported = r["max_reciprocity_error"].as_f64().unwrap();
    assert!((worst - reported).abs() <= 1e-6, "{worst} against {reported}");
    assert!(reported < 1e-3, "{reported}");
    assert_eq!(r["clamped"], 0);
}

#[test]
fn ff_text_summarises_the_matrix() {
    let out = xtask(&["ff", "--scene", "furnace:res=2"]).success().get_output().stdout.clone();
    let text = String::from_utf8(out).unwrap();
    for words in ["24 patches", "closed: every row should sum to 1", "analytic:order=", "row sums", "non-zeros"] {
        assert!(text.contains(words), "missing '{words}' in\n{text}");
    }
    assert!(text.contains("dense f32") || text.contains("sparse f32"), "{text}");
    // A closed scene lists the rows farthest from 1 with a cause; the empty furnace traces no
    // shadow rays, so what its rows miss is the quadrature's.
    assert!(text.contains("worst rows   farthest from 1"), "{text}");
    assert_eq!(text.matches(": quadrature, no shadow rays are traced").count(), 5, "{text}");
}

#[test]
fn ff_against_compares_sampled_rows_without_assembling() {
    // The office is refused for assembly, but any scene can be compared row by row.
    let args =
        ["ff", "--scene", "furnace:res=6", "--ff", "hierarchical:eps=0.05", "--against", "analytic", "--rows", "3"];
    let out = xtask(&args).success().get_output().stdout.clone();
    let text = String::from_utf8(out).unwrap();
    for words in [
        "216 patches",
        "hierarchical:eps=5e-2:shadows=0.03:rays=14:trust=1.5:budget=512:order=8:tol=1e-3:seed=0:oracle=flux:floor=0.1:passes=1:closure=true built in",
        "far links",
        "natively",
        "3 sampled rows",
    ] {
        assert!(text.contains(words), "missing '{words}' in\n{text}");
    }
    assert_eq!(text.matches("   row ").count(), 3, "{text}");
    // The operator's own exact solution, its transfer error and its distance to the
    // analytic backend's exact solution (the furnace emits, and is small enough to solve).
    for words in ["transfer     ", "B̃ by gmres-30 over the product", "solutions    e_rms "] {
        assert!(text.contains(words), "missing '{words}' in\n{text}");
    }
    let e_rms: f64 = text.split("solutions    e_rms ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!(e_rms > 0.0 && e_rms < 2e-2, "{text}");
    let e = failure(&["ff", "--scene", "furnace:res=2", "--against", "analytic", "--rows", "0"]);
    assert!(e.contains("--rows"), "{e}");
}

#[test]
fn ff_refuses_bad_backends_and_large_scenes() {
    let e = failure(&["ff", "--scene", "furnace:res=2", "--ff", "nonsense"]);
    assert!(e.contains("'nonsense'") && e.contains("analytic, hemicube, montecarlo, hierarchical, matrix"), "{e}");
    let e = failure(&["ff", "--scene", "furnace:res=2", "--ff", "analytic:order=0"]);
    assert!(e.contains("order=0"), "{e}");
    let e = failure(&["ff", "--scene", "office"]);
    assert!(e.contains("patches") && e.contains("--force"), "{e}");
    let e = failure(&["ff", "--scene", "nowhere"]);
    assert!(e.contains("unknown scene 'nowhere'"), "{e}");
}

/// Runs `ff` with `RADIOSITY_CACHE_DIR` set; returns (stdout, stderr).
fn ff_cached(cache: &std::path::Path, args: &[&str]) -> (String, String) {
    run_cached(cache, &[&["ff"][..], args].concat())
}

#[test]
fn ff_matrix_is_cached_and_loaded_the_second_time() {
    let cache = std::env::temp_dir().join(format!("radiosity-ff-cache-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&cache);
    let args = ["--scene", "furnace:res=2", "--ff", "matrix"];
    let (first, _) = ff_cached(&cache, &args);
    assert!(first.contains("assembled in") && first.contains("written to"), "{first}");
    let (second, _) = ff_cached(&cache, &args);
    assert!(second.contains("loaded from cache"), "{second}");
    let files: Vec<_> = std::fs::read_dir(&cache).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(files.len(), 1, "{files:?}");
    assert!(second.contains(&files[0].display().to_string()), "{second}");

    // The stored matrix is the analytic one, entry for entry.
    let (json, _) = ff_cached(&cache, &[&args[..], &["--json"]].concat());
    let stored: Value = serde_json::from_str(&json).unwrap();
    assert_eq!(stored["cache"]["loaded"], true);
    assert_eq!(stored["F"], ff_json(&["--scene", "furnace:res=2"])["F"]);

    // Another backend parameter is another file; a damaged file is replaced, with a warning.
    let (other, _) = ff_cached(&cache, &["--scene", "furnace:res=2", "--ff", "matrix:rebalance=true"]);
    assert!(other.contains("written to") && other.contains("rebalance"), "{other}");
    std::fs::write(&files[0], b"not a matrix").unwrap();
    let (again, warning) = ff_cached(&cache, &args);
    assert!(again.contains("written to"), "{again}");
    assert!(warning.contains("warning: replacing cache file") && warning.contains("not a stored"), "{warning}");
    let (last, _) = ff_cached(&cache, &args);
    assert!(last.contains("loaded from cache"), "{last}");
    std::fs::remove_dir_all(&cache).unwrap();
}

#[test]
fn solve_reports_error_against_the_reference() {
    let r = quick_pr("columns=480");
    let stats = &r["stats"];
    assert_eq!(stats["columns"], 480);
    assert_eq!(stats["steps"], 480);
    let e_rms = stats["e_rms"].as_f64().unwrap();
    // Half-way-ish convergence: clearly better than nothing, clearly not converged.
    assert!(e_rms > 1e-5 && e_rms < 1e-1, "{e_rms}");
    assert!(stats["termination"].as_str().unwrap().contains("480 columns"));
    assert!(stats["reference"]["method"].as_str().unwrap().contains("dense LU"), "{stats}");
    assert_eq!(stats["reference"]["kind"], "matrix", "{stats}");
    assert!(stats["bound"].as_f64().unwrap() >= 0.0, "{stats}");
    assert_eq!(r["patches"].as_array().unwrap().len(), 480);
    for key in ["id", "area", "centroid", "normal", "reflectivity", "emission", "radiosity"] {
        assert!(r["patches"][0].get(key).is_some(), "patch key {key}");
    }
    // Run long enough, a shooting solver reaches the reference of the same columns.
    let r = stdout_json(&[
        "solve",
        "--scene",
        "furnace:res=2",
        "--solver",
        "pr",
        "--until",
        "residual=1e-13,steps=100n",
        "--json",
    ]);
    assert!(r["stats"]["e_rms"].as_f64().unwrap() < 1e-10, "{}", r["stats"]);
}

#[test]
fn solve_reference_is_the_exact_solution_and_group_methods_run() {
    let r = stdout_json(&["solve", "--scene", "furnace:res=2", "--solver", "reference", "--json"]);
    assert_eq!(r["stats"]["e_rms"], 0.0);
    assert!(r["stats"]["termination"].as_str().unwrap().contains("dense LU"), "{}", r["stats"]);
    assert_eq!(r["stats"]["columns"], 24);
    // A group-accelerated run reports the time spent on groups; group gathering runs on the
    // spatial order the scene gives.
    for solver in ["xu-g8-m16:f=4", "group-gs-g8:groups=spatial"] {
        let r =
            stdout_json(&["solve", "--scene", "cornell:res=2", "--solver", solver, "--until", "steps=60", "--json"]);
        let s = &r["stats"];
        assert!(s["group_seconds"].as_f64().unwrap() > 0.0, "{solver}: {s}");
        assert!(s["group_seconds"].as_f64() <= s["seconds"].as_f64(), "{solver}: {s}");
    }
}

#[test]
fn solve_tells_where_the_time_and_memory_went() {
    // `--json` holds every phase before the output, in order, its seconds adding up to no more
    // than the command's; `--verbose` prints the same phases on stderr, the output's too.
    let start = std::time::Instant::now();
    let args = ["solve", "--scene", "cornell:res=2", "--solver", "pr", "--until", "steps=40"];
    let r = stdout_json(&[&args[..], &["--json"]].concat());
    let wall = start.elapsed().as_secs_f64();
    let phases = r["phases"].as_array().unwrap();
    let names: Vec<&str> = phases.iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "loading",
            "building the BVH",
            "probing for hidden geometry",
            "analysing the scene",
            "setting up the backend",
            "setting up the reference",
            "solving"
        ]
    );
    let seconds: Vec<f64> = phases.iter().map(|p| p["seconds"].as_f64().unwrap()).collect();
    assert!(seconds.iter().all(|&s| s >= 0.0) && seconds.iter().sum::<f64>() <= wall, "{seconds:?} in {wall} s");
    let peaks: Vec<u64> = phases.iter().filter_map(|p| p["peak_bytes"].as_u64()).collect();
    assert!(peaks.windows(2).all(|w| w[0] <= w[1]), "a peak only grows: {peaks:?}");
    // CPU seconds where the phase was timed as it ran (not for the set-ups split after the
    // fact), never more than the machine's threads could spend in its wall seconds.
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    for (p, wall) in phases.iter().zip(&seconds) {
        let name = p["name"].as_str().unwrap();
        match p["cpu_seconds"].as_f64() {
            Some(cpu) => assert!(cpu >= 0.0 && cpu <= threads * wall + 0.05, "{name}: {cpu} CPU s in {wall} s"),
            None => assert!(name.starts_with("setting up"), "{name} has no CPU seconds"),
        }
    }
    let out = xtask(&[&args[..], &["--verbose"]].concat()).success().get_output().clone();
    let err = String::from_utf8_lossy(&out.stderr);
    for name in names.iter().chain(&["writing the output", "total"]) {
        assert!(err.lines().any(|l| l.starts_with(name)), "{name} missing from:\n{err}");
    }
    assert!(!String::from_utf8_lossy(&out.stdout).contains("peak memory"), "the table goes to stderr");
}

#[test]
fn solve_stops_at_every_kind_of_rule() {
    let stats = |rules: &str| {
        let r = quick_pr(rules);
        r["stats"].clone()
    };
    let s = stats("columns=100");
    assert_eq!((s["columns"].as_u64(), s["termination"].as_str()), (Some(100), Some("100 columns computed")));
    let s = stats("columns=0.5n");
    assert_eq!(s["columns"], 240);
    let s = stats("steps=70,columns=100");
    assert_eq!((s["steps"].as_u64(), s["termination"].as_str()), (Some(70), Some("70 steps taken")));
    let s = stats("rms=1e-2");
    assert!(s["termination"].as_str().unwrap().starts_with("e_rms reached"), "{s}");
    assert!(s["e_rms"].as_f64().unwrap() <= 1e-2, "{s}");
    // Where e_rms first fell to 1e-1 and 1e-2: the second is where the run stopped.
    let reached = s["reached"].as_array().unwrap();
    assert_eq!(reached.iter().map(|r| r["e_rms"].as_f64().unwrap()).collect::<Vec<_>>(), [1e-1, 1e-2], "{s}");
    assert!(reached[0]["columns"].as_u64() <= reached[1]["columns"].as_u64(), "{s}");
    assert_eq!(reached[1]["columns"], s["columns"]);
    let s = stats("residual=1e-2");
    assert!(s["termination"].as_str().unwrap().starts_with("residual power reached"), "{s}");
    // 480 columns take about 0.3 s: 20 ms stops the run early, after at least 20 ms.
    let s = stats("time=20ms");
    assert!(s["termination"].as_str().unwrap().starts_with("time limit"), "{s}");
    assert_eq!(s["clock"], "measured", "solve computes its columns: {s}");
    assert!(s["seconds"].as_f64().unwrap() >= 0.02 && s["columns"].as_u64().unwrap() < 480, "{s}");
    // An error below round-off cannot be reached: the run ends at round-off, and says so.
    let r = stdout_json(&["solve", "--scene", "furnace:res=2", "--solver", "pr", "--until", "rms=1e-30", "--json"]);
    let termination = r["stats"]["termination"].as_str().unwrap().to_string();
    assert!(termination == "converged to round-off" || termination.starts_with("step cap"), "{termination}");
}

#[test]
fn a_time_rule_lifts_the_step_cap_and_a_capped_run_says_so() {
    // A stiff furnace (ρ = 0.99, 24 patches) over its stored matrix: Jacobi needs thousands of
    // steps to a residual of 1e-8, far past the cap of 20n = 480.
    let args =
        ["solve", "--scene", "furnace:res=2:rho=0.99", "--ff", "matrix", "--reference", "none", "--solver", "jacobi"];
    let args = [&args[..], &["--json", "--until"]].concat();
    let out = xtask(&[&args[..], &["residual=1e-8,time=300s"]].concat()).success().get_output().clone();
    let stats = serde_json::from_slice::<Value>(&out.stdout).unwrap()["stats"].clone();
    assert!(stats["termination"].as_str().unwrap().starts_with("residual power reached"), "{stats}");
    assert!(stats["steps"].as_u64().unwrap() > 480, "{stats}");
    assert!(out.stderr.is_empty(), "{}", String::from_utf8_lossy(&out.stderr));
    // Without it the cap ends the run, which says so on stderr in one sentence.
    let out = xtask(&[&args[..], &["residual=1e-8"]].concat()).success().get_output().clone();
    let stats = serde_json::from_slice::<Value>(&out.stdout).unwrap()["stats"].clone();
    assert_eq!(stats["steps"], 480, "{stats}");
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("jacobi stopped at the step cap of 480 steps") && stderr.contains("not converged"),
        "{stderr}"
    );
}

#[test]
fn solve_gathers_exact_rows_or_says_it_cannot() {
    // Analytic rows are exact: Gauss–Seidel reaches the reference of the same columns.
    let args = ["solve", "--scene", "furnace:res=2:block=true", "--solver", "gauss-seidel", "--until", "steps=40n"];
    let out = xtask(&[&args[..], &["--json"]].concat()).success().get_output().clone();
    assert!(out.stderr.is_empty(), "{}", String::from_utf8_lossy(&out.stderr));
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(r["stats"]["e_rms"].as_f64().unwrap() < 1e-10, "{}", r["stats"]);
    // Hemicube rows come by reciprocity, which hemicube columns do not satisfy: a warning.
    let out = xtask(&[&args[..], &["--ff", "hemicube:res=16"]].concat()).success().get_output().clone();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains("warning: gauss-seidel gathers along rows") && stderr.contains("reciprocity"), "{stderr}");
    // Shooting needs only columns: no warning.
    let out = xtask(&["solve", "--scene", "furnace:res=2", "--solver", "xu", "--ff", "hemicube:res=16"])
        .success()
        .get_output()
        .clone();
    assert!(out.stderr.is_empty(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn solve_refuses_bad_arguments_before_any_work() {
    let e = failure(&["solve", "--scene", "multi-cubes", "--solver", "xu-q30"]);
    assert!(e.contains("unknown solver 'xu-q30' (did you mean 'xu-g30'?)") && e.contains("solve --help"), "{e}");
    let e = failure(&["solve", "--scene", "multi-cubes", "--solver", "pr", "--until", "columns=abc"]);
    assert!(e.contains("invalid stop rule 'columns=abc'"), "{e}");
    let e = failure(&["solve", "--scene", "multi-cubes", "--solver", "pr", "--ff", "radiance"]);
    assert!(e.contains("unknown form-factor backend 'radiance'"), "{e}");
    let e = failure(&["solve", "--scene", "multicubes", "--solver", "pr"]);
    assert!(e.contains("unknown scene"), "{e}");
}

/// Runs `args` with the cache in `cache`; returns (stdout, stderr).
fn run_cached(cache: &std::path::Path, args: &[&str]) -> (String, String) {
    let out = Command::cargo_bin("xtask")
        .unwrap()
        .args(args)
        .env("RADIOSITY_CACHE_DIR", cache)
        .assert()
        .success()
        .get_output()
        .clone();
    (String::from_utf8(out.stdout).unwrap(), String::from_utf8(out.stderr).unwrap())
}

#[test]
fn the_reference_is_cached_and_a_second_solve_assembles_nothing() {
    let cache = std::env::temp_dir().join(format!("radiosity-reference-cache-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&cache);
    let args = ["solve", "--scene", "cornell:res=2", "--solver", "xu", "--json"];
    let first: Value = serde_json::from_str(&run_cached(&cache, &args).0).unwrap();
    let files: Vec<_> = std::fs::read_dir(&cache).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert!(files.len() == 1 && files[0].to_string_lossy().starts_with("reference-"), "{files:?}");
    let second: Value = serde_json::from_str(&run_cached(&cache, &args).0).unwrap();
    let (a, b) = (&first["stats"], &second["stats"]);
    // The same reference, so the same errors; F was assembled only the first time.
    assert_eq!(a["e_rms"], b["e_rms"]);
    assert_eq!(a["reference"], b["reference"]);
    assert_eq!(a["residual_of"], "displayed radiosity");
    assert!(b["residual_of"].as_str().unwrap().contains("cache"), "{b}");
    // The solver's own residual (of the shot radiosity) is there instead, and small.
    assert!(b["residual"].as_f64().unwrap() < a["residual"].as_f64().unwrap() * 100.0, "{a} {b}");
    // A damaged entry is replaced with a warning, and the run goes on.
    let entry = std::fs::read_dir(&cache).unwrap().next().unwrap().unwrap().path();
    std::fs::write(&entry, b"not a reference").unwrap();
    let (_, stderr) = run_cached(&cache, &args);
    assert!(stderr.contains("warning: replacing") && stderr.contains("not a stored reference"), "{stderr}");
    std::fs::remove_dir_all(&cache).unwrap();
}

#[test]
fn render_and_export_stop_at_an_rms_rule() {
    let dir = std::env::temp_dir().join(format!("radiosity-rms-rule-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (command, file) in [("render", "rms.png"), ("export", "rms.glb")] {
        let out = dir.join(file);
        let args =
            ["--scene", "cornell:res=2", "--solver", "pr", "--until", "rms=1e-1", "--out", out.to_str().unwrap()];
        let output = xtask(&[&[command][..], &args].concat()).success().get_output().clone();
        let stderr = String::from_utf8(output.stderr).unwrap();
        assert!(stderr.contains("pr stopped: e_rms reached"), "{command}: {stderr}");
        let stopped = stderr.lines().find(|l| l.starts_with("pr stopped")).unwrap();
        let steps: u64 = stopped.split("; ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
        assert!(steps < 40, "{command} ran {steps} steps for e_rms 1e-1: {stderr}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn validate_sets_the_path_traced_means_beside_each_resolution() {
    let r = stdout_json(&["validate", "--scene", "furnace:res=2", "--samples", "4000", "--json"]);
    assert_eq!(r["scene"], "furnace:res=2");
    let scenes: Vec<&str> = r["resolutions"].as_array().unwrap().iter().map(|s| s["scene"].as_str().unwrap()).collect();
    assert_eq!(scenes, ["furnace:res=2", "furnace:res=4", "furnace:res=8"]);
    let objects = r["objects"].as_array().unwrap();
    assert_eq!(objects.len(), 1);
    let box_ = &objects[0];
    for key in ["name", "area", "path_traced", "stderr", "discrete"] {
        assert!(!box_[key].is_null(), "missing {key} in {box_}");
    }
    // E / (1 − ρ) = 2 exactly: the tracer within 4 standard errors, every mesh within 1e-3.
    let (mean, stderr) = (box_["path_traced"][0].as_f64().unwrap(), box_["stderr"][0].as_f64().unwrap());
    assert!((mean - 2.0).abs() < 4.0 * stderr && stderr < 0.02, "{mean} ± {stderr}");
    for d in box_["discrete"].as_array().unwrap() {
        assert!((d["mean"][0].as_f64().unwrap() - 2.0).abs() < 1e-3, "{d}");
        assert!(d["scene"].is_string() && d["patches"].is_u64(), "{d}");
    }
    let out =
        xtask(&["validate", "--scene", "furnace:res=2", "--samples", "4000"]).success().get_output().stdout.clone();
    let text = String::from_utf8(out).unwrap();
    assert!(text.contains("path traced") && text.contains("furnace:res=8"), "{text}");
    let e = failure(&["validate", "--scene", "furnace:res=2", "--samples", "1"]);
    assert!(e.contains("samples"), "{e}");
}

#[test]
fn reference_none_reports_the_bound_alone_end_to_end() {
    let args = ["solve", "--scene", "furnace:res=2", "--solver", "xu", "--reference", "none", "--json"];
    let r = stdout_json(&args);
    let stats = &r["stats"];
    assert!(stats["e_rms"].is_null() && stats["e_max"].is_null(), "{stats}");
    assert_eq!(stats["reference"]["kind"], "none", "{stats}");
    let bound = stats["bound"].as_f64().unwrap();
    // Against the matrix reference the same run has the same solution and a bound no
    // smaller than its error.
    let with = stdout_json(&args[..args.len() - 3].iter().chain(&["--json"]).copied().collect::<Vec<_>>());
    assert_eq!(r["patches"], with["patches"]);
    assert!(with["stats"]["e_rms"].as_f64().unwrap() <= 1e-3 && bound <= 1e-2, "{stats} {}", with["stats"]);
    // The text report says there is no reference.
    let out = xtask(&args[..args.len() - 1]).success().get_output().stdout.clone();
    let text = String::from_utf8(out).unwrap();
    assert!(text.contains("no e_rms") && text.contains("reference    none"), "{text}");
    // compare plots and tabulates the bound.
    let out = std::env::temp_dir().join(format!("radiosity-compare-none-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let compare = [
        "compare",
        "--scene",
        "furnace:res=2",
        "--solvers",
        "pr,xu",
        "--reference",
        "none",
        "--out",
        out.to_str().unwrap(),
    ];
    xtask(&compare).success();
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("Reference `none`"), "{report}");
    assert!(out.join("bound-seconds.png").exists() && !out.join("e_rms-seconds.png").exists());
    std::fs::remove_dir_all(&out).unwrap();
    // What cannot be done without a reference is refused before any work.
    for (solver, until, why) in
        [("pr", "rms=1e-3", "rms= rule needs a reference"), ("reference", "columns=n", "needs a reference")]
    {
        let args = ["solve", "--scene", "furnace:res=2", "--solver", solver, "--until", until, "--reference", "none"];
        let e = failure(&args);
        assert!(e.contains(why), "{e}");
    }
    let e = failure(&["solve", "--scene", "furnace:res=2", "--solver", "pr", "--reference", "exact"]);
    assert!(e.contains("auto, matrix, shooting or none"), "{e}");
}

#[test]
fn a_matrix_over_the_memory_budget_is_refused_and_auto_shoots_instead() {
    let args = ["solve", "--scene", "furnace:res=2", "--solver", "pr", "--reference", "matrix"];
    let out = Command::cargo_bin("xtask")
        .unwrap()
        .args(args)
        .env("RADIOSITY_CACHE_DIR", cache_dir())
        .env("RADIOSITY_MEMORY", "1K")
        .assert()
        .failure()
        .code(1)
        .get_output()
        .clone();
    let e = String::from_utf8(out.stderr).unwrap();
    assert!(e.contains("RADIOSITY_MEMORY") && e.contains("needs about"), "{e}");
    let out = Command::cargo_bin("xtask")
        .unwrap()
        .args(["solve", "--scene", "furnace:res=2", "--solver", "pr", "--json"])
        .env("RADIOSITY_CACHE_DIR", cache_dir())
        .env("RADIOSITY_MEMORY", "1K")
        .assert()
        .success()
        .get_output()
        .clone();
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["stats"]["reference"]["kind"], "shooting", "{}", r["stats"]);
    assert!(r["stats"]["reference"]["method"].as_str().unwrap().starts_with("xu without a matrix"));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains("reference: shooting"), "{stderr}");
}
