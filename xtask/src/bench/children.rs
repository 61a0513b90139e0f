//! The end-to-end and scale sections, each case in a child process of its own (this
//! executable, `bench` with hidden arguments), so that its peak memory is its own and nothing
//! it allocates is left to the next. The child measures with the library
//! ([`radiosity_eval::bench::e2e::time_to_accuracy`], [`radiosity_eval::bench::scale::scale_run`])
//! and prints its report as one JSON line, which the parent reads back.

use super::{Config, Findings, progress};
use crate::bars::Bars;
use crate::experiment::prepare;
use anyhow::{Context, Result, bail};
use radiosity_core::Real;
use radiosity_eval::bench::e2e::{self, EndToEndReport, ReferenceNote};
use radiosity_eval::bench::scale::{self, ScaleReport};
use radiosity_eval::bench::stochastic;
use radiosity_eval::{Lab, LabOptions};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::SolverRegistry;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Runs this executable again with `args` and reads the JSON line it prints last; `what` names
/// the case in errors.
fn run_child<T: serde::de::DeserializeOwned>(args: &[String], what: &str) -> Result<T> {
    let exe = std::env::current_exe().context("cannot find this executable to run the child cases")?;
    let output = std::process::Command::new(exe).args(args).output().with_context(|| format!("cannot start {what}"))?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let why = stderr.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("no message");
        bail!("{what} failed: {}", why.trim_start_matches("error: "));
    }
    let stdout = String::from_utf8_lossy(&output.stdout);
    let line = stdout.lines().rev().find(|l| l.starts_with('{')).unwrap_or_default();
    serde_json::from_str(line).with_context(|| format!("{what} printed no report"))
}

/// The child of an end-to-end case: loads the scene on the clock, runs the case and prints
/// its report.
pub(crate) fn e2e_child(scene: &str, solver: &str, ff: &str, reference: &Path, max_seconds: Real) -> Result<()> {
    let spec = BackendSpec::parse(ff)?;
    let mut solver = SolverRegistry::builtin().build(solver)?;
    let star = read_reference(reference)?;
    let start = Instant::now();
    let prepared = prepare(scene)?;
    let scene_seconds = start.elapsed().as_secs_f64();
    let report = e2e::time_to_accuracy(&prepared, start, scene_seconds, solver.as_mut(), &spec, &star, max_seconds)?;
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}

/// The child of a stochastic case: loads the scene on the clock and runs `solver` with rays
/// in it, or over the backend `ff`.
pub(crate) fn sampled_child(
    scene: &str,
    solver: &str,
    ff: Option<&str>,
    reference: &Path,
    max_seconds: Real,
) -> Result<()> {
    let mut solver = SolverRegistry::builtin().build(solver)?;
    let case = match ff {
        None => stochastic::Case::Rays,
        Some(ff) => stochastic::Case::Backend(BackendSpec::parse(ff)?),
    };
    let star = read_reference(reference)?;
    let start = Instant::now();
    let prepared = prepare(scene)?;
    let scene_seconds = start.elapsed().as_secs_f64();
    let report = stochastic::sampled_run(&prepared, start, scene_seconds, solver.as_mut(), &case, &star, max_seconds)?;
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}

/// A reference solution written by [`write_reference`].
fn read_reference(path: &Path) -> Result<Vec<Real>> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    Ok(bytes.chunks_exact(8).map(|c| Real::from_le_bytes(c.try_into().expect("chunks of 8 bytes"))).collect())
}

/// The child of a scale case: `solver` over the backend `ff`.
pub(crate) fn scale_child(scene: &str, solver: &str, ff: &str, max_seconds: Real) -> Result<()> {
    let spec = BackendSpec::parse(ff)?;
    let mut solver = SolverRegistry::builtin().build(solver)?;
    let start = Instant::now();
    let prepared = prepare(scene)?;
    let scene_seconds = start.elapsed().as_secs_f64();
    let report = scale::scale_run(&prepared, start, scene_seconds, solver.as_mut(), &spec, max_seconds)?;
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

/// The analytic reference of `prepared`, solved (or read from the cache) once, outside every
/// timed run, written to a file the children read, with how it was solved.
fn write_reference(prepared: &PreparedScene) -> Result<(TempFile, ReferenceNote)> {
    let spinner = progress(1, "reference");
    spinner.set_message("solved once, outside every timed run");
    let start = Instant::now();
    let experiment = Lab::new(prepared, &BackendSpec::parse("analytic")?, LabOptions::default(), &Bars::new())?;
    let seconds = start.elapsed().as_secs_f64();
    let reference = experiment.reference().context("the timed runs need a reference")?;
    let note = ReferenceNote {
        method: reference.method().to_string(),
        certificate: reference.certificate().to_string(),
        seconds,
    };
    let file = TempFile(std::env::temp_dir().join(format!("radiosity-bench-reference-{}.bin", std::process::id())));
    let bytes: Vec<u8> = reference.values().iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&file.0, bytes).with_context(|| format!("cannot write {}", file.0.display()))?;
    // The stored reference matrix is not kept while the runs are timed.
    drop(experiment);
    spinner.finish_and_clear();
    Ok((file, note))
}

/// Runs the end-to-end section: the reference once, outside every timed run, then every case
/// `--runs` times in its own process.
pub(crate) fn e2e(config: &Config, prepared: &PreparedScene, findings: &mut Findings) -> Result<String> {
    let (file, note) = write_reference(prepared)?;

    let mut cases: Vec<(String, String)> = config.solvers.iter().map(|s| (s.clone(), "analytic".to_string())).collect();
    cases.push(("gauss-seidel".to_string(), "matrix".to_string()));
    let bar = progress((cases.len() * config.runs_heavy) as u64, "end-to-end");
    let mut results: Vec<Vec<EndToEndReport>> = Vec::new();
    for (solver, ff) in &cases {
        let mut runs = Vec::new();
        for r in 0..config.runs_heavy {
            bar.set_message(format!("{solver} over {ff}, run {}/{}", r + 1, config.runs_heavy));
            let mut args: Vec<String> = ["bench", "--scene", &config.scene, "--child-solver", solver, "--child-ff", ff]
                .iter()
                .map(|s| s.to_string())
                .collect();
            args.extend(["--child-reference".to_string(), file.0.display().to_string()]);
            args.extend(["--max-seconds".to_string(), config.max_seconds.to_string()]);
            runs.push(run_child(&args, &format!("the end-to-end run of {solver} over {ff}"))?);
            bar.inc(1);
        }
        results.push(runs);
    }
    bar.finish_and_clear();
    let section = e2e::report(&cases, &results, &note, config.max_seconds);
    findings.fastest = section.fastest;
    findings.peak_memory = section.peak_memory;
    findings.json.e2e = section.json;
    Ok(section.markdown)
}

/// Runs the stochastic section on RenderPark's classroom (`--scene` otherwise; with `--quick`
/// a small Cornell box): the analytic reference once, then every solver (`--solvers`, or
/// [`stochastic::SOLVERS`]) with rays in the scene and every comparator
/// ([`stochastic::COMPARATORS`]) `--runs` times in its own process.
pub(crate) fn stochastic(config: &Config, findings: &mut Findings) -> Result<String> {
    let scene = config.stochastic_scene.clone();
    let prepared = prepare(&scene)?;
    let (file, note) = write_reference(&prepared)?;
    let mut cases: Vec<(String, Option<String>)> =
        config.stochastic_solvers.iter().map(|s| (s.clone(), None)).collect();
    cases.extend(stochastic::COMPARATORS.iter().map(|(s, ff)| (s.to_string(), Some(ff.to_string()))));
    let bar = progress((cases.len() * config.runs_heavy) as u64, "stochastic");
    let mut results: Vec<Vec<stochastic::SampledReport>> = Vec::new();
    let mut inapplicable: Vec<(String, String)> = Vec::new();
    for (solver, ff) in &cases {
        let mut runs = Vec::new();
        // A method that does not apply to this scene (a control variate on an open one) is
        // reported as such, not run.
        if ff.is_none() {
            if let Some(why) = stochastic::refusal(&prepared, SolverRegistry::builtin().build(solver)?.as_ref())? {
                inapplicable.push((solver.clone(), why));
                bar.inc(config.runs_heavy as u64);
                results.push(runs);
                continue;
            }
        }
        for r in 0..config.runs_heavy {
            bar.set_message(format!("{solver}, run {}/{}", r + 1, config.runs_heavy));
            let mut args: Vec<String> = [
                "bench",
                "--scene",
                &scene,
                "--child-sampled",
                solver,
                "--child-reference",
                &file.0.display().to_string(),
                "--max-seconds",
                &config.sampled_seconds.to_string(),
            ]
            .iter()
            .map(|s| s.to_string())
            .collect();
            if let Some(ff) = ff {
                args.extend(["--child-ff".to_string(), ff.clone()]);
            }
            runs.push(run_child(&args, &format!("the stochastic section's run of {solver}"))?);
            bar.inc(1);
        }
        results.push(runs);
    }
    bar.finish_and_clear();
    let section = stochastic::report(
        &scene,
        prepared.loaded.scene.len(),
        &cases,
        &results,
        &inapplicable,
        &note,
        config.sampled_seconds,
    );
    findings.json.stochastic = section.json;
    Ok(section.markdown)
}

/// Runs the scale section, every case `--runs` times in its own process.
pub(crate) fn scale(config: &Config) -> Result<String> {
    let scenes: Vec<&str> = if config.quick { vec!["cornell:res=4", "cornell:res=8"] } else { scale::SCENES.to_vec() };
    // The `--solvers` over the analytic backend, then the hierarchical operator's methods.
    let mut cases: Vec<(&str, String)> = config.solvers.iter().map(|s| ("analytic", s.clone())).collect();
    cases.extend(scale::HIERARCHICAL_SOLVERS.iter().map(|s| ("hierarchical", s.to_string())));
    let bar = progress((scenes.len() * cases.len() * config.runs_heavy) as u64, "scale");
    let mut rows = Vec::new();
    for (ff, solver) in &cases {
        for scene in &scenes {
            let mut runs: Vec<ScaleReport> = Vec::new();
            for r in 0..config.runs_heavy {
                bar.set_message(format!("{solver} over {ff} on {scene}, run {}/{}", r + 1, config.runs_heavy));
                let seconds = config.scale_seconds.to_string();
                let args =
                    ["bench", "--scene", scene, "--child-scale", solver, "--child-ff", ff, "--max-seconds", &seconds];
                let what = format!("the scale run of {solver} over {ff} on {scene}");
                runs.push(run_child(&args.map(String::from), &what)?);
                bar.inc(1);
            }
            rows.push((scene.to_string(), ff.to_string(), solver.clone(), runs));
        }
    }
    bar.finish_and_clear();
    Ok(scale::report(&rows, config.scale_seconds))
}
