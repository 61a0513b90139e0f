//! One run's figures, as every front end shows them ([`RunSummary`]): `cargo xtask solve`'s
//! JSON `stats` and text, and Python's `Run.stats`, built once here from the lab and the run's
//! outcome and serialized by serde, so that a figure added here reaches every front end.
//!
//! Keys are stable: `steps`, then the run's cost as flat keys ([`Cost`]: `clock` of every
//! seconds figure, one count per unit, `columns`, `columns_reused`, `products`, `rays`,
//! `links`, and the seconds, `seconds`, `ff_seconds`, `group_seconds`), the errors (`e_rms`, `e_max`, `residual` and `residual_of`, `bound`,
//! `standard_error`, `replicates`), `transport`, `termination`, `reached`, `record` (the
//! solver's own figures, the unshot power of a stochastic run among them), `reference`, and,
//! when there are any, `operator` and `ranks`. A figure not known is `null`.

use crate::error::LabError;
use crate::lab::outcome::Outcome;
use crate::lab::setup::Lab;
use radiosity_core::Real;
use radiosity_solvers::{Cost, Record, State, Unit, Value};
use serde::Serialize;

/// One run's figures (module doc).
#[derive(Clone, Debug, Serialize)]
pub struct RunSummary {
    /// The solver's name, parameters spelled out (`reference` for the exact solution).
    #[serde(skip)]
    pub solver: String,
    /// Steps taken.
    pub steps: u64,
    /// What the run spent, as flat keys: `clock` (of every seconds figure), every unit's count
    /// (`columns`, `columns_reused`, `products`, `rays`, `links`), `seconds` (form factors and
    /// solving), `ff_seconds` (of them, form factors', or rays' for a solver that samples
    /// transport) and `group_seconds` (of them, solving groups').
    #[serde(flatten)]
    pub cost: Cost,
    /// e_rms against the reference, when there is one.
    pub e_rms: Option<Real>,
    /// e_max against the reference, when there is one.
    pub e_max: Option<Real>,
    /// The residual power of the displayed radiosity, or else the solver's own.
    pub residual: Option<Real>,
    /// Which vector `residual` is the residual of, and why F's is not known when it is not.
    pub residual_of: String,
    /// The certified bound on the relative L1 error of the displayed radiosity.
    pub bound: Option<Real>,
    /// The solver's standard error, relative as e_rms is: a spread, not a bound.
    pub standard_error: Option<Real>,
    /// The replicates the standard error rests on.
    pub replicates: Option<usize>,
    /// Where the rays went (`scene` or `matrix`), when the solver cast some.
    pub transport: Option<String>,
    /// Why the run ended.
    pub termination: String,
    /// With an `rms=` rule: where e_rms first fell to each power of ten.
    pub reached: Vec<Reached>,
    /// The solver's own figures: counts and finite reals as numbers, anything else as text.
    pub record: serde_json::Map<String, serde_json::Value>,
    /// The reference the run was measured against.
    pub reference: ReferenceSummary,
    /// What building the backend cost, when it says (the hierarchical operator).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub operator: Option<OperatorSummary>,
    /// Each rank's part, when the run was distributed over MPI ranks.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ranks: Option<Vec<RankReport>>,
}

/// Where a run stood when its e_rms first fell to `e_rms`.
#[derive(Clone, Debug, Serialize)]
pub struct Reached {
    /// The power of ten.
    pub e_rms: Real,
    /// Steps by then.
    pub steps: u64,
    /// What the run had spent by then, as flat keys ([`RunSummary::cost`]).
    #[serde(flatten)]
    pub cost: Cost,
}

/// The reference a run was measured against.
#[derive(Clone, Debug, Serialize)]
pub struct ReferenceSummary {
    /// `matrix`, `shooting` or `none`.
    pub kind: String,
    /// Why it was chosen.
    pub why: String,
    /// How it was computed, unless `none`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method: Option<String>,
    /// Its certificate, unless `none`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certificate: Option<String>,
}

/// What building the backend cost ([`radiosity_ff::BackendFigures`]).
#[derive(Clone, Debug, Serialize)]
pub struct OperatorSummary {
    /// Seconds to build (the build's, when read back from the cache).
    pub build_seconds: Real,
    /// Whether it was read back from the cache rather than built.
    pub loaded: bool,
    /// Bytes held.
    pub bytes: usize,
    /// Of them, the links'.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub link_bytes: Option<Real>,
    /// One line.
    pub summary: String,
    /// The build's seconds stage by stage, where the backend times them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub stages: Vec<(String, Real)>,
    /// The bytes held part by part, where the backend counts them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub parts: Vec<(String, usize)>,
}

/// A record value as JSON: counts and finite reals as numbers, anything else as text.
fn json_value(v: &Value) -> serde_json::Value {
    match v {
        Value::Count(c) => (*c).into(),
        Value::Real(r) if r.is_finite() => (*r).into(),
        other => other.to_string().into(),
    }
}

impl Lab<'_> {
    /// The summary of `outcome`, a run on this lab; `reached` when an `rms=` rule asked for
    /// where e_rms fell to each power of ten.
    pub fn summary(&self, outcome: &Outcome, reached: bool) -> RunSummary {
        let reached = if reached { outcome.reached_powers() } else { Vec::new() };
        let reached = reached.into_iter().map(|(e_rms, p)| Reached { e_rms, steps: p.step, cost: p.cost }).collect();
        let termination = outcome.termination.to_string();
        self.summarize(&outcome.solver, &outcome.state, termination, &outcome.last, reached, &outcome.record)
    }

    /// The summary of the reference itself as a run, whose state is `state`
    /// ([`Lab::reference_state`]): its cost is assembling F and solving it.
    pub fn reference_summary(&self, state: &State) -> Result<RunSummary, LabError> {
        let method = self.reference().map(|r| r.method().to_string()).unwrap_or_default();
        let last = self.reference_metrics()?;
        let termination = format!("solved exactly: {method}");
        Ok(self.summarize("reference", state, termination, &last, Vec::new(), &Record::default()))
    }

    fn summarize(
        &self,
        solver: &str,
        s: &State,
        termination: String,
        last: &crate::FinalMetrics,
        reached: Vec<Reached>,
        record: &Record,
    ) -> RunSummary {
        let no_f = match self.reference() {
            Some(_) => "F was not assembled, the reference came from the cache",
            None => "F was not assembled: there is no reference",
        };
        let (residual, residual_of) = match (last.residual, last.solver_residual) {
            (Some(r), _) => (Some(r), "displayed radiosity".to_string()),
            (None, Some(r)) => {
                (Some(r), format!("the solver's own (for shooting methods, the shot radiosity); {no_f}"))
            }
            (None, None) => (None, format!("not known: {no_f}")),
        };
        // Every seconds figure of the lab's runs, the reference's too, is on the lab's clock.
        let mut cost = s.cost;
        cost.clock = self.clock();
        RunSummary {
            solver: solver.to_string(),
            steps: s.step,
            cost,
            e_rms: last.e_rms,
            e_max: last.e_max,
            residual,
            residual_of,
            bound: last.bound,
            standard_error: last.standard_error,
            replicates: last.replicates,
            transport: (s.cost[Unit::Rays] > 0).then(|| self.transport().name().to_string()),
            termination,
            reached,
            record: record.iter().map(|(k, v)| (k.to_string(), json_value(v))).collect(),
            reference: ReferenceSummary {
                kind: self.chosen().kind.to_string(),
                why: self.chosen().why.clone(),
                method: self.reference().map(|r| r.method().to_string()),
                certificate: self.reference().map(|r| r.certificate().to_string()),
            },
            operator: self.backend_figures().map(|f| OperatorSummary {
                build_seconds: f.seconds,
                loaded: f.loaded,
                bytes: f.bytes,
                link_bytes: f.count("link bytes"),
                summary: f.summary.clone(),
                stages: f.stages.clone(),
                parts: f.parts.clone(),
            }),
            ranks: None,
        }
    }
}

/// One rank's part of a distributed run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RankReport {
    /// The rank.
    pub rank: usize,
    /// Seconds it took to build its part of the operator.
    pub build_seconds: Real,
    /// Those seconds, stage by stage (empty where the operator is not split).
    pub build_stages: Vec<(String, Real)>,
    /// Bytes its part of the operator holds (its links, and what every rank holds).
    pub operator_bytes: u64,
    /// Of them, its links' bytes.
    pub link_bytes: u64,
    /// Its links: far links, near links and far pairs.
    pub links: u64,
    /// Shadow rays it traced for its links.
    pub rays: u64,
    /// Refinement tasks dealt to it.
    pub tasks: u64,
    /// Its share of the refinement's estimated cost.
    pub estimated_share: Real,
    /// The high-water mark of its resident memory, in bytes (`None` without `/proc`).
    pub peak_rss: Option<u64>,
    /// Seconds the run spent in the operator on this rank (products, columns, rows), its sums
    /// included.
    pub run_operator_seconds: Real,
    /// Collective sums during the run.
    pub run_sums: u64,
    /// Seconds in those sums, waiting for the other ranks included.
    pub run_sum_seconds: Real,
    /// Bytes this rank sent in those sums.
    pub run_bytes_sent: u64,
    /// Rays it cast in the run (a solver that samples transport; 0 for the others).
    pub run_rays: u64,
}
