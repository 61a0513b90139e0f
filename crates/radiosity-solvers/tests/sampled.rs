//! A solver that samples transport ([`StepKind::Sampled`]) under the executor: observers that
//! ask for it get the solver's standard error on every state they see, as they get its residual
//! bound; and a charged clock counts the rays' measured seconds, which no source charges for.

use super::clock::Priced;
use super::cube;
use radiosity_core::{Channels, ColumnTransport, LinearSystem, Real};
use radiosity_solvers::*;
use std::time::{Duration, Instant};

/// One Jacobi sweep of light by rays per step, in two replicates with independent streams:
/// `G_i = Σ_j (power of j landing on i) / A_i` estimated from `rays` rays per emitting patch,
/// `B = E + ρ G` of the mean of the replicates. Sleeps `pause` inside the cast, so that its
/// rays take a known least time.
struct RayJacobi {
    rays: usize,
    pause: Duration,
    replicates: Vec<Vec<Real>>,
    error: Option<StandardError>,
}

impl RayJacobi {
    fn new(rays: usize, pause: Duration) -> RayJacobi {
        RayJacobi { rays, pause, replicates: Vec::new(), error: None }
    }
}

impl Solver for RayJacobi {
    fn name(&self) -> String {
        "ray-jacobi".into()
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let (system, n) = (problem.system(), problem.n());
        let shot: Vec<Real> = state.radiosity.clone();
        let replicates = problem.cast(&self.name(), |rays| {
            std::thread::sleep(self.pause);
            (0..2u64)
                .map(|r| {
                    let mut gathered = vec![0.0; n];
                    for j in (0..n).filter(|&j| shot[j] > 0.0) {
                        let mut stream = Sequence::Random.stream(7, [r, state.step, j as u64]);
                        let power = system.areas()[j] * shot[j] * rays.ray_weight(j) / self.rays as Real;
                        for _ in 0..self.rays {
                            if let Some(i) = rays.cast(j, stream.next_point()) {
                                gathered[i] += power / system.areas()[i];
                            }
                        }
                    }
                    (0..n).map(|i| system.emissions()[i] + system.reflectivities()[i] * gathered[i]).collect()
                })
                .collect::<Vec<Vec<Real>>>()
        })?;
        let views: Vec<&[Real]> = replicates.iter().map(Vec::as_slice).collect();
        let error = StandardError::of_replicates(&views, &mut state.radiosity);
        state.unshot.fill(0.0);
        self.replicates = replicates;
        self.error = Some(error);
        Ok(Record::new())
    }

    fn residual_power(&self, _problem: &Problem<'_>, _state: &State) -> Option<Real> {
        None
    }

    fn standard_error(&self, _problem: &Problem<'_>, _state: &State) -> Option<StandardError> {
        self.error.clone()
    }

    fn step_kind(&self) -> StepKind {
        StepKind::Sampled
    }
}

/// What an observer that wants standard errors saw: one entry per state, before its step.
#[derive(Default)]
struct Spread {
    seen: Vec<(u64, Option<usize>)>,
    steps: Vec<u64>,
}

impl Observer for Spread {
    fn observe_step(&mut self, state: &State, _figures: &Record) {
        self.steps.push(state.step);
    }

    fn wants_standard_error(&self) -> bool {
        true
    }

    fn observe_standard_error(&mut self, state: &State, error: Option<&StandardError>) {
        self.seen.push((state.step, error.map(|e| e.replicates)));
    }
}

/// The cube, ρ = 0.5, its top emitting.
fn system() -> LinearSystem {
    let mut e = vec![0.0; 6];
    e[1] = 1.0;
    LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], e).unwrap()
}

#[test]
fn observers_get_the_standard_error_before_every_state_they_see() {
    let (system, f) = (system(), cube());
    let transport = ColumnTransport::new(&f, system.areas()).unwrap();
    let problem = Problem::new(&system, &f).unwrap().with_transport(&transport).unwrap();
    let (mut spread, mut quiet) = (Spread::default(), Spread::default());
    let mut solver = RayJacobi::new(100, Duration::ZERO);
    let run = Executor::new(&mut solver, StopRules::parse("steps=3").unwrap())
        .add_observer(&mut spread, ObserverMode::Always)
        .add_observer(&mut quiet, ObserverMode::Every(2))
        .run(&problem)
        .unwrap();
    assert_eq!(run.state.step, 3);
    // The initial state has no estimate yet; every step's has its two replicates.
    assert_eq!(spread.seen, vec![(0, None), (1, Some(2)), (2, Some(2)), (3, Some(2))]);
    assert_eq!(spread.steps, vec![0, 1, 2, 3]);
    // An observer called every other step is given the standard error only on those states.
    assert_eq!(quiet.seen, vec![(0, None), (2, Some(2))]);
    // Two replicates of 100 rays from the one emitter at each step: 3 · 2 · 100 rays, then
    // from every lit patch after the first step.
    assert!(
        run.state.cost[Unit::Rays] >= 200 && run.state.cost[Unit::Rays] == problem.spent(Unit::Rays),
        "{}",
        run.state.cost[Unit::Rays]
    );
}

#[test]
fn a_charged_clock_counts_the_rays_measured_seconds() {
    let system = system();
    let source = Priced::new(1.0);
    let transport = ColumnTransport::new(&source.columns, system.areas()).unwrap();
    let problem = Problem::new(&system, &source).unwrap().with_transport(&transport).unwrap();
    assert_eq!(problem.clock(), radiosity_core::Clock::Charged);
    let pause = Duration::from_millis(20);
    let mut solver = RayJacobi::new(10, pause);
    let start = Instant::now();
    let run = Executor::new(&mut solver, StopRules::parse("steps=2").unwrap()).run(&problem).unwrap();
    let wall = start.elapsed().as_secs_f64();
    // No column was charged; the two casts slept 20 ms each, inside the rays' seconds.
    assert_eq!(run.state.cost[Unit::Columns], 0);
    let rays = run.state.cost.ff_seconds;
    assert!(rays >= 2.0 * pause.as_secs_f64() && rays <= wall, "ray seconds {rays} (wall {wall})");
    assert!(
        run.state.cost.solve_seconds <= wall - rays + 1e-9,
        "solving {} counts the rays",
        run.state.cost.solve_seconds
    );
}
