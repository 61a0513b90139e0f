//! One group step, group system solved by LU against inner Gauss–Seidel, as the group grows:
//! where the iterative solve starts to pay (the paper's future work on larger groups).
//!
//! The system is a 3400-patch (labyrinth-sized) RGB enclosure with `F_ij = G_ij / A_i`, `G`
//! symmetric and rows summing to 0.9, reflectivity 0.6; each step solves one group of `m`
//! patches and shoots it to all 3400. Both solves share that `O(n m)` update, so the
//! difference is the group solve.
//!
//! Run with `cargo bench -p radiosity-solvers --bench group_solve`.

use criterion::{BenchmarkId, Criterion, criterion_main};
use radiosity_core::{Channels, DenseColumns, LinearSystem, Real};
use radiosity_solvers::{InnerSolve, Problem, State, group_shot};
use std::hint::black_box;
use std::time::Duration;

/// A deterministic value in `[0, 1)` for a pair.
fn hash01(i: usize, j: usize) -> Real {
    let (a, b) = (i.min(j) as u64, i.max(j) as u64);
    let x = a.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ b.wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    (x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as Real / (1u64 << 53) as Real
}

fn system(n: usize) -> (LinearSystem, DenseColumns) {
    let area: Vec<Real> = (0..n).map(|i| 1.0 + (i % 7) as Real * 0.2).collect();
    let row_sum: Vec<Real> = (0..n).map(|i| (0..n).filter(|&j| j != i).map(|j| hash01(i, j)).sum()).collect();
    let scale = 0.9 / (0..n).map(|i| row_sum[i] / area[i]).fold(0.0, Real::max);
    let f = DenseColumns::from_fn(n, |i, j| if i == j { 0.0 } else { scale * hash01(i, j) / area[i] });
    let e: Vec<Real> = (0..3 * n).map(|idx| if (idx / 3) % 50 == 0 { 1.0 } else { 0.0 }).collect();
    (LinearSystem::new(Channels::Rgb, area, vec![0.6; 3 * n], e).unwrap(), f)
}

fn group_solve(c: &mut Criterion) {
    let n = 3400;
    let (system, f) = system(n);
    let problem = Problem::new(&system, &f).unwrap();
    let mut bench = c.benchmark_group("group_step");
    bench.sample_size(10).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(2));
    for m in [25, 50, 100, 200, 400] {
        let group: Vec<usize> = (0..m).map(|a| a * (n / m)).collect();
        let columns: Vec<&[Real]> = group.iter().map(|&g| f.column(g)).collect();
        let plus = vec![0.0; m * 3];
        let start = State::from_emission(system.emissions(), 3);
        for (label, inner) in [("lu", InnerSolve::Lu), ("gs", InnerSolve::GaussSeidel)] {
            bench.bench_with_input(BenchmarkId::new(label, m), &m, |b, _| {
                b.iter(|| {
                    let mut state = start.clone();
                    group_shot(&problem, &mut state, &group, &columns, &plus, inner).unwrap();
                    black_box(state.radiosity[0])
                })
            });
        }
    }
    bench.finish();
}

fn benches() {
    let mut c = Criterion::default().configure_from_args();
    group_solve(&mut c);
}

criterion_main!(benches);
