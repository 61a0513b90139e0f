//! What one run did and measured ([`Outcome`]): its points, its recorded rows, its final state
//! and the metrics of its final radiosity ([`FinalMetrics`]).

use crate::lab::recorder::{Point, TableRow};
use radiosity_core::{Clock, Real};
use radiosity_solvers::Unit;
use radiosity_solvers::{Record, StandardError, State, StopRule, StopRules, TerminationReason};

/// The metrics of a run's final radiosity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FinalMetrics {
    /// e_rms against the reference, when there is one.
    pub e_rms: Option<Real>,
    /// e_max against the reference, when there is one.
    pub e_max: Option<Real>,
    /// The residual power of the displayed radiosity, when F is kept.
    pub residual: Option<Real>,
    /// The certified bound on its area-weighted L1 error relative to the reference's L1 norm:
    /// the solver's own ([`SolverBound`]), or from F's residual when the solver knows none and F
    /// is kept; `None` when neither is there.
    ///
    /// [`SolverBound`]: crate::SolverBound
    pub bound: Option<Real>,
    /// The residual power the solver knows without F (for shooting methods, that of the shot
    /// radiosity), when it knows one.
    pub solver_residual: Option<Real>,
    /// The solver's standard error of its final radiosity, relative as e_rms is
    /// ([`StandardError::relative_rms`]), when its answer is an estimate with one: a spread,
    /// not a promise (module doc of [`StandardError`]).
    pub standard_error: Option<Real>,
    /// The independent replicates the standard error rests on.
    pub replicates: Option<usize>,
}

/// What one run did and measured.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The solver's name.
    pub solver: String,
    /// e_rms after every step.
    pub points: Vec<Point>,
    /// Every metric at the planned steps.
    pub rows: Vec<TableRow>,
    /// The final state.
    pub state: State,
    /// Why the run ended.
    pub termination: TerminationReason,
    /// The solver's own figures (group sizes, condition numbers, fallbacks).
    pub record: Record,
    /// Seconds spent measuring, outside the run.
    pub overhead: Real,
    /// The final radiosity's metrics.
    pub last: FinalMetrics,
    /// The clock its seconds were counted on (its points', rows' and state's).
    pub clock: Clock,
    /// The solver's standard error of its final radiosity, patch by patch, when it has one.
    pub standard_error: Option<StandardError>,
}

impl Outcome {
    /// e_rms after `step` steps (the last point if the run ended before).
    pub fn at_step(&self, step: u64) -> Option<Real> {
        self.points.iter().take_while(|p| p.step <= step).last().map(|p| p.e_rms)
    }

    /// The columns computed after `step` steps.
    pub fn columns_at_step(&self, step: u64) -> Option<u64> {
        self.points.iter().take_while(|p| p.step <= step).last().map(|p| p.cost[Unit::Columns])
    }

    /// e_rms when `columns` columns had been computed (the first step there).
    pub fn at_columns(&self, columns: u64) -> Option<Real> {
        self.at_columns_point(columns).map(|p| p.e_rms)
    }

    /// The point where `columns` columns had been computed (the first step there).
    pub fn at_columns_point(&self, columns: u64) -> Option<Point> {
        self.points
            .iter()
            .find(|p| p.cost[Unit::Columns] >= columns)
            .filter(|p| p.cost[Unit::Columns] == columns)
            .copied()
    }

    /// The first point whose certified bound is at or below `target`.
    pub fn bound_reached(&self, target: Real) -> Option<&Point> {
        self.points.iter().find(|p| p.bound <= target)
    }

    /// The first point at or below `target`.
    pub fn reached(&self, target: Real) -> Option<&Point> {
        self.points.iter().find(|p| p.e_rms <= target)
    }

    /// The points where e_rms first fell to each power of ten from 1e-1 down.
    pub fn reached_powers(&self) -> Vec<(Real, Point)> {
        let mut out = Vec::new();
        for k in 1..=15 {
            let target = 10f64.powi(-k);
            match self.reached(target) {
                Some(p) => out.push((target, *p)),
                None => break,
            }
        }
        out
    }

    /// One sentence when the run ended at the step cap, before any of its rules held: it has
    /// not converged to what was asked, and the caller says so (on stderr, in the report).
    pub fn cap_note(&self) -> Option<String> {
        match self.termination {
            TerminationReason::StepCap(k) => Some(format!(
                "{} stopped at the step cap of {k} steps before any rule held, so it has not converged: give it a \
                 time=, steps= or columns= rule to run on",
                self.solver
            )),
            _ => None,
        }
    }

    /// One sentence for each budget of `rules` (a unit of cost) the run went past, on a
    /// system of `n` patches: a run stops only between steps, and one step may spend much at
    /// once (a product of F is n columns), so the last step may overshoot what was asked.
    pub fn overshoot_notes(&self, rules: &StopRules, n: usize) -> Vec<String> {
        let s = &self.state;
        rules
            .rules
            .iter()
            .filter_map(|rule| {
                let StopRule::Spent(unit, c) = *rule else { return None };
                let (spent, limit) = (s.cost[unit], c.resolve(n));
                (spent > limit).then(|| {
                    format!(
                        "{} spent {spent} {}, past {rule} ({limit}): it stops only between steps, and its last step \
                         spent {} at once",
                        self.solver,
                        unit.name(),
                        if unit == Unit::Columns && s.cost[Unit::Products] > 0 {
                            "a whole product of F"
                        } else {
                            "more than was left"
                        }
                    )
                })
            })
            .collect()
    }

    /// The group-solve share of the run's time.
    pub fn group_share(&self) -> Real {
        let total = self.state.cost.seconds();
        if total > 0.0 { self.state.cost.group_seconds / total } else { 0.0 }
    }

    /// The run's own seconds: form factors and solving.
    pub fn seconds(&self) -> Real {
        self.state.cost.seconds()
    }
}
