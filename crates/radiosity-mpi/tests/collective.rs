//! `MpiWorld` under `mpirun`, started through `launch`: the collective-check program's ranks
//! write what they summed and received, and these tests check it against sums taken here in
//! rank order, bit for bit; a rank that exits early must end the run with one sentence.

use radiosity_mpi::launch;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

/// Why the tests here are ignored in a build without the feature `mpi`, whose programs they run.
const NEEDS_MPI: &str = "needs MPI: run with --features mpi, Open MPI and libclang installed (as .ci/run does)";

/// Runs collective-check as `ranks` ranks with `mode` (if any), failing the test when the run
/// takes longer than `limit`; returns the run's result and its output directory.
fn run_check(ranks: usize, mode: Option<&str>, limit: Duration) -> (Result<(), String>, PathBuf) {
    let name = format!("collective-{ranks}-{}-{}", mode.unwrap_or("sums"), std::process::id());
    let out_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&out_dir);
    std::fs::create_dir_all(&out_dir).unwrap();
    let mut args = vec![out_dir.clone().into_os_string()];
    args.extend(mode.map(Into::into));
    let (done, outcome) = mpsc::channel();
    std::thread::spawn(move || {
        // Built only with the feature `mpi`; without it the tests are ignored.
        let Some(program) = option_env!("CARGO_BIN_EXE_collective-check") else { panic!("{NEEDS_MPI}") };
        let program = Path::new(program);
        let _ = done.send(launch(ranks, program, &args).map_err(|e| e.to_string()));
    });
    let result = outcome.recv_timeout(limit).unwrap_or_else(|_| panic!("{ranks} ranks ran past {limit:?}"));
    (result, out_dir)
}

/// One rank's report, as (label, values) lines; values are `f64` bits in hexadecimal except on
/// the `agree` and `traffic` lines.
fn read_report(out_dir: &Path, rank: usize) -> Vec<(String, Vec<String>)> {
    let text = std::fs::read_to_string(out_dir.join(format!("rank-{rank}.txt"))).unwrap();
    text.lines()
        .map(|line| {
            let mut words = line.split_whitespace().map(str::to_string);
            (words.next().unwrap(), words.collect())
        })
        .collect()
}

fn floats(words: &[String]) -> Vec<f64> {
    words.iter().map(|w| f64::from_bits(u64::from_str_radix(w, 16).unwrap())).collect()
}

fn line<'a>(report: &'a [(String, Vec<String>)], label: &str) -> Vec<&'a [String]> {
    report.iter().filter(|(l, _)| l == label).map(|(_, v)| v.as_slice()).collect()
}

fn check_sums(ranks: usize) {
    let (result, out_dir) = run_check(ranks, None, Duration::from_secs(120));
    result.unwrap();
    let reports: Vec<_> = (0..ranks).map(|r| read_report(&out_dir, r)).collect();
    let cases = line(&reports[0], "input").len();
    assert_eq!(cases, 5);
    let mut values_summed = 0u64;
    for case in 0..cases {
        let inputs: Vec<Vec<f64>> = reports.iter().map(|rep| floats(line(rep, "input")[case])).collect();
        // The truth: x₀ + x₁ + … element by element, in rank order, here in one process.
        let mut expected = inputs[0].clone();
        for input in &inputs[1..] {
            expected.iter_mut().zip(input).for_each(|(e, x)| *e += x);
        }
        values_summed += expected.len() as u64;
        for (rank, report) in reports.iter().enumerate() {
            let got = floats(line(report, "sum")[case]);
            let (got_bits, expected_bits): (Vec<u64>, Vec<u64>) =
                got.iter().zip(&expected).map(|(g, e)| (g.to_bits(), e.to_bits())).unzip();
            assert_eq!(got.len(), expected.len(), "case {case}, rank {rank}");
            assert_eq!(got_bits, expected_bits, "case {case}, rank {rank}");
        }
        if ranks == 3 && !expected.is_empty() {
            // (1e16 + 1) − 1e16 in rank order is 0, where 1e16 − 1e16 + 1 would be 1.
            assert_eq!(expected[0], 0.0);
        }
    }
    let gathered: Vec<f64> = (0..ranks).flat_map(|r| [r as f64, 0.5 + 10.0 * r as f64]).collect();
    let mut total_bytes = 0;
    for (rank, report) in reports.iter().enumerate() {
        assert_eq!(floats(line(report, "gather")[0]), gathered, "rank {rank}");
        assert_eq!(line(report, "agree")[0], ["true", "false"], "rank {rank}");
        let traffic: Vec<u64> = line(report, "traffic")[0].iter().map(|w| w.parse().unwrap()).collect();
        // Five sums, one gather of 2 values a rank, two agreements of one value.
        assert_eq!(traffic[..2], [8, values_summed + 2 * ranks as u64 + 2], "rank {rank}");
        total_bytes += traffic[2];
    }
    // Each value leaves its rank twice, to each of the others but once in all (module doc of
    // world): 2·N·(K − 1) values over all ranks.
    assert_eq!(total_bytes, 16 * (ranks as u64 - 1) * (values_summed + 2 * ranks as u64 + 2));
}

#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs MPI: run with --features mpi, Open MPI and libclang installed (as .ci/run does)"
)]
fn two_ranks_sum_in_rank_order_with_the_same_bits_everywhere() {
    check_sums(2);
}

#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs MPI: run with --features mpi, Open MPI and libclang installed (as .ci/run does)"
)]
fn three_ranks_sum_in_rank_order_with_the_same_bits_everywhere() {
    check_sums(3);
}

#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs MPI: run with --features mpi, Open MPI and libclang installed (as .ci/run does)"
)]
fn a_rank_that_exits_early_ends_the_run_with_one_sentence() {
    let (result, _) = run_check(3, Some("exit-early"), Duration::from_secs(20));
    assert_eq!(result, Err("rank 1 of 3 ended with exit status 3 before the distributed run finished".to_string()));
}
