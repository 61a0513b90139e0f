//! `cargo xtask solve --scene SCENE --solver SOLVER [--ff BACKEND] [--transport WHERE]
//! [--until RULES] [--reference KIND] [--json | --out FILE]`: runs one solver and reports its
//! error against the reference solution of the same discrete system, its certified bound, and
//! for a solver whose answer is an estimate its rays and standard error (docs/cli.md).
//!
//! Every argument is parsed before any geometry is built, so a typo fails at once. The
//! reference comes from the cache when it is there (then F is not assembled and the residual
//! reported is the solver's own), otherwise it is computed once, outside the run: from the
//! stored matrix, or by a long shooting run when the matrix does not fit
//! (`--reference auto|matrix|shooting|none`). With `none` there is no e_rms, only the
//! certified bound. The run's columns, steps and seconds are the solver's alone.

use crate::bars::Bars;
use crate::experiment::{SolveArgs, check_output_file, lab, prepare_over};
use anyhow::{Context, Result};
use radiosity_core::Real;
use radiosity_eval::rgb;
use radiosity_eval::{ColumnCost, Phase, Phases, RecordPlan, ReferenceMark, RunSummary};
use serde::Serialize;
use std::cell::RefCell;
use std::path::PathBuf;

/// Arguments of `solve`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub run: SolveArgs,
    #[command(flatten)]
    pub ranks: crate::ranks::RanksArg,
    /// Print the patches and the run's figures as JSON.
    #[arg(long, conflicts_with = "out")]
    json: bool,
    /// Write the JSON to this file instead of printing a summary.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Print on stderr where the time and memory went, phase by phase (also in the JSON).
    #[arg(long)]
    verbose: bool,
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
struct SolveJson<'a> {
    scene: &'a str,
    solver: &'a str,
    ff: String,
    /// Each rank's threads and the ranks: the run's configuration, for the projection.
    threads: usize,
    ranks: usize,
    patches: Vec<PatchJson>,
    stats: &'a RunSummary,
    /// Every phase before the output: its seconds and the peak memory when it ended.
    phases: &'a [Phase],
}

/// Runs `solve`.
pub fn run(args: &Args, ranks: &crate::ranks::Ranks) -> Result<()> {
    let (spec, solver, rules, kind) = args.run.check_on(ranks)?;
    if let Some(out) = &args.out {
        check_output_file(out)?;
    }
    let phases = RefCell::new(Phases::new());
    let world = ranks.world();
    let prepared = prepare_over(&args.run.scene, Some(&phases), world.as_deref())?;
    phases.borrow_mut().begin("setting up the backend");
    // One solver's run: its columns are computed (and timed), whether or not the reference
    // was cached and the matrix assembled.
    let transport = args.run.transport.transport;
    let bars = Bars::new();
    let mark = ReferenceMark::new(&bars);
    let mut lab = lab(&prepared, &spec, false, kind, ColumnCost::Computed, transport, &mark)?;
    if let Some((at, peak)) = mark.began() {
        phases.borrow_mut().begin_at("setting up the reference", at, peak);
    }
    if let Some(world) = world.clone() {
        // The solvers that sample transport divide their rays between the ranks.
        lab = lab.over_ranks(world);
    }
    let traffic = lab.traffic();
    // Built and referenced: a run that casts no ray through the scene frees its BVH.
    let released = lab.release_rays(solver.as_deref());
    phases.borrow_mut().begin("solving");
    let (summary, state) = match solver {
        // `reference` is the exact solution itself: its cost is assembling F and solving it.
        None => {
            let state = lab.reference_state()?;
            (lab.reference_summary(&state)?, state)
        }
        Some(mut solver) => {
            let o = lab.run(solver.as_mut(), &rules, &RecordPlan::errors_only(), &Bars::new())?;
            if let Some(note) = o.cap_note() {
                eprintln!("warning: {note}");
            }
            (lab.summary(&o, rules.needs_error()), o.state)
        }
    };
    let summary = RunSummary { ranks: traffic.and_then(|before| lab.rank_reports(before, &summary)), ..summary };
    let scene = prepared.scene();
    phases.borrow_mut().begin("writing the output");
    let verbose = || {
        phases.borrow_mut().end();
        if args.verbose && ranks.reports() {
            eprint!("{}", phases.borrow().text());
            let held = prepared.memory();
            let per = |bytes: usize| bytes as f64 / prepared.scene().len().max(1) as f64;
            match released {
                0 => eprintln!(
                    "held         the scene {:.0} and its BVH {:.0} bytes a patch",
                    per(held.scene),
                    per(held.bvh)
                ),
                freed => eprintln!(
                    "held         the scene {:.0} bytes a patch; its BVH ({:.0}) released before the solve, which casts \
                     no ray through it",
                    per(held.scene),
                    per(freed)
                ),
            }
        }
    };
    if !args.json && args.out.is_none() {
        print!("{}", summary.text(&args.run.scene, scene.len(), lab.backend()));
        verbose();
        return Ok(());
    }
    let patches = scene
        .patches()
        .iter()
        .zip(rgb(&state))
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
    let done = phases.borrow().list().to_vec();
    let json = SolveJson {
        scene: &args.run.scene,
        solver: &summary.solver,
        ff: lab.backend().to_string(),
        threads: rayon::current_num_threads(),
        ranks: world.as_ref().map_or(1, |w| w.ranks()),
        patches,
        stats: &summary,
        phases: &done,
    };
    let text = serde_json::to_string(&json)?;
    match &args.out {
        // Distributed, rank 0 alone writes.
        Some(path) if ranks.reports() => {
            std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?
        }
        Some(_) => {}
        None => println!("{text}"),
    }
    verbose();
    Ok(())
}
