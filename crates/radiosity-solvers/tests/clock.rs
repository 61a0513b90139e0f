//! The run's clock ([`radiosity_core::Clock`]): over a source that charges a price for each
//! column, a `time=` rule stops, and `:f=timed` groups, where the charged seconds say, the
//! same seconds the state reports; over an ordinary source, on measured time.

use super::cube;
use radiosity_core::{Channels, Clock, ColumnSource, DenseColumns, LinearSystem, Real};
use radiosity_solvers::*;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// The cube's columns, each charged `price` seconds, whatever it takes to read.
pub(crate) struct Priced {
    /// The columns served.
    pub(crate) columns: DenseColumns,
    price: Real,
    charged: Mutex<Real>,
}

impl Priced {
    pub(crate) fn new(price: Real) -> Priced {
        Priced { columns: cube(), price, charged: Mutex::new(0.0) }
    }
}

impl ColumnSource for Priced {
    fn patch_count(&self) -> usize {
        self.columns.patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        self.columns.fill_column(j, column);
        *self.charged.lock().unwrap() += self.price;
    }

    fn charged_seconds(&self) -> Option<Real> {
        Some(*self.charged.lock().unwrap())
    }

    fn reset_memory(&self) {
        *self.charged.lock().unwrap() = 0.0;
    }
}

/// The cube, ρ = 0.5, its top emitting.
fn system() -> LinearSystem {
    let mut e = vec![0.0; 6];
    e[1] = 1.0;
    LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], e).unwrap()
}

/// What a run showed its observer: the steps after which a group step ran (those whose
/// figures name a group size), and the run's seconds after every step.
#[derive(Default)]
struct Seen {
    groups: Vec<u64>,
    seconds: Vec<Real>,
}

impl Observer for Seen {
    fn observe_step(&mut self, state: &State, figures: &Record) {
        if figures.get("group_size").is_some() {
            self.groups.push(state.step);
        }
        self.seconds.push(state.cost.ff_seconds + state.cost.solve_seconds);
    }
}

/// Runs `name` under `rules` over `source`: the run, what it showed, and its clock.
fn run(name: &str, rules: &str, source: &dyn ColumnSource) -> (Run, Seen, Clock) {
    let system = system();
    let problem = Problem::new(&system, source).unwrap();
    let mut seen = Seen::default();
    let mut solver = solver_by_name(name).unwrap();
    let run = Executor::new(solver.as_mut(), StopRules::parse(rules).unwrap())
        .add_observer(&mut seen, ObserverMode::Always)
        .run(&problem)
        .unwrap();
    (run, seen, problem.clock())
}

/// The run stopped at the first state whose seconds passed `limit`.
fn stopped_at_limit(run: &Run, seen: &Seen, limit: Real) {
    assert_eq!(run.termination, TerminationReason::Time(Duration::from_secs_f64(limit)));
    let [.., before, last] = seen.seconds[..] else { panic!("{:?}", seen.seconds) };
    assert!(before < limit && last >= limit, "{:?}", seen.seconds);
    assert_eq!(last, run.state.cost.ff_seconds + run.state.cost.solve_seconds);
}

#[test]
fn a_time_rule_stops_on_the_charged_seconds() {
    // At 1 s a column, 3.5 s are passed by the fourth column (4 s and microseconds of
    // solving), not the third (3 s and microseconds): `pr` takes one column a step.
    let source = Priced::new(1.0);
    let start = Instant::now();
    let (run, seen, clock) = run("pr", "time=3.5s", &source);
    assert_eq!(clock, Clock::Charged);
    stopped_at_limit(&run, &seen, 3.5);
    assert_eq!((run.state.step, run.state.cost[Unit::Columns]), (4, 4));
    assert_eq!(run.state.cost.ff_seconds, 4.0, "the form factors' seconds are the charge");
    // Solving is measured: microseconds here, none of the charge.
    assert!(run.state.cost.solve_seconds < 0.1, "{} s solving", run.state.cost.solve_seconds);
    assert!(start.elapsed().as_secs_f64() < 1.0, "the run took its charge, not its wall time");
}

/// The cube's columns, each taking at least a millisecond, charging nothing.
struct Slow(DenseColumns);

impl ColumnSource for Slow {
    fn patch_count(&self) -> usize {
        self.0.patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        std::thread::sleep(Duration::from_millis(1));
        self.0.fill_column(j, column);
    }
}

#[test]
fn a_time_rule_stops_on_measured_seconds_over_an_ordinary_source() {
    let source = Slow(cube());
    let (run, seen, clock) = run("pr", "time=3.5ms", &source);
    assert_eq!(clock, Clock::Measured);
    stopped_at_limit(&run, &seen, 3.5e-3);
    assert!(
        run.state.cost.ff_seconds >= 1e-3 * run.state.cost[Unit::Columns] as Real,
        "{} s for {} columns",
        run.state.cost.ff_seconds,
        run.state.cost[Unit::Columns]
    );
}

#[test]
fn a_timed_group_frequency_divides_by_the_charged_column() {
    // f = max(1, ⌈c_group / (target · c_column)⌉) with c_column the charged seconds of a
    // column. At 1000 s a column, a group step of microseconds is due at every step, as with
    // f=1; at 1e-15 s a column, never again after the first, as with an f beyond the run.
    let rules = "steps=40";
    let (dear, dear_seen, _) = run("pr-g2:f=timed", rules, &Priced::new(1e3));
    let (every, every_seen, _) = run("pr-g2:f=1", rules, &cube());
    assert!(every_seen.groups.len() > 20, "{:?}", every_seen.groups);
    assert_eq!(dear_seen.groups, every_seen.groups);
    assert_eq!(dear.state.radiosity, every.state.radiosity);
    assert_eq!(dear.record.count("group_period"), Some(1));

    let (cheap, cheap_seen, _) = run("pr-g2:f=timed", rules, &Priced::new(1e-15));
    let (once, once_seen, _) = run("pr-g2:f=1000000", rules, &cube());
    assert_eq!(cheap_seen.groups.len(), 1, "{:?}", cheap_seen.groups);
    assert_eq!(cheap_seen.groups, once_seen.groups);
    assert_eq!(cheap.state.radiosity, once.state.radiosity);
}
