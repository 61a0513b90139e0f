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
use crate::experiment::{SolveArgs, check_output_file, lab, prepare};
use anyhow::{Context, Result};
use radiosity_core::Real;
use radiosity_eval::bench::report_text::human_bytes;
use radiosity_eval::rgb;
use radiosity_eval::value_cell;
use radiosity_eval::{FinalMetrics, RankReport, RecordPlan};
use radiosity_solvers::State;
use radiosity_solvers::{Record, Value};
use serde::Serialize;
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
}

/// Where a run stood when its `e_rms` first fell to `e_rms`.
#[derive(Serialize)]
struct ReachedJson {
    e_rms: Real,
    steps: u64,
    columns: u64,
    rays: u64,
    seconds: Real,
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
    /// The clock of every seconds figure ([`radiosity_core::Clock::name`]): `measured`, or
    /// `charged` when the columns were read from the stored matrix and charged.
    clock: &'static str,
    columns: u64,
    columns_reused: u64,
    /// Products `F x` the backend computed itself (a stored matrix's, the hierarchical
    /// operator's), beside the columns.
    products: u64,
    steps: u64,
    /// Rays cast by a solver that samples transport.
    rays: u64,
    /// Links of the hierarchy touched (0 over a backend that shows none).
    links: u64,
    seconds: Real,
    ff_seconds: Real,
    group_seconds: Real,
    #[serde(skip_serializing_if = "Option::is_none")]
    e_rms: Option<Real>,
    #[serde(skip_serializing_if = "Option::is_none")]
    e_max: Option<Real>,
    /// The residual power of the displayed radiosity, or else the solver's own.
    residual: Option<Real>,
    /// Which vector `residual` is the residual of.
    residual_of: String,
    /// The certified bound on the area-weighted L1 error of the displayed radiosity, relative
    /// to the reference's (null when the solver knows none and F is not kept).
    bound: Option<Real>,
    /// The solver's standard error of the displayed radiosity, relative as e_rms is (null when
    /// the solver has none): a spread of independent replicates, not a promise.
    standard_error: Option<Real>,
    /// The replicates the standard error rests on (null without one).
    replicates: Option<usize>,
    /// Where the rays were cast (`scene` or `matrix`), when the solver samples transport.
    #[serde(skip_serializing_if = "Option::is_none")]
    transport: Option<&'static str>,
    termination: String,
    /// With an `rms=` rule: the first step at which `e_rms` fell to each power of ten.
    reached: Vec<ReachedJson>,
    /// The solver's own figures (group steps, sizes, condition numbers, fallbacks).
    record: serde_json::Map<String, serde_json::Value>,
    reference: ReferenceJson,
    /// What building the backend cost, when it says (the hierarchical operator): seconds,
    /// bytes held, and its summary; distributed, the slowest rank's seconds and the bytes of
    /// all ranks.
    #[serde(skip_serializing_if = "Option::is_none")]
    operator: Option<OperatorJson>,
    /// Each rank's part, when the run was distributed over MPI ranks.
    #[serde(skip_serializing_if = "Option::is_none")]
    ranks: Option<Vec<RankReport>>,
}

/// What building the backend cost ([`radiosity_ff::BackendFigures`]).
#[derive(Serialize)]
struct OperatorJson {
    build_seconds: Real,
    bytes: usize,
    /// Of them, the links' (the hierarchical operator's `link bytes`).
    #[serde(skip_serializing_if = "Option::is_none")]
    link_bytes: Option<Real>,
    summary: String,
}

/// The reference a run was measured against.
#[derive(Serialize)]
struct ReferenceJson {
    /// `matrix`, `shooting` or `none`.
    kind: String,
    /// Why it was chosen.
    why: String,
    /// How it was computed, unless `none`.
    #[serde(skip_serializing_if = "Option::is_none")]
    method: Option<String>,
    /// Its certificate, unless `none`.
    #[serde(skip_serializing_if = "Option::is_none")]
    certificate: Option<String>,
}

#[derive(Serialize)]
struct SolveJson<'a> {
    scene: &'a str,
    solver: String,
    ff: String,
    patches: Vec<PatchJson>,
    stats: StatsJson,
}

/// What a run left, for the report.
struct Outcome {
    solver: String,
    state: State,
    termination: String,
    last: FinalMetrics,
    reached: Vec<ReachedJson>,
    record: Record,
}

/// A record value as JSON: counts and finite reals as numbers, anything else as text.
fn json_value(v: &Value) -> serde_json::Value {
    match v {
        Value::Count(c) => (*c).into(),
        Value::Real(r) if r.is_finite() => (*r).into(),
        other => other.to_string().into(),
    }
}

/// Runs `solve`.
pub fn run(args: &Args, ranks: &crate::ranks::Ranks) -> Result<()> {
    let (spec, solver, rules, kind) = args.run.check_on(ranks)?;
    if let Some(out) = &args.out {
        check_output_file(out)?;
    }
    let prepared = prepare(&args.run.scene)?;
    // One solver's run: its columns are computed (and timed), whether or not the reference
    // was cached and the matrix assembled.
    let transport = args.run.transport.transport;
    let lab = lab(&prepared, &spec, false, kind, radiosity_eval::ColumnCost::Computed, transport)?;
    let traffic = lab.traffic();
    let outcome = match solver {
        // `reference` is the exact solution itself: its cost is assembling F and solving it.
        None => Outcome {
            solver: "reference".into(),
            state: lab.reference_state()?,
            termination: format!(
                "solved exactly: {}",
                lab.reference().map(|r| r.method().to_string()).unwrap_or_default()
            ),
            last: lab.reference_metrics()?,
            reached: Vec::new(),
            record: Record::default(),
        },
        Some(mut solver) => {
            let plan = RecordPlan::errors_only();
            let o = lab.run(solver.as_mut(), &rules, &plan, &Bars::new())?;
            if let Some(note) = o.cap_note() {
                eprintln!("warning: {note}");
            }
            let reached = if rules.needs_error() {
                o.reached_powers()
                    .into_iter()
                    .map(|(e_rms, p)| ReachedJson {
                        e_rms,
                        steps: p.step,
                        columns: p.columns,
                        rays: p.rays,
                        seconds: p.seconds,
                    })
                    .collect()
            } else {
                Vec::new()
            };
            Outcome {
                solver: o.solver,
                state: o.state,
                termination: o.termination.to_string(),
                last: o.last,
                reached,
                record: o.record,
            }
        }
    };
    let reference = ReferenceJson {
        kind: lab.chosen().kind.to_string(),
        why: lab.chosen().why.clone(),
        method: lab.reference().map(|r| r.method().to_string()),
        certificate: lab.reference().map(|r| r.certificate().to_string()),
    };
    let no_f = match lab.reference() {
        Some(_) => "F was not assembled, the reference came from the cache",
        None => "F was not assembled: there is no reference",
    };
    let (residual, residual_of) = match (outcome.last.residual, outcome.last.solver_residual) {
        (Some(r), _) => (Some(r), "displayed radiosity".to_string()),
        (None, Some(_)) => (
            outcome.last.solver_residual,
            format!("the solver's own (for shooting methods, the shot radiosity); {no_f}"),
        ),
        (None, None) => (None, format!("not known: {no_f}")),
    };
    let s = &outcome.state;
    let stats = StatsJson {
        clock: lab.clock().name(),
        columns: s.columns,
        columns_reused: s.columns_reused,
        products: s.products,
        steps: s.step,
        rays: s.rays,
        links: s.links,
        seconds: s.ff_seconds + s.solve_seconds,
        ff_seconds: s.ff_seconds,
        group_seconds: s.group_seconds,
        e_rms: outcome.last.e_rms,
        e_max: outcome.last.e_max,
        residual,
        residual_of,
        bound: outcome.last.bound,
        standard_error: outcome.last.standard_error,
        replicates: outcome.last.replicates,
        transport: (s.rays > 0).then(|| lab.transport().name()),
        termination: outcome.termination.clone(),
        reached: outcome.reached,
        record: outcome.record.iter().map(|(k, v)| (k.to_string(), json_value(v))).collect(),
        reference,
        operator: lab.backend_figures().map(|f| OperatorJson {
            build_seconds: f.seconds,
            bytes: f.bytes,
            link_bytes: f.count("link bytes"),
            summary: f.summary.clone(),
        }),
        ranks: traffic.and_then(|before| lab.rank_reports(before, s.ff_seconds)),
    };
    let scene = prepared.scene();
    if !args.json && args.out.is_none() {
        println!("scene        {}: {} patches", args.run.scene, scene.len());
        match stats.transport {
            // A solver that samples transport casts rays; the backend only serves the reference.
            Some(transport) => println!(
                "solver       {} with rays ({transport}; the reference over {})",
                outcome.solver,
                lab.backend()
            ),
            None => println!("solver       {} with {}", outcome.solver, lab.backend()),
        }
        println!("stopped      {}", stats.termination);
        let reused = match stats.columns_reused {
            0 => String::new(),
            k => format!(" (and {k} served again from memory)"),
        };
        let products = match stats.products {
            0 => String::new(),
            k => format!(", {k} products"),
        };
        let links = match stats.links {
            0 => String::new(),
            k => format!(", {k} links"),
        };
        let (rays, in_ff) = match (stats.rays, stats.transport) {
            (0, _) => (String::new(), "in form factors"),
            (r, transport) => (format!(", {r} rays ({})", transport.unwrap_or_default()), "in form factors and rays"),
        };
        println!(
            "work         {} steps, {} columns{reused}{products}{links}{rays}, {:.3} s ({:.3} s {in_ff}; {} seconds)",
            stats.steps, stats.columns, stats.seconds, stats.ff_seconds, stats.clock
        );
        if stats.group_seconds > 0.0 {
            println!(
                "groups       {:.3} s solving groups, {:.2}% of the run",
                stats.group_seconds,
                100.0 * stats.group_seconds / stats.seconds
            );
        }
        let residual = match (outcome.last.residual, outcome.last.solver_residual) {
            (Some(r), _) => format!("residual power {r:.4e}"),
            (None, Some(r)) => {
                format!("the solver's own residual power {r:.4e} (for shooting, of the shot radiosity; {no_f})")
            }
            (None, None) => format!("residual not measured ({no_f})"),
        };
        let errors = match (stats.e_rms, stats.e_max) {
            (Some(r), Some(m)) => format!("e_rms {r:.4e}, e_max {m:.4e}, "),
            _ => "no e_rms (no reference), ".into(),
        };
        println!("error        {errors}{residual}");
        match stats.bound {
            Some(b) => println!("bound        certified relative L1 error ≤ {b:.4e}"),
            None => println!("bound        none: the solver knows no bound on its residual"),
        }
        if let Some(s) = stats.standard_error {
            let replicates = stats.replicates.map_or(String::new(), |r| format!(" of {r} independent replicates"));
            println!("spread       standard error {s:.4e}, relative as e_rms is{replicates} (a spread, not a bound)");
        }
        for r in &stats.reached {
            println!(
                "reached      e_rms {:.0e} after {} steps, {} columns, {:.3} s",
                r.e_rms, r.steps, r.columns, r.seconds
            );
        }
        if !outcome.record.is_empty() {
            let items: Vec<String> = outcome.record.iter().map(|(k, v)| format!("{k} {}", value_cell(v))).collect();
            println!("recorded     {}", items.join(", "));
        }
        for r in stats.ranks.iter().flatten() {
            println!(
                "rank {:<7} {} links ({} tasks, {:.1}% of the estimated cost), {} operator ({} of links) built in \
                 {:.2} s; peak memory {}; the run: {:.3} s in the operator, {:.3} s in {} sums, {} sent",
                r.rank,
                r.links,
                r.tasks,
                100.0 * r.estimated_share,
                human_bytes(r.operator_bytes),
                human_bytes(r.link_bytes),
                r.build_seconds,
                r.peak_rss.map_or("n/a".into(), human_bytes),
                r.run_operator_seconds,
                r.run_sum_seconds,
                r.run_sums,
                human_bytes(r.run_bytes_sent)
            );
        }
        let r = &stats.reference;
        match (&r.method, &r.certificate) {
            (Some(method), Some(certificate)) => {
                println!("reference    {} ({}): {method}; {certificate}", r.kind, r.why)
            }
            _ => println!("reference    none ({})", r.why),
        }
        return Ok(());
    }
    let patches = scene
        .patches()
        .iter()
        .zip(rgb(&outcome.state))
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
    let json =
        SolveJson { scene: &args.run.scene, solver: outcome.solver, ff: lab.backend().to_string(), patches, stats };
    let text = serde_json::to_string(&json)?;
    match &args.out {
        // Distributed, rank 0 alone writes.
        Some(path) if ranks.reports() => {
            std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?
        }
        Some(_) => {}
        None => println!("{text}"),
    }
    Ok(())
}
