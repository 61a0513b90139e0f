//! The hierarchical operator split over MPI ranks, started through `launch`: the
//! split-operator-check program's ranks write their links, a product and a gmres-30 solution;
//! on 2 and 3 ranks the links are disjoint and together one rank's (the single process's), and
//! the results are the same bits on every rank, the same on a second run, and within 1e-12 of
//! one rank's.

use radiosity_mpi::launch;
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

/// Why the tests here are ignored in a build without the feature `mpi`, whose programs they run.
const NEEDS_MPI: &str = "needs MPI: run with --features mpi, Open MPI and libclang installed (as .ci/run does)";

/// A scene with occluders and far links between clusters at this threshold.
const SCENE: &str = "cornell:res=8";
const EPS: &str = "0.05";

/// What one rank wrote.
struct Report {
    links: Vec<String>,
    product: Vec<u64>,
    solution: Vec<u64>,
}

/// Runs the program as `ranks` ranks (failing past two minutes) and reads every rank's report.
fn run(ranks: usize, tag: &str) -> Vec<Report> {
    let out_dir: PathBuf =
        Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("operator-{ranks}-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out_dir);
    std::fs::create_dir_all(&out_dir).unwrap();
    let args = [SCENE.into(), EPS.into(), out_dir.clone().into_os_string()];
    let (done, outcome) = mpsc::channel();
    std::thread::spawn(move || {
        // Built only with the feature `mpi`; without it the tests are ignored.
        let Some(program) = option_env!("CARGO_BIN_EXE_split-operator-check") else { panic!("{NEEDS_MPI}") };
        let program = Path::new(program);
        let _ = done.send(launch(ranks, program, &args).map_err(|e| e.to_string()));
    });
    let result =
        outcome.recv_timeout(Duration::from_secs(120)).unwrap_or_else(|_| panic!("{ranks} ranks ran past 2 minutes"));
    result.unwrap();
    (0..ranks)
        .map(|r| {
            let text = std::fs::read_to_string(out_dir.join(format!("rank-{r}.txt"))).unwrap();
            let mut report = Report { links: Vec::new(), product: Vec::new(), solution: Vec::new() };
            for line in text.lines() {
                let (label, rest) = line.split_once(' ').unwrap();
                let bits = || rest.split(' ').map(|w| u64::from_str_radix(w, 16).unwrap()).collect();
                match label {
                    "product" => report.product = bits(),
                    "solution" => report.solution = bits(),
                    _ => report.links.push(line.to_string()),
                }
            }
            report
        })
        .collect()
}

fn gap(a: &[u64], b: &[u64]) -> f64 {
    let (a, b): (Vec<f64>, Vec<f64>) =
        (a.iter().map(|&x| f64::from_bits(x)).collect(), b.iter().map(|&x| f64::from_bits(x)).collect());
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs MPI: run with --features mpi, Open MPI and libclang installed (as .ci/run does)"
)]
fn two_and_three_ranks_split_the_single_process_operator_and_solve_as_it_does() {
    let one = run(1, "one").pop().unwrap();
    assert!(one.links.len() > 1000, "{} links", one.links.len());
    let whole: HashSet<&String> = one.links.iter().collect();
    for ranks in [2, 3] {
        let parts = run(ranks, "split");
        let mut union = HashSet::new();
        for (r, part) in parts.iter().enumerate() {
            assert!(!part.links.is_empty(), "{ranks} ranks: rank {r} built no link");
            for link in &part.links {
                assert!(union.insert(link), "{ranks} ranks: {link} built by two ranks");
            }
            assert_eq!(part.product, parts[0].product, "{ranks} ranks: rank {r}'s product is not rank 0's");
            assert_eq!(part.solution, parts[0].solution, "{ranks} ranks: rank {r}'s solution is not rank 0's");
        }
        assert_eq!(union, whole, "{ranks} ranks: the ranks' links are not one rank's");
        for (what, a, b) in
            [("product", &parts[0].product, &one.product), ("solution", &parts[0].solution, &one.solution)]
        {
            let gap = gap(a, b);
            assert!(gap <= 1e-12, "{ranks} ranks: the {what} is {gap:e} from one rank's");
        }
        let again = run(ranks, "again");
        assert_eq!(again[0].solution, parts[0].solution, "{ranks} ranks: a second run differs");
    }
}
