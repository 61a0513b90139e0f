//! Running a solver: the [`Solver`] trait, [`Observer`]s and the [`Executor`] that applies
//! the stop rules (the argmin pattern: a solver defines one step, the executor loops).
//!
//! Timing: a run's time is split into form-factor seconds (measured by the [`Problem`] around
//! every column, or charged by its source: the run's clock, [`Problem::clock`]) and solve
//! seconds (the rest of each step's wall time, the source's measured time taken out). A
//! `time=` rule reads their sum, on the run's clock, as every report of the run does.
//! Observers run between steps, outside both, so computing metrics against a reference never
//! counts as solver time.
//!
//! ## Observers, the error monitor and breakdowns
//!
//! As in argmin, observers watch, and a run has any number of them, each with an
//! [`ObserverMode`] ([`Executor::add_observer`]): an [`Observer`] is called once on the initial
//! state ([`Observer::observe_init`], after [`Solver::init`]), after every step its mode takes
//! ([`Observer::observe_step`], with the figures the step handed back) and once with the
//! finished [`Run`] ([`Observer::observe_final`]). Observers that ask for it
//! ([`Observer::wants_residual_bound`]) also get, just before each of the first two, the
//! solver's bound on the residual of the displayed radiosity
//! ([`Observer::observe_residual_bound`], [`Solver::residual_bound`],
//! [`crate::run::residual_bound`]), computed once for all of them, and likewise the solver's
//! standard error ([`Observer::wants_standard_error`], [`Observer::observe_standard_error`],
//! [`Solver::standard_error`]), for the solvers whose answer is an estimate. The `rms=` rule stops on
//! the e_rms an [`ErrorMonitor`] measures ([`Executor::monitor`]), a separate part; a run with
//! such a rule and no monitor is refused before its first step
//! ([`SolverError::ErrorNotMeasured`]), since the rule could never hold and the run would go
//! on to the step cap. At the end the executor stores the solver's own figures
//! ([`Solver::record`]) in [`Run::record`]. An observer may also end the run between steps
//! ([`Observer::wants_stop`]: a caller that has seen enough), which then ends with
//! [`TerminationReason::Stopped`] and its state; it changes nothing else.
//!
//! A method that cannot go on (conjugate gradients on a system seen not to be positive
//! definite) reports [`SolverError::Breakdown`] from its step, leaving the state as it was;
//! the run then ends with [`TerminationReason::Breakdown`] and its state, which says why.
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
use crate::run::cost::Unit;
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::ResidualBound;
use crate::run::standard_error::StandardError;
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

/// What one step of a solver is, which decides how the executor counts it and how a lab
/// records it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum StepKind {
    /// One shot: a column, or a group of columns, shot to every patch (the default).
    #[default]
    Shot,
    /// One patch, or one group, gathered along rows of F ([`Problem::row`]): the solver's
    /// system is then the column system only if the source serves exact rows.
    Gather,
    /// One iteration of a solver that samples transport with rays ([`Problem::cast`]): its
    /// cost is counted in rays, and a lab records every such step.
    Sampled,
    /// One whole matrix–vector product, up to `n` columns (the Krylov solvers, such as
    /// [`crate::Gmres`]). The step cap counts it as `n` steps, so that it allows as many
    /// columns as it allows a gathering solver, and a lab records every such step.
    Product,
    /// One round of shooting on a hierarchy ([`crate::NodeShooting`]): some nodes shoot
    /// through their links, then one push and one pull over every node. Its cost is counted in
    /// links ([`Problem::spent`]); the step cap counts it as one step, and a lab
    /// records every such step.
    Round,
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

    /// Takes one step ([`Solver::step_kind`]) and hands back what only this step knows (a
    /// group step's size and condition number; empty for most), which every observer sees
    /// ([`Observer::observe_step`]).
    ///
    /// A solver whose method cannot go on (a recurrence that breaks down, a system seen not to
    /// be positive definite) returns [`SolverError::Breakdown`] with `state` as it was before
    /// the step: the executor ends the run with [`TerminationReason::Breakdown`] and the state
    /// kept. Any other error ends the run without a state.
    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError>;

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

    /// The solver's own error bar on its displayed radiosity, when it is an estimate with one
    /// ([`StandardError`]: the spread of independent replicates, for the solvers that sample
    /// transport); `None` by default. Needs no reference and no column; called between steps,
    /// outside the timed region, like [`Solver::residual_bound`].
    fn standard_error(&self, problem: &Problem<'_>, state: &State) -> Option<StandardError> {
        let _ = (problem, state);
        None
    }

    /// What one step is ([`StepKind::Shot`] by default).
    fn step_kind(&self) -> StepKind {
        StepKind::Shot
    }

    /// The solver's own figures so far (group steps, condition numbers, fallbacks; see
    /// [`Record`]); the executor stores them in [`Run::record`] at the end of a run.
    /// Empty by default.
    fn record(&self) -> Record {
        Record::new()
    }
}

/// Watches a run: called between steps, outside the timed region (module doc). An observer
/// only watches; what a stop rule needs to measure comes from an [`ErrorMonitor`].
pub trait Observer {
    /// Called once on the initial state (`B = ΔB = E`) after [`Solver::init`], with the
    /// solver's name; by default observed as a step that handed back nothing.
    fn observe_init(&mut self, solver: &str, state: &State) {
        let _ = solver;
        self.observe_step(state, &Record::new());
    }

    /// Called after a step (every step, or as its [`ObserverMode`] says), with what the step
    /// handed back ([`Solver::next_step`]).
    fn observe_step(&mut self, state: &State, figures: &Record);

    /// Called once with the finished run, before the executor returns it.
    fn observe_final(&mut self, run: &Run) {
        let _ = run;
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

    /// Whether the executor passes the solver's standard error to
    /// [`Observer::observe_standard_error`] (false by default: computing it costs `O(n k R)`
    /// for a solver that has one).
    fn wants_standard_error(&self) -> bool {
        false
    }

    /// Called, when [`Observer::wants_standard_error`], just before [`Observer::observe_init`]
    /// and each [`Observer::observe_step`] (after [`Observer::observe_residual_bound`]), on the
    /// same state, with the solver's standard error of its displayed radiosity
    /// ([`Solver::standard_error`]; `None` when it has none). Outside the timed region, like
    /// every observer call.
    fn observe_standard_error(&mut self, state: &State, error: Option<&StandardError>) {
        let _ = (state, error);
    }

    /// Whether the run should end before its next step (false by default): asked of every
    /// observer before every step, whatever its mode; the run then ends with
    /// [`TerminationReason::Stopped`].
    fn wants_stop(&self) -> bool {
        false
    }
}

/// When an observer is called (argmin's modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ObserverMode {
    /// After every step (the default).
    #[default]
    Always,
    /// After the steps that are multiples of `n` (`0` is taken as 1).
    Every(u64),
    /// Never after a step.
    Never,
}

impl ObserverMode {
    /// Whether an observer in this mode is called after step `step`. The initial state and
    /// the finished run are observed in every mode.
    pub fn observes(self, step: u64) -> bool {
        match self {
            ObserverMode::Always => true,
            ObserverMode::Every(n) => step % n.max(1) == 0,
            ObserverMode::Never => false,
        }
    }
}

/// Measures, between steps and outside the timed region, the error an `rms=` rule stops on:
/// e_rms against a reference. A run with such a rule and no monitor is refused before its
/// first step ([`SolverError::ErrorNotMeasured`]), since the rule could never hold.
pub trait ErrorMonitor {
    /// The e_rms of `state`'s displayed radiosity, or `None` when it cannot be measured.
    fn e_rms(&mut self, state: &State) -> Option<Real>;
}

impl<F: FnMut(&State) -> Option<Real>> ErrorMonitor for F {
    fn e_rms(&mut self, state: &State) -> Option<Real> {
        self(state)
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

/// Runs a solver under stop rules, with any number of observers and at most one error
/// monitor (argmin's `Executor::new(problem, solver).add_observer(..).run()`).
pub struct Executor<'a> {
    solver: &'a mut dyn Solver,
    rules: StopRules,
    observers: Vec<(&'a mut dyn Observer, ObserverMode)>,
    monitor: Option<&'a mut dyn ErrorMonitor>,
}

impl<'a> Executor<'a> {
    /// An executor for `solver` with `rules`, no observer and no monitor.
    pub fn new(solver: &'a mut dyn Solver, rules: StopRules) -> Executor<'a> {
        Executor { solver, rules, observers: Vec::new(), monitor: None }
    }

    /// Adds an observer, called as `mode` says.
    pub fn add_observer(mut self, observer: &'a mut dyn Observer, mode: ObserverMode) -> Executor<'a> {
        self.observers.push((observer, mode));
        self
    }

    /// Sets the monitor whose e_rms the `rms=` rule stops on.
    pub fn monitor(mut self, monitor: &'a mut dyn ErrorMonitor) -> Executor<'a> {
        self.monitor = Some(monitor);
        self
    }

    /// Runs from `B = ΔB = E` until a rule holds, round-off, the step cap, a divergence or a
    /// breakdown (module doc). Refuses, before anything runs, an `rms=` rule without a
    /// monitor.
    pub fn run(mut self, problem: &Problem<'_>) -> Result<Run, SolverError> {
        if self.rules.needs_error() && self.monitor.is_none() {
            let rule = self.rules.rules.iter().find(|r| matches!(r, StopRule::Rms(_)));
            return Err(SolverError::ErrorNotMeasured { rule: rule.map(ToString::to_string).unwrap_or_default() });
        }
        let n = problem.n();
        let mut state = State::from_emission(problem.system().emissions(), problem.channels());
        let start_ff = Spent::of(problem);
        if !problem.forms_columns() && self.solver.step_kind() != StepKind::Sampled {
            return Err(SolverError::NotApplicable {
                solver: self.solver.name(),
                reason: "it needs form factors, and this problem only samples transport with rays (Problem::sampled)"
                    .into(),
            });
        }
        self.solver.applicable(problem)?;
        let start = Instant::now();
        self.solver.init(problem, &mut state)?;
        self.account(problem, &mut state, start.elapsed().as_secs_f64(), start_ff);
        let name = self.solver.name();
        self.observe(problem, &state, |o| o.observe_init(&name, &state), StepOrInit::Init);
        let mut error = self.measure(&state);
        let mut watch = Watch::new();
        let cap = self.step_cap(n);
        let termination = loop {
            let clocked = self.clocked(problem, &state);
            if clocked[0] {
                break TerminationReason::Stopped { step: state.step };
            }
            if let Some(reason) = self.check(problem, &state, error, n, &mut watch, &clocked[1..])? {
                break reason;
            }
            if state.step >= cap {
                break TerminationReason::StepCap(cap);
            }
            let ff_before = Spent::of(problem);
            let step_start = Instant::now();
            let step = self.solver.next_step(problem, &mut state);
            let wall = step_start.elapsed().as_secs_f64();
            let figures = match step {
                Ok(figures) => figures,
                Err(SolverError::Breakdown { reason, .. }) => {
                    // The state is as it was before the step; its columns were spent.
                    self.account(problem, &mut state, wall, ff_before);
                    break TerminationReason::Breakdown { step: state.step + 1, reason };
                }
                Err(e) => return Err(e),
            };
            state.step += 1;
            self.account(problem, &mut state, wall, ff_before);
            self.observe(problem, &state, |o| o.observe_step(&state, &figures), StepOrInit::Step(state.step));
            error = self.measure(&state);
        };
        let run = Run { state, termination, solver: name, record: self.solver.record() };
        for (observer, _) in &mut self.observers {
            observer.observe_final(&run);
        }
        Ok(run)
    }

    /// The steps after which a run of `n` patches ends if no rule held: none with a `time=`
    /// rule, which ends every run by itself (the clock advances with every step, charged or
    /// not); otherwise the cap guards runs whose rules cannot be met, and an explicit `steps=` or
    /// `columns=` beyond it raises it (one step costs at least one column or none). A step that
    /// is a whole matrix–vector product counts as n steps.
    fn step_cap(&self, n: usize) -> u64 {
        if self.rules.rules.iter().any(|r| matches!(r, StopRule::Time(_))) {
            return u64::MAX;
        }
        let explicit = self.rules.rules.iter().filter_map(|r| match *r {
            StopRule::Steps(c) | StopRule::Spent(Unit::Columns, c) => Some(c.resolve(n)),
            _ => None,
        });
        let per_step = if self.solver.step_kind() == StepKind::Product { n.max(1) as f64 } else { 1.0 };
        explicit.fold((self.rules.step_cap * n as f64 / per_step).ceil() as u64, u64::max)
    }

    /// Calls `call` on every observer whose mode takes `step` (`true`: the initial state,
    /// which every observer sees), after giving those that want them the solver's residual
    /// bound and standard error; each is computed once, and only if some observer wants it.
    fn observe(
        &mut self,
        problem: &Problem<'_>,
        state: &State,
        mut call: impl FnMut(&mut dyn Observer),
        step: StepOrInit,
    ) {
        let takes = |mode: ObserverMode| match step {
            StepOrInit::Init => true,
            StepOrInit::Step(k) => mode.observes(k),
        };
        let wanted = self.observers.iter().any(|(o, mode)| takes(*mode) && o.wants_residual_bound());
        let bound = wanted.then(|| self.solver.residual_bound(problem, state)).flatten();
        let wanted = self.observers.iter().any(|(o, mode)| takes(*mode) && o.wants_standard_error());
        let spread = wanted.then(|| self.solver.standard_error(problem, state)).flatten();
        for (observer, mode) in &mut self.observers {
            if !takes(*mode) {
                continue;
            }
            if observer.wants_residual_bound() {
                observer.observe_residual_bound(state, bound.as_ref());
            }
            if observer.wants_standard_error() {
                observer.observe_standard_error(state, spread.as_ref());
            }
            call(&mut **observer);
        }
    }

    /// The monitor's e_rms of `state`, when there is a monitor and a rule that needs it.
    fn measure(&mut self, state: &State) -> Option<Real> {
        match &mut self.monitor {
            Some(monitor) if self.rules.needs_error() => monitor.e_rms(state),
            _ => None,
        }
    }

    /// Adds a step's columns and seconds to the state: its form factors on the run's clock,
    /// and its wall time less the source's measured time as solving.
    fn account(&self, problem: &Problem<'_>, state: &mut State, wall: f64, ff_before: Spent) {
        let now = Spent::of(problem);
        let cost = &mut state.cost;
        for unit in Unit::ALL {
            cost[unit] = problem.spent(unit);
        }
        cost.clock = problem.clock();
        cost.ff_seconds += now.clock - ff_before.clock;
        cost.solve_seconds += (wall - (now.measured - ff_before.measured)).max(0.0);
    }

    /// The decisions that may read a clock: whether an observer wants the run stopped, then
    /// whether each `time=` rule holds, in order. Over a source split over ranks they are rank
    /// 0's on every rank ([`radiosity_core::Collective::agree_all`]), so that every rank stops
    /// at the same step.
    fn clocked(&self, problem: &Problem<'_>, state: &State) -> Vec<bool> {
        let spent = Duration::from_secs_f64(state.cost.seconds());
        let mut flags = vec![self.observers.iter().any(|(o, _)| o.wants_stop())];
        flags.extend(self.rules.rules.iter().filter_map(|r| match *r {
            StopRule::Time(limit) => Some(spent >= limit),
            _ => None,
        }));
        if let Some(c) = problem.collective() {
            c.agree_all(&mut flags);
        }
        flags
    }

    /// Why the run ends before the next step, if it does: a residual power that is not finite
    /// (an error) or shows a divergence, then the stop rules in order (`time_up` holds whether
    /// each `time=` rule holds, [`Self::clocked`]), then round-off.
    fn check(
        &self,
        problem: &Problem<'_>,
        state: &State,
        error: Option<Real>,
        n: usize,
        watch: &mut Watch,
        time_up: &[bool],
    ) -> Result<Option<TerminationReason>, SolverError> {
        let mut time_up = time_up.iter();
        let residual = self.solver.residual_power(problem, state);
        if let Some(r) = residual {
            if !r.is_finite() {
                return not_finite(state, r, watch).map(Some);
            }
            if let Some(diverged) = watch.see(state, r) {
                return Ok(Some(diverged));
            }
        }
        // The solver's standard error, only when a rule reads it: it costs O(n k R).
        let spread = self
            .rules
            .needs_standard_error()
            .then(|| self.solver.standard_error(problem, state))
            .flatten()
            .map(|s| s.relative_rms(problem.system(), &state.radiosity));
        for rule in &self.rules.rules {
            let reason = match *rule {
                StopRule::Spent(unit, c) if state.cost[unit] >= c.resolve(n) => {
                    TerminationReason::Spent(unit, state.cost[unit])
                }
                StopRule::Steps(c) if state.step >= c.resolve(n) => TerminationReason::Steps(state.step),
                StopRule::Rms(target) if error.is_some_and(|e| e <= target) => TerminationReason::Rms(error.unwrap()),
                StopRule::Residual(target) if residual.is_some_and(|r| r <= target) => {
                    TerminationReason::Residual(residual.unwrap())
                }
                StopRule::StdError(target) if spread.is_some_and(|s| s <= target) => {
                    TerminationReason::StdError(spread.unwrap())
                }
                StopRule::Time(limit) if time_up.next() == Some(&true) => TerminationReason::Time(limit),
                _ => continue,
            };
            return Ok(Some(reason));
        }
        Ok(residual.is_some_and(|r| r <= ROUND_OFF).then_some(TerminationReason::RoundOff))
    }
}

/// The form-factor seconds of a problem at one moment: on the run's clock, and measured.
#[derive(Clone, Copy)]
struct Spent {
    clock: f64,
    measured: f64,
}

impl Spent {
    fn of(problem: &Problem<'_>) -> Spent {
        Spent { clock: problem.ff_seconds(), measured: problem.measured_ff_seconds() }
    }
}

/// Which call an observer is about to get: the initial state's, or step `k`'s.
#[derive(Clone, Copy)]
enum StepOrInit {
    Init,
    Step(u64),
}
