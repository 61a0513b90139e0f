//! Stochastic relaxation from scene load: wall time and rays to e_rms ≤ 1e-2, 3e-3 and 1e-3
//! on a real scene, for solvers that sample transport with rays in the scene, against the
//! analytic reference.
//!
//! [`sampled_run`] runs one case: the clock starts before the scene is loaded and counts what
//! a user waits for (load, BVH, analysis, the sampler's or the backend's setup and the solve).
//! A case is a solver with rays in the scene, or a deterministic comparator over a backend
//! ([`Case`]: `xu` over the analytic columns, `gmres-30` over the hierarchical operator), timed
//! the same way to the same thresholds. After every step
//! an observer measures e_rms against a reference solved beforehand and takes that time out
//! of the wall clock, as [`crate::bench::e2e`] does for the deterministic solvers. The report
//! ([`report`]) gives, per solver, the median wall seconds and rays to each threshold, and for
//! every quasi-random sequence the rays it needed against `seq=random` at the same e_rms.
//!
//! Beside them, when given a RenderPark executable, the section times RenderPark's own
//! stochastic Jacobi on the same scene file in the same run ([`crate::bench::peer`]); without
//! one it says it has no peer measurement.

use crate::error::LabError;
use crate::lab::backends::fresh_backend;
use crate::lab::timing::median;
use crate::memory::peak_rss;
use crate::progress::NoProgress;
use crate::reference::metrics::errors_against;
use crate::reports::report_text::{duration, human_bytes, sig};
use crate::suites::bench::e2e::{Recorded, ReferenceNote, Setup, check_reference, recorded_run};
use radiosity_core::{LinearSystem, Real};
use radiosity_ff::{BackendSpec, SceneTransport};
use radiosity_geom::PreparedScene;
use radiosity_solvers::Unit;
use radiosity_solvers::{Problem, Solver, SolverError, StopRules};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::time::Instant;

/// The scene of the section (a third-party scene, from the scenes folder).
pub const SCENE: &str = "mgf/salon/classroom.mgf";

/// The e_rms thresholds timed, largest first; the runs stop at the last.
pub const THRESHOLDS: [Real; 3] = [1e-2, 3e-3, 1e-3];

/// The solvers of the section by default.
pub const SOLVERS: [&str; 7] = [
    "stochastic-jacobi",
    "stochastic-jacobi:seq=sobol",
    "stochastic-jacobi:seq=halton",
    "stochastic-jacobi:lines=global",
    "stochastic-jacobi:form=gathering",
    "stochastic-jacobi:form=gathering:cv=true",
    "random-walk",
];

/// The deterministic comparators of the section by default: (solver, backend).
pub const COMPARATORS: [(&str, &str); 2] = [("xu", "analytic"), ("gmres-30", "hierarchical")];

/// What a case runs over.
#[derive(Clone, Debug, PartialEq)]
pub enum Case {
    /// Rays in the scene ([`SceneTransport`]).
    Rays,
    /// A backend's form factors, built fresh on the clock.
    Backend(BackendSpec),
}

/// When a run's e_rms first fell to a threshold.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReachedRays {
    /// The threshold.
    pub e_rms: Real,
    /// Wall seconds from the start of the scene load, measurement excluded.
    pub seconds: Real,
    /// Rays cast by then.
    pub rays: u64,
    /// Columns computed by then (a comparator's).
    #[serde(default)]
    pub columns: u64,
    /// Products by then (a comparator's).
    #[serde(default)]
    pub products: u64,
}

/// What one run reports.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SampledReport {
    /// Where the setup went (`backend`: the sampler's).
    pub setup: Setup,
    /// Each threshold of [`THRESHOLDS`] reached, in order.
    pub reached: Vec<ReachedRays>,
    /// e_rms at the end.
    pub e_rms: Real,
    /// The solver's standard error at the end, in the form of e_rms (`None` without one).
    pub standard_error: Option<Real>,
    /// Rays cast in all.
    pub rays: u64,
    /// Columns computed in all (a comparator's cost).
    #[serde(default)]
    pub columns: u64,
    /// Products by the operator in all.
    #[serde(default)]
    pub products: u64,
    /// Steps taken.
    pub steps: u64,
    /// Why the run stopped.
    pub termination: String,
    /// Wall seconds of the whole run, measurement excluded.
    pub seconds: Real,
    /// Seconds spent measuring e_rms, taken out of every figure.
    pub measurement: Real,
    /// Peak resident memory in bytes.
    pub peak_rss: Option<u64>,
}

/// Why `solver` cannot run with rays in `prepared`, if it cannot (a control variate in a scene
/// that is not closed): its own refusal, asked before any ray ([`Solver::applicable`]).
pub fn refusal(prepared: &PreparedScene, solver: &dyn Solver) -> Result<Option<String>, LabError> {
    let system = LinearSystem::from_scene(&prepared.loaded.scene);
    let transport = SceneTransport::from_prepared(prepared)?;
    let problem = Problem::sampled(&system, &transport)?;
    Ok(match solver.applicable(&problem) {
        Ok(()) => None,
        Err(SolverError::NotApplicable { reason, .. }) => Some(reason),
        Err(e) => return Err(e.into()),
    })
}

/// Runs `solver` over `case` in `prepared` until e_rms ≤ 1e-3 against `star` or for
/// `max_seconds` of solver time, timing from `start`, the instant the caller began loading the
/// scene, which took `scene_seconds`.
pub fn sampled_run(
    prepared: &PreparedScene,
    start: Instant,
    scene_seconds: Real,
    solver: &mut dyn Solver,
    case: &Case,
    star: &[Real],
    max_seconds: Real,
) -> Result<SampledReport, LabError> {
    let system = LinearSystem::from_scene(&prepared.loaded.scene);
    check_reference(&system, star)?;
    let transport = SceneTransport::from_prepared(prepared)?;
    let backend = match case {
        Case::Rays => None,
        Case::Backend(spec) => Some(fresh_backend(prepared, spec, &NoProgress)?),
    };
    let setup_seconds = start.elapsed().as_secs_f64() - scene_seconds;
    let problem = match &backend {
        None => Problem::sampled(&system, &transport)?,
        Some(backend) => Problem::new(&system, &**backend)?,
    };
    let last = THRESHOLDS[THRESHOLDS.len() - 1];
    let rules = StopRules::parse(&format!("rms={last},time={}ms", (max_seconds * 1e3).ceil() as u64))?;
    let Recorded { run, recorder, seconds, measurement } = recorded_run(&system, star, start, solver, rules, &problem)?;
    let reached = THRESHOLDS
        .iter()
        .map_while(|&t| {
            let p = recorder.points().iter().find(|p| p.e_rms <= t)?;
            Some(ReachedRays {
                e_rms: t,
                seconds: p.wall,
                rays: p.cost[Unit::Rays],
                columns: p.cost[Unit::Columns],
                products: p.cost[Unit::Products],
            })
        })
        .collect();
    let standard_error =
        solver.standard_error(&problem, &run.state).map(|s| s.relative_rms(&system, &run.state.radiosity));
    Ok(SampledReport {
        setup: Setup { scene: scene_seconds, backend: setup_seconds },
        reached,
        e_rms: errors_against(&system, star, &run.state.radiosity)?.e_rms,
        standard_error,
        rays: run.state.cost[Unit::Rays],
        columns: run.state.cost[Unit::Columns],
        products: run.state.cost[Unit::Products],
        steps: run.state.step,
        termination: run.termination.to_string(),
        seconds,
        measurement,
        peak_rss: peak_rss(),
    })
}

/// One solver's medians, for `--json`.
#[derive(Debug, Serialize, Deserialize)]
pub struct StochasticJson {
    /// The solver.
    pub method: String,
    /// The backend, for a deterministic comparator (`null`: rays in the scene).
    pub over: Option<String>,
    /// Median wall seconds from scene load to each threshold (`null`: not reached in every run).
    pub seconds_to: std::collections::BTreeMap<String, Option<Real>>,
    /// Median rays to each threshold (0 for a comparator, which counts columns and products).
    pub rays_to: std::collections::BTreeMap<String, Option<Real>>,
}

/// The section and what the targets are judged on.
#[derive(Debug)]
pub struct StochasticSection {
    /// The Markdown section.
    pub markdown: String,
    /// One entry per solver.
    pub json: Vec<StochasticJson>,
}

/// The median of a threshold's figure over runs, when every run reached it.
fn median_to(runs: &[SampledReport], k: usize, figure: impl Fn(&ReachedRays) -> Real) -> Option<Real> {
    let values: Vec<Real> = runs.iter().filter_map(|r| r.reached.get(k).map(&figure)).collect();
    (values.len() == runs.len() && !runs.is_empty()).then(|| median(&values))
}

/// The section from the runs of each case on `scene` (`patches` patches): a solver with rays
/// in the scene (`None`), or over the backend named.
pub fn report(
    scene: &str,
    patches: usize,
    cases: &[(String, Option<String>)],
    results: &[Vec<SampledReport>],
    inapplicable: &[(String, String)],
    reference: &ReferenceNote,
    max_seconds: Real,
) -> StochasticSection {
    let mut out = String::from("## Stochastic relaxation from scene load\n\n");
    let _ = writeln!(
        out,
        "`{scene}` ({patches} patches), rays in the scene (`SceneTransport`), e_rms against the analytic reference \
         ({}, solved in {} before the runs; {}). Wall time from the start of the scene load (load, BVH, analysis, \
         solve) until e_rms first falls to each threshold, in a child process per run, the time spent measuring \
         e_rms taken out; runs stop at e_rms ≤ 1e-3 or after {} s.\n",
        reference.method,
        duration(reference.seconds),
        reference.certificate,
        sig(max_seconds, 3),
    );
    out += "| solver | over | to 1e-2 | to 3e-3 | to 1e-3 | cost to 3e-3 | cost to 1e-3 | setup | last e_rms | last \
            standard error | peak memory |\n|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
    let mut json = Vec::new();
    for ((solver, over), runs) in cases.iter().zip(results) {
        if runs.is_empty() {
            let _ = writeln!(out, "| `{solver}` | not applicable here (below) | | | | | | | | | |");
            continue;
        }
        let cell = |k: usize| match median_to(runs, k, |r| r.seconds) {
            Some(s) => duration(s),
            None => "not reached".to_string(),
        };
        let cost = |k: usize| match over {
            None => median_to(runs, k, |r| r.rays as Real).map_or("—".to_string(), |r| format!("{r:.3e} rays")),
            Some(_) => median_to(runs, k, |r| r.columns as Real).map_or("—".to_string(), |c| {
                let products = median_to(runs, k, |r| r.products as Real).unwrap_or(0.0);
                if products > 0.0 { format!("{products:.0} products") } else { format!("{c:.0} columns") }
            }),
        };
        let setup = median(&runs.iter().map(|r| r.setup.scene + r.setup.backend).collect::<Vec<_>>());
        let last = runs.last();
        let _ = writeln!(
            out,
            "| `{solver}` | {} | {} | {} | {} | {} | {} | {} | {:.2e} | {} | {} |",
            over.as_deref().map_or("rays in the scene".to_string(), |ff| format!("`{ff}`")),
            cell(0),
            cell(1),
            cell(2),
            cost(1),
            cost(2),
            duration(setup),
            last.map_or(Real::NAN, |r| r.e_rms),
            last.and_then(|r| r.standard_error).map_or("—".to_string(), |s| format!("{s:.2e}")),
            runs.iter().filter_map(|r| r.peak_rss).max().map_or("n/a".to_string(), human_bytes),
        );
        json.push(StochasticJson {
            method: solver.clone(),
            over: over.clone(),
            seconds_to: THRESHOLDS
                .iter()
                .enumerate()
                .map(|(k, t)| (format!("{t:.0e}"), median_to(runs, k, |r| r.seconds)))
                .collect(),
            rays_to: THRESHOLDS
                .iter()
                .enumerate()
                .map(|(k, t)| (format!("{t:.0e}"), median_to(runs, k, |r| r.rays as Real)))
                .collect(),
        });
    }
    for (solver, why) in inapplicable {
        let _ = writeln!(out, "\n`{solver}` does not apply to this scene: {why}.");
    }
    // Quasi-random against pseudo-random, at the same e_rms.
    let random = cases.iter().position(|(c, over)| c == "stochastic-jacobi" && over.is_none());
    let quasi_random = cases.iter().any(|(c, over)| c.contains("seq=") && over.is_none());
    if let (Some(random), true) = (random, quasi_random) {
        out += "\nRays against `stochastic-jacobi` (pseudo-random) at the same e_rms:\n\n";
        for ((solver, _), runs) in cases.iter().zip(results).filter(|((c, _), _)| c.contains("seq=")) {
            let ratios: Vec<String> = (0..THRESHOLDS.len())
                .map(|k| {
                    match (median_to(runs, k, |r| r.rays as Real), median_to(&results[random], k, |r| r.rays as Real)) {
                        (Some(a), Some(b)) => format!("{:.2} at {:.0e}", a / b, THRESHOLDS[k]),
                        _ => format!("— at {:.0e}", THRESHOLDS[k]),
                    }
                })
                .collect();
            let _ = writeln!(out, "- `{solver}`: {}", ratios.join(", "));
        }
    }
    let measurement = results.iter().flatten().map(|r| r.measurement).fold(0.0, Real::max);
    let _ = writeln!(
        out,
        "\nMeasuring e_rms after every step took at most {} of a run (taken out of the figures above).\n",
        duration(measurement)
    );
    StochasticSection { markdown: out, json }
}
