//! `cargo xtask bench [--out FILE.md] [--json FILE.json] [--quick] [--only SECTIONS] [--runs N]
//! [--renderpark FILE]`: the performance figures, as one Markdown report of medians over several
//! runs, and with `--json` the same medians under stable keys.
//!
//! The sections (columns, assembly, lu, e2e, scale, stochastic), their defaults, their
//! measurements, the report and its targets are the library's ([`radiosity_eval::bench`], whose
//! module doc says what each section measures; [`radiosity_eval::bench::plan`] decides). This
//! module parses the arguments, runs the sections with progress bars, spawns the child
//! processes of the heavy cases ([`children`]) and prints.
//!
//! Reproduce with `cargo xtask bench --out bench.md` on a quiet machine (docs/bench-office.md's
//! stamp says how long a full run took; sections can be run alone with `--only columns,lu`).
//! `--quick` shrinks everything into a smoke test of a few seconds whose figures mean nothing.

mod children;

use crate::bars::Bars;
use crate::experiment::{check_output_file, prepare};
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use radiosity_eval::bench::children::ChildCase;
use radiosity_eval::bench::peer::Peer;
use radiosity_eval::bench::plan::{self, BenchConfig, BenchOptions, Findings};
use radiosity_eval::bench::{Machine, SceneJson, assembly, columns, lu};
use radiosity_geom::PreparedScene;
use std::io::IsTerminal;
use std::path::PathBuf;

/// Arguments of `bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Also write the Markdown report to this file.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Also write the figures as JSON to this file, under stable keys: `machine`, `columns`
    /// (backend, columns_per_second by thread count, rays_per_column, raw_share), `e2e`
    /// (method, backend, seconds_to by e_rms, columns_to_1e-3, peak_bytes), `stochastic` and
    /// `peer` (RenderPark's process times, or why there are none).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// A smoke test: a small scene, few columns, small backends, few runs (figures mean nothing).
    #[arg(long)]
    quick: bool,
    /// Only these sections, comma-separated: columns, assembly, lu, e2e (e2e includes memory),
    /// scale (not run by default: about two hours), stochastic (not run by default: the
    /// stochastic solvers on RenderPark's classroom, from the scenes folder, and beside them
    /// the RenderPark build given by --renderpark).
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
    /// A RenderPark executable you built (default: the RENDERPARK setting; its commit in
    /// RENDERPARK_COMMIT): the stochastic section times its stochastic Jacobi on the same MGF
    /// scene, in the same run. Without one the section says it has no peer measurement.
    #[arg(long, value_name = "FILE")]
    renderpark: Option<PathBuf>,
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

/// Runs `bench` (or, with the hidden child arguments, one case of a child process).
pub fn run(args: &Args) -> Result<()> {
    if let Some(case) = child_case(args)? {
        let Some(scene) = &args.scene else { bail!("a child run of the bench needs --scene") };
        println!("{}", case.run(scene, args.max_seconds.unwrap_or(300.0))?);
        return Ok(());
    }
    let sections = plan::sections(args.only.as_deref())?;
    for out in [&args.out, &args.json].into_iter().flatten() {
        check_output_file(out)?;
    }
    let config = BenchConfig::new(&BenchOptions {
        quick: args.quick,
        runs: args.runs,
        scene: args.scene.clone(),
        columns: args.columns,
        solvers: args.solvers.clone(),
        max_seconds: args.max_seconds,
        peer: Peer::from_arg_or_env(args.renderpark.as_deref())?,
    })?;
    // `lu` and `scale` bring their own systems and scenes: the bench scene is loaded by the
    // first section that measures on it, and the header, written last, names it only then.
    let mut prepared: Option<PreparedScene> = None;
    let mut body = String::new();
    let mut findings = Findings::default();
    for section in &sections {
        body += &match *section {
            "lu" => lu::report(&lu::measure(&config.lu_params(), &Bars::new())?),
            "scale" => children::scale(&config)?,
            "stochastic" => children::stochastic(&config, &mut findings)?,
            on_scene => {
                let scene = match prepared {
                    Some(ref scene) => scene,
                    None => prepared.insert(prepare(&config.scene)?),
                };
                match on_scene {
                    "columns" => {
                        let section = columns::run(scene, &config.scene, &config.columns_params()?, &Bars::new())?;
                        findings.analytic_ratio = section.analytic_ratio;
                        findings.json.columns = section.json;
                        section.markdown
                    }
                    "assembly" => {
                        let assemblies = assembly::measure(scene, &config.assembly_params(), &Bars::new())?;
                        assembly::report(&config.scene, scene.loaded.scene.len(), &assemblies)
                    }
                    _ => children::e2e(&config, scene, &mut findings)?,
                }
            }
        };
    }
    let patches = prepared.as_ref().map(|p| p.loaded.scene.len());
    let report = plan::header(&config, patches, &sections) + &body + &plan::targets(&findings, &config.scene);
    print!("{report}");
    if let Some(out) = &args.out {
        std::fs::write(out, &report).with_context(|| format!("cannot write {}", out.display()))?;
    }
    if let Some(out) = &args.json {
        let mut json = findings.json;
        json.machine = Machine::this();
        json.scene = patches.map(|patches| SceneJson { name: config.scene.clone(), patches });
        let text = serde_json::to_string_pretty(&json)?;
        std::fs::write(out, text + "\n").with_context(|| format!("cannot write {}", out.display()))?;
    }
    Ok(())
}

/// The case of a child run, from the hidden arguments; `None` for a plain `bench`.
fn child_case(args: &Args) -> Result<Option<ChildCase>> {
    let (ff, reference) = (args.child_ff.clone(), args.child_reference.clone());
    Ok(Some(match (&args.child_solver, &args.child_sampled, &args.child_scale) {
        (Some(solver), _, _) => {
            let (Some(ff), Some(reference)) = (ff, reference) else {
                bail!("an end-to-end child run needs --child-ff and --child-reference");
            };
            ChildCase::EndToEnd { solver: solver.clone(), ff, reference }
        }
        (_, Some(solver), _) => {
            let Some(reference) = reference else { bail!("a stochastic child run needs --child-reference") };
            ChildCase::Sampled { solver: solver.clone(), ff, reference }
        }
        (_, _, Some(solver)) => ChildCase::Scale { solver: solver.clone(), ff: ff.unwrap_or("analytic".into()) },
        _ => return Ok(None),
    }))
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
