//! `solve --ranks K` and `compare --ranks 2` (an xtask built with `--features mpi`): the same
//! answer as one process to 1e-12, printed and written once, with every rank's part reported;
//! and, without MPI, `--ranks` refused in one sentence.

use super::xtask;

/// `solve` of gmres-30 over the hierarchical operator of the Cornell box, with `extra`
/// arguments.
fn solve(extra: &[&str]) -> assert_cmd::assert::Assert {
    let mut args = vec![
        "solve",
        "--scene",
        "cornell:res=8",
        "--ff",
        "hierarchical:eps=0.05",
        "--solver",
        "gmres-30",
        "--until",
        "steps=40",
        "--reference",
        "none",
    ];
    args.extend(extra);
    xtask(&args)
}

#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs MPI: run with --features mpi, Open MPI and libclang installed (as .ci/run does)"
)]
fn solve_over_two_and_three_ranks_gives_the_single_process_answer_once() {
    use serde_json::Value;
    let json = |extra: &[&str]| -> Value {
        let out = solve(&[extra, &["--json"]].concat()).success().get_output().stdout.clone();
        serde_json::from_slice(&out).unwrap()
    };
    let radiosity = |v: &Value| -> Vec<f64> {
        v["patches"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|p| p["radiosity"].as_array().unwrap().iter().map(|c| c.as_f64().unwrap()))
            .collect()
    };
    let one = json(&[]);
    assert!(one["stats"].get("ranks").is_none(), "one process reports no ranks");
    let b1 = radiosity(&one);
    let scale = b1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for k in ["2", "3"] {
        let split = json(&["--ranks", k]);
        let gap = radiosity(&split).iter().zip(&b1).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(gap <= 1e-12 * scale, "{k} ranks: {gap:e} from one process");
        let ranks = split["stats"]["ranks"].as_array().unwrap();
        assert_eq!(ranks.len(), k.parse::<usize>().unwrap());
        assert!(ranks.iter().all(|r| r["links"].as_u64().unwrap() > 0 && r["run_sums"].as_u64().unwrap() >= 40));
    }
    // The summary is printed once, by rank 0, with a line for each rank.
    let text = String::from_utf8(solve(&["--ranks", "2"]).success().get_output().stdout.clone()).unwrap();
    assert_eq!(text.matches("scene        ").count(), 1, "{text}");
    assert_eq!(text.matches("\nrank ").count(), 2, "{text}");
}

#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs MPI: run with --features mpi, Open MPI and libclang installed (as .ci/run does)"
)]
fn the_solvers_that_sample_give_the_single_process_answer_over_two_and_three_ranks() {
    // Stochastic Jacobi's ranks cast their shares of every iteration's rays, random walks'
    // their replicates, and sums share what they found: the same bits, rays and standard
    // error as one process, whatever the ranks. Each rank reports the rays it cast: part of
    // them, and together all.
    use serde_json::Value;
    for solver in ["stochastic-jacobi:seq=sobol", "random-walk"] {
        let json = |extra: &[&str]| -> Value {
            let mut args = vec![
                "solve",
                "--scene",
                "cornell:res=6",
                "--solver",
                solver,
                "--until",
                "rays=2e5",
                "--reference",
                "none",
                "--json",
            ];
            args.extend(extra);
            serde_json::from_slice(&xtask(&args).success().get_output().stdout).unwrap()
        };
        let one = json(&[]);
        for k in ["2", "3"] {
            let split = json(&["--ranks", k]);
            assert_eq!(split["patches"], one["patches"], "{solver}, {k} ranks");
            for key in ["rays", "steps", "standard_error"] {
                assert_eq!(split["stats"][key], one["stats"][key], "{solver}, {k} ranks: {key}");
            }
            let total = one["stats"]["rays"].as_u64().unwrap();
            let ranks = split["stats"]["ranks"].as_array().unwrap_or_else(|| panic!("{solver}: no ranks"));
            assert_eq!(ranks.len(), k.parse::<usize>().unwrap(), "{solver}, {k} ranks");
            let shares: Vec<u64> = ranks.iter().map(|r| r["run_rays"].as_u64().unwrap()).collect();
            assert!(shares.iter().all(|&s| s > 0 && s < total), "{solver}, {k} ranks: {shares:?} of {total}");
            assert_eq!(shares.iter().sum::<u64>(), total, "{solver}, {k} ranks: {shares:?}");
        }
    }
}

#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs MPI: run with --features mpi, Open MPI and libclang installed (as .ci/run does)"
)]
fn compare_over_two_ranks_writes_the_single_process_table_once() {
    let dir = std::env::temp_dir().join(format!("radiosity-compare-ranks-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let table = |name: &str, extra: &[&str]| -> Vec<Vec<String>> {
        let out = dir.join(name);
        let out_arg = out.to_str().unwrap();
        let mut args = vec![
            "compare",
            "--scene",
            "cornell:res=6",
            "--ff",
            "hierarchical:eps=0.05",
            "--solvers",
            "gmres-30,xu",
            "--until",
            "steps=30",
            "--out",
            out_arg,
        ];
        args.extend(extra);
        xtask(&args).success();
        let text = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
        text.lines().map(|l| l.split(',').map(str::to_string).collect()).collect()
    };
    let one = table("one", &[]);
    let split = table("split", &["--ranks", "2"]);
    // Rank 0 alone wrote: one folder each, nothing beside them.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2);
    assert_eq!(split.len(), one.len());
    // Columns by name: a split operator shows no links of its own to count, so the single
    // process's table alone has `links`.
    let (header, split_header) = (&one[0], &split[0]);
    assert!(header.contains(&"links".to_string()) && !split_header.contains(&"links".to_string()));
    for (a, b) in split.iter().zip(&one).skip(1) {
        for (k, name) in header.iter().enumerate() {
            let Some(at) = split_header.iter().position(|h| h == name) else { continue };
            match name.as_str() {
                // Measured on each run's own clock.
                "seconds" | "ff_seconds" => {}
                // Printed to 4 significant digits; the runs agree to 1e-12.
                "e_rms" | "e_max" | "residual" | "bound" => {
                    let (x, y): (f64, f64) = (a[at].parse().unwrap(), b[k].parse().unwrap());
                    assert!((x - y).abs() <= 1e-3 * y.abs(), "{name}: {x} against {y} in {a:?}");
                }
                _ => assert_eq!(a[at], b[k], "{name} in {a:?}"),
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[cfg(not(feature = "mpi"))]
#[test]
fn ranks_without_mpi_are_refused_in_one_sentence() {
    let err = solve(&["--ranks", "2"]).failure().get_output().stderr.clone();
    let err = String::from_utf8(err).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("--ranks needs an xtask built with MPI"), "{err}");
}
