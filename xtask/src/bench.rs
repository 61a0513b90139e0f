//! `cargo xtask bench [--out FILE.md] [--json FILE.json] [--quick] [--only SECTIONS] [--runs N]`:
//! the performance figures, as one Markdown report of medians over several runs, and with
//! `--json` the same medians under stable keys ([`BenchJson`]).
//!
//! The measurements, their medians, their Markdown and their JSON keys are the library's
//! ([`radiosity_eval::bench`]); this module parses the arguments, runs the sections with
//! progress bars, runs the end-to-end and scale cases in child processes ([`children`]) and
//! judges the targets. Form factors dominate the cost of radiosity, so speed is measured where
//! it is spent and against what limits it:
//!
//! 1. **`columns`**: form-factor columns per second for each backend on `office`, on 1 and 2
//!    threads (dedicated rayon pools), over a fixed, seeded sample of columns spread over the
//!    scene; beside them, rays per second for the **same rays** traced straight through the
//!    BVH, once through [`radiosity_geom::Visibility`] (the exact `f64` queries the backends
//!    call) and once with obvhs's own `f32` triangle test ([`radiosity_geom::visibility::RawTracer`]).
//!    The rays are listed by [`radiosity_ff::ColumnRays`] without computing the columns. The
//!    ratio of the rates is how close the pipeline gets to the ray-tracing limit.
//! 2. **`assembly`**: the time to assemble `office`'s full matrix with the analytic backend
//!    at k = 1 and k = 4 shadow rays per pair, each pair computed once
//!    ([`radiosity_ff::StoredMatrix::assemble_reciprocal`]), beside column-by-column assembly
//!    (what `--ff matrix` does); storage and bytes of the stored matrix, its row sums and
//!    reciprocity.
//! 3. **`lu`**: one group system `Φ_rr y = s` (with the second right-hand side of the condition
//!    estimate, as a group step solves it) for group sizes m = 20 to 500, nalgebra's LU against
//!    faer's ([`radiosity_core::dense_lu`], what the solvers use), on the synthetic
//!    labyrinth-sized system of the `group_solve` criterion bench.
//! 4. **`e2e`**: wall time from scene load (load, BVH, analysis, form-factor setup, solve) to
//!    e_rms ≤ 1e-1, 1e-2 and 1e-3 on `office`, for `pr`, `xu`, a group-accelerated variant and
//!    the full-matrix alternative (`gauss-seidel` over `--ff matrix`, assembled fresh, the
//!    assembly counted), each in a child process (this executable, re-invoked) whose **peak
//!    resident memory** (`VmHWM`) is reported too. The reference is solved once, before and
//!    outside every timed run, and handed to the children in a file; the children compute
//!    e_rms between steps and subtract that time from the wall time.
//!
//! 5. **`scale`** ([`scale`](radiosity_eval::bench::scale)): `office` at 10 990, 33 179 and
//!    95 832 patches and the largest real scene (`office.mgf` cut to 114 042 patches), each
//!    method in a child process with no reference and no matrix: setup, seconds per column, columns per second, peak memory,
//!    and wall time from scene load to a certified bound of 1e-1, 1e-2 and 1e-3, with the
//!    growth exponent of the time per column in `n`; then the same scenes over the
//!    hierarchical operator with `cg`, `gauss-seidel`, `xu` and `xu-g50-m500`: its build
//!    seconds, links and memory, the seconds of a product, and the wall times from scene load
//!    to bounds 1e-2 and 1e-3, with the growth of the build in `n`. Not part of a plain
//!    `cargo xtask bench`: it takes up to `--max-seconds` (default 120 s) per run and method
//!    and scene, about two hours at three runs; `--only scale --runs 1 --max-seconds 60
//!    --solvers cg` takes about half an hour.
//!
//! Each section's medians are over `--runs` runs (default 5 for `columns` and `lu`, 3 for
//! `assembly` and `e2e`). The report states the machine's core count and ends with the
//! performance targets beside the measurement.
//!
//! Reproduce with `cargo xtask bench --out bench.md` on a quiet machine (docs/bench-office.md's
//! stamp says how long a full run took; sections can be run alone with `--only columns,lu`).
//! `--quick` shrinks everything (a 171-patch Cornell box, a dozen columns, small backends, one
//! end-to-end run) into a smoke test of a few seconds whose figures mean nothing.

mod children;

use crate::bars::Bars;
use crate::experiment::check_output_file;
use crate::experiment::prepare;
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use radiosity_eval::bench::assembly::AssemblyParams;
use radiosity_eval::bench::columns::ColumnsParams;
use radiosity_eval::bench::lu::LuParams;
use radiosity_eval::bench::report_text::{duration, human_bytes, sig};
use radiosity_eval::bench::{BenchJson, Machine, SceneJson, assembly, columns, lu};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::PathBuf;

/// The sections, in report order.
const SECTIONS: [&str; 6] = ["columns", "assembly", "lu", "e2e", "scale", "stochastic"];

/// The sections a plain `cargo xtask bench` runs (`scale` and `stochastic` are asked for by
/// name).
const DEFAULT_SECTIONS: [&str; 4] = ["columns", "assembly", "lu", "e2e"];

/// Arguments of `bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Also write the Markdown report to this file.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Also write the figures as JSON to this file, under stable keys: `machine`, `columns`
    /// (backend, columns_per_second by thread count, rays_per_column, raw_share) and `e2e`
    /// (method, backend, seconds_to by e_rms, columns_to_1e-3, peak_bytes).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// A smoke test: a small scene, few columns, small backends, few runs (figures mean nothing).
    #[arg(long)]
    quick: bool,
    /// Only these sections, comma-separated: columns, assembly, lu, e2e (e2e includes memory),
    /// scale (not run by default: about two hours), stochastic (not run by default: the
    /// stochastic solvers on RenderPark's classroom, from the scenes folder).
    #[arg(long, value_name = "SECTIONS")]
    only: Option<String>,
    /// Runs per measurement (default 5 for columns and lu, 3 for assembly and e2e; with
    /// --quick 2 and 1).
    #[arg(long, value_name = "N")]
    runs: Option<usize>,
    /// The scene (default office; with --quick cornell:res=4).
    #[arg(long, value_name = "SCENE")]
    scene: Option<String>,
    /// Columns in the sample of the columns section (default 200; with --quick 12).
    #[arg(long, value_name = "N")]
    columns: Option<usize>,
    /// End-to-end solvers, besides the full-matrix alternative (default pr,xu,xu-g50-m500).
    #[arg(long, value_name = "S1,S2,…")]
    solvers: Option<String>,
    /// Longest solver time (form factors and solve) of one end-to-end run, in seconds
    /// (default 300, for scale 120; with --quick 60, for scale 5).
    #[arg(long, value_name = "SECONDS")]
    max_seconds: Option<f64>,
    /// Internal: run one end-to-end case in this process and print its figures as JSON.
    #[arg(long, hide = true, value_name = "SOLVER")]
    child_solver: Option<String>,
    /// Internal: the backend of the end-to-end or scale case.
    #[arg(long, hide = true, value_name = "BACKEND")]
    child_ff: Option<String>,
    /// Internal: the reference solution, raw little-endian f64.
    #[arg(long, hide = true, value_name = "FILE")]
    child_reference: Option<PathBuf>,
    /// Internal: run one scale case in this process and print its figures as JSON.
    #[arg(long, hide = true, value_name = "SOLVER")]
    child_scale: Option<String>,
    /// Internal: run one stochastic case (rays in the scene) and print its figures as JSON.
    #[arg(long, hide = true, value_name = "SOLVER")]
    child_sampled: Option<String>,
}

/// What every section is run with.
pub(crate) struct Config {
    quick: bool,
    scene: String,
    /// Runs of the cheap sections (columns, lu).
    runs_cheap: usize,
    /// Runs of the heavy sections (assembly, e2e).
    runs_heavy: usize,
    /// Columns in the sample of section 1.
    columns: usize,
    /// Backends of section 1.
    backends: Vec<String>,
    /// Shadow rays per pair in section 2.
    assembly_rays: Vec<usize>,
    /// Group sizes of section 3.
    group_sizes: Vec<usize>,
    /// Solvers of section 4, besides the full-matrix alternative.
    solvers: Vec<String>,
    /// Wall-time cap of one end-to-end run.
    max_seconds: f64,
    /// Solver-time cap of one scale run.
    scale_seconds: f64,
    /// The scene of the stochastic section.
    stochastic_scene: String,
    /// The solvers of the stochastic section.
    stochastic_solvers: Vec<String>,
    /// Solver-time cap of one stochastic run.
    sampled_seconds: f64,
    /// The shortest timed measurement in section 1: shorter ones are repeated.
    min_seconds: f64,
}

impl Config {
    fn new(args: &Args) -> Result<Config> {
        let quick = args.quick;
        if args.runs == Some(0) {
            bail!("--runs must be at least 1");
        }
        if args.columns == Some(0) {
            bail!("--columns must be at least 1");
        }
        if let Some(s) = args.max_seconds {
            if !(s.is_finite() && s > 0.0) {
                bail!("--max-seconds must be a positive number of seconds, not {s}");
            }
        }
        let default_solvers = if quick { "pr,xu,xu-g10-m40" } else { "pr,xu,xu-g50-m500" };
        let solvers: Vec<String> = args
            .solvers
            .as_deref()
            .unwrap_or(default_solvers)
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect();
        for s in &solvers {
            radiosity_solvers::SolverRegistry::builtin()
                .build(s)
                .context("--solvers names a solver that does not exist")?;
        }
        let backends = if quick {
            ["analytic", "hemicube:res=32", "montecarlo:rays=2000"]
        } else {
            ["analytic", "hemicube", "montecarlo"]
        };
        Ok(Config {
            quick,
            scene: args.scene.clone().unwrap_or_else(|| if quick { "cornell:res=4" } else { "office" }.to_string()),
            runs_cheap: args.runs.unwrap_or(if quick { 2 } else { 5 }),
            runs_heavy: args.runs.unwrap_or(if quick { 1 } else { 3 }),
            columns: args.columns.unwrap_or(if quick { 12 } else { 200 }),
            backends: backends.iter().map(|s| s.to_string()).collect(),
            assembly_rays: vec![1, 4],
            group_sizes: if quick { vec![20, 50] } else { vec![20, 50, 100, 200, 500] },
            solvers: solvers.clone(),
            max_seconds: args.max_seconds.unwrap_or(if quick { 60.0 } else { 300.0 }),
            scale_seconds: args.max_seconds.unwrap_or(if quick { 5.0 } else { 120.0 }),
            stochastic_scene: args.scene.clone().unwrap_or_else(|| {
                if quick { "cornell:res=4" } else { radiosity_eval::bench::stochastic::SCENE }.to_string()
            }),
            stochastic_solvers: match &args.solvers {
                Some(_) => solvers.clone(),
                None => radiosity_eval::bench::stochastic::SOLVERS.iter().map(|s| s.to_string()).collect(),
            },
            sampled_seconds: args.max_seconds.unwrap_or(if quick { 5.0 } else { 60.0 }),
            min_seconds: if quick { 0.05 } else { 0.2 },
        })
    }
}

/// Which sections to run, from `--only`.
fn sections(only: Option<&str>) -> Result<Vec<&'static str>> {
    let Some(only) = only else { return Ok(DEFAULT_SECTIONS.to_vec()) };
    let mut chosen = Vec::new();
    for name in only.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let Some(section) = SECTIONS.iter().find(|s| **s == name || (name == "memory" && **s == "e2e")) else {
            bail!("unknown bench section '{name}'; the sections are {}", SECTIONS.join(", "));
        };
        if !chosen.contains(section) {
            chosen.push(*section);
        }
    }
    if chosen.is_empty() {
        bail!("--only names no section; the sections are {}", SECTIONS.join(", "));
    }
    Ok(SECTIONS.iter().copied().filter(|s| chosen.contains(s)).collect())
}

/// `analytic`'s columns per second on `office`, 2 threads, before the throughput work
/// (`docs/bench-office.md` of that time): its target is twice as many.
const COLUMNS_BEFORE: f64 = 58.8;

/// What the sections found that the performance targets are judged on.
#[derive(Default)]
pub(crate) struct Findings {
    /// Analytic k = 1: pipeline rays/s ÷ raw obvhs rays/s, and ÷ raw `Visibility` rays/s, on
    /// 2 threads.
    analytic_ratio: Option<(f64, f64)>,
    /// The fastest method to each e_rms threshold: (threshold, method, seconds).
    fastest: Vec<(f64, String, Option<f64>)>,
    /// The largest peak resident memory of an end-to-end run, and its method.
    peak_memory: Option<(u64, String)>,
    /// Everything `--json` writes.
    pub(crate) json: BenchJson,
}

/// Runs `bench` (or, with the hidden child arguments, one end-to-end case).
pub fn run(args: &Args) -> Result<()> {
    if let Some(solver) = &args.child_scale {
        let Some(scene) = &args.scene else { bail!("a scale child run needs --scene") };
        let ff = args.child_ff.as_deref().unwrap_or("analytic");
        return children::scale_child(scene, solver, ff, args.max_seconds.unwrap_or(120.0));
    }
    if let Some(solver) = &args.child_sampled {
        let (Some(reference), Some(scene)) = (&args.child_reference, &args.scene) else {
            bail!("a stochastic child run needs --scene and --child-reference");
        };
        return children::sampled_child(
            scene,
            solver,
            args.child_ff.as_deref(),
            reference,
            args.max_seconds.unwrap_or(60.0),
        );
    }
    if let Some(solver) = &args.child_solver {
        let (Some(ff), Some(reference), Some(scene)) = (&args.child_ff, &args.child_reference, &args.scene) else {
            bail!("an end-to-end child run needs --scene, --child-ff and --child-reference");
        };
        return children::e2e_child(scene, solver, ff, reference, args.max_seconds.unwrap_or(300.0));
    }
    let sections = sections(args.only.as_deref())?;
    for out in [&args.out, &args.json].into_iter().flatten() {
        check_output_file(out)?;
    }
    let config = Config::new(args)?;
    // `lu` and `scale` bring their own systems and scenes: the bench scene is loaded by the
    // first section that measures on it, and the header, written last, names it only then.
    let mut prepared: Option<PreparedScene> = None;
    let mut body = String::new();
    let mut findings = Findings::default();
    for section in &sections {
        body += &match *section {
            "lu" => {
                let params = LuParams {
                    group_sizes: config.group_sizes.clone(),
                    runs: config.runs_cheap,
                    budget: if config.quick { 0.002 } else { 0.05 },
                };
                lu::report(&lu::measure(&params, &Bars::new())?)
            }
            "scale" => children::scale(&config)?,
            "stochastic" => children::stochastic(&config, &mut findings)?,
            on_scene => {
                let scene = match prepared {
                    Some(ref scene) => scene,
                    None => prepared.insert(prepare(&config.scene)?),
                };
                match on_scene {
                    "columns" => {
                        let params = ColumnsParams {
                            backends: config
                                .backends
                                .iter()
                                .map(|b| BackendSpec::parse(b))
                                .collect::<Result<_, _>>()?,
                            columns: config.columns,
                            runs: config.runs_cheap,
                            min_seconds: config.min_seconds,
                        };
                        let section = columns::run(scene, &config.scene, &params, &Bars::new())?;
                        findings.analytic_ratio = section.analytic_ratio;
                        findings.json.columns = section.json;
                        section.markdown
                    }
                    "assembly" => {
                        let params = AssemblyParams { rays: config.assembly_rays.clone(), runs: config.runs_heavy };
                        let assemblies = assembly::measure(scene, &params, &Bars::new())?;
                        assembly::report(&config.scene, scene.loaded.scene.len(), &assemblies)
                    }
                    _ => children::e2e(&config, scene, &mut findings)?,
                }
            }
        };
    }
    let mut report = header(&config, prepared.as_ref(), &sections) + &body;
    report += &targets(&findings, &config.scene);
    print!("{report}");
    if let Some(out) = &args.out {
        std::fs::write(out, &report).with_context(|| format!("cannot write {}", out.display()))?;
    }
    if let Some(out) = &args.json {
        let mut json = findings.json;
        json.machine = Machine::this();
        json.scene = prepared.as_ref().map(|p| SceneJson { name: config.scene.clone(), patches: p.loaded.scene.len() });
        let text = serde_json::to_string_pretty(&json)?;
        std::fs::write(out, text + "\n").with_context(|| format!("cannot write {}", out.display()))?;
    }
    Ok(())
}

/// The title, the machine and how the figures were taken.
fn header(config: &Config, prepared: Option<&PreparedScene>, sections: &[&str]) -> String {
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mut out = String::from("# Benchmarks (`cargo xtask bench`)\n\n");
    if config.quick {
        out += "**Smoke test (`--quick`): small scene and backends, figures mean nothing.**\n\n";
    }
    let scene = match prepared {
        Some(prepared) => format!("Scene `{}`: {} patches. ", config.scene, prepared.loaded.scene.len()),
        None => String::new(),
    };
    let _ = writeln!(
        out,
        "Machine: {cores} cores available ({} rayon threads by default), {} {}, release build: {}. \
         {scene}Figures are medians over the runs of each: {} (assembly, end-to-end and scale: {}).\n",
        rayon::current_num_threads(),
        std::env::consts::OS,
        std::env::consts::ARCH,
        if cfg!(debug_assertions) { "no (debug assertions on)" } else { "yes" },
        config.runs_cheap,
        config.runs_heavy,
    );
    let _ = writeln!(out, "Sections: {}.\n", sections.join(", "));
    out
}

/// The performance targets beside the measurements.
fn targets(findings: &Findings, scene: &str) -> String {
    if findings.analytic_ratio.is_none()
        && findings.fastest.is_empty()
        && findings.peak_memory.is_none()
        && findings.json.columns.is_empty()
    {
        return String::new();
    }
    let mut out = String::from("## Targets\n\n| target | measured | met |\n|---|---|---|\n");
    let verdict = |ok: bool| if ok { "yes" } else { "**no**" };
    if let Some((obvhs, vis)) = findings.analytic_ratio {
        let _ = writeln!(
            out,
            "| `analytic` k = 1 reaches ≥ 80% of the raw ray-tracing rate on the same rays (2 threads) | {}% of \
             raw obvhs, {}% of raw `Visibility` | {} |",
            sig(100.0 * obvhs, 2),
            sig(100.0 * vis, 2),
            verdict(obvhs >= 0.8)
        );
    }
    for (threshold, limit, what) in [(1e-3, 10.0, "e_rms ≤ 1e-3"), (1e-1, 1.0, "a first useful image (e_rms ≤ 1e-1)")]
    {
        if let Some((_, method, seconds)) = findings.fastest.iter().find(|(t, _, _)| *t == threshold) {
            let measured = match seconds {
                Some(s) => format!("{} (`{method}`, fastest)", duration(*s)),
                None => "not reached by any method".to_string(),
            };
            let _ = writeln!(
                out,
                "| `{scene}`: {what} in ≤ {limit} s of wall time from scene load | {measured} | {} |",
                verdict(seconds.is_some_and(|s| s <= limit))
            );
        }
    }
    if let Some(c) = findings.json.columns.iter().find(|c| c.backend.starts_with("analytic:") && scene == "office") {
        let rate = c.columns_per_second.get("2").copied().unwrap_or(f64::NAN);
        let _ = writeln!(
            out,
            "| `office`: `analytic` at its defaults computes ≥ {} columns/s on 2 threads (twice the {} measured \
             before the throughput work) | {} | {} |",
            sig(2.0 * COLUMNS_BEFORE, 3),
            sig(COLUMNS_BEFORE, 3),
            sig(rate, 3),
            verdict(rate >= 2.0 * COLUMNS_BEFORE)
        );
    }
    if let Some(matrix) = findings.json.e2e.iter().find(|e| e.backend == "matrix") {
        for (threshold, limit) in [("1e-2", 0.3), ("1e-3", 0.8)] {
            let best = findings
                .json
                .e2e
                .iter()
                .filter(|e| e.backend != "matrix")
                .filter_map(|e| Some((e.seconds_to.get(threshold).copied().flatten()?, &e.method)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let Some(gs) = matrix.seconds_to.get(threshold).copied().flatten() else { continue };
            let (measured, met) = match best {
                Some((s, method)) => (
                    format!("{} (`{method}` {} against {})", sig(s / gs, 2), duration(s), duration(gs)),
                    s <= limit * gs,
                ),
                None => ("no shooting method reached it".to_string(), false),
            };
            let _ = writeln!(
                out,
                "| `{scene}`: the best shooting method reaches e_rms {threshold} in ≤ {limit}× the time of \
                 `{}` over the reciprocally assembled matrix | {measured} | {} |",
                matrix.method,
                verdict(met)
            );
        }
    }
    if let Some((bytes, method)) = &findings.peak_memory {
        let _ = writeln!(
            out,
            "| `{scene}`: peak memory ≤ 2 GB | {} (largest, `{method}`) | {} |",
            human_bytes(*bytes),
            verdict(*bytes <= 2_000_000_000)
        );
    }
    out.push('\n');
    out
}

/// A progress bar on stderr over `len` steps, hidden when stderr is not a terminal.
pub(crate) fn progress(len: u64, prefix: &str) -> ProgressBar {
    let bar = if std::io::stderr().is_terminal() { ProgressBar::new(len) } else { ProgressBar::hidden() };
    if let Ok(style) = ProgressStyle::with_template("{prefix:>12} [{bar:30}] {pos}/{len} {msg} {elapsed}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(prefix.to_string());
    bar
}
