//! Running one solver in a lab: a [`Recorder`] set up for it, its columns paid for as the lab
//! says ([`crate::ColumnCost`]), its rays cast through the lab's transport sampler when it
//! samples transport ([`Lab::transport_sampler`]), its final metrics; and the reference itself
//! as a final state.

use crate::error::LabError;
use crate::lab::outcome::{FinalMetrics, Outcome};
use crate::lab::recorder::{Point, ProgressUnit, RecordPlan, Recorder, matrix_relative_bound};
use crate::lab::setup::{Lab, ReferenceOrigin};
use crate::progress::Progress;
use crate::reference::certificate::SolverBound;
use crate::reference::metrics::errors;
use crate::reference::solution::Method;
use radiosity_core::{Real, TransportSampler};
use radiosity_solvers::Unit;
use radiosity_solvers::{Executor, ObserverMode, Problem, Solver, State, StepKind, StopRule, StopRules};
use std::ops::ControlFlow;
use std::rc::Rc;
use std::time::Instant;

impl Lab<'_> {
    /// Why `solver` will not converge to the reference on this source, if it will not: it
    /// gathers along rows the source cannot give exactly.
    pub fn row_warning(&self, solver: &dyn Solver) -> Option<String> {
        (solver.step_kind() == StepKind::Gather && !self.serves_rows).then(|| {
            format!(
                "{} gathers along rows of F, which {} cannot give exactly; they are taken from its columns by \
                 reciprocity, which these form factors do not satisfy, so the run converges to another system's \
                 solution, off the reference by as much as their reciprocity error (`cargo xtask ff` reports it)",
                solver.name(),
                self.backend
            )
        })
    }

    /// Why `solver`, a shooter from the nodes of a hierarchy, will not shoot through links on
    /// this source, if it will not: an operator split over ranks keeps each rank's links apart
    /// and shows none, so the shooter runs one level, every patch a node and its column its
    /// links, and computes columns (design.md §4.10).
    pub fn link_warning(&self, solver: &dyn Solver) -> Option<String> {
        let split = self.source.collective().is_some() && self.source.link_source().is_none();
        (solver.step_kind() == StepKind::Round && split).then(|| {
            format!(
                "{} shoots from the nodes of a hierarchy, but {} is split over ranks and shows no links, so it runs \
                 one level, every patch a node, and computes a column for every shot",
                solver.name(),
                self.backend
            )
        })
    }

    /// Runs `solver` under `rules`, recording as `plan` says, reporting to `progress`.
    pub fn run(
        &self,
        solver: &mut dyn Solver,
        rules: &StopRules,
        plan: &RecordPlan,
        progress: &dyn Progress,
    ) -> Result<Outcome, LabError> {
        self.run_watched(solver, rules, plan, progress, &mut |_, _| ControlFlow::Continue(()))
    }

    /// [`Lab::run`], showing `watch` every point recorded (after every step) with its state,
    /// outside the run's timed region; `ControlFlow::Break` ends the run before its next step
    /// ([`radiosity_solvers::TerminationReason::Stopped`]), with its state, points and final
    /// metrics as any other.
    pub fn run_watched(
        &self,
        solver: &mut dyn Solver,
        rules: &StopRules,
        plan: &RecordPlan,
        progress: &dyn Progress,
        watch: &mut dyn FnMut(&Point, &State) -> ControlFlow<()>,
    ) -> Result<Outcome, LabError> {
        check_rules(solver, rules)?;
        // Built before the run (set-up, not the run's time), only for a run that casts rays.
        let built = match solver.step_kind() {
            StepKind::Sampled => Some(self.transport_sampler()?),
            _ => None,
        };
        self.run_on(solver, rules, plan, progress, watch, built.as_ref().map(|b| &*b.sampler as &dyn TransportSampler))
    }

    /// [`Lab::run_watched`], a solver that samples transport casting its rays through
    /// `sampler` ([`Lab::transport_sampler`], built by the caller: once for a comparison).
    /// The caller has checked the rules ([`check_rules`]), before building the sampler.
    pub(crate) fn run_on(
        &self,
        solver: &mut dyn Solver,
        rules: &StopRules,
        plan: &RecordPlan,
        progress: &dyn Progress,
        watch: &mut dyn FnMut(&Point, &State) -> ControlFlow<()>,
        sampler: Option<&dyn TransportSampler>,
    ) -> Result<Outcome, LabError> {
        for w in [self.row_warning(solver), self.link_warning(solver)].into_iter().flatten() {
            progress.warn(&w);
        }
        let name = solver.name();
        let sampled = solver.step_kind() == StepKind::Sampled;
        let sampler = if sampled { sampler } else { None };
        let evaluator = self.evaluator()?;
        let counts_columns = !matches!(solver.step_kind(), StepKind::Product | StepKind::Round);
        let (target, unit) = progress_target(rules, self.n(), sampled, counts_columns);
        let n = self.n() as u64;
        let mut recorder = Recorder {
            system: &self.system,
            reference: self.reference.as_ref().map(|r| r.values()),
            contraction: Some(&self.contraction),
            known: None,
            spread: None,
            clock: Instant::now(),
            evaluator: evaluator.as_ref(),
            solver: name.clone(),
            // A step that is a whole product by F is a sweep's worth of columns, and one by rays
            // an iteration over every patch: every one is recorded.
            every: plan.every.unwrap_or(
                if matches!(solver.step_kind(), StepKind::Product | StepKind::Round | StepKind::Sampled) {
                    1
                } else {
                    (target / 100).max(1)
                },
            ),
            marks: if plan.marks { vec![n / 4, n / 2, n, 2 * n] } else { Vec::new() },
            points: Vec::new(),
            rows: Vec::new(),
            overhead: 0.0,
            progress: Some(progress),
            unit,
            latest: Rc::default(),
            watch: Some(watch),
            stop: false,
            sampled,
        };
        progress.begin(&name, target, unit.name());
        // Every run starts from columns as costly as the first ones: what an earlier run left
        // in the source's memory (the analytic backend's visible fractions) would make later
        // solvers look faster.
        self.source.reset_memory();
        let mut problem = Problem::new(&self.system, &*self.source)?.with_patch_order(&self.order)?;
        if let Some(sampler) = sampler {
            problem = problem.with_transport(sampler)?;
        }
        if let Some(ranks) = self.ranks.as_deref() {
            problem = problem.with_collective(ranks);
        }
        let mut monitor = recorder.monitor();
        let mut executor = Executor::new(solver, rules.clone());
        if let Some(monitor) = monitor.as_mut() {
            executor = executor.monitor(monitor);
        }
        let run = executor.add_observer(&mut recorder, ObserverMode::Always).run(&problem);
        progress.end();
        let run = run?;
        let solver_residual = solver.residual_power(&problem, &run.state);
        let known = solver.residual_bound(&problem, &run.state);
        let solver_bound =
            known.map(|k| SolverBound::new(&self.system, &self.contraction, &k, &run.state.radiosity).relative);
        let spread = solver.standard_error(&problem, &run.state);
        let standard_error = spread.as_ref().map(|s| s.relative_rms(&self.system, &run.state.radiosity));
        let replicates = spread.as_ref().map(|s| s.replicates);
        let last = match (&evaluator, &self.reference) {
            (Some(e), _) => {
                let m = e.evaluate(&run.state.radiosity)?;
                // F's bound on the displayed radiosity stands in for a deterministic solver that
                // has none of its own; a solver that samples transport shows its standard error
                // only, never a certified bound it did not compute (docs/design.md §4.9).
                let matrix_bound = (m.bound.certified && !sampled)
                    .then(|| matrix_relative_bound(&self.system, &m, &run.state.radiosity));
                FinalMetrics {
                    e_rms: Some(m.e_rms),
                    e_max: Some(m.e_max),
                    residual: Some(m.residual),
                    bound: solver_bound.or(matrix_bound),
                    solver_residual,
                    standard_error,
                    replicates,
                }
            }
            (None, Some(reference)) => {
                let e = errors(&self.system, reference, &run.state.radiosity)?;
                FinalMetrics {
                    e_rms: Some(e.e_rms),
                    e_max: Some(e.e_max),
                    residual: None,
                    bound: solver_bound,
                    solver_residual,
                    standard_error,
                    replicates,
                }
            }
            (None, None) => FinalMetrics {
                e_rms: None,
                e_max: None,
                residual: None,
                bound: solver_bound,
                solver_residual,
                standard_error,
                replicates,
            },
        };
        Ok(Outcome {
            solver: run.solver,
            points: recorder.points,
            rows: recorder.rows,
            termination: run.termination,
            record: run.record,
            overhead: recorder.overhead,
            last,
            state: run.state,
            clock: self.clock(),
            standard_error: spread,
        })
    }

    /// The reference as a final state: its cost is assembling F (form-factor time) and
    /// solving it, or reading it from the cache. Fails when the reference is `none`.
    pub fn reference_state(&self) -> Result<State, LabError> {
        let reference = self.reference.as_ref().ok_or_else(no_reference)?;
        let mut state = State::from_emission(self.system.emissions(), self.system.channels().count());
        state.radiosity.copy_from_slice(reference.values());
        state.unshot.fill(0.0);
        state.cost[Unit::Columns] = match reference.method() {
            Method::Shooting { columns, .. } => *columns,
            _ => self.system.len() as u64,
        };
        match self.origin {
            ReferenceOrigin::Solved { assembly_seconds, solve_seconds } => {
                state.cost.ff_seconds = assembly_seconds;
                state.cost.solve_seconds = solve_seconds;
            }
            ReferenceOrigin::Cached { seconds, .. } => state.cost.solve_seconds = seconds,
            ReferenceOrigin::NotComputed => {}
        }
        Ok(state)
    }

    /// The metrics of the reference itself (zero error; its residual when F is kept, and its
    /// certificate's bound).
    pub fn reference_metrics(&self) -> Result<FinalMetrics, LabError> {
        let reference = self.reference.as_ref().ok_or_else(no_reference)?;
        let residual = match self.evaluator()? {
            Some(e) => Some(e.evaluate(reference.values())?),
            None => None,
        };
        let certificate = reference.certificate();
        Ok(FinalMetrics {
            e_rms: Some(0.0),
            e_max: Some(0.0),
            residual: residual.map(|m| m.residual),
            bound: certificate.certified.then_some(certificate.relative_bound),
            solver_residual: None,
            standard_error: None,
            replicates: None,
        })
    }

    /// The RGB radiosity of every patch after running `solver` under `rules` (the reference
    /// when `solver` is `None`): what renders and exports show. An `rms=` rule is measured.
    pub fn radiosity_rgb(
        &self,
        solver: Option<&mut dyn Solver>,
        rules: &StopRules,
        progress: &dyn Progress,
    ) -> Result<Vec<[Real; 3]>, LabError> {
        let state = match solver {
            None => self.reference_state()?,
            Some(solver) => self.run(solver, rules, &RecordPlan::errors_only(), progress)?.state,
        };
        Ok(rgb(&state))
    }
}

/// The error of asking for the reference of a lab without one.
fn no_reference() -> LabError {
    LabError::Invalid("there is no reference solution with --reference none".into())
}

/// The radiosity of every patch of `state` as RGB (a grey channel repeated three times).
pub fn rgb(state: &State) -> Vec<[Real; 3]> {
    let k = state.channels;
    state.radiosity.chunks_exact(k).map(|b| if k == 1 { [b[0]; 3] } else { [b[0], b[1], b[2]] }).collect()
}

/// Refuses, before any work, a solver that samples transport under rules that only count
/// other units than rays (`columns=`, `products=`, `links=`): it spends none of them, so they
/// could never stop it, and its step cap (`20n` steps of rays over every patch) is far off; and
/// a solver whose answer is not an estimate under rules that only read a standard error
/// (`std_error=`), which it has not.
pub fn check_rules(solver: &dyn Solver, rules: &StopRules) -> Result<(), LabError> {
    let spread_only = !rules.rules.is_empty() && rules.rules.iter().all(|r| matches!(r, StopRule::StdError(_)));
    if solver.step_kind() != StepKind::Sampled && spread_only {
        return Err(LabError::Invalid(format!(
            "{} is not an estimate and has no standard error, so {} would never stop it: add a columns=, steps=, \
             time=, residual= or rms= rule",
            solver.name(),
            rules.rules.iter().map(ToString::to_string).collect::<Vec<_>>().join(",")
        )));
    }
    let other = |r: &StopRule| matches!(r, StopRule::Spent(u, _) if *u != Unit::Rays);
    if solver.step_kind() == StepKind::Sampled && rules.rules.iter().all(other) {
        let written: Vec<String> = rules.rules.iter().map(ToString::to_string).collect();
        let others: Vec<&str> =
            Unit::ALL.into_iter().filter(|&u| u.paid() && u != Unit::Rays).map(Unit::name).collect();
        let (last, first) = others.split_last().unwrap_or((&"", &[]));
        return Err(LabError::Invalid(format!(
            "{} casts rays and spends no {} or {last}, so {} would never stop it: add a rays=, steps=, time= or rms= \
             rule (e.g. rays=1e7)",
            solver.name(),
            first.join(", "),
            written.join(",")
        )));
    }
    Ok(())
}

/// The count a run's progress is measured against, and its unit: for a solver that samples
/// transport (`sampled`), its first `rays=` or `steps=` rule (rays, with no target,
/// otherwise); for the others, their first `steps=` rule or rule on another unit of cost
/// (`2n` columns otherwise, or steps with no target for a solver whose steps are products or
/// rounds, which may compute no column at all). A rule that counts what the run does not
/// spend never holds for it: in a comparison that mixes both, each solver stops on its own.
fn progress_target(rules: &StopRules, n: usize, sampled: bool, counts_columns: bool) -> (u64, ProgressUnit) {
    rules
        .rules
        .iter()
        .find_map(|r| match *r {
            StopRule::Spent(unit, c) if sampled == (unit == Unit::Rays) => {
                Some((c.resolve(n), ProgressUnit::Spent(unit)))
            }
            StopRule::Steps(c) => Some((c.resolve(n), ProgressUnit::Steps)),
            _ => None,
        })
        .unwrap_or(match (sampled, counts_columns) {
            (true, _) => (0, ProgressUnit::Spent(Unit::Rays)),
            (false, true) => (2 * n as u64, ProgressUnit::Spent(Unit::Columns)),
            (false, false) => (0, ProgressUnit::Steps),
        })
}
