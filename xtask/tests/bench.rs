//! `cargo xtask bench --quick`: every section is in the report, with sane figures. Nothing
//! here asserts a time: a smoke run on a loaded machine proves nothing about speed.

use super::{cache_dir, failure, xtask};
use assert_cmd::Command;

/// The cells of the rows of the first table after the line starting with `heading`.
fn table(report: &str, heading: &str) -> Vec<Vec<String>> {
    let start = report.find(heading).unwrap_or_else(|| panic!("no '{heading}' in\n{report}"));
    report[start..]
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2)
        .map(|l| l.trim_matches('|').split(" | ").map(|c| c.trim().to_string()).collect())
        .collect()
}

/// A number as the report prints it (thousands separators allowed).
fn number(cell: &str) -> f64 {
    let text: String = cell.split_whitespace().next().unwrap_or_default().replace(',', "");
    text.trim_end_matches('%').parse().unwrap_or_else(|_| panic!("not a number: '{cell}'"))
}

/// A duration as the report prints it, in seconds.
fn seconds(cell: &str) -> f64 {
    let scale = if cell.ends_with(" µs") {
        1e-6
    } else if cell.ends_with(" ms") {
        1e-3
    } else if cell.ends_with(" s") {
        1.0
    } else {
        panic!("not a duration: '{cell}'")
    };
    number(cell) * scale
}

#[test]
fn quick_bench_reports_every_section_with_sane_figures() {
    let out = std::env::temp_dir().join(format!("radiosity-bench-{}.md", std::process::id()));
    let json_out = out.with_extension("json");
    let args = [
        "bench",
        "--quick",
        "--scene",
        "cornell:res=2",
        "--out",
        out.to_str().unwrap(),
        "--json",
        json_out.to_str().unwrap(),
    ];
    let stdout = xtask(&args).success().get_output().stdout.clone();
    let report = String::from_utf8(stdout).unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), report);
    std::fs::remove_file(&out).unwrap();
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json_out).unwrap()).unwrap();
    std::fs::remove_file(&json_out).unwrap();
    assert!(report.contains("Smoke test") && report.contains("cores available"), "{report}");

    // 1. Three backends, each on 1 thread, 2 threads and 2 threads one column at a time.
    // Rates are timings, so only their consistency is checked: each ratio is the pipeline's
    // rate over the raw one, as printed (to the whole percent).
    let rows = table(&report, "## 1.");
    assert_eq!(rows.len(), 9, "{report}");
    for row in &rows {
        assert!(number(&row[2]) > 0.0 && number(&row[4]) > 0.0, "{row:?}");
        assert!(number(&row[5]) > 0.0 && number(&row[7]) > 0.0, "{row:?}");
        for (raw, ratio) in [(&row[5], &row[6]), (&row[7], &row[8])] {
            let expected = 100.0 * number(&row[4]) / number(raw);
            assert!((number(ratio) - expected).abs() <= 1.0, "ratio {ratio} against {expected} in {row:?}");
        }
    }
    assert!(rows[0][0].starts_with("`analytic") && rows[3][0].starts_with("`hemicube"), "{rows:?}");
    assert!(report.contains("listing its segments"), "{report}");
    // The analytic column's time by sampling path: every pair of the sample is on one row, and
    // the shares of pairs and of time each add up to the whole (to the rounding of the cells).
    let paths: Vec<Vec<String>> = table(&report.replace("\n  |", "\n|"), "Where the column's time goes");
    let names: Vec<&str> = paths.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(
        names,
        ["no ray traced", "few rays, both ends jointly", "few rays, Lambert and Arvo", "16 rays or more, probed"]
    );
    for column in [1, 3] {
        let total: f64 = paths.iter().map(|r| number(&r[column])).sum();
        assert!((total - 100.0).abs() <= 2.0, "column {column} adds up to {total}: {paths:?}");
    }
    assert_eq!(number(&paths[0][2]), 0.0, "{paths:?}");

    // 2. Each pair once at k = 1 and 4, and column by column: exact reciprocity for the former.
    let rows = table(&report, "## 2.");
    assert_eq!(rows.len(), 3, "{report}");
    for row in &rows {
        assert!(number(&row[2]) > 0.0 && number(&row[3]) > 0.0, "{row:?}");
        assert!(row[5].ends_with("kB") || row[5].ends_with("MB"), "{row:?}");
    }
    for row in &rows[..2] {
        assert!(number(&row[8]) < 1e-5, "reciprocity of {row:?}");
    }
    assert_eq!((rows[0][1].as_str(), rows[1][1].as_str(), rows[2][1].as_str()), ("1", "4", "1"));

    // 3. Both LU solvers at every group size.
    let rows = table(&report, "## 3.");
    assert_eq!(rows.iter().map(|r| r[0].as_str()).collect::<Vec<_>>(), ["20", "50"]);
    for row in &rows {
        assert!(seconds(&row[1]) > 0.0 && seconds(&row[2]) > 0.0, "{row:?}");
    }

    // 4 and 5. Every method reaches 1e-3 on this small scene, in order, with its memory.
    let rows = table(&report, "## 4.");
    let methods: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(methods, ["`pr`", "`xu`", "`xu-g10-m40`", "`gauss-seidel`"], "{report}");
    assert_eq!(rows[3][1], "`matrix`");
    for row in &rows {
        let (a, b, c) = (seconds(&row[2]), seconds(&row[3]), seconds(&row[4]));
        assert!(0.0 < a && a <= b && b <= c, "{row:?}");
        assert!(number(&row[7]) <= 1e-3, "{row:?}");
        assert!(row[8].ends_with("MB") || row[8] == "n/a", "{row:?}");
    }
    assert!(report.contains("## Targets"), "{report}");

    // --json: the same figures under the stable keys, one entry per backend and per method.
    assert!(json["machine"]["cores"].as_u64().unwrap() >= 1, "{json}");
    assert_eq!(json["scene"]["name"], "cornell:res=2");
    let columns = json["columns"].as_array().unwrap();
    let backends: Vec<&str> = columns.iter().map(|c| c["backend"].as_str().unwrap()).collect();
    assert!(backends.len() == 3 && backends[0].starts_with("analytic:") && backends[1].starts_with("hemicube:"));
    let printed = table(&report, "## 1.");
    for (c, rows) in columns.iter().zip(printed.chunks(3)) {
        for (threads, row) in [("1", &rows[0]), ("2", &rows[1])] {
            let rate = c["columns_per_second"][threads].as_f64().unwrap();
            assert!((rate / number(&row[2]) - 1.0).abs() < 0.01, "{threads} threads: {rate} against {row:?}");
        }
        let share = c["raw_share"].as_f64().unwrap();
        assert!((100.0 * share - number(&rows[1][8])).abs() <= 1.0, "raw share {share} against {:?}", rows[1]);
        assert!(c["rays_per_column"].as_f64().unwrap() > 0.0, "{c}");
    }
    let e2e = json["e2e"].as_array().unwrap();
    let methods: Vec<&str> = e2e.iter().map(|e| e["method"].as_str().unwrap()).collect();
    assert_eq!(methods, ["pr", "xu", "xu-g10-m40", "gauss-seidel"], "{json}");
    for (e, row) in e2e.iter().zip(&rows) {
        let to = |t: &str| e["seconds_to"][t].as_f64().unwrap_or_else(|| panic!("no seconds to {t} in {e}"));
        assert!(0.0 < to("1e-1") && to("1e-1") <= to("1e-2") && to("1e-2") <= to("1e-3"), "{e}");
        assert!((to("1e-3") / seconds(&row[4]) - 1.0).abs() < 0.05, "{e} against {row:?}");
        assert!(e["columns_to_1e-3"].as_f64().unwrap() > 0.0 && e.get("peak_bytes").is_some(), "{e}");
    }
}

#[test]
fn bench_refuses_bad_arguments() {
    let e = failure(&["bench", "--only", "columns,speed"]);
    assert!(e.contains("unknown bench section 'speed'") && e.contains("assembly"), "{e}");
    let e = failure(&["bench", "--runs", "0"]);
    assert!(e.contains("--runs must be at least 1"), "{e}");
    let e = failure(&["bench", "--quick", "--solvers", "pr,magic"]);
    assert!(e.contains("magic"), "{e}");
    let file = std::env::temp_dir().join(format!("radiosity-bench-file-{}", std::process::id()));
    std::fs::write(&file, b"").unwrap();
    let out = file.join("bench.md");
    let e = failure(&["bench", "--quick", "--only", "lu", "--out", out.to_str().unwrap()]);
    assert!(e.contains("is a file, not a folder"), "{e}");
    std::fs::remove_file(&file).unwrap();
}

/// A closed unit box in MGF, every face inward, the ceiling emitting.
const BOX_MGF: &str = "m wall =\n\tc\n\trd 0.6\nm lamp =\n\tc\n\trd 0.1\n\ted 5\n\
v a = \n\tp 0 0 0\nv b = \n\tp 1 0 0\nv c = \n\tp 1 1 0\nv d = \n\tp 0 1 0\n\
v e = \n\tp 0 0 1\nv f = \n\tp 1 0 1\nv g = \n\tp 1 1 1\nv h = \n\tp 0 1 1\n\
m wall\nf a b c d\nf a e f b\nf d c g h\nf a d h e\nf b f g c\nm lamp\nf e h g f\n";

/// `bench --only stochastic` on a small MGF box with one solver, as JSON and Markdown, with
/// `env` added to the environment (and `RENDERPARK` removed).
fn stochastic_bench(dir: &std::path::Path, extra: &[&str], env: &[(&str, &str)]) -> (String, serde_json::Value) {
    let scene = dir.join("box.mgf");
    std::fs::write(&scene, BOX_MGF).unwrap();
    let json_out = dir.join("bench.json");
    let mut args = vec!["bench", "--quick", "--only", "stochastic", "--runs", "1", "--max-seconds", "1"];
    args.extend(["--solvers", "stochastic-jacobi", "--scene", scene.to_str().unwrap()]);
    args.extend(["--json", json_out.to_str().unwrap()]);
    args.extend(extra);
    let mut command = Command::cargo_bin("xtask").unwrap();
    command.args(&args).env("RADIOSITY_CACHE_DIR", cache_dir()).env_remove("RENDERPARK");
    for (key, value) in env {
        command.env(key, value);
    }
    let report = String::from_utf8(command.assert().success().get_output().stdout.clone()).unwrap();
    let json = serde_json::from_str(&std::fs::read_to_string(&json_out).unwrap()).unwrap();
    (report, json)
}

#[test]
fn stochastic_bench_times_the_given_renderpark_beside_ours_or_says_it_has_none() {
    let dir = std::env::temp_dir().join(format!("radiosity-bench-peer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();

    // Without an executable: one sentence, and no figures.
    let (report, json) = stochastic_bench(&dir, &[], &[]);
    assert!(report.contains("No peer measurement") && report.contains("--renderpark FILE"), "{report}");
    let missing = json["peer"]["missing"].as_str().unwrap_or_default();
    assert!(missing.starts_with("No peer measurement") && json["peer"]["peer"].is_null(), "{json}");
    assert_eq!(json["peer"]["cases"].as_array().unwrap().len(), 0, "{json}");

    // A stand-in that records its arguments and sleeps 0.3 s: its wall time is read back, at
    // least the sleep, with little CPU.
    use std::os::unix::fs::PermissionsExt;
    let standin = dir.join("rpk");
    let args_file = dir.join("args");
    std::fs::write(&standin, format!("#!/bin/sh\necho \"$@\" > {}\nsleep 0.3\n", args_file.display())).unwrap();
    std::fs::set_permissions(&standin, std::fs::Permissions::from_mode(0o755)).unwrap();
    let (report, json) =
        stochastic_bench(&dir, &["--renderpark", standin.to_str().unwrap()], &[("RENDERPARK_COMMIT", "abc1234")]);
    assert!(!report.contains("No peer measurement") && report.contains("abc1234"), "{report}");
    let args = std::fs::read_to_string(&args_file).unwrap();
    let scene = dir.join("box.mgf");
    assert_eq!(
        args.trim(),
        format!("{} -raytracing-method none -radiance-method StochJacobi -iterations 20 -timings", scene.display())
    );
    let rows = table(&report, "### RenderPark");
    assert_eq!(rows.len(), 1, "{report}");
    assert_eq!((rows[0][0].as_str(), rows[0][1].as_str(), rows[0][2].as_str()), ("`StochJacobi`", "20", "1"));
    assert!(seconds(&rows[0][3]) >= 0.3, "{rows:?}");
    let run = &json["peer"]["cases"][0]["runs"][0];
    let (wall, cpu) = (run["wall"].as_f64().unwrap(), run["user"].as_f64().unwrap() + run["system"].as_f64().unwrap());
    assert!(wall >= 0.3 && cpu < 0.2 && json["peer"]["missing"].is_null(), "{run}");
    assert!((wall / seconds(&rows[0][3]) - 1.0).abs() < 0.01, "{run} against {rows:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
