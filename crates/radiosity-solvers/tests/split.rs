//! Solvers over a source split over ranks (threads standing in for MPI ranks): every rank runs
//! the same solver, each column, row and product a collective sum, and every rank stops at the
//! same step with the same answer, the single process's to the order of summation, even when
//! the ranks' clocks disagree (a `time=` rule is rank 0's decision).

use super::{enclosure, solvers, twelve};
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

/// `ColumnTransport` over `f`, counting the rays cast through it.
struct Counted {
    inner: radiosity_core::ColumnTransport,
    cast: std::sync::atomic::AtomicU64,
}

impl radiosity_core::TransportSampler for Counted {
    fn patch_count(&self) -> usize {
        self.inner.patch_count()
    }

    fn cast(&self, from: usize, u: [Real; 4]) -> Option<usize> {
        self.cast.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.inner.cast(from, u)
    }

    fn ray_weight(&self, from: usize) -> Real {
        self.inner.ray_weight(from)
    }

    fn global_line(&self, u: [Real; 4], line: &mut radiosity_core::LineTransfers) -> bool {
        let has = self.inner.global_line(u, line);
        self.cast.fetch_add(if has { line.rays } else { 0 }, std::sync::atomic::Ordering::Relaxed);
        has
    }

    fn row_sum(&self, i: usize) -> Option<Real> {
        self.inner.row_sum(i)
    }

    fn cost(&self) -> radiosity_core::SampleCost {
        self.inner.cost()
    }
}

#[test]
fn the_solvers_that_sample_divide_their_rays_between_the_ranks() {
    // Over 2, 3 and 8 ranks (threads standing in for MPI ranks), every rank ends with the
    // single process's bits, steps and rays, and together the ranks cast the world's rays,
    // each once. Stochastic Jacobi divides every iteration's rays: each rank casts those of
    // its blocks of patches (of lines) for every replicate, and one sum an iteration shares
    // the deposits, so its 4 replicates keep 8 ranks busy, each with about its share where
    // the power is spread (600 patches; on 12 the emitters' ranks cast most). Random walks
    // deal whole replicates: a rank beyond them casts none (as a rank may that is dealt none of
    // the 12 patches' blocks).
    let run = |(system, f): &(radiosity_core::LinearSystem, DenseColumns),
               name: &str,
               collective: Option<&dyn Collective>| {
        let sampler = Counted {
            inner: radiosity_core::ColumnTransport::new(f, system.areas()).unwrap(),
            cast: Default::default(),
        };
        let mut problem = Problem::new(system, f).unwrap().with_transport(&sampler).unwrap();
        if let Some(c) = collective {
            problem = problem.with_collective(c);
        }
        let mut solver = solver_by_name(name).unwrap();
        let rules = StopRules { step_cap: 1e6, ..StopRules::parse("rays=30000").unwrap() };
        let run = Executor::new(solver.as_mut(), rules).run(&problem).unwrap();
        (run, sampler.cast.into_inner())
    };
    // 600 patches, one in four emitting, so that power and rays are spread over the blocks.
    let (small, large) = (twelve(), enclosure(600));
    for name in [
        "stochastic-jacobi:seq=sobol",
        "stochastic-jacobi:form=gathering",
        "stochastic-jacobi:lines=global",
        "random-walk",
        "random-walk:form=gathering",
    ] {
        let divided = name.starts_with("stochastic-jacobi");
        for (system, even) in [(&small, false), (&large, divided)] {
            let (one, cast) = run(system, name, None);
            assert_eq!(one.state.cost[Unit::Rays], cast, "{name}");
            for ranks in [2, 3, 8] {
                let runs = InProcessRanks::run(ranks, |c| run(system, name, Some(&*c)));
                for (rank, (r, here)) in runs.iter().enumerate() {
                    let at =
                        format!("{name}, {} patches, rank {rank} of {ranks}: {here} of {cast} rays", system.0.len());
                    assert_eq!(r.state.radiosity, one.state.radiosity, "{at}");
                    assert_eq!((r.state.step, r.state.cost[Unit::Rays]), (one.state.step, cast), "{at}");
                    let fair = cast as Real / ranks as Real;
                    if even {
                        assert!((*here as Real) > 0.7 * fair && (*here as Real) < 1.3 * fair, "{at}");
                    } else if ranks <= 3 {
                        // 12 blocks, or 4 replicates: every rank has some.
                        assert!(*here > 0 && *here < cast, "{at}");
                    }
                }
                assert_eq!(runs.iter().map(|(_, here)| here).sum::<u64>(), cast, "{name}, {ranks} ranks");
            }
        }
    }
}
