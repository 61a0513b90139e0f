//! `collective-check OUT_DIR [exit-early]`: run under `mpirun`, each rank sums vectors through
//! [`MpiWorld`] and writes, to `OUT_DIR/rank-R.txt`, its inputs, the sums it received, what
//! `gather` and `agree` returned and its traffic, so that a test (tests/collective.rs) can check
//! them against a sum taken here in rank order. It also tries an MPI installation by hand:
//! `cargo build -p radiosity-mpi --features mpi` then
//! `mpirun -np 3 target/debug/collective-check /tmp/out`.
//!
//! With `exit-early`, rank 1 exits with status 3 before the first sum, leaving the others
//! waiting in it: a failure that the launcher must end.
//!
//! Values are written as the hexadecimal bits of each `f64`, so that the check is bit for bit.

use radiosity_core::Collective;
use radiosity_mpi::MpiWorld;
use std::fmt::Write as _;
use std::path::PathBuf;

/// The vector lengths summed: empty, shorter than the ranks, and long enough for every block.
const LENGTHS: [usize; 5] = [0, 1, 2, 7, 1000];

fn main() {
    if let Err(message) = run() {
        eprintln!("collective-check: {message}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let mut args = std::env::args_os().skip(1);
    let out_dir = PathBuf::from(args.next().ok_or("usage: collective-check OUT_DIR [exit-early]")?);
    let exit_early = args.next().is_some_and(|mode| mode == "exit-early");
    let world = MpiWorld::init().map_err(|e| e.to_string())?;
    let rank = world.rank();
    if exit_early && rank == 1 {
        std::process::exit(3);
    }
    let mut report = String::new();
    for length in LENGTHS {
        let input = rank_values(rank, length);
        let mut sum = input.clone();
        world.sum(&mut sum);
        writeln!(report, "input {}", bits(&input)).map_err(|e| e.to_string())?;
        writeln!(report, "sum {}", bits(&sum)).map_err(|e| e.to_string())?;
    }
    let gathered = world.gather(&[rank as f64, 0.5 + 10.0 * rank as f64]);
    writeln!(report, "gather {}", bits(&gathered.concat())).map_err(|e| e.to_string())?;
    let agreed = [world.agree(rank == 0), world.agree(rank != 0)];
    writeln!(report, "agree {} {}", agreed[0], agreed[1]).map_err(|e| e.to_string())?;
    let traffic = world.traffic();
    writeln!(report, "traffic {} {} {}", traffic.sums, traffic.values, traffic.bytes_sent)
        .map_err(|e| e.to_string())?;
    let path = out_dir.join(format!("rank-{rank}.txt"));
    std::fs::write(&path, report).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Rank `rank`'s vector of `length` values: first the pattern 1e16, 1, −1e16 (rank order
/// matters: (1e16 + 1) − 1e16 is 0, not 1), then values of mixed sign and magnitudes from
/// 1e-8 to 1e8 drawn by a xorshift generator seeded by the rank.
fn rank_values(rank: usize, length: usize) -> Vec<f64> {
    let mut state = 0x9E37_79B9_7F4A_7C15_u64 ^ (rank as u64 + 1).wrapping_mul(0xD1B5_4A32_D192_ED03);
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    (0..length)
        .map(|i| {
            if i == 0 {
                [1e16, 1.0, -1e16][rank % 3]
            } else {
                let r = next();
                let unit = (r >> 11) as f64 / (1u64 << 53) as f64;
                let sign = if r & 1 == 0 { 1.0 } else { -1.0 };
                sign * unit * 10f64.powi((r >> 1 & 15) as i32 - 8)
            }
        })
        .collect()
}

/// The values' bits in hexadecimal, separated by blanks.
fn bits(values: &[f64]) -> String {
    values.iter().map(|v| format!("{:016x}", v.to_bits())).collect::<Vec<_>>().join(" ")
}
