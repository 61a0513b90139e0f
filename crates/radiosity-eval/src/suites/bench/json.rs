//! The figures of `cargo xtask bench --json FILE` under stable keys ([`BenchJson`]): the
//! machine, the bench scene, columns per second and time to accuracy.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

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
    /// Stochastic relaxation from scene load, one entry per solver.
    #[serde(default)]
    pub stochastic: Vec<crate::bench::stochastic::StochasticJson>,
    /// RenderPark's process times beside the stochastic section, or why there are none
    /// (`null` when the section did not run).
    #[serde(default)]
    pub peer: Option<crate::bench::peer::PeerJson>,
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

/// One backend's columns per second ([`columns`](crate::bench::columns)).
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

/// One method's time to accuracy ([`e2e`](crate::bench::e2e)).
#[derive(Debug, Serialize, Deserialize)]
pub struct E2eJson {
    /// The solver's name.
    pub method: String,
    /// The backend argument.
    pub backend: String,
    /// The clock of `seconds_to` ([`radiosity_core::Clock::name`]): always `measured`, wall
    /// time, since every column is computed.
    pub clock: String,
    /// Wall seconds from scene load to e_rms ≤ `"1e-1"`, `"1e-2"`, `"1e-3"`.
    pub seconds_to: BTreeMap<String, Option<f64>>,
    /// Columns computed until e_rms ≤ 1e-3.
    #[serde(rename = "columns_to_1e-3")]
    pub columns_to_1e_3: Option<f64>,
    /// The largest peak resident memory over the runs.
    pub peak_bytes: Option<u64>,
}
