//! Dense LU with partial pivoting on `I − diag(ρ) F`, one right-hand side: nalgebra against
//! faer (sequential and on the rayon pool), at the sizes of `multi-cubes` (480) and
//! `labyrinth` (≈3400). The medians are quoted in the `reference` module doc, which explains
//! the choice.
//!
//! Run with `cargo bench -p radiosity-eval --bench lu`.

use criterion::{BenchmarkId, Criterion, criterion_main};
use radiosity_core::dense_lu::lu_solve;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::time::Duration;

/// A row-major `I − ρ F` with `F` random, non-negative, rows summing to 0.99, `ρ = 0.7`.
fn system(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        let row = &mut a[i * n..(i + 1) * n];
        for (j, v) in row.iter_mut().enumerate() {
            *v = if i == j { 0.0 } else { rng.random::<f64>() };
        }
        let s: f64 = row.iter().sum();
        for (j, v) in row.iter_mut().enumerate() {
            *v = f64::from(i == j) - 0.7 * 0.99 * *v / s;
        }
    }
    let e = (0..n).map(|i| if i % 17 == 0 { 1.0 } else { 0.0 }).collect();
    (a, e)
}

/// The reference's own solver (`radiosity_core::dense_lu::lu_solve`), so the figures are
/// those of the code that runs.
fn faer_solve(a: &[f64], e: &[f64], n: usize, parallel: bool) -> f64 {
    lu_solve(n, parallel, |i, j| a[i * n + j], |i| e[i]).expect("the test matrix is regular")[0]
}

fn nalgebra_solve(a: &[f64], e: &[f64], n: usize) -> f64 {
    let m = nalgebra::DMatrix::from_row_slice(n, n, a);
    let rhs = nalgebra::DVector::from_column_slice(e);
    m.lu().solve(&rhs).expect("the test matrix is regular")[0]
}

fn lu(c: &mut Criterion) {
    let mut group = c.benchmark_group("lu");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
    for n in [480, 3400] {
        let (a, e) = system(n);
        // The three agree before they are timed.
        let x = nalgebra_solve(&a, &e, n);
        assert!((faer_solve(&a, &e, n, false) - x).abs() < 1e-12 * x.abs().max(1.0));
        group.bench_with_input(BenchmarkId::new("nalgebra", n), &n, |b, &n| {
            b.iter(|| black_box(nalgebra_solve(&a, &e, n)))
        });
        group.bench_with_input(BenchmarkId::new("faer-seq", n), &n, |b, &n| {
            b.iter(|| black_box(faer_solve(&a, &e, n, false)))
        });
        group.bench_with_input(BenchmarkId::new("faer-rayon", n), &n, |b, &n| {
            b.iter(|| black_box(faer_solve(&a, &e, n, true)))
        });
    }
    group.finish();
}

// criterion's macros generate undocumented items.
#[allow(missing_docs)]
mod harness {
    criterion::criterion_group!(benches, super::lu);
}
criterion_main!(harness::benches);
