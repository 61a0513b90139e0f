//! `cargo xtask stress`: the stress table is snapshot-tested, the stiff furnace reaches its
//! exact answer with some solver, and the table says which solvers fail there and why.

use assert_cmd::Command;

/// One row of `stress.csv`, by column name.
struct Row(std::collections::HashMap<String, String>);

impl Row {
    fn get(&self, key: &str) -> &str {
        self.0.get(key).map(String::as_str).unwrap_or_else(|| panic!("no column {key}"))
    }

    fn number(&self, key: &str) -> f64 {
        self.get(key).parse().unwrap_or(f64::NAN)
    }
}

fn read_csv(path: &std::path::Path) -> Vec<Row> {
    let mut reader = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    reader
        .records()
        .map(|record| Row(header.iter().cloned().zip(record.unwrap().iter().map(String::from)).collect()))
        .collect()
}

#[test]
fn the_stress_table_is_stable_and_the_stiff_furnace_is_solved_exactly() {
    let dir = std::env::temp_dir().join(format!("radiosity-stress-{}", std::process::id()));
    let out = Command::cargo_bin("xtask").unwrap().args(["stress", "--out"]).arg(&dir).assert().success();
    let stdout = String::from_utf8(out.get_output().stdout.clone()).unwrap();
    assert!(stdout.contains("rho-0.999"), "{stdout}");

    let rows = read_csv(&dir.join("stress.csv"));
    let stiff: Vec<&Row> = rows.iter().filter(|r| r.get("case") == "rho-0.999").collect();
    // With rows closed in f64 the furnace identity is the exact answer of the solved system:
    // some solver must reach it to 1e-6 relative, with a certified bound.
    let exact: Vec<&str> = stiff
        .iter()
        .filter(|r| r.get("backend") == "analytic+closure")
        .filter(|r| r.get("converged") == "true" && r.number("e_rms_exact") <= 1e-6)
        .map(|r| r.get("solver"))
        .collect();
    assert!(!exact.is_empty(), "no solver reached the furnace identity at rho = 0.999");
    // And the table shows failures there, with their reason.
    let failed: Vec<&&Row> = stiff.iter().filter(|r| r.get("converged") != "true").collect();
    assert!(!failed.is_empty(), "every solver converged at rho = 0.999: the case is not stiff");
    assert!(failed.iter().all(|r| !r.get("detail").is_empty()));

    // Scale invariance, through the whole pipeline: the two scaled scenes converge in the
    // same runs to the same answers. (Paths may differ: the scene is symmetric, so shooting
    // methods meet ties that round-off breaks either way.) A solver that samples transport
    // draws its rays from alias tables whose entries differ in their last bits between the
    // scales, so a few rays land elsewhere and the two runs are two realizations of the same
    // estimator: their errors agree within 3 of their standard errors (each e_rms is of the
    // size of its standard error), and their verdicts may differ.
    let outcomes = |case: &str| -> Vec<(String, String, String, f64, f64)> {
        rows.iter()
            .filter(|r| r.get("case") == case)
            .map(|r| {
                let (backend, solver, converged) = (r.get("backend"), r.get("solver"), r.get("converged"));
                (backend.into(), solver.into(), converged.into(), r.number("e_rms_exact"), r.number("standard_error"))
            })
            .collect()
    };
    let (small, large) = (outcomes("scale-1e-4"), outcomes("scale-1e4"));
    assert_eq!(small.len(), large.len());
    for (a, b) in small.iter().zip(&large) {
        assert_eq!((&a.0, &a.1), (&b.0, &b.1));
        let spread = a.4.max(b.4);
        if spread.is_finite() {
            assert!((a.3 - b.3).abs() <= 3.0 * spread, "{a:?} against {b:?}");
            continue;
        }
        assert_eq!(a.2, b.2, "{a:?} against {b:?}");
        let scale = a.3.max(b.3);
        let same = (a.3.is_nan() && b.3.is_nan()) || scale < 1e-10 || (a.3 - b.3).abs() <= 0.1 * scale;
        assert!(same, "{a:?} against {b:?}");
    }

    let md = std::fs::read_to_string(dir.join("stress.md")).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    insta::assert_snapshot!("stress_table", md);
}
