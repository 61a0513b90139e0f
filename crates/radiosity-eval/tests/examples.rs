//! The examples in `examples/` run and write what `cargo xtask compare` writes, or time a
//! backend with the bench's library functions; and a comparison with the automatic group
//! frequency gives the same table twice.

#[allow(dead_code)]
#[path = "../examples/custom_solver.rs"]
mod custom_solver;

#[allow(dead_code)]
#[path = "../examples/time_backend.rs"]
mod time_backend;

#[allow(dead_code)]
#[path = "../examples/refinement_curve.rs"]
mod refinement_curve;

// The timing example brings the backend of one's own with it.
use time_backend::custom_backend;

use radiosity_eval::{Lab, LabOptions, NoProgress};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::{SolverRegistry, StopRules};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("radiosity-example-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The files `compare` writes, each non-empty, and the CSV naming every solver.
fn check_report(dir: &Path, solvers: &[&str]) {
    let csv = std::fs::read_to_string(dir.join("convergence.csv")).unwrap();
    assert!(csv.starts_with("solver,step,columns,seconds,ff_seconds,clock,e_rms,e_max,residual,bound\n"), "{csv}");
    // Labs compute their columns by default: measured seconds.
    assert!(csv.lines().skip(1).all(|l| l.contains(",measured,")), "{csv}");
    for solver in solvers {
        assert!(csv.lines().any(|l| l.starts_with(&format!("{solver},"))), "{solver} missing from\n{csv}");
    }
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for section in ["n/4", "1e-3", "Where the time went", "Left out", "e_rms-steps.png"] {
        assert!(report.contains(section), "missing {section} in\n{report}");
    }
    for plot in ["e_rms-steps", "e_rms-columns", "e_rms-seconds"] {
        assert!(std::fs::read(dir.join(format!("{plot}.png"))).unwrap().starts_with(b"\x89PNG"), "{plot}");
        assert!(std::fs::read_to_string(dir.join(format!("{plot}.svg"))).unwrap().contains("<svg"), "{plot}");
    }
}

#[test]
fn custom_solver_is_compared_with_pr_and_xu() {
    let dir = scratch("solver");
    let summary = custom_solver::compare("cornell:res=2", &dir).unwrap();
    for solver in ["pr", "xu", "damped-jacobi-0.9"] {
        assert!(summary.contains(solver), "{summary}");
    }
    check_report(&dir, &["pr", "xu", "damped-jacobi-0.9"]);
    // Damped Jacobi converges to the same reference: its e_rms after 2n columns is far below
    // the emission's (1 at step 0).
    let csv = std::fs::read_to_string(dir.join("convergence.csv")).unwrap();
    let last = csv.lines().rfind(|l| l.starts_with("damped-jacobi-0.9,")).unwrap();
    let e_rms: f64 = last.split(',').nth(6).unwrap().parse().unwrap();
    assert!(e_rms < 0.1, "{last}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn custom_backend_runs_under_the_built_in_solvers() {
    let dir = scratch("backend");
    let summary = custom_backend::compare("cornell:res=2", "point-disc", &dir).unwrap();
    check_report(&dir, &["pr", "xu", "xu-g30-m480"]);
    assert!(summary.contains("xu-g30-m480"), "{summary}");
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("form factors `point-disc:disc=1`"), "{report}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_registered_backend_is_named_as_the_built_ins_are() {
    let backends = custom_backend::backends();
    // Stored as a matrix, its parameters passed through `of`.
    let stored = backends.parse("matrix:of=point-disc:disc=2").unwrap();
    assert_eq!(stored.canonical(), "matrix:of=point-disc:rebalance=false:disc=2");
    assert_eq!(stored.stores().map(|(of, _)| of.name()), Some("point-disc"));
    let e = backends.parse("point-disk").unwrap_err().to_string();
    assert!(e.contains("did you mean 'point-disc'?") && e.contains("hierarchical, matrix, point-disc"), "{e}");
    let e = backends.parse("point-disc:disc=0").unwrap_err().to_string();
    assert!(e.contains("form-factor backend 'point-disc'") && e.contains("disc=0"), "{e}");
    // The built-in registry does not know it.
    assert!(BackendSpec::parse("point-disc").is_err());
}

#[test]
fn a_backend_of_ones_own_is_timed_beside_the_analytic_one() {
    let (timings, table) = time_backend::measure("cornell:res=2").unwrap();
    assert_eq!(timings.iter().map(|t| t.backend.as_str()).collect::<Vec<_>>(), ["analytic", "centroid-disc"]);
    for t in &timings {
        assert!(t.columns_per_second > 0.0 && t.columns_per_second.is_finite(), "{table}");
        // xu reaches every threshold against its own system's reference, in order.
        let reached: Vec<f64> = t.run.reached.iter().map(|r| r.e_rms).collect();
        assert_eq!(reached, [1e-1, 1e-2, 1e-3], "{} in\n{table}", t.backend);
        assert!(t.run.reached.windows(2).all(|w| w[0].seconds <= w[1].seconds && w[0].columns <= w[1].columns));
        assert!(t.run.e_rms <= 1e-3, "{table}");
    }
    assert!(table.contains("| `centroid-disc` |"), "{table}");
}

/// Two comparisons with the automatic group frequency give the same table, timings aside:
/// the frequency comes from counted operations, not from the clock.
#[test]
fn automatic_frequency_is_reproducible() {
    let table = || {
        let scene = PreparedScene::load("cornell:res=2").unwrap();
        let lab =
            Lab::new(&scene, &BackendSpec::parse("analytic").unwrap(), LabOptions::default(), &NoProgress).unwrap();
        let registry = SolverRegistry::builtin();
        let names = ["pr-g8", "xu-g8", "pr-g8-m40", "xu-g8-m40"];
        let solvers = names.iter().map(|s| registry.build(s).unwrap()).collect();
        let comparison = lab.compare(solvers, &StopRules::parse("columns=2n").unwrap(), &NoProgress).unwrap();
        let mut csv = Vec::new();
        comparison.table().without_timings().write_csv(&mut csv).unwrap();
        let steps: Vec<u64> = comparison.outcomes.iter().map(|o| o.state.step).collect();
        (String::from_utf8(csv).unwrap(), steps)
    };
    let (first, second) = (table(), table());
    assert_eq!(first.1, second.1);
    assert_eq!(first.0, second.0);
    // The memory variants run past n on stored columns, so group steps happened.
    assert!(first.0.lines().count() > 20, "{}", first.0);
}

#[test]
fn the_refinement_curve_measures_every_setting_and_draws_them() {
    let dir = scratch("curve");
    let cache = radiosity_eval::Cache::at(dir.join("cache"));
    let series: &[(&str, &[&str])] =
        &[("trust", &["eps=0.05:trust=1", "eps=0.05:trust=4096"]), ("eps", &["eps=0.1", "eps=0.02"])];
    let points = refinement_curve::curve("cornell:res=4", series, &cache, &dir).unwrap();
    assert_eq!(points.len(), 4);
    // The Cornell box occludes: every operator traces rays, and each lies within a few percent of
    // the analytic system's solution.
    assert!(points.iter().all(|p| p.rays > 0.0 && p.links > 0.0 && p.e_rms > 0.0 && p.e_rms < 0.05), "{points:?}");
    let csv = std::fs::read_to_string(dir.join("curve.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5, "{csv}");
    assert!(csv.lines().nth(1).unwrap().starts_with("trust,hierarchical:eps=5e-2:"), "{csv}");
    assert!(std::fs::read(dir.join("curve.png")).unwrap().starts_with(b"\x89PNG"));
}
