//! `cargo xtask solve --scene SCENE --solver SOLVER [--ff BACKEND] [--until RULES]
//! [--json | --out FILE]`: runs one solver and reports its error against the reference
//! solution of the same discrete system (DESIGN §7).
//!
//! Order of work: every argument is parsed before any geometry is built, so a typo fails at
//! once. Then the scene is prepared, F fetched once (every column, outside the run's
//! accounting) to solve the reference and later to measure the final residual, and the
//! solver run under the stop rules. The run's columns, steps and seconds are the solver's
//! alone.

use crate::experiment::{Experiment, SolveArgs, check_output_file, require_emitters, rgb};
use crate::scene_report::{prepare, print_warnings};
use anyhow::{Context, Result};
use radiosity_core::{LinearSystem, Real};
use radiosity_eval::metrics::errors;
use radiosity_eval::{Evaluator, ReferenceSolution};
use radiosity_solvers::{Observer, State};
use serde::Serialize;
use std::path::PathBuf;

/// Arguments of `solve`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    run: SolveArgs,
    /// Print the patches and the run's figures as JSON.
    #[arg(long, conflicts_with = "out")]
    json: bool,
    /// Write the JSON to this file instead of printing a summary.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
}

/// Computes `e_rms` against the reference between steps, when a rule needs it, and records
/// when it first fell to each power of ten.
struct RmsObserver<'a> {
    system: &'a LinearSystem,
    reference: &'a ReferenceSolution,
    needed: bool,
    reached: Vec<ReachedJson>,
}

/// Where a run stood when its `e_rms` first fell to `e_rms`.
#[derive(Serialize)]
struct ReachedJson {
    e_rms: Real,
    steps: u64,
    columns: u64,
    seconds: Real,
}

impl Observer for RmsObserver<'_> {
    fn observe(&mut self, state: &State) -> Option<Real> {
        if !self.needed {
            return None;
        }
        let e_rms = errors(self.system, self.reference, &state.radiosity).ok()?.e_rms;
        // Powers of ten from 1e-1 down to 1e-15, each recorded once, in order.
        let power = |k: usize| 10f64.powi(-(k as i32) - 1);
        while self.reached.len() < 15 && e_rms <= power(self.reached.len()) {
            let seconds = state.ff_seconds + state.solve_seconds;
            let e_rms = power(self.reached.len());
            self.reached.push(ReachedJson { e_rms, steps: state.step, columns: state.columns, seconds });
        }
        Some(e_rms)
    }
}

#[derive(Serialize)]
struct PatchJson {
    id: usize,
    area: Real,
    centroid: [Real; 3],
    normal: [Real; 3],
    reflectivity: [Real; 3],
    emission: [Real; 3],
    radiosity: [Real; 3],
}

#[derive(Serialize)]
struct StatsJson {
    columns: u64,
    columns_reused: u64,
    steps: u64,
    seconds: Real,
    ff_seconds: Real,
    group_seconds: Real,
    e_rms: Real,
    e_max: Real,
    residual: Real,
    termination: String,
    /// With an `rms=` rule: the first step at which `e_rms` fell to each power of ten.
    reached: Vec<ReachedJson>,
    reference: String,
    certificate: String,
}

#[derive(Serialize)]
struct SolveJson<'a> {
    scene: &'a str,
    solver: String,
    ff: String,
    patches: Vec<PatchJson>,
    stats: StatsJson,
}

/// Runs `solve`.
pub fn run(args: &Args) -> Result<()> {
    let (spec, rules) = args.run.check()?;
    if let Some(out) = &args.out {
        check_output_file(out)?;
    }
    // `reference` is the exact solution itself: its cost is assembling F and solving it.
    let exact = args.run.solver == "reference";
    let prepared = prepare(&args.run.scene)?;
    print_warnings(&prepared.report());
    require_emitters(&prepared)?;
    let experiment = Experiment::new(&prepared, spec)?;
    if exact {
        let run = Outcome { state: experiment.exact_state(), termination: None, solver: "reference".into() };
        return report(args, &experiment, run, Vec::new());
    }
    let mut observer = RmsObserver {
        system: &experiment.system,
        reference: &experiment.reference,
        needed: rules.needs_error(),
        reached: Vec::new(),
    };
    let run = experiment.run(&args.run.solver, rules, &mut observer)?;
    let run = Outcome { state: run.state, termination: Some(run.termination.to_string()), solver: run.solver };
    report(args, &experiment, run, observer.reached)
}

/// What a run left, for the report: the exact reference has no termination.
struct Outcome {
    state: State,
    termination: Option<String>,
    solver: String,
}

/// Prints the summary or writes the JSON of a run.
fn report(args: &Args, experiment: &Experiment<'_>, run: Outcome, reached: Vec<ReachedJson>) -> Result<()> {
    let (system, reference, spec) = (&experiment.system, &experiment.reference, &experiment.spec);
    let scene = &experiment.prepared.loaded.scene;
    let metrics = Evaluator::new(system, &experiment.matrix, reference)?.evaluate(&run.state.radiosity)?;
    let stats = StatsJson {
        columns: run.state.columns,
        columns_reused: run.state.columns_reused,
        steps: run.state.step,
        seconds: run.state.ff_seconds + run.state.solve_seconds,
        ff_seconds: run.state.ff_seconds,
        group_seconds: run.state.group_seconds,
        e_rms: metrics.e_rms,
        e_max: metrics.e_max,
        residual: metrics.residual,
        termination: run.termination.unwrap_or_else(|| format!("solved exactly: {}", reference.method())),
        reached,
        reference: reference.method().to_string(),
        certificate: reference.certificate().to_string(),
    };
    if !args.json && args.out.is_none() {
        println!("scene        {}: {} patches", args.run.scene, scene.len());
        println!("solver       {} with {}", run.solver, spec.canonical());
        println!("stopped      {}", stats.termination);
        let reused = match stats.columns_reused {
            0 => String::new(),
            k => format!(" (and {k} served again from memory)"),
        };
        println!(
            "work         {} steps, {} columns{reused}, {:.3} s ({:.3} s in form factors)",
            stats.steps, stats.columns, stats.seconds, stats.ff_seconds
        );
        if stats.group_seconds > 0.0 {
            println!(
                "groups       {:.3} s solving groups, {:.2}% of the run",
                stats.group_seconds,
                100.0 * stats.group_seconds / stats.seconds
            );
        }
        println!(
            "error        e_rms {:.4e}, e_max {:.4e}, residual power {:.4e}",
            stats.e_rms, stats.e_max, stats.residual
        );
        for r in &stats.reached {
            println!(
                "reached      e_rms {:.0e} after {} steps, {} columns, {:.3} s",
                r.e_rms, r.steps, r.columns, r.seconds
            );
        }
        println!("reference    {}; {}", stats.reference, stats.certificate);
        return Ok(());
    }
    let patches = scene
        .patches()
        .iter()
        .zip(rgb(&run.state))
        .enumerate()
        .map(|(i, (p, radiosity))| PatchJson {
            id: i,
            area: p.area(),
            centroid: p.centroid().to_array(),
            normal: p.normal().to_array(),
            reflectivity: scene.reflectivity(i).0,
            emission: scene.emission(i).0,
            radiosity,
        })
        .collect();
    let json = SolveJson { scene: &args.run.scene, solver: run.solver.clone(), ff: spec.canonical(), patches, stats };
    let text = serde_json::to_string(&json)?;
    match &args.out {
        Some(path) => std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?,
        None => println!("{text}"),
    }
    Ok(())
}
