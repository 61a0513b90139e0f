//! The end-to-end, stochastic and scale sections: each case in a child process of its own
//! (this executable, `bench` with hidden arguments, running a
//! [`ChildCase`](radiosity_eval::bench::children::ChildCase)), read back from the JSON line it
//! prints; and beside the stochastic section, the RenderPark build the user gave
//! ([`radiosity_eval::bench::peer`]). The cases, the reference and the reports are the
//! library's; this module spawns and shows progress.

use super::progress;
use crate::bars::Bars;
use crate::experiment::prepare;
use anyhow::{Context, Result, bail};
use radiosity_eval::bench::children::ReferenceFile;
use radiosity_eval::bench::e2e::{self, EndToEndReport};
use radiosity_eval::bench::peer::{self, PeerRun};
use radiosity_eval::bench::plan::{BenchConfig, Findings};
use radiosity_eval::bench::scale::{self, ScaleReport};
use radiosity_eval::bench::stochastic;
use radiosity_geom::{PreparedScene, SceneSpec, ScenesFolder};
use radiosity_solvers::SolverRegistry;

/// Runs this executable as `bench --scene SCENE --max-seconds S` with `args` after, and reads
/// the JSON line it prints last; `what` names the case in errors.
fn run_child<T: serde::de::DeserializeOwned>(scene: &str, seconds: f64, args: &[&str], what: &str) -> Result<T> {
    let exe = std::env::current_exe().context("cannot find this executable to run the child cases")?;
    let output = std::process::Command::new(exe)
        .args(["bench", "--scene", scene, "--max-seconds", &seconds.to_string()])
        .args(args)
        .output()
        .with_context(|| format!("cannot start {what}"))?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let why = stderr.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("no message");
        bail!("{what} failed: {}", why.trim_start_matches("error: "));
    }
    let stdout = String::from_utf8_lossy(&output.stdout);
    let line = stdout.lines().rev().find(|l| l.starts_with('{')).unwrap_or_default();
    serde_json::from_str(line).with_context(|| format!("{what} printed no report"))
}

/// The analytic reference of `prepared`, solved once outside every timed run, in a file.
fn reference(prepared: &PreparedScene) -> Result<ReferenceFile> {
    let spinner = progress(1, "reference");
    spinner.set_message("solved once, outside every timed run");
    let file = ReferenceFile::solve(prepared, &Bars::new())?;
    spinner.finish_and_clear();
    Ok(file)
}

/// Runs the end-to-end section: the reference once, then every case `--runs` times.
pub(crate) fn e2e(config: &BenchConfig, prepared: &PreparedScene, findings: &mut Findings) -> Result<String> {
    let file = reference(prepared)?;
    let path = file.path().display().to_string();
    let cases = config.e2e_cases();
    let bar = progress((cases.len() * config.runs_heavy) as u64, "end-to-end");
    let mut results: Vec<Vec<EndToEndReport>> = Vec::new();
    for (solver, ff) in &cases {
        let mut runs = Vec::new();
        for r in 0..config.runs_heavy {
            bar.set_message(format!("{solver} over {ff}, run {}/{}", r + 1, config.runs_heavy));
            let args = ["--child-solver", solver, "--child-ff", ff, "--child-reference", &path];
            let what = format!("the end-to-end run of {solver} over {ff}");
            runs.push(run_child(&config.scene, config.max_seconds, &args, &what)?);
            bar.inc(1);
        }
        results.push(runs);
    }
    bar.finish_and_clear();
    let section = e2e::report(&cases, &results, file.note(), config.max_seconds);
    findings.fastest = section.fastest;
    findings.peak_memory = section.peak_memory;
    findings.json.e2e = section.json;
    Ok(section.markdown)
}

/// Runs the stochastic section: the reference once, every case `--runs` times (a solver that
/// refuses the scene is reported, not run), then the RenderPark build, if given, as many times.
pub(crate) fn stochastic(config: &BenchConfig, findings: &mut Findings) -> Result<String> {
    let scene = &config.stochastic_scene;
    let prepared = prepare(scene)?;
    let file = reference(&prepared)?;
    let path = file.path().display().to_string();
    let cases = config.stochastic_cases();
    let bar = progress((cases.len() * config.runs_heavy) as u64, "stochastic");
    let (mut results, mut inapplicable) = (Vec::new(), Vec::new());
    for (solver, ff) in &cases {
        let mut runs: Vec<stochastic::SampledReport> = Vec::new();
        if ff.is_none() {
            if let Some(why) = stochastic::refusal(&prepared, SolverRegistry::builtin().build(solver)?.as_ref())? {
                inapplicable.push((solver.clone(), why));
            }
        }
        let applies = ff.is_some() || !inapplicable.iter().any(|(s, _)| s == solver);
        if !applies {
            bar.inc(config.runs_heavy as u64);
        }
        for r in (0..config.runs_heavy).filter(|_| applies) {
            bar.set_message(format!("{solver}, run {}/{}", r + 1, config.runs_heavy));
            let mut args = vec!["--child-sampled", solver, "--child-reference", &path];
            args.extend(ff.iter().flat_map(|ff| ["--child-ff", ff.as_str()]));
            let what = format!("the stochastic section's run of {solver}");
            runs.push(run_child(scene, config.sampled_seconds, &args, &what)?);
            bar.inc(1);
        }
        results.push(runs);
    }
    bar.finish_and_clear();
    let section = stochastic::report(
        scene,
        prepared.loaded.scene.len(),
        &cases,
        &results,
        &inapplicable,
        file.note(),
        config.sampled_seconds,
    );
    findings.json.stochastic = section.json;
    let (peer_markdown, peer_json) = renderpark(config)?;
    findings.json.peer = Some(peer_json);
    Ok(section.markdown + &peer_markdown)
}

/// RenderPark's cases on the stochastic section's scene file, `--runs` times each, when the
/// user gave a build; otherwise the section's sentence saying there is no peer measurement.
fn renderpark(config: &BenchConfig) -> Result<(String, peer::PeerJson)> {
    let Some(renderpark) = &config.peer else { return Ok(peer::report(None, &[], None)) };
    let spec = SceneSpec::parse(&config.stochastic_scene)?;
    let Some(file) = spec.file().filter(|f| f.extension().is_some_and(|e| e.eq_ignore_ascii_case("mgf"))) else {
        let why = format!("No peer measurement: RenderPark reads MGF files, and `{}` is not one.", spec);
        return Ok(peer::report(Some(renderpark), &[], Some(&why)));
    };
    let file = ScenesFolder::from_env().resolve(file);
    let bar = progress((peer::CASES.len() * config.runs_heavy) as u64, "renderpark");
    let mut runs = Vec::new();
    for case in &peer::CASES {
        let mut times = Vec::new();
        for r in 0..config.runs_heavy {
            bar.set_message(format!("{} × {}, run {}/{}", case.method, case.iterations, r + 1, config.runs_heavy));
            times.push(peer::run_case(renderpark, case, &file)?);
            bar.inc(1);
        }
        let command = peer::command(renderpark, case, &file);
        runs.push(PeerRun { method: case.method.into(), iterations: case.iterations, command, runs: times });
    }
    bar.finish_and_clear();
    Ok(peer::report(Some(renderpark), &runs, None))
}

/// Runs the scale section, every case `--runs` times.
pub(crate) fn scale(config: &BenchConfig) -> Result<String> {
    let (scenes, cases) = (config.scale_scenes(), config.scale_cases());
    let bar = progress((scenes.len() * cases.len() * config.runs_heavy) as u64, "scale");
    let mut rows = Vec::new();
    for (ff, solver) in &cases {
        for scene in &scenes {
            let mut runs: Vec<ScaleReport> = Vec::new();
            for r in 0..config.runs_heavy {
                bar.set_message(format!("{solver} over {ff} on {scene}, run {}/{}", r + 1, config.runs_heavy));
                let what = format!("the scale run of {solver} over {ff} on {scene}");
                let args = ["--child-scale", solver, "--child-ff", ff];
                runs.push(run_child(scene, config.scale_seconds, &args, &what)?);
                bar.inc(1);
            }
            rows.push((scene.clone(), ff.clone(), solver.clone(), runs));
        }
    }
    bar.finish_and_clear();
    Ok(scale::report(&rows, config.scale_seconds))
}
