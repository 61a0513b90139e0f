//! Solvers over a source split over ranks (threads standing in for MPI ranks): every rank runs
//! the same solver, each column, row and product a collective sum, and every rank stops at the
//! same step with the same answer, the single process's to the order of summation, even when
//! the ranks' clocks disagree (a `time=` rule is rank 0's decision).

use super::{solvers, twelve};
use radiosity_core::{Collective, ColumnSource, DenseColumns, InProcessRanks, Real};
use radiosity_solvers::*;
use std::sync::Arc;
use std::time::Duration;

/// A rank's share of a matrix: entry `(i, j)` on rank `(i + 2j) mod K`, zero elsewhere. Rank 1
/// is slow (each column, row and product sleeps).
struct Share {
    f: DenseColumns,
    collective: Arc<InProcessRanks>,
}

impl Share {
    fn mine(&self, i: usize, j: usize) -> bool {
        (i + 2 * j) % self.collective.ranks() == self.collective.rank()
    }

    fn lag(&self) {
        if self.collective.rank() == 1 {
            std::thread::sleep(Duration::from_micros(300));
        }
    }
}

impl ColumnSource for Share {
    fn patch_count(&self) -> usize {
        self.f.patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        self.lag();
        self.f.fill_column(j, column);
        column.iter_mut().enumerate().for_each(|(i, v)| *v = if self.mine(i, j) { *v } else { 0.0 });
        self.collective.sum(column);
    }

    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        self.lag();
        self.f.fill_row(i, row);
        row.iter_mut().enumerate().for_each(|(j, v)| *v = if self.mine(i, j) { *v } else { 0.0 });
        self.collective.sum(row);
        true
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        self.f.reciprocity_bound()
    }

    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        self.lag();
        let n = self.patch_count();
        let mut column = vec![0.0; n];
        out.fill(0.0);
        for j in 0..n {
            self.f.fill_column(j, &mut column);
            for i in (0..n).filter(|&i| self.mine(i, j)) {
                for c in 0..channels {
                    out[i * channels + c] += column[i] * x[j * channels + c];
                }
            }
        }
        self.collective.sum(out);
        true
    }

    fn collective(&self) -> Option<&dyn Collective> {
        Some(&*self.collective)
    }
}

fn run(
    name: &str,
    rules: &str,
    f: &dyn ColumnSource,
    system: &radiosity_core::LinearSystem,
) -> Result<Run, SolverError> {
    let mut solver = solver_by_name(name).unwrap();
    let problem = Problem::new(system, f).unwrap();
    Executor::new(solver.as_mut(), StopRules::parse(rules).unwrap()).run(&problem)
}

#[test]
fn every_solver_gives_the_single_process_answer_on_every_rank() {
    let (system, f) = twelve();
    for name in solvers() {
        // The solvers that refuse these form factors (they state no reciprocity) refuse them
        // split too: the same error on every rank, before any sum.
        let Ok(one) = run(&name, "steps=40", &f, &system) else { continue };
        for ranks in [2, 3] {
            let runs = InProcessRanks::run(ranks, |collective| {
                let share = Share { f: f.clone(), collective };
                run(&name, "steps=40", &share, &system).unwrap()
            });
            let scale = one.state.radiosity.iter().fold(0.0, |m: Real, v| m.max(v.abs()));
            for (rank, r) in runs.iter().enumerate() {
                assert_eq!(
                    r.state.radiosity, runs[0].state.radiosity,
                    "{name}, {ranks} ranks: rank {rank} differs from rank 0"
                );
                assert_eq!(r.state.step, one.state.step, "{name}, {ranks} ranks");
                let gap = r
                    .state
                    .radiosity
                    .iter()
                    .zip(&one.state.radiosity)
                    .fold(0.0, |m: Real, (x, y)| m.max((x - y).abs()));
                assert!(gap <= 1e-12 * scale, "{name}, {ranks} ranks: {gap:e} from one process");
            }
        }
    }
}

#[test]
fn a_time_rule_stops_every_rank_at_rank_zeros_step() {
    let (system, f) = twelve();
    for name in ["xu", "gauss-seidel", "jacobi"] {
        let runs = InProcessRanks::run(2, |collective| {
            // Rank 1 starts late (a slower scene load), so rank 0's first sum waits for it
            // and rank 0's clock runs 10 ms ahead: on its own clock it would stop steps
            // earlier and leave rank 1 waiting in a sum (a panic here, a hang under MPI).
            if collective.rank() == 1 {
                std::thread::sleep(Duration::from_millis(10));
            }
            let share = Share { f: f.clone(), collective };
            run(name, "time=20ms", &share, &system).unwrap()
        });
        assert_eq!(runs[0].state.step, runs[1].state.step, "{name}");
        assert!(matches!(runs[1].termination, TerminationReason::Time(_)), "{name}: {:?}", runs[1].termination);
    }
}
