//! The recorder: an observer the executor calls between steps, outside the timed region, that
//! measures e_rms, the certified bound and the solver's standard error after every step and
//! every metric at planned steps ([`RecordPlan`]), its own time kept apart.
//!
//! The standard error is the solver's own error bar, for a solver whose answer is an estimate
//! ([`radiosity_solvers::Solver::standard_error`], the spread of independent replicates),
//! summarised as e_rms is ([`StandardError::relative_rms`]), so that the two read side by side;
//! NaN for the solvers that have none. A bound is a promise that holds every time; a standard
//! error a spread, which the true error exceeds now and then (module doc of
//! [`StandardError`]).

use crate::progress::Progress;
use crate::reference::certificate::{Contraction, SolverBound, relative_without_reference};
use crate::reference::metrics::{Evaluator, Metrics, errors_against};
use radiosity_core::{LinearSystem, Real};
use radiosity_solvers::{Cost, ErrorMonitor, Observer, Record, ResidualBound, StandardError, State, Unit};
use std::cell::Cell;
use std::ops::ControlFlow;
use std::rc::Rc;
use std::time::Instant;

/// How often a run's metrics are recorded.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct RecordPlan {
    /// Every metric every this many steps (`None`: about 100 points over the run's budget, and
    /// every step of a solver whose step is a whole product by F, `StepKind::Product`, a round
    /// of shooting on a hierarchy, `StepKind::Round`, or an iteration by rays,
    /// `StepKind::Sampled`).
    /// e_rms is recorded after every step regardless.
    pub every: Option<u64>,
    /// Also record every metric at `n/4`, `n/2`, `n` and `2n` columns.
    pub marks: bool,
}

impl Default for RecordPlan {
    fn default() -> Self {
        RecordPlan { every: None, marks: true }
    }
}

impl RecordPlan {
    /// Every metric every `steps` steps, and at the marks.
    pub fn every(steps: u64) -> RecordPlan {
        RecordPlan { every: Some(steps.max(1)), marks: true }
    }

    /// e_rms after every step, and every metric only on the initial state: the cheapest
    /// recording that still serves an `rms=` rule.
    pub fn errors_only() -> RecordPlan {
        RecordPlan { every: Some(u64::MAX), marks: false }
    }
}

/// One step of a run: where it stood, its e_rms and its certified bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Steps done.
    pub step: u64,
    /// What the run had spent: columns, products, rays, links, and seconds on the run's clock
    /// ([`crate::Lab::clock`]), measurement excluded ([`Cost::seconds`] is what a `time=` rule
    /// reads).
    pub cost: Cost,
    /// Wall seconds since the recorder's clock started (for a lab's runs, when the run was
    /// set up), its own measuring taken out: the run's seconds and the executor's bookkeeping.
    pub wall: Real,
    /// e_rms against the reference (NaN without one).
    pub e_rms: Real,
    /// The certified bound on the displayed radiosity's area-weighted L1 error relative to the
    /// reference's, from what the solver knows without extra columns ([`SolverBound`]); NaN
    /// when the solver knows none.
    pub bound: Real,
    /// The solver's standard error of the displayed radiosity, summarised as e_rms is
    /// ([`StandardError::relative_rms`]); NaN when the solver has none.
    pub std_error: Real,
}

/// One measured point of a run. Fields are plain data, so rows are written as literals.
#[derive(Clone, Debug, PartialEq)]
pub struct TableRow {
    /// The solver's name (as on the command line, e.g. `pr-g30`).
    pub solver: String,
    /// Steps done (shooting steps, or sweeps for gathering methods).
    pub step: u64,
    /// What the run had spent: columns, products, rays, links, and seconds (metrics
    /// excluded) on the run's clock ([`crate::Lab::clock`]).
    pub cost: Cost,
    /// Area-weighted relative RMS error.
    pub e_rms: Real,
    /// Largest error relative to the largest reference value.
    pub e_max: Real,
    /// Residual power `R`.
    pub residual: Real,
    /// The certified bound on the area-weighted L1 error, relative to `Σ A |B|` of the reference
    /// (infinite where the system is not certifiable; NaN where F was not available).
    pub bound: Real,
    /// The solver's standard error, relative as e_rms is ([`Point::std_error`]; NaN when the
    /// solver has none).
    pub std_error: Real,
}

/// What watches a run's points ([`crate::Lab::run_watched`]): `Break` ends the run.
pub(crate) type PointWatch<'w> = dyn FnMut(&Point, &State) -> ControlFlow<()> + 'w;

/// What a run's progress counts (`Progress::advance`): steps, or a unit of cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ProgressUnit {
    Steps,
    Spent(Unit),
}

impl ProgressUnit {
    /// The unit's name, for progress bars.
    pub(crate) fn name(self) -> &'static str {
        match self {
            ProgressUnit::Steps => "steps",
            ProgressUnit::Spent(unit) => unit.name(),
        }
    }

    /// The count of `state` in this unit.
    fn of(self, state: &State) -> u64 {
        match self {
            ProgressUnit::Steps => state.step,
            ProgressUnit::Spent(unit) => state.cost[unit],
        }
    }
}

/// Records e_rms, the certified bound and the standard error after every step and every
/// metric at planned steps ([`RecordPlan`]), outside the run's timed region, its own time kept
/// apart as measurement.
pub struct Recorder<'a> {
    pub(super) system: &'a LinearSystem,
    /// The exact answer, patch-major like the system's vectors, when there is one.
    pub(super) reference: Option<&'a [Real]>,
    /// The contraction the certified bound rests on; no bound without one.
    pub(super) contraction: Option<&'a Contraction>,
    /// The solver's residual bound on the state about to be observed.
    pub(super) known: Option<ResidualBound>,
    /// The solver's standard error on the state about to be observed.
    pub(super) spread: Option<StandardError>,
    /// Where [`Point::wall`] counts from.
    pub(super) clock: Instant,
    pub(super) evaluator: Option<&'a Evaluator<'a>>,
    pub(super) solver: String,
    pub(super) every: u64,
    pub(super) marks: Vec<u64>,
    pub(super) points: Vec<Point>,
    pub(super) rows: Vec<TableRow>,
    pub(super) overhead: Real,
    /// Where each step is reported, if anywhere (no message is formatted otherwise).
    pub(super) progress: Option<&'a dyn Progress>,
    pub(super) unit: ProgressUnit,
    /// The e_rms of the last state observed, which [`Recorder::monitor`] hands the `rms=` rule.
    pub(super) latest: Rc<Cell<Option<Real>>>,
    /// Shown every point recorded with its state; `Break` ends the run ([`Lab::run_watched`]).
    ///
    /// [`Lab::run_watched`]: crate::Lab::run_watched
    pub(super) watch: Option<&'a mut PointWatch<'a>>,
    /// Whether the watch asked the run to end.
    pub(super) stop: bool,
    /// Whether the solver samples transport: its rows then never take F's bound for their
    /// own (docs/design.md §6.3).
    pub(super) sampled: bool,
}

impl<'a> Recorder<'a> {
    /// A recorder of e_rms after every step against `reference` (patch-major, like the
    /// system's vectors) and nothing else, for a caller with a reference of its own (read
    /// from a file, or a closed form); [`Point::wall`] counts from `clock`.
    pub fn errors(system: &'a LinearSystem, reference: &'a [Real], clock: Instant) -> Recorder<'a> {
        Recorder {
            system,
            reference: Some(reference),
            contraction: None,
            known: None,
            spread: None,
            clock,
            evaluator: None,
            solver: String::new(),
            every: u64::MAX,
            marks: Vec::new(),
            points: Vec::new(),
            rows: Vec::new(),
            overhead: 0.0,
            progress: None,
            unit: ProgressUnit::Spent(Unit::Columns),
            latest: Rc::default(),
            watch: None,
            stop: false,
            sampled: false,
        }
    }

    /// Also records the certified bound after every step, on `contraction` (measured on a
    /// stored matrix, or [`Contraction::assumed`]).
    pub fn with_bound(mut self, contraction: &'a Contraction) -> Recorder<'a> {
        self.contraction = Some(contraction);
        self
    }

    /// The points recorded so far.
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// Seconds spent measuring so far.
    pub fn overhead(&self) -> Real {
        self.overhead
    }
}

impl Recorder<'_> {
    /// The monitor an `rms=` rule asks: the e_rms this recorder measured on the same state
    /// (it observes every step), so nothing is measured twice. `None` without a reference.
    pub fn monitor(&self) -> Option<impl ErrorMonitor + 'static> {
        let latest = self.latest.clone();
        self.reference.is_some().then_some(move |_: &State| latest.get())
    }
}

impl Observer for Recorder<'_> {
    fn observe_step(&mut self, state: &State, _figures: &Record) {
        let start = Instant::now();
        let errors = match self.reference {
            Some(reference) => match errors_against(self.system, reference, &state.radiosity) {
                Ok(e) => Some(e),
                Err(_) => {
                    self.latest.set(None);
                    return;
                }
            },
            None => None,
        };
        let e_rms = errors.map_or(Real::NAN, |e| e.e_rms);
        let bound = match (self.known.take(), self.contraction) {
            (Some(known), Some(c)) => SolverBound::new(self.system, c, &known, &state.radiosity).relative,
            _ => Real::NAN,
        };
        let std_error = self.spread.take().map_or(Real::NAN, |s| s.relative_rms(self.system, &state.radiosity));
        let columns = state.cost[Unit::Columns];
        let new_mark =
            self.marks.contains(&columns) && self.points.last().is_none_or(|p| p.cost[Unit::Columns] != columns);
        if state.step % self.every == 0 || new_mark {
            let row = |e_max, residual, bound| TableRow {
                solver: self.solver.clone(),
                step: state.step,
                cost: state.cost,
                e_rms,
                e_max,
                residual,
                bound,
                std_error,
            };
            match self.evaluator.map(|e| e.evaluate(&state.radiosity)) {
                Some(Ok(m)) => {
                    let fallback = if self.sampled {
                        Real::NAN
                    } else if m.bound.certified {
                        matrix_relative_bound(self.system, &m, &state.radiosity)
                    } else {
                        Real::INFINITY
                    };
                    self.rows.push(row(m.e_max, m.residual, if bound.is_nan() { fallback } else { bound }))
                }
                Some(Err(_)) => {}
                None => self.rows.push(row(errors.map_or(Real::NAN, |e| e.e_max), Real::NAN, bound)),
            }
        }
        let wall = (start - self.clock).as_secs_f64() - self.overhead;
        let point = Point { step: state.step, cost: state.cost, wall, e_rms, bound, std_error };
        self.points.push(point);
        if let Some(watch) = self.watch.as_mut() {
            self.stop |= watch(&point, state).is_break();
        }
        if let Some(progress) = self.progress {
            let mut message = match (e_rms.is_nan(), bound.is_nan()) {
                (false, _) => format!("e_rms {e_rms:.2e}"),
                (true, false) => format!("bound {bound:.2e}"),
                (true, true) => String::new(),
            };
            if !std_error.is_nan() {
                let gap = if message.is_empty() { "" } else { ", " };
                message.push_str(&format!("{gap}standard error {std_error:.2e}"));
            }
            progress.advance(self.unit.of(state), &message);
        }
        self.overhead += start.elapsed().as_secs_f64();
        self.latest.set((!e_rms.is_nan()).then_some(e_rms));
    }

    fn wants_residual_bound(&self) -> bool {
        self.contraction.is_some()
    }

    fn wants_stop(&self) -> bool {
        self.stop
    }

    fn observe_residual_bound(&mut self, _state: &State, bound: Option<&ResidualBound>) {
        self.known = bound.cloned();
    }

    fn wants_standard_error(&self) -> bool {
        true
    }

    fn observe_standard_error(&mut self, _state: &State, error: Option<&StandardError>) {
        self.spread = error.cloned();
    }
}

/// The F-based certified bound of `b` relative to `Σ A |B*|`, in the reference-free form of
/// [`SolverBound`] (so that it reads like the solver's own).
pub(crate) fn matrix_relative_bound(system: &LinearSystem, m: &Metrics, b: &[Real]) -> Real {
    relative_without_reference(system, m.bound.bound, b, false)
}
