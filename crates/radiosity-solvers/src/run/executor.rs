//! Running a solver: the [`Solver`] trait, [`Observer`]s and the [`Executor`] that applies
//! the stop rules (the argmin pattern: a solver defines one step, the executor loops).
//!
//! Timing: a run's time is split into form-factor seconds (measured by the [`Problem`] around
//! every column) and solve seconds (the rest of each step). Observers run between steps,
//! outside both, so computing metrics against a reference never counts as solver time.
//!
//! ## Observers
//!
//! As in argmin, an [`Observer`] is called once on the initial state
//! ([`Observer::observe_init`], after [`Solver::init`]), after every step
//! ([`Observer::observe_step`]) and once with the finished [`Run`]
//! ([`Observer::observe_final`]). An observer that asks for it
//! ([`Observer::wants_residual_bound`]) also gets, just before each of the first two, the
//! solver's bound on the residual of the displayed radiosity
//! ([`Observer::observe_residual_bound`], [`Solver::residual_bound`],
//! [`crate::run::residual_bound`]). [`Every`] (or [`Observer::every`]) passes on only the steps
//! that are multiples of `n`. The `rms=` rule stops on the e_rms an observer returns; a run
//! with such a rule and an observer that does not measure it ([`Observer::measures_error`]
//! false) is refused before its first step ([`SolverError::ErrorNotMeasured`]), since the
//! rule could never hold and the run would go on to the step cap. At the end the executor
//! stores the solver's own figures ([`Solver::record`]) in [`Run::record`].
//!
//! ## Divergence and values that are not finite
//!
//! Before every step the executor reads the solver's residual power `R`
//! ([`Solver::residual_power`], when it knows one) and keeps `R_first`, the first one known,
//! and `R_min`, the smallest so far. The run ends with [`TerminationReason::Diverged`] when
//!
//! `R > DIVERGENCE_FACTOR · max(R_min, DIVERGENCE_FLOOR · R_first)`
//!
//! with [`DIVERGENCE_FACTOR`] = 1e4 and [`DIVERGENCE_FLOOR`] = 1e-6, `R_min` taken before `R`.
//! A convergent iteration's residual need not fall monotonically (overshooting and
//! over-relaxation raise it for a while, gathering reports an estimate), but it does not rise
//! ten thousandfold above its best. The floor keeps round-off out: near convergence a residual
//! of 1e-15 may rebound by large factors without meaning anything, so the rise is measured
//! from no lower than 1e-6 of the first residual. A divergent run returns its state: that the
//! method diverges on these form factors is a result worth reporting, not an error. The rule
//! is checked before the stop rules, so a divergence is never reported as a rule that held.
//!
//! A residual power that is not finite ends the run with [`SolverError::NonFinite`], naming
//! the steps taken and the first patch whose radiosity (or shot radiosity `B − ΔB`) is not
//! finite. The solvers check every value they update and stop the step that produced it
//! first; this check catches what they cannot see. If every value is finite and only their
//! sum overflowed, the run ends as diverged, with an infinite residual.

use crate::error::SolverError;
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::ResidualBound;
use crate::run::state::State;
use crate::run::stop::{StopRule, StopRules, TerminationReason};
use radiosity_core::Real;
use std::time::{Duration, Instant};

/// Relative residual power below which a run has converged to round-off.
pub const ROUND_OFF: Real = 1e-14;

/// How far the residual power may rise above its smallest value so far before the run is
/// declared divergent (module doc).
pub const DIVERGENCE_FACTOR: Real = 1e4;

/// The floor under the smallest residual power in the divergence rule, relative to the first
/// residual power known (module doc): rebounds from below it are round-off.
pub const DIVERGENCE_FLOOR: Real = 1e-6;

/// The residual powers the divergence rule remembers.
#[derive(Clone, Copy, Debug)]
struct Watch {
    /// The first residual power known.
    first: Option<Real>,
    /// The smallest so far (infinite before the first).
    minimum: Real,
}

impl Watch {
    fn new() -> Watch {
        Watch { first: None, minimum: Real::INFINITY }
    }

    /// Takes the residual power `r` of `state` (finite): a divergence, if `r` shows one.
    fn see(&mut self, state: &State, r: Real) -> Option<TerminationReason> {
        let first = *self.first.get_or_insert(r);
        let minimum = self.minimum;
        self.minimum = minimum.min(r);
        (minimum.is_finite() && r > DIVERGENCE_FACTOR * minimum.max(DIVERGENCE_FLOOR * first))
            .then_some(TerminationReason::Diverged { step: state.step, residual: r, minimum })
    }
}

/// Why the residual power `r` of `state` is not finite: the first patch whose radiosity, or
/// else whose shot radiosity `B − ΔB`, is not finite; a divergence with an infinite residual
/// when every value is finite and only the sum overflowed.
fn not_finite(state: &State, r: Real, watch: &Watch) -> Result<TerminationReason, SolverError> {
    let k = state.channels;
    let shot = |idx: usize| state.radiosity[idx] - state.unshot[idx];
    let bad = (0..state.radiosity.len())
        .find(|&idx| !state.radiosity[idx].is_finite())
        .map(|idx| (idx, state.radiosity[idx]))
        .or_else(|| (0..state.radiosity.len()).find(|&idx| !shot(idx).is_finite()).map(|idx| (idx, shot(idx))));
    match bad {
        Some((idx, value)) => Err(SolverError::NonFinite { step: state.step, patch: idx / k, value }),
        None => Ok(TerminationReason::Diverged { step: state.step, residual: r, minimum: watch.minimum }),
    }
}

/// One solver: how to start and how to take one step.
pub trait Solver {
    /// The solver's name, as on the command line (`pr`, `sor-1.2`).
    fn name(&self) -> String;

    /// Refuses, before any work, a problem whose form factors do not satisfy the solver's
    /// hypothesis ([`SolverError::NotApplicable`]; `cg` needs reciprocity). Cheap: it computes
    /// no column, so a caller can ask every solver before running any. The executor asks
    /// before [`Solver::init`]. Every problem is accepted by default.
    fn applicable(&self, _problem: &Problem<'_>) -> Result<(), SolverError> {
        Ok(())
    }

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

    /// A bound on the residual of the displayed radiosity known without extra columns
    /// ([`ResidualBound`]), or None when the solver knows none.
    fn residual_bound(&self, problem: &Problem<'_>, state: &State) -> Option<ResidualBound> {
        let _ = (problem, state);
        None
    }

    /// Whether the solver gathers along rows of F ([`Problem::row`]) rather than shooting
    /// columns: its system is then the column system only if the source serves exact rows.
    fn gathers_rows(&self) -> bool {
        false
    }

    /// Whether one step is a whole matrix–vector product, up to `n` columns (the Krylov
    /// solvers, such as [`crate::Gmres`]), rather than one shot or one gathered patch. The step cap
    /// then counts each step as `n` steps, so that it allows as many columns as it allows
    /// a gathering solver, and a lab records every step.
    fn step_is_sweep(&self) -> bool {
        false
    }

    /// The solver's own figures so far (group steps, condition numbers, fallbacks; see
    /// [`Record`]); the executor stores them in [`Run::record`] at the end of a run.
    /// Empty by default.
    fn record(&self) -> Record {
        Record::new()
    }
}

/// Watches a run: called between steps, outside the timed region (module doc).
pub trait Observer {
    /// Called once on the initial state (`B = ΔB = E`) after [`Solver::init`], with the
    /// solver's name; returns the e_rms when it measures one.
    fn observe_init(&mut self, solver: &str, state: &State) -> Option<Real> {
        let _ = solver;
        self.observe_step(state)
    }

    /// Called after every step; returns the e_rms when it measures one (needed by `rms=`
    /// rules).
    fn observe_step(&mut self, state: &State) -> Option<Real>;

    /// Called once with the finished run, before the executor returns it.
    fn observe_final(&mut self, run: &Run) {
        let _ = run;
    }

    /// Whether `observe_*` return the e_rms; an `rms=` rule with an observer that does not
    /// measure it is an error ([`SolverError::ErrorNotMeasured`]).
    fn measures_error(&self) -> bool {
        false
    }

    /// Whether the executor passes the solver's residual bound to
    /// [`Observer::observe_residual_bound`] (false by default: computing it costs `O(n k)`).
    fn wants_residual_bound(&self) -> bool {
        false
    }

    /// Called, when [`Observer::wants_residual_bound`], just before [`Observer::observe_init`]
    /// and each [`Observer::observe_step`], on the same state, with the solver's bound on the
    /// residual of its displayed radiosity ([`Solver::residual_bound`]; `None` when it knows
    /// none). Outside the timed region, like every observer call.
    fn observe_residual_bound(&mut self, state: &State, bound: Option<&ResidualBound>) {
        let _ = (state, bound);
    }

    /// This observer, called after every `n`-th step only ([`Every`]).
    fn every(self, n: u64) -> Every<Self>
    where
        Self: Sized,
    {
        Every::new(n, self)
    }
}

impl<O: Observer + ?Sized> Observer for &mut O {
    fn observe_init(&mut self, solver: &str, state: &State) -> Option<Real> {
        (**self).observe_init(solver, state)
    }

    fn observe_step(&mut self, state: &State) -> Option<Real> {
        (**self).observe_step(state)
    }

    fn observe_final(&mut self, run: &Run) {
        (**self).observe_final(run)
    }

    fn wants_residual_bound(&self) -> bool {
        (**self).wants_residual_bound()
    }

    fn observe_residual_bound(&mut self, state: &State, bound: Option<&ResidualBound>) {
        (**self).observe_residual_bound(state, bound)
    }

    fn measures_error(&self) -> bool {
        (**self).measures_error()
    }
}

/// An observer that watches nothing.
#[derive(Debug, Default)]
pub struct NoObserver;

impl Observer for NoObserver {
    fn observe_step(&mut self, _state: &State) -> Option<Real> {
        None
    }
}

/// An observer called only after the steps that are multiples of `n` (and always on the
/// initial state and the finished run). Between them it returns no e_rms, so an `rms=` rule
/// is checked at those steps only.
#[derive(Clone, Debug)]
pub struct Every<O> {
    n: u64,
    inner: O,
}

impl<O> Every<O> {
    /// `inner`, called after every `n`-th step (`n = 0` is taken as 1).
    pub fn new(n: u64, inner: O) -> Every<O> {
        Every { n: n.max(1), inner }
    }

    /// The observer inside.
    pub fn into_inner(self) -> O {
        self.inner
    }

    /// The observer inside.
    pub fn inner(&self) -> &O {
        &self.inner
    }
}

impl<O: Observer> Observer for Every<O> {
    fn observe_init(&mut self, solver: &str, state: &State) -> Option<Real> {
        self.inner.observe_init(solver, state)
    }

    fn observe_step(&mut self, state: &State) -> Option<Real> {
        if state.step % self.n == 0 { self.inner.observe_step(state) } else { None }
    }

    fn observe_final(&mut self, run: &Run) {
        self.inner.observe_final(run)
    }

    fn wants_residual_bound(&self) -> bool {
        self.inner.wants_residual_bound()
    }

    fn observe_residual_bound(&mut self, state: &State, bound: Option<&ResidualBound>) {
        if state.step % self.n == 0 {
            self.inner.observe_residual_bound(state, bound)
        }
    }

    fn measures_error(&self) -> bool {
        self.inner.measures_error()
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
    /// The solver's own figures at the end ([`Solver::record`]; empty for most point
    /// solvers).
    pub record: Record,
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

    /// Runs from `B = ΔB = E` until a rule holds, round-off, the step cap, or a divergence
    /// (module doc). Refuses, before anything runs, an `rms=` rule with an `observer` that does
    /// not measure the error.
    pub fn run(&mut self, problem: &Problem<'_>, observer: &mut dyn Observer) -> Result<Run, SolverError> {
        if self.rules.needs_error() && !observer.measures_error() {
            let rule = self.rules.rules.iter().find(|r| matches!(r, StopRule::Rms(_)));
            return Err(SolverError::ErrorNotMeasured { rule: rule.map(ToString::to_string).unwrap_or_default() });
        }
        let n = problem.n();
        let mut state = State::from_emission(problem.system().emissions(), problem.channels());
        let start_ff = problem.ff_seconds();
        self.solver.applicable(problem)?;
        let start = Instant::now();
        self.solver.init(problem, &mut state)?;
        self.account(problem, &mut state, start.elapsed().as_secs_f64(), start_ff);
        self.pass_bound(problem, &state, observer);
        let mut error = observer.observe_init(&self.solver.name(), &state);
        let mut watch = Watch::new();
        // The cap guards runs whose rules cannot be met; an explicit `steps=` or `columns=`
        // beyond it raises it (one step costs at least one column or none). A step that is a
        // whole matrix–vector product counts as n steps.
        let explicit = self.rules.rules.iter().filter_map(|r| match *r {
            StopRule::Steps(c) | StopRule::Columns(c) => Some(c.resolve(n)),
            _ => None,
        });
        let per_step = if self.solver.step_is_sweep() { n.max(1) as f64 } else { 1.0 };
        let cap = explicit.fold((self.rules.step_cap * n as f64 / per_step).ceil() as u64, u64::max);
        let termination = loop {
            if let Some(reason) = self.check(problem, &state, error, n, &mut watch)? {
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
            self.pass_bound(problem, &state, observer);
            error = observer.observe_step(&state);
        };
        let run = Run { state, termination, solver: self.solver.name(), record: self.solver.record() };
        observer.observe_final(&run);
        Ok(run)
    }

    /// Gives `observer` the solver's residual bound on `state`, if it wants it.
    fn pass_bound(&self, problem: &Problem<'_>, state: &State, observer: &mut dyn Observer) {
        if observer.wants_residual_bound() {
            observer.observe_residual_bound(state, self.solver.residual_bound(problem, state).as_ref());
        }
    }

    /// Adds a step's columns and seconds to the state.
    fn account(&self, problem: &Problem<'_>, state: &mut State, wall: f64, ff_before: f64) {
        let ff = problem.ff_seconds() - ff_before;
        state.columns = problem.columns_fetched();
        state.columns_reused = problem.columns_reused();
        state.ff_seconds += ff;
        state.solve_seconds += (wall - ff).max(0.0);
    }

    /// Why the run ends before the next step, if it does: a residual power that is not finite
    /// (an error) or shows a divergence, then the stop rules in order, then round-off.
    fn check(
        &self,
        problem: &Problem<'_>,
        state: &State,
        error: Option<Real>,
        n: usize,
        watch: &mut Watch,
    ) -> Result<Option<TerminationReason>, SolverError> {
        let residual = self.solver.residual_power(problem, state);
        if let Some(r) = residual {
            if !r.is_finite() {
                return not_finite(state, r, watch).map(Some);
            }
            if let Some(diverged) = watch.see(state, r) {
                return Ok(Some(diverged));
            }
        }
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
            return Ok(Some(reason));
        }
        Ok(residual.is_some_and(|r| r <= ROUND_OFF).then_some(TerminationReason::RoundOff))
    }
}
