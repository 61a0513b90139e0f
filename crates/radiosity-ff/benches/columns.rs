//! Throughput of every form-factor backend on `office`: columns per second, computed in
//! parallel over rayon's threads (`RAYON_NUM_THREADS` sets how many).
//!
//! `cargo bench -p radiosity-ff --bench columns`; criterion reports the median time per batch
//! of columns and the columns per second. Every iteration computes the same columns, so the
//! analytic backend's record of visible fractions is off: with it, every iteration after the
//! first would take its visible fractions from the first and trace nothing.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_main};
use radiosity_core::ColumnSource;
use radiosity_ff::{AnalyticParams, BackendSpec, FormFactorInput};
use radiosity_geom::{SceneAnalysis, Visibility, load_scene};
use rayon::prelude::*;
use std::time::Duration;

/// Columns per measured batch, spread over the scene.
const BATCH: usize = 64;

fn columns(c: &mut Criterion) {
    let scene = load_scene("office").expect("office builds").scene;
    let visibility = Visibility::new(&scene);
    let analysis = SceneAnalysis::new(&scene, &visibility);
    let input = FormFactorInput { scene: &scene, visibility: visibility.clone(), analysis: &analysis };
    let n = scene.len();
    let shooters: Vec<usize> = (0..BATCH).map(|k| k * n / BATCH).collect();
    let mut group = c.benchmark_group("office columns");
    group.throughput(Throughput::Elements(BATCH as u64)).sample_size(10).measurement_time(Duration::from_secs(8));
    let specs = std::env::var("FF_BENCH_BACKENDS")
        .unwrap_or_else(|_| "analytic,analytic:tol=1,hemicube,montecarlo".to_string());
    for arg in specs.split(',') {
        let spec = BackendSpec::parse(arg).expect("valid backend");
        // Columns timed as computed for the first time: no record of visible fractions.
        let spec = match spec.params::<AnalyticParams>() {
            Some(p) => BackendSpec::new(AnalyticParams { cache_mib: 0, ..*p }),
            None => spec,
        };
        let backend = spec.build(input.clone()).expect("the backend builds");
        group.bench_function(BenchmarkId::from_parameter(arg), |b| {
            b.iter(|| {
                shooters.par_iter().for_each_init(
                    || vec![0.0; n],
                    |column, &j| {
                        backend.fill_column(j, column);
                        std::hint::black_box(&column);
                    },
                )
            })
        });
    }
    group.finish();
}

// criterion's macros generate undocumented items.
#[allow(missing_docs)]
mod harness {
    criterion::criterion_group!(benches, super::columns);
}
criterion_main!(harness::benches);
