//! The Rust side of the package's overhead measurement (`bench/overhead.py` is the Python
//! side): the same analytic columns and stored-matrix products on `office`, timed in Rust.
//!
//! `cargo run --release -p radiosity-py --example overhead -- columns|products`
//! (products read the stored matrix from `$RADIOSITY_CACHE_DIR`, where the Python side left
//! it, or assemble it).

use radiosity_core::ColumnSource;
use radiosity_eval::{CACHE_DIR_VAR, Cache, FormFactors, NoProgress, backend, obtain_matrix};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use std::error::Error;
use std::time::Instant;

/// The median of `times`.
fn median(mut times: Vec<f64>) -> f64 {
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() -> Result<(), Box<dyn Error>> {
    let what = std::env::args().nth(1).unwrap_or_else(|| "columns".into());
    let prepared = PreparedScene::load("office")?;
    let n = prepared.scene().len();
    let mut times = Vec::new();
    if what == "columns" {
        // 40 columns j = k n / 40 from a fresh backend, as the Python side fetches them.
        let analytic = backend(&prepared, &BackendSpec::parse("analytic")?, None, &NoProgress)?;
        let mut column = vec![0.0; n];
        for k in 0..40 {
            let start = Instant::now();
            analytic.fill_column(k * n / 40, &mut column);
            times.push(start.elapsed().as_secs_f64());
        }
        println!("rust column median {:.6} s", median(times));
    } else {
        let cache = std::env::var_os(CACHE_DIR_VAR).map(Cache::at);
        let stored = obtain_matrix(&prepared, &BackendSpec::parse("matrix")?, cache.as_ref(), &NoProgress)?;
        let matrix = FormFactors::from_stored(stored.matrix);
        let (x, mut out) = (vec![1.0; n], vec![0.0; n]);
        for _ in 0..21 {
            let start = Instant::now();
            matrix.multiply(&x, 1, &mut out);
            times.push(start.elapsed().as_secs_f64());
        }
        println!("rust product median {:.6} s", median(times));
    }
    Ok(())
}
