//! Running a solver: the [`Solver`] trait, [`Observer`]s and the [`Executor`] that applies
//! the stop rules (the argmin pattern: a solver defines one step, the executor loops).
//!
//! Timing: a run's time is split into form-factor seconds (measured by the [`Problem`] around
//! every column) and solve seconds (the rest of each step). Observers run between steps,
//! outside both, so computing metrics against a reference never counts as solver time.

use crate::error::SolverError;
use crate::problem::Problem;
use crate::state::State;
use crate::stop::{StopRule, StopRules, TerminationReason};
use radiosity_core::Real;
use std::time::{Duration, Instant};

/// Relative residual power below which a run has converged to round-off.
pub const ROUND_OFF: Real = 1e-14;

/// One solver: how to start and how to take one step.
pub trait Solver {
    /// The solver's name, as on the command line (`pr`, `sor-1.2`).
    fn name(&self) -> String;

    /// Prepares the state before the first step (the state starts at `B = ΔB = E`).
    fn init(&mut self, _problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        Ok(())
    }

    /// Takes one step: one shot, or one patch gathered.
    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError>;

    /// The residual power the solver knows without extra columns, relative to the emitted
    /// power (for shooting methods that of the shot radiosity, `Σ A |ΔB| / Σ A E`), or `None`
    /// while it does not know one.
    fn residual_power(&self, problem: &Problem<'_>, state: &State) -> Option<Real>;

    /// Whether the solver gathers along rows of F ([`Problem::row`]) rather than shooting
    /// columns: its system is then the column system only if the source serves exact rows.
    fn gathers_rows(&self) -> bool {
        false
    }
}

/// Watches a run between steps.
pub trait Observer {
    /// Called on the initial state and after every step. May return the current `e_rms`
    /// (needed by the `rms=` rule).
    fn observe(&mut self, state: &State) -> Option<Real>;
}

/// An observer that watches nothing.
#[derive(Debug, Default)]
pub struct NoObserver;

impl Observer for NoObserver {
    fn observe(&mut self, _state: &State) -> Option<Real> {
        None
    }
}

/// The outcome of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The final state.
    pub state: State,
    /// Why it ended.
    pub termination: TerminationReason,
    /// The solver's name.
    pub solver: String,
}

/// Runs a solver under stop rules.
pub struct Executor<'s> {
    solver: &'s mut dyn Solver,
    rules: StopRules,
}

impl<'s> Executor<'s> {
    /// An executor for `solver` with `rules`.
    pub fn new(solver: &'s mut dyn Solver, rules: StopRules) -> Executor<'s> {
        Executor { solver, rules }
    }

    /// Runs from `B = ΔB = E` until a rule holds, round-off, or the step cap.
    pub fn run(&mut self, problem: &Problem<'_>, observer: &mut dyn Observer) -> Result<Run, SolverError> {
        let n = problem.n();
        let mut state = State::from_emission(problem.system().emissions(), problem.channels());
        let start_ff = problem.ff_seconds();
        let start = Instant::now();
        self.solver.init(problem, &mut state)?;
        self.account(problem, &mut state, start.elapsed().as_secs_f64(), start_ff);
        let mut error = observer.observe(&state);
        // The cap guards runs whose rules cannot be met; an explicit `steps=` or `columns=`
        // beyond it raises it (one step costs at least one column or none).
        let explicit = self.rules.rules.iter().filter_map(|r| match *r {
            StopRule::Steps(c) | StopRule::Columns(c) => Some(c.resolve(n)),
            _ => None,
        });
        let cap = explicit.fold((self.rules.step_cap * n as f64).ceil() as u64, u64::max);
        let termination = loop {
            if let Some(reason) = self.check(problem, &state, error, n) {
                break reason;
            }
            if state.step >= cap {
                break TerminationReason::StepCap(cap);
            }
            let ff_before = problem.ff_seconds();
            let step_start = Instant::now();
            self.solver.next_step(problem, &mut state)?;
            state.step += 1;
            self.account(problem, &mut state, step_start.elapsed().as_secs_f64(), ff_before);
            error = observer.observe(&state);
        };
        Ok(Run { state, termination, solver: self.solver.name() })
    }

    /// Adds a step's columns and seconds to the state.
    fn account(&self, problem: &Problem<'_>, state: &mut State, wall: f64, ff_before: f64) {
        let ff = problem.ff_seconds() - ff_before;
        state.columns = problem.columns_fetched();
        state.columns_reused = problem.columns_reused();
        state.ff_seconds += ff;
        state.solve_seconds += (wall - ff).max(0.0);
    }

    fn check(&self, problem: &Problem<'_>, state: &State, error: Option<Real>, n: usize) -> Option<TerminationReason> {
        let residual = self.solver.residual_power(problem, state);
        for rule in &self.rules.rules {
            let reason = match *rule {
                StopRule::Columns(c) if state.columns >= c.resolve(n) => TerminationReason::Columns(state.columns),
                StopRule::Steps(c) if state.step >= c.resolve(n) => TerminationReason::Steps(state.step),
                StopRule::Rms(target) if error.is_some_and(|e| e <= target) => TerminationReason::Rms(error.unwrap()),
                StopRule::Residual(target) if residual.is_some_and(|r| r <= target) => {
                    TerminationReason::Residual(residual.unwrap())
                }
                StopRule::Time(limit) if Duration::from_secs_f64(state.ff_seconds + state.solve_seconds) >= limit => {
                    TerminationReason::Time(limit)
                }
                _ => continue,
            };
            return Some(reason);
        }
        residual.is_some_and(|r| r <= ROUND_OFF).then_some(TerminationReason::RoundOff)
    }
}
