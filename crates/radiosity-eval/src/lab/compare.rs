//! Running a comparison: every solver in turn on one lab, under the same stop rules and
//! recording ([`Lab::compare`]), and what it measured ([`Comparison`]), which
//! [`crate::reports`] writes as `convergence.csv`, `report.md`, plots and a terminal summary.
//! Without a reference (`--reference none`) the certified bound of every step stands in for
//! e_rms ([`Comparison::metric`]).
//!
//! Measurement never counts as solver time: it is reported apart (see [`crate::lab`]).

use crate::error::LabError;
use crate::lab::options::ColumnCharge;
use crate::lab::options::Transport;
use crate::lab::outcome::Outcome;
use crate::lab::recorder::{Point, RecordPlan};
use crate::lab::run::check_rules;
use crate::lab::setup::{ChosenReference, Lab, ReferenceOrigin};
use crate::progress::Progress;
use radiosity_core::TransportSampler;
use radiosity_core::{Clock, Real};
use radiosity_geom::SceneReport;
use radiosity_solvers::{Problem, Solver, State, StepKind, StopRules};
use std::ops::ControlFlow;

impl Lab<'_> {
    /// Runs every solver in turn under the same rules and recording: the comparison that
    /// [`Comparison::write`] reports. A solver that refuses these form factors
    /// ([`Solver::applicable`]) stops the comparison before anything runs; so does a lab whose
    /// transport sampler cannot be built, when some solver samples transport.
    pub fn compare(
        &self,
        solvers: Vec<Box<dyn Solver>>,
        rules: &StopRules,
        progress: &dyn Progress,
    ) -> Result<Comparison, LabError> {
        self.compare_watched(solvers, rules, progress, &mut ())
    }

    /// [`Lab::compare`], showing `watch` each run's start, every point recorded with its state,
    /// and each run's outcome ([`ComparisonWatch`]). A `Break` from the watch ends the run it
    /// watches and the comparison: solvers not yet started are left out, and a note says so.
    pub fn compare_watched(
        &self,
        solvers: Vec<Box<dyn Solver>>,
        rules: &StopRules,
        progress: &dyn Progress,
        watch: &mut dyn ComparisonWatch,
    ) -> Result<Comparison, LabError> {
        // A solver whose hypothesis these form factors break is refused before any runs, on
        // the problem it will have: with the lab's sampler when it samples transport.
        // The sampler is built once, before any run, only when some solver casts rays.
        let built = match solvers.iter().any(|s| s.step_kind() == StepKind::Sampled) {
            true => Some(self.transport_sampler()?),
            false => None,
        };
        let sampler = built.as_ref().map(|b| &*b.sampler as &dyn TransportSampler);
        let mut problem = Problem::new(self.system(), self.source())?.with_patch_order(&self.order)?;
        if let Some(sampler) = sampler {
            problem = problem.with_transport(sampler)?;
        }
        if let Some(ranks) = self.ranks.as_deref() {
            problem = problem.with_collective(ranks);
        }
        for solver in &solvers {
            check_rules(solver.as_ref(), rules)?;
            solver.applicable(&problem)?;
        }
        let mut outcomes = Vec::with_capacity(solvers.len());
        let plan = RecordPlan::default();
        let names: Vec<String> = solvers.iter().map(|s| s.name()).collect();
        let mut interrupted = None;
        for (index, mut solver) in solvers.into_iter().enumerate() {
            watch.begin(index, &names[index]);
            let mut stopped = false;
            let mut on_point = |p: &Point, s: &State| {
                let flow = watch.point(index, p, s);
                stopped |= flow.is_break();
                flow
            };
            let outcome = self.run_on(solver.as_mut(), rules, &plan, progress, &mut on_point, sampler)?;
            watch.end(index, &outcome);
            outcomes.push(outcome);
            if stopped {
                interrupted = Some(index);
                break;
            }
        }
        let mut comparison = Comparison::new(self, rules, outcomes);
        if let Some(index) = interrupted {
            let left = &names[index + 1..];
            let rest = match left.is_empty() {
                true => String::new(),
                false => format!("; not run: {}", left.join(", ")),
            };
            comparison.notes.push(format!("the comparison was stopped during {}'s run{rest}", names[index]));
        }
        comparison.transport = built.as_ref().map(|b| {
            let mixed = (self.transport() == Transport::Scene && comparison.has_reference()).then(|| {
                format!(
                    "; rays in the scene sample the exact kernel while the reference solves `{}`'s F, so those \
                     solvers' e_rms includes that backend's own distance from the exact kernel (`cargo xtask ff \
                     --against` measures it; `--transport matrix` samples the reference's own F)",
                    comparison.backend
                )
            });
            format!("{}{}", b.describe(), mixed.unwrap_or_default())
        });
        Ok(comparison)
    }
}

/// What watches a comparison as it runs ([`Lab::compare_watched`]): each run's start, its points
/// with the state they were measured on, and its outcome. `()` watches nothing.
pub trait ComparisonWatch {
    /// The run of solver `index` (in the order given), called `name`, starts.
    fn begin(&mut self, index: usize, name: &str) {
        let _ = (index, name);
    }

    /// Solver `index` recorded `point` on `state`; `Break` ends its run and the comparison.
    fn point(&mut self, index: usize, point: &Point, state: &State) -> ControlFlow<()> {
        let _ = (index, point, state);
        ControlFlow::Continue(())
    }

    /// The run of solver `index` ended with `outcome`.
    fn end(&mut self, index: usize, outcome: &Outcome) {
        let _ = (index, outcome);
    }
}

impl ComparisonWatch for () {}

/// What a comparison measured, with what it needs to report it.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// The scene's report.
    pub scene: SceneReport,
    /// Patches.
    pub n: u64,
    /// The backend's label.
    pub backend: String,
    /// The stop rules every solver ran under, as written.
    pub rules: String,
    /// The reference's kind and why it was chosen.
    pub reference_kind: ChosenReference,
    /// The reference's method, unless the reference is `none`.
    pub reference_method: Option<String>,
    /// The reference's certificate, unless the reference is `none`.
    pub reference_certificate: Option<String>,
    /// Where the reference came from.
    pub reference_origin: ReferenceOrigin,
    /// One per solver, in order.
    pub outcomes: Vec<Outcome>,
    /// What each column was charged, when the lab served columns from its stored matrix
    /// (`None`: every column was computed and timed).
    pub charge: Option<ColumnCharge>,
    /// The clock every run's seconds were counted on ([`Lab::clock`]), named wherever they are
    /// printed.
    pub clock: Clock,
    /// Where the solvers that sample transport cast their rays, what a ray is and what the
    /// sampler took to build ([`TransportBuilt::describe`]), when some solver sampled
    /// transport; set by [`Lab::compare`].
    pub transport: Option<String>,
    /// How the backend was built, when it says ([`Lab::backend_figures`]: the hierarchical
    /// operator): `built in 15.20 s`, or read back from the cache; outside every solver's
    /// seconds.
    pub backend_build: Option<String>,
    /// What the runs did not do as asked, one sentence each: runs ended at the step cap, not
    /// converged ([`Outcome::cap_note`]), and budgets overshot by a last step
    /// ([`Outcome::overshoot_notes`]). Printed on stderr by the command line and in
    /// `report.md`.
    pub notes: Vec<String>,
}

impl Comparison {
    /// The comparison of `outcomes`, run on `lab` under `rules`.
    pub fn new(lab: &Lab<'_>, rules: &StopRules, outcomes: Vec<Outcome>) -> Comparison {
        let notes =
            outcomes.iter().flat_map(|o| o.cap_note().into_iter().chain(o.overshoot_notes(rules, lab.n()))).collect();
        Comparison {
            scene: lab.report().clone(),
            n: lab.n() as u64,
            backend: lab.backend().to_string(),
            rules: rules.rules.iter().map(|r| r.to_string()).collect::<Vec<_>>().join(","),
            reference_kind: lab.chosen().clone(),
            reference_method: lab.reference().map(|r| r.method().to_string()),
            reference_certificate: lab.reference().map(|r| r.certificate().to_string()),
            reference_origin: lab.origin().clone(),
            outcomes,
            charge: lab.charge().copied(),
            clock: lab.clock(),
            transport: None,
            notes,
            backend_build: lab.backend_figures().map(|f| {
                if f.loaded {
                    format!("read back from the cache (built in {:.2} s when it was made)", f.seconds)
                } else {
                    format!("built in {:.2} s", f.seconds)
                }
            }),
        }
    }

    /// The outcome of `solver`, by name.
    pub fn outcome(&self, solver: &str) -> Option<&Outcome> {
        self.outcomes.iter().find(|o| o.solver == solver)
    }

    /// Whether the runs were measured against a reference (otherwise the certified bound
    /// stands in for e_rms).
    pub fn has_reference(&self) -> bool {
        self.reference_method.is_some()
    }

    /// The name of the curve the tables and plots show: `e_rms`, or `bound` without a
    /// reference.
    pub fn metric(&self) -> &'static str {
        if self.has_reference() { "e_rms" } else { "bound" }
    }

    /// The shown metric of a point.
    pub(crate) fn value(&self, p: &Point) -> Real {
        if self.has_reference() { p.e_rms } else { p.bound }
    }

    /// The first point of `o` where the shown metric ([`Comparison::metric`]) is at or below
    /// `target`.
    pub fn reached<'o>(&self, o: &'o Outcome, target: Real) -> Option<&'o Point> {
        o.points.iter().find(|p| self.value(p) <= target)
    }

    /// The shown metric of `o` after `step` steps (the last point if the run ended before).
    pub fn at_step(&self, o: &Outcome, step: u64) -> Option<Real> {
        o.points.iter().take_while(|p| p.step <= step).last().map(|p| self.value(p)).filter(|v| !v.is_nan())
    }
}
