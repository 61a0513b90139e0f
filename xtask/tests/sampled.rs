//! The solvers that sample transport on the command line: `solve` reports their rays and
//! standard error (text and JSON), `--transport` chooses where the rays go, `compare` puts them
//! in one table and one set of plots with deterministic solvers, and every misuse is refused
//! in one sentence before any work.

use super::{failure, stdout_json, xtask};

#[test]
fn solve_reports_the_rays_and_the_standard_error_of_a_stochastic_solver() {
    let args = [
        "solve",
        "--scene",
        "cornell:res=2",
        "--solver",
        "stochastic-jacobi:seed=3",
        "--transport",
        "matrix",
        "--until",
        "rays=2e5",
    ];
    let json = stdout_json(&[&args[..], &["--json"]].concat());
    let stats = &json["stats"];
    let rays = stats["rays"].as_u64().unwrap();
    assert!(rays >= 200_000 && stats["columns"] == 0, "{stats}");
    assert_eq!(stats["transport"], "matrix");
    assert_eq!(stats["replicates"], 4);
    let (e_rms, spread) = (stats["e_rms"].as_f64().unwrap(), stats["standard_error"].as_f64().unwrap());
    // On the stored matrix the rays sample the reference's own system, so the estimate is
    // unbiased and its e_rms is of the size of its standard error: the squared summaries have
    // the same expectation, each a sum over 53 patches of 4 replicates. 3 leaves room for
    // their spread, at a fixed seed.
    assert!(spread > 0.0 && e_rms <= 3.0 * spread, "e_rms {e_rms}, standard error {spread}");
    assert!(stats["termination"].as_str().unwrap().contains("rays"), "{stats}");
    // The power its incremental series left unshot, at most its threshold (1e-4 of the emitted).
    let unshot = stats["record"]["unshot_power"].as_f64().unwrap();
    assert!((0.0..=1e-4).contains(&unshot), "unshot power {unshot}");
    // A deterministic solver's JSON has no standard error and no rays.
    let pr = stdout_json(&["solve", "--scene", "cornell:res=2", "--solver", "pr", "--json"]);
    assert!(pr["stats"]["standard_error"].is_null() && pr["stats"]["rays"] == 0, "{}", pr["stats"]);
    // The text names the rays, where they went and the spread beside the bound.
    let text = String::from_utf8(xtask(&args).success().get_output().stdout.clone()).unwrap();
    assert!(text.contains(" rays (matrix)"), "{text}");
    let spread = text.lines().find(|l| l.starts_with("spread ")).unwrap_or_else(|| panic!("{text}"));
    assert!(spread.contains("of 4 independent replicates") && spread.contains("not a bound"), "{spread}");
}

#[test]
fn compare_puts_deterministic_and_stochastic_solvers_in_one_table_and_one_set_of_plots() {
    let dir = std::env::temp_dir().join(format!("radiosity-compare-sampled-{}", std::process::id()));
    let args = [
        "compare",
        "--scene",
        "cornell:res=2",
        "--solvers",
        "pr,stochastic-jacobi",
        "--until",
        "columns=n,rays=2e4",
        "--out",
        dir.to_str().unwrap(),
    ];
    let summary = String::from_utf8(xtask(&args).success().get_output().stdout.clone()).unwrap();
    let header = summary.lines().next().unwrap();
    assert!(header.contains("rays") && header.contains("std error") && header.contains("bound end"), "{summary}");
    let csv = std::fs::read_to_string(dir.join("convergence.csv")).unwrap();
    assert!(csv.starts_with("solver,step,columns,rays,") && csv.lines().next().unwrap().ends_with(",bound,std_error"));
    assert!(csv.lines().any(|l| l.starts_with("pr,")) && csv.lines().any(|l| l.starts_with("stochastic-jacobi,")));
    for plot in ["e_rms-steps", "e_rms-columns", "e_rms-rays", "e_rms-seconds"] {
        assert!(dir.join(format!("{plot}.svg")).exists() && dir.join(format!("{plot}.png")).exists(), "{plot}");
    }
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("certified bounds and standard errors") && report.contains("Rays: `scene`"), "{report}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn misuses_of_rays_are_refused_in_one_sentence() {
    let e = failure(&["solve", "--scene", "cornell:res=2", "--solver", "stochastic-jacobi"]);
    assert!(e.contains("spends no columns, products or links") && e.contains("rays="), "{e}");
    let e = failure(&["compare", "--scene", "cornell:res=2", "--solvers", "pr,stochastic-jacobi"]);
    assert!(e.contains("stochastic-jacobi casts rays"), "{e}");
    let e = failure(&["solve", "--scene", "cornell:res=2", "--solver", "pr", "--transport", "nowhere"]);
    assert!(e.contains("it must be scene or matrix"), "{e}");
    let e = failure(&[
        "solve",
        "--scene",
        "cornell:res=2",
        "--solver",
        "stochastic-jacobi",
        "--until",
        "rays=1e4",
        "--transport",
        "matrix",
        "--reference",
        "none",
    ]);
    assert!(e.contains("--transport matrix") && e.contains("keeps none"), "{e}");
}
