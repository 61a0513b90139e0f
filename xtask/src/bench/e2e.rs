//! Sections 4 and 5: wall time from scene load to e_rms ≤ 1e-1, 1e-2 and 1e-3, and the peak
//! resident memory of each run.
//!
//! Every run is a child process (this executable, `bench` with hidden arguments), so that its
//! peak memory is its own and nothing it allocates is left to the next. The child starts its
//! clock before loading the scene, and counts everything a user would wait for: load, BVH,
//! analysis, the backend's setup (for `matrix`, assembling the full matrix, always fresh,
//! never from the cache) and the solve. After every step the library's `Recorder` computes
//! e_rms against the reference the parent solved beforehand, and takes that measurement's
//! time out of its wall clock, which starts with the child's. It prints its figures as one JSON line, with `VmHWM` from `/proc/self/status`
//! (the high-water mark of its resident memory; absent where `/proc` is not).

use super::{Config, E2eJson, Findings, duration, human_bytes, median, progress, run_child, sig};
use crate::bars::Bars;
use crate::experiment::prepare;
use anyhow::{Context, Result, bail};
use radiosity_core::{LinearSystem, Real};
use radiosity_eval::backends::fresh_backend;
use radiosity_eval::lab::Recorder;
use radiosity_eval::metrics::errors_against;
use radiosity_eval::{Lab, LabOptions};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::{Executor, Problem, SolverRegistry, StopRules};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The e_rms thresholds timed, largest first; the runs stop at the last.
const THRESHOLDS: [Real; 3] = [1e-1, 1e-2, 1e-3];

/// When a run's e_rms first fell to a threshold.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Reached {
    e_rms: Real,
    /// Wall seconds from the start of the scene load, measurement excluded.
    seconds: Real,
    columns: u64,
    steps: u64,
}

/// Where a child's setup time went.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Setup {
    /// Load, BVH and analysis.
    scene: Real,
    /// The backend's setup (for `matrix`, the assembly).
    backend: Real,
}

/// What one child reports.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct ChildReport {
    setup: Setup,
    reached: Vec<Reached>,
    e_rms: Real,
    columns: u64,
    steps: u64,
    termination: String,
    /// Wall seconds of the whole run, measurement excluded.
    seconds: Real,
    /// Seconds spent measuring e_rms, taken out of every figure.
    measurement: Real,
    /// Peak resident memory in bytes.
    peak_rss: Option<u64>,
}

/// The high-water mark of this process's resident memory, in bytes (Linux).
pub(crate) fn peak_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.trim_start_matches("VmHWM:").trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kb * 1024)
}

/// Runs one end-to-end case in this process and prints its [`ChildReport`] as JSON.
pub(crate) fn child(scene: &str, solver: &str, ff: &str, reference: &Path, max_seconds: Real) -> Result<()> {
    let spec = BackendSpec::parse(ff)?;
    let rules = StopRules::parse(&format!("rms={},time={}ms", THRESHOLDS[2], (max_seconds * 1e3).ceil() as u64))?;
    let mut solver = SolverRegistry::builtin().build(solver)?;
    let bytes = std::fs::read(reference).with_context(|| format!("cannot read {}", reference.display()))?;
    let star: Vec<Real> =
        bytes.chunks_exact(8).map(|c| Real::from_le_bytes(c.try_into().expect("chunks of 8 bytes"))).collect();
    let start = Instant::now();
    let prepared = prepare(scene)?;
    let scene_seconds = start.elapsed().as_secs_f64();
    let system = LinearSystem::from_scene(&prepared.loaded.scene);
    if star.len() != system.len() * system.channels().count() {
        bail!("the reference in {} is not one of scene {scene}", reference.display());
    }
    let backend = fresh_backend(&prepared, &spec, &Bars::new())?;
    let order = radiosity_geom::spatial_order(&prepared.loaded.scene);
    let backend_seconds = start.elapsed().as_secs_f64() - scene_seconds;
    let problem = Problem::new(&system, &backend)?.with_patch_order(&order)?;
    let mut recorder = Recorder::errors(&system, &star, start);
    let run = Executor::new(solver.as_mut(), rules).run(&problem, &mut recorder)?;
    let measurement = recorder.overhead();
    let seconds = start.elapsed().as_secs_f64() - measurement;
    let mut reached = Vec::new();
    for threshold in THRESHOLDS {
        let Some(p) = recorder.points().iter().find(|p| p.e_rms <= threshold) else { break };
        reached.push(Reached { e_rms: threshold, seconds: p.wall, columns: p.columns, steps: p.step });
    }
    let e_rms = errors_against(&system, &star, &run.state.radiosity)?.e_rms;
    let report = ChildReport {
        setup: Setup { scene: scene_seconds, backend: backend_seconds },
        reached,
        e_rms,
        columns: run.state.columns,
        steps: run.state.step,
        termination: run.termination.to_string(),
        seconds,
        measurement,
        peak_rss: peak_rss(),
    };
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}

/// A file removed when dropped.
struct TempFile(PathBuf);

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// Runs one child and reads its report.
fn spawn(config: &Config, solver: &str, ff: &str, reference: &Path) -> Result<ChildReport> {
    let mut args: Vec<String> = ["bench", "--scene", &config.scene, "--child-solver", solver, "--child-ff", ff]
        .iter()
        .map(|s| s.to_string())
        .collect();
    args.extend(["--child-reference".to_string(), reference.display().to_string()]);
    args.extend(["--max-seconds".to_string(), config.max_seconds.to_string()]);
    run_child(&args, &format!("the end-to-end run of {solver} over {ff}"))
}

/// Runs sections 4 and 5.
pub(crate) fn run(config: &Config, prepared: &PreparedScene, findings: &mut Findings) -> Result<String> {
    let spinner = progress(1, "reference");
    spinner.set_message("solved once, outside every timed run");
    let start = Instant::now();
    let experiment = Lab::new(prepared, &BackendSpec::parse("analytic")?, LabOptions::default(), &Bars::new())?;
    let reference_seconds = start.elapsed().as_secs_f64();
    let reference = experiment.reference().context("the end-to-end runs need a reference")?;
    let method = reference.method().to_string();
    let certificate = reference.certificate().to_string();
    let file = TempFile(std::env::temp_dir().join(format!("radiosity-bench-reference-{}.bin", std::process::id())));
    let bytes: Vec<u8> = reference.values().iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&file.0, bytes).with_context(|| format!("cannot write {}", file.0.display()))?;
    // The stored reference matrix is not kept while the runs are timed.
    drop(experiment);
    spinner.finish_and_clear();

    let mut cases: Vec<(String, String)> = config.solvers.iter().map(|s| (s.clone(), "analytic".to_string())).collect();
    cases.push(("gauss-seidel".to_string(), "matrix".to_string()));
    let bar = progress((cases.len() * config.runs_heavy) as u64, "end-to-end");
    let mut results: Vec<Vec<ChildReport>> = Vec::new();
    for (solver, ff) in &cases {
        let mut runs = Vec::new();
        for r in 0..config.runs_heavy {
            bar.set_message(format!("{solver} over {ff}, run {}/{}", r + 1, config.runs_heavy));
            runs.push(spawn(config, solver, ff, &file.0)?);
            bar.inc(1);
        }
        results.push(runs);
    }
    bar.finish_and_clear();

    let mut out = String::from("## 4. End-to-end time to accuracy, and 5. peak memory\n\n");
    let _ = writeln!(
        out,
        "Wall time from the start of the scene load (load, BVH, analysis, form-factor setup, solve) until e_rms \
         first falls to each threshold, measured in a child process per run, the time spent measuring e_rms taken \
         out. Analytic form factors at their defaults; `matrix` assembles them all first, each pair once by \
         reciprocity and fresh (never from `target/ff-cache`), and its setup is that assembly. Runs stop at e_rms ≤ 1e-3 or after \
         {} s of solver time. Peak memory is the child's `VmHWM` (largest over the runs). Reference: {method}, \
         solved in {} before the runs; {certificate}.\n",
        sig(config.max_seconds, 3),
        duration(reference_seconds),
    );
    out += "| method | backend | to 1e-1 | to 1e-2 | to 1e-3 | setup (scene + backend) | columns to 1e-3 | last e_rms | \
            peak memory |\n|---|---|--:|--:|--:|--:|--:|--:|--:|\n";
    let mut fastest: Vec<(Real, String, Option<Real>)> = THRESHOLDS.iter().map(|&t| (t, String::new(), None)).collect();
    for ((solver, ff), runs) in cases.iter().zip(&results) {
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
            if findings.peak_memory.as_ref().is_none_or(|(b, _)| p > *b) {
                findings.peak_memory = Some((p, format!("{solver} over {ff}")));
            }
        }
        findings.json.e2e.push(E2eJson {
            method: solver.clone(),
            backend: ff.clone(),
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
    findings.fastest = fastest;
    Ok(out)
}
