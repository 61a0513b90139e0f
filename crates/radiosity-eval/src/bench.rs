//! Performance measurements: columns per second against the ray-tracing limit, time and
//! memory from scene load to accuracy, and the cost of a column as scenes grow; their medians,
//! their Markdown sections and their JSON keys.
//!
//! Form factors dominate the cost of radiosity, so speed is measured where it is spent and
//! against what limits it:
//!
//! - [`columns`]: form-factor columns per second on 1 and 2 threads over a fixed, seeded
//!   sample of columns, beside the rate at which **the same rays** are traced straight through
//!   the BVH ([`radiosity_ff::ColumnRays`] lists them); [`columns::time_parallel`] and
//!   [`columns::time_sequential`] time any [`ColumnSource`](radiosity_core::ColumnSource), a
//!   researcher's own included.
//! - [`e2e`]: wall time from scene load (load, BVH, analysis, form-factor setup, solve) to
//!   e_rms ≤ 1e-1, 1e-2 and 1e-3 for any [`Solver`](radiosity_solvers::Solver), with the
//!   time spent measuring e_rms taken out, and the peak resident memory.
//! - [`scale`]: the same without a reference or a matrix, to a certified bound, with the growth
//!   exponent of the time per column in `n`.
//!
//! Each measurement returns typed figures; [`median`] aggregates runs, each section module
//! writes its Markdown section from them, and [`BenchJson`] holds the figures under the stable
//! keys of `cargo xtask bench --json`. Running the cases of a section in child processes, so
//! that each peak memory is its own, is the caller's part: the command line re-invokes itself
//! and reads each child's report, which serialises to one JSON line.

pub mod columns;
pub mod e2e;
pub mod report_text;
pub mod scale;

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The median of `values` (the mean of the middle two for an even count), NaNs left out; NaN
/// when nothing is left.
pub fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let k = v.len();
    if k % 2 == 1 { v[k / 2] } else { 0.5 * (v[k / 2 - 1] + v[k / 2]) }
}

/// The high-water mark of this process's resident memory (`VmHWM` of `/proc/self/status`), in
/// bytes; `None` where there is no `/proc`.
pub fn peak_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.trim_start_matches("VmHWM:").trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kb * 1024)
}

/// The figures of `cargo xtask bench --json FILE`, under keys that stay the same from run to
/// run (medians, as in the Markdown report; `null` where a figure was not measured or not
/// reached).
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct BenchJson {
    /// The machine and build.
    pub machine: Machine,
    /// The bench scene and its patch count, when a section measured on it.
    pub scene: Option<SceneJson>,
    /// Columns per second, one entry per backend.
    pub columns: Vec<ColumnsJson>,
    /// Time to accuracy, one entry per method and backend.
    pub e2e: Vec<E2eJson>,
}

/// The machine the figures were taken on.
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct Machine {
    /// Cores available to this process.
    pub cores: usize,
    /// Threads of rayon's global pool.
    pub rayon_threads: usize,
    /// `std::env::consts::OS`.
    pub os: String,
    /// `std::env::consts::ARCH`.
    pub arch: String,
    /// Whether this is an optimised build without debug assertions.
    pub release: bool,
}

impl Machine {
    /// The machine this process runs on.
    pub fn this() -> Machine {
        Machine {
            cores: std::thread::available_parallelism().map_or(0, |n| n.get()),
            rayon_threads: rayon::current_num_threads(),
            os: std::env::consts::OS.to_string(),
            arch: std::env::consts::ARCH.to_string(),
            release: !cfg!(debug_assertions),
        }
    }
}

/// The bench scene.
#[derive(Debug, Serialize, Deserialize)]
pub struct SceneJson {
    /// The scene argument.
    pub name: String,
    /// Its patches.
    pub patches: usize,
}

/// One backend's columns per second ([`columns`]).
#[derive(Debug, Serialize, Deserialize)]
pub struct ColumnsJson {
    /// The canonical backend argument.
    pub backend: String,
    /// Columns per second by thread count (`"1"`, `"2"`: columns in parallel on a dedicated
    /// pool).
    pub columns_per_second: BTreeMap<String, f64>,
    /// Rays (segments) traced per column.
    pub rays_per_column: f64,
    /// Pipeline rays per second over raw obvhs rays per second on the same rays, 2 threads.
    pub raw_share: f64,
    /// Analytic: columns per second when every pair's visible fraction is recorded, one at a
    /// time on 2 threads.
    pub recorded_columns_per_second: Option<f64>,
}

/// One method's time to accuracy ([`e2e`]).
#[derive(Debug, Serialize, Deserialize)]
pub struct E2eJson {
    /// The solver's name.
    pub method: String,
    /// The backend argument.
    pub backend: String,
    /// Wall seconds from scene load to e_rms ≤ `"1e-1"`, `"1e-2"`, `"1e-3"`.
    pub seconds_to: BTreeMap<String, Option<f64>>,
    /// Columns computed until e_rms ≤ 1e-3.
    #[serde(rename = "columns_to_1e-3")]
    pub columns_to_1e_3: Option<f64>,
    /// The largest peak resident memory over the runs.
    pub peak_bytes: Option<u64>,
}

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn medians_of_odd_and_even_counts_leave_nans_out() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(&[f64::NAN, 5.0]), 5.0);
        assert!(median(&[]).is_nan());
    }
}
