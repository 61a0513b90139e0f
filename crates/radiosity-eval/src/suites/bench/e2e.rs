//! Wall time from scene load to e_rms ≤ 1e-1, 1e-2 and 1e-3, and the peak resident memory of
//! each run.
//!
//! [`time_to_accuracy`] runs one case: the clock starts before the scene is loaded, and counts
//! everything a user would wait for: load, BVH, analysis, the backend's setup (for `matrix`,
//! assembling the full matrix, always fresh, never from the cache) and the solve. After every
//! step a [`Recorder`] computes e_rms against a reference solved beforehand and takes that
//! measurement's time out of its wall clock. The report carries `VmHWM` (the high-water mark
//! of the process's resident memory, [`peak_rss`]), so a caller that wants each case's
//! peak memory on its own runs each in a process of its own, as `cargo xtask bench` does, and
//! reads back the report, which serialises to JSON. [`report`] writes the section from the
//! runs of every case.

use crate::error::LabError;
use crate::lab::backends::fresh_backend;
use crate::lab::recorder::Recorder;
use crate::lab::timing::median;
use crate::memory::peak_rss;
use crate::progress::NoProgress;
use crate::reference::metrics::errors_against;
use crate::reports::report_text::{duration, human_bytes, sig};
use crate::suites::bench::json::E2eJson;
use radiosity_core::{Clock, ColumnSource, LinearSystem, Real};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::Unit;
use radiosity_solvers::{Executor, ObserverMode, Problem, Run, Solver, StopRules};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::time::Instant;

/// The e_rms thresholds timed, largest first; the runs stop at the last.
pub const THRESHOLDS: [Real; 3] = [1e-1, 1e-2, 1e-3];

/// When a run's e_rms first fell to a threshold.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Reached {
    /// The threshold.
    pub e_rms: Real,
    /// Wall seconds from the start of the scene load, measurement excluded.
    pub seconds: Real,
    /// Columns computed by then.
    pub columns: u64,
    /// Steps taken by then.
    pub steps: u64,
}

/// Where a child's setup time went.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Setup {
    /// Load, BVH and analysis.
    pub scene: Real,
    /// The backend's setup (for `matrix`, the assembly).
    pub backend: Real,
}

/// What one run reports.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct EndToEndReport {
    /// Where the setup time went.
    pub setup: Setup,
    /// Each threshold of [`THRESHOLDS`] reached, in order.
    pub reached: Vec<Reached>,
    /// e_rms at the end.
    pub e_rms: Real,
    /// Columns computed in all.
    pub columns: u64,
    /// Steps taken in all.
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

/// Runs `solver` on `prepared` over the backend `spec` until e_rms ≤ 1e-3 against the
/// reference `star` (patch-major, as [`LinearSystem`]) or for `max_seconds` of solver time,
/// timing from `start`, the instant the caller began loading the scene, which took
/// `scene_seconds`. The backend's setup (for `matrix`, the assembly, fresh) is on the clock.
pub fn time_to_accuracy(
    prepared: &PreparedScene,
    start: Instant,
    scene_seconds: Real,
    solver: &mut dyn Solver,
    spec: &BackendSpec,
    star: &[Real],
    max_seconds: Real,
) -> Result<EndToEndReport, LabError> {
    // A reference of another scene is refused before any form factor is computed.
    check_reference(&LinearSystem::from_scene(&prepared.loaded.scene), star)?;
    let backend = fresh_backend(prepared, spec, &NoProgress)?;
    time_to_accuracy_over(prepared, start, scene_seconds, solver, &backend, star, max_seconds)
}

/// [`time_to_accuracy`] over any column source, a researcher's own included, set up by the
/// caller after `start` (its setup counts as the time from `start` less `scene_seconds`).
pub fn time_to_accuracy_over(
    prepared: &PreparedScene,
    start: Instant,
    scene_seconds: Real,
    solver: &mut dyn Solver,
    source: &dyn ColumnSource,
    star: &[Real],
    max_seconds: Real,
) -> Result<EndToEndReport, LabError> {
    let rules = StopRules::parse(&format!("rms={},time={}ms", THRESHOLDS[2], (max_seconds * 1e3).ceil() as u64))?;
    let system = LinearSystem::from_scene(&prepared.loaded.scene);
    check_reference(&system, star)?;
    let order = radiosity_geom::spatial_order(&prepared.loaded.scene);
    let backend_seconds = start.elapsed().as_secs_f64() - scene_seconds;
    let problem = Problem::new(&system, source)?.with_patch_order(&order)?;
    let Recorded { run, recorder, seconds, measurement } = recorded_run(&system, star, start, solver, rules, &problem)?;
    let mut reached = Vec::new();
    for threshold in THRESHOLDS {
        let Some(p) = recorder.points().iter().find(|p| p.e_rms <= threshold) else { break };
        reached.push(Reached { e_rms: threshold, seconds: p.wall, columns: p.cost[Unit::Columns], steps: p.step });
    }
    let e_rms = errors_against(&system, star, &run.state.radiosity)?.e_rms;
    Ok(EndToEndReport {
        setup: Setup { scene: scene_seconds, backend: backend_seconds },
        reached,
        e_rms,
        columns: run.state.cost[Unit::Columns],
        steps: run.state.step,
        termination: run.termination.to_string(),
        seconds,
        measurement,
        peak_rss: peak_rss(),
    })
}

/// A run timed from scene load, with every point's error against the reference
/// ([`recorded_run`]).
pub(crate) struct Recorded<'a> {
    pub run: Run,
    pub recorder: Recorder<'a>,
    /// Seconds from `start` to the end of the run, less the recorder's own.
    pub seconds: Real,
    /// The recorder's own seconds.
    pub measurement: Real,
}

/// Runs `solver` on `problem` under `rules`, recording e_rms against `star` after every step
/// (the `rms=` rule's monitor), timed from `start`.
pub(crate) fn recorded_run<'a>(
    system: &'a LinearSystem,
    star: &'a [Real],
    start: Instant,
    solver: &mut dyn Solver,
    rules: StopRules,
    problem: &Problem<'_>,
) -> Result<Recorded<'a>, LabError> {
    let mut recorder = Recorder::errors(system, star, start);
    let mut monitor = recorder.monitor().expect("a recorder of errors has a reference");
    let run = Executor::new(solver, rules)
        .monitor(&mut monitor)
        .add_observer(&mut recorder, ObserverMode::Always)
        .run(problem)?;
    let measurement = recorder.overhead();
    Ok(Recorded { run, recorder, seconds: start.elapsed().as_secs_f64() - measurement, measurement })
}

/// Refuses a reference that is not one of `system`'s.
pub(crate) fn check_reference(system: &LinearSystem, star: &[Real]) -> Result<(), LabError> {
    let expected = system.len() * system.channels().count();
    if star.len() == expected {
        Ok(())
    } else {
        Err(LabError::Invalid(format!(
            "the reference has {} values, not the {expected} of this scene's system",
            star.len()
        )))
    }
}

/// The section's figures besides its Markdown: what the targets are judged on.
#[derive(Debug)]
pub struct E2eSection {
    /// The section, headed `## 4. End-to-end time to accuracy, and 5. peak memory`.
    pub markdown: String,
    /// One entry per case.
    pub json: Vec<E2eJson>,
    /// The fastest case to each threshold of [`THRESHOLDS`]: (threshold, `"method over
    /// backend"`, median seconds), `None` where no case reached it in every run.
    pub fastest: Vec<(Real, String, Option<Real>)>,
    /// The largest peak resident memory of a run, and its case.
    pub peak_memory: Option<(u64, String)>,
}

/// How the reference of the runs was solved, for the section's text.
#[derive(Clone, Debug)]
pub struct ReferenceNote {
    /// The method, as [`crate::ReferenceSolution::method`] shows it.
    pub method: String,
    /// Its certificate, as shown.
    pub certificate: String,
    /// The seconds it took.
    pub seconds: Real,
}

/// The section from the runs of each case `(solver, backend)`, stopped after `max_seconds`.
pub fn report(
    cases: &[(String, String)],
    results: &[Vec<EndToEndReport>],
    reference: &ReferenceNote,
    max_seconds: Real,
) -> E2eSection {
    let mut section = E2eSection { markdown: String::new(), json: Vec::new(), fastest: Vec::new(), peak_memory: None };
    let ReferenceNote { method, certificate, seconds: reference_seconds } = reference;
    let mut out = String::from("## 4. End-to-end time to accuracy, and 5. peak memory\n\n");
    let _ = writeln!(
        out,
        "Wall time from the start of the scene load (load, BVH, analysis, form-factor setup, solve) until e_rms \
         first falls to each threshold, measured in a child process per run, the time spent measuring e_rms taken \
         out. Analytic form factors at their defaults; `matrix` assembles them all first, each pair once by \
         reciprocity and fresh (never from `target/ff-cache`), and its setup is that assembly. Runs stop at e_rms ≤ 1e-3 or after \
         {} s of solver time. Peak memory is the child's `VmHWM` (largest over the runs). Reference: {method}, \
         solved in {} before the runs; {certificate}.\n",
        sig(max_seconds, 3),
        duration(*reference_seconds),
    );
    out += "| method | backend | to 1e-1 | to 1e-2 | to 1e-3 | setup (scene + backend) | columns to 1e-3 | last e_rms | \
            peak memory |\n|---|---|--:|--:|--:|--:|--:|--:|--:|\n";
    let mut fastest: Vec<(Real, String, Option<Real>)> = THRESHOLDS.iter().map(|&t| (t, String::new(), None)).collect();
    for ((solver, ff), runs) in cases.iter().zip(results) {
        let mut cells = Vec::new();
        for (k, &threshold) in THRESHOLDS.iter().enumerate() {
            let times: Vec<Real> = runs.iter().filter_map(|r| r.reached.get(k).map(|x| x.seconds)).collect();
            if times.len() == runs.len() {
                let s = median(&times);
                cells.push(duration(s));
                let best = &mut fastest[k];
                if best.2.is_none_or(|b| s < b) {
                    *best = (threshold, format!("{solver} over {ff}"), Some(s));
                }
            } else {
                cells.push(format!("not reached ({} of {} runs)", runs.len() - times.len(), runs.len()));
            }
        }
        let scene_setup = median(&runs.iter().map(|r| r.setup.scene).collect::<Vec<_>>());
        let backend_setup = median(&runs.iter().map(|r| r.setup.backend).collect::<Vec<_>>());
        let columns: Vec<Real> = runs.iter().filter_map(|r| r.reached.get(2).map(|x| x.columns as Real)).collect();
        let peak = runs.iter().filter_map(|r| r.peak_rss).max();
        if let Some(p) = peak {
            if section.peak_memory.as_ref().is_none_or(|(b, _)| p > *b) {
                section.peak_memory = Some((p, format!("{solver} over {ff}")));
            }
        }
        section.json.push(E2eJson {
            method: solver.clone(),
            backend: ff.clone(),
            clock: Clock::Measured.name().to_string(),
            seconds_to: THRESHOLDS
                .iter()
                .enumerate()
                .map(|(k, t)| {
                    let times: Vec<Real> = runs.iter().filter_map(|r| r.reached.get(k).map(|x| x.seconds)).collect();
                    (format!("{t:.0e}"), (times.len() == runs.len()).then(|| median(&times)))
                })
                .collect(),
            columns_to_1e_3: (columns.len() == runs.len()).then(|| median(&columns)),
            peak_bytes: peak,
        });
        let last = runs.last().map_or(Real::NAN, |r| r.e_rms);
        let _ = writeln!(
            out,
            "| `{solver}` | `{ff}` | {} | {} | {} | {} + {} | {} | {:.2e} | {} |",
            cells[0],
            cells[1],
            cells[2],
            duration(scene_setup),
            duration(backend_setup),
            if columns.len() == runs.len() { format!("{:.0}", median(&columns)) } else { "—".to_string() },
            last,
            peak.map_or("n/a".to_string(), human_bytes),
        );
    }
    let measurement = results.iter().flatten().map(|r| r.measurement).fold(0.0, Real::max);
    let _ = writeln!(
        out,
        "\nMeasuring e_rms after every step took at most {} of a run (taken out of the figures above).\n",
        duration(measurement)
    );
    section.fastest = fastest;
    section.markdown = out;
    section
}
