//! `cargo xtask compare [--scene SCENE] [--solvers S1,S2,…] [--ff BACKEND] [--until RULES]
//! [--out DIR]`: runs several solvers on one scene against its reference, and writes what a
//! researcher reads and shows.
//!
//! Into `results/<scene>-<date-time>/` (or `--out`): `convergence.csv` (every measured point),
//! `report.md` (e_rms at n/4, n/2, n and 2n columns; columns and seconds to reach e_rms 1e-2
//! and 1e-3; the time split; what the scene analysis left out; the reference and its
//! certificate) and plots of e_rms against shooting steps (the paper's axis), columns and
//! wall seconds, as SVG and PNG. A summary table ends the output.
//!
//! Measurement never counts as solver time: e_rms is computed between steps by an observer,
//! and the residual power (a product with F) only at about 100 points of each run. Its cost
//! is reported apart as measurement overhead.

use crate::experiment::{Experiment, require_emitters};
use crate::scene_report::{prepare, print_warnings};
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use radiosity_core::Real;
use radiosity_eval::metrics::errors;
use radiosity_eval::plot::{Curve, PlotSpec, write_png, write_svg};
use radiosity_eval::table::round_significant;
use radiosity_eval::{ConvergenceTable, Evaluator, TableRow};
use radiosity_ff::BackendSpec;
use radiosity_solvers::{Observer, State, StopRule, StopRules, solver_by_name};
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime};

/// The paper's multi-cubes comparison (its figure 1).
pub const DEFAULT_SOLVERS: &str = "pr,xu,pr-g30,xu-g30,pr-g30-m480,xu-g30-m480";

/// Arguments of `compare`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene: a built-in name with `:key=value` parameters, or a .gltf/.glb path.
    #[arg(long, default_value = "multi-cubes")]
    scene: String,
    /// The solvers, comma-separated (names as for `solve`).
    #[arg(long, default_value = DEFAULT_SOLVERS)]
    solvers: String,
    /// The form-factor backend, with `:key=value` parameters.
    #[arg(long = "ff", value_name = "BACKEND", default_value = "analytic")]
    ff: String,
    /// Stop rules for every solver.
    #[arg(long, value_name = "RULES", default_value = "columns=2n")]
    until: String,
    /// The output folder (default `results/<scene>-<date-time>/`).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

/// One step of a run: where it stood and its error.
#[derive(Clone, Copy, Debug)]
struct Point {
    step: u64,
    columns: u64,
    seconds: Real,
    e_rms: Real,
}

/// Records e_rms after every step, and every metric at sampled steps.
struct Recorder<'e> {
    experiment: &'e Experiment<'e>,
    evaluator: Evaluator<'e>,
    points: Vec<Point>,
    rows: Vec<TableRow>,
    solver: String,
    /// Steps between full measurements.
    every: u64,
    /// Columns at which to measure fully as well (n/4, n/2, n, 2n).
    marks: Vec<u64>,
    overhead: Real,
    bar: ProgressBar,
    /// Whether the bar counts columns (or steps).
    by_columns: bool,
}

impl Observer for Recorder<'_> {
    fn observe(&mut self, state: &State) -> Option<Real> {
        let start = Instant::now();
        let e_rms = errors(&self.experiment.system, &self.experiment.reference, &state.radiosity).ok()?.e_rms;
        let seconds = state.ff_seconds + state.solve_seconds;
        let point = Point { step: state.step, columns: state.columns, seconds, e_rms };
        let new_mark =
            self.marks.contains(&state.columns) && self.points.last().is_none_or(|p| p.columns != state.columns);
        if state.step % self.every == 0 || new_mark {
            if let Ok(m) = self.evaluator.evaluate(&state.radiosity) {
                self.rows.push(TableRow {
                    solver: self.solver.clone(),
                    step: state.step,
                    columns: state.columns,
                    seconds,
                    ff_seconds: state.ff_seconds,
                    e_rms: m.e_rms,
                    e_max: m.e_max,
                    residual: m.residual,
                });
            }
        }
        self.points.push(point);
        self.bar.set_position(if self.by_columns { state.columns } else { state.step });
        self.bar.set_message(format!("{} e_rms {e_rms:.2e}", self.solver));
        self.overhead += start.elapsed().as_secs_f64();
        Some(e_rms)
    }
}

/// What one solver did.
pub struct Outcome {
    /// The solver's name.
    pub solver: String,
    points: Vec<Point>,
    state: State,
    termination: String,
    overhead: Real,
}

impl Outcome {
    /// e_rms after `step` steps (the last point if the run ended before).
    pub fn at_step(&self, step: u64) -> Option<Real> {
        self.points.iter().take_while(|p| p.step <= step).last().map(|p| p.e_rms)
    }

    /// The columns computed after `step` steps.
    pub fn columns_at_step(&self, step: u64) -> Option<u64> {
        self.points.iter().take_while(|p| p.step <= step).last().map(|p| p.columns)
    }

    /// The first point at or below `target`: its columns and seconds.
    pub fn reached_at(&self, target: Real) -> Option<(u64, Real)> {
        self.reached(target).map(|p| (p.columns, p.seconds))
    }

    /// The group-solve share of the run's time.
    pub fn group_share(&self) -> Real {
        let total = self.state.ff_seconds + self.state.solve_seconds;
        if total > 0.0 { self.state.group_seconds / total } else { 0.0 }
    }

    /// The first point at or below `target`.
    fn reached(&self, target: Real) -> Option<&Point> {
        self.points.iter().find(|p| p.e_rms <= target)
    }

    /// e_rms when `columns` columns had been computed (the first step there).
    pub fn at_columns(&self, columns: u64) -> Option<Real> {
        self.points.iter().find(|p| p.columns >= columns).filter(|p| p.columns == columns).map(|p| p.e_rms)
    }
}

/// A progress bar on stderr, hidden when stderr is not a terminal.
fn progress(total: u64, columns: bool) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total);
    let unit = if columns { "columns" } else { "steps" };
    let template = format!("{{spinner}} {{msg:32}} [{{bar:30}}] {{pos}}/{{len}} {unit} {{elapsed}}");
    bar.set_style(ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar()));
    bar
}

/// The folder name for a run: scene name (without parameters or path) and UTC date-time.
pub fn default_out(scene: &str) -> PathBuf {
    let stem = Path::new(scene.split(':').next().unwrap_or(scene))
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let stamp = humantime::format_rfc3339_seconds(SystemTime::now()).to_string().replace(':', "-");
    PathBuf::from("results").join(format!("{stem}-{stamp}"))
}

/// A comparison whose arguments were all checked.
pub struct Plan {
    /// The scene argument.
    pub scene: String,
    /// The solvers, in order.
    pub names: Vec<String>,
    spec: BackendSpec,
    rules: StopRules,
    until: String,
}

impl Plan {
    /// Checks every argument before any geometry is built, so a typo fails at once.
    pub fn new(scene: &str, solvers: &str, ff: &str, until: &str) -> Result<Plan> {
        let spec = BackendSpec::parse(ff)?;
        let names: Vec<String> =
            solvers.split(',').map(str::trim).filter(|s| !s.is_empty()).map(String::from).collect();
        if names.is_empty() {
            bail!("--solvers names no solver");
        }
        for name in &names {
            solver_by_name(name)?;
        }
        let rules = StopRules::parse(until)?;
        Ok(Plan { scene: scene.to_string(), names, spec, rules, until: until.to_string() })
    }
}

/// What a comparison measured.
pub struct Comparison {
    /// Patches.
    pub n: u64,
    /// One per solver, in order.
    pub outcomes: Vec<Outcome>,
}

/// Runs `compare`.
pub fn run(args: &Args) -> Result<()> {
    let plan = Plan::new(&args.scene, &args.solvers, &args.ff, &args.until)?;
    let out = args.out.clone().unwrap_or_else(|| default_out(&args.scene));
    check_out_dir(&out)?;
    let comparison = execute(&plan, &out)?;
    print_summary(&comparison.outcomes, comparison.n);
    println!("wrote {} (report.md, convergence.csv and plots)", out.display());
    Ok(())
}

/// Checks, before any work, that `dir` is a directory or can be created as one: the nearest
/// part of it that exists is a directory.
fn check_out_dir(dir: &Path) -> Result<()> {
    if let Some(existing) = dir.ancestors().find(|a| !a.as_os_str().is_empty() && a.exists()) {
        if !existing.is_dir() {
            bail!(
                "cannot create the output folder {}: {} is a file, not a directory",
                dir.display(),
                existing.display()
            );
        }
    }
    Ok(())
}

/// The count a run's progress is measured against: its first `columns=` or `steps=` rule.
fn progress_target(rules: &StopRules, n: usize) -> (u64, bool) {
    rules
        .rules
        .iter()
        .find_map(|r| match r {
            StopRule::Columns(c) => Some((c.resolve(n), true)),
            StopRule::Steps(c) => Some((c.resolve(n), false)),
            _ => None,
        })
        .unwrap_or((2 * n as u64, true))
}

/// Runs every solver of `plan` and writes `convergence.csv`, `report.md` and the plots into
/// `out`.
pub fn execute(plan: &Plan, out: &Path) -> Result<Comparison> {
    let prepared = prepare(&plan.scene)?;
    let report = prepared.report();
    print_warnings(&report);
    require_emitters(&prepared)?;
    let n = report.patches as u64;
    eprintln!("{}: {} patches; left out: {}", report.scene, n, left_out(&report.left_out));
    let spinner = progress(0, true);
    spinner.set_message(format!("{}: F and the reference", report.scene));
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    let experiment = Experiment::new(&prepared, plan.spec.clone())?;
    spinner.finish_and_clear();

    let (target, by_columns) = progress_target(&plan.rules, n as usize);
    let mut outcomes = Vec::new();
    let mut table = ConvergenceTable::new();
    for name in &plan.names {
        let mut recorder = Recorder {
            experiment: &experiment,
            evaluator: Evaluator::new(&experiment.system, &experiment.matrix, &experiment.reference)?,
            points: Vec::new(),
            rows: Vec::new(),
            solver: name.to_string(),
            every: (target / 100).max(1),
            marks: vec![n / 4, n / 2, n, 2 * n],
            overhead: 0.0,
            bar: progress(target, by_columns),
            by_columns,
        };
        let run = experiment.run(name, plan.rules.clone(), &mut recorder)?;
        recorder.bar.finish_and_clear();
        for row in recorder.rows {
            table.push(row);
        }
        outcomes.push(Outcome {
            solver: run.solver.clone(),
            points: recorder.points,
            state: run.state,
            termination: run.termination.to_string(),
            overhead: recorder.overhead,
        });
    }

    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let csv = out.join("convergence.csv");
    table.write_csv(create(&csv)?).with_context(|| format!("cannot write {}", csv.display()))?;
    let plots = write_plots(out, &report.scene, &outcomes)?;
    let text = report_markdown(&experiment, &report, &plan.until, &outcomes, &plots, n);
    let md = out.join("report.md");
    std::fs::write(&md, &text).with_context(|| format!("cannot write {}", md.display()))?;
    Ok(Comparison { n, outcomes })
}

fn create(path: &Path) -> Result<std::fs::File> {
    std::fs::File::create(path).with_context(|| format!("cannot write {}", path.display()))
}

fn left_out(items: &[String]) -> String {
    if items.is_empty() { "nothing".into() } else { items.join("; ") }
}

/// Writes the three plots as SVG and PNG; returns their file stems and titles.
fn write_plots(out: &Path, scene: &str, outcomes: &[Outcome]) -> Result<Vec<(String, String)>> {
    type Axis = fn(&Point) -> Real;
    let axes: [(&str, &str, Axis); 3] = [
        ("e_rms-steps", "shooting steps", |p| p.step as Real),
        ("e_rms-columns", "form-factor columns computed", |p| p.columns as Real),
        ("e_rms-seconds", "wall seconds (form factors and solving)", |p| p.seconds),
    ];
    let mut written = Vec::new();
    for (stem, x_label, x) in axes {
        let curves: Vec<Curve> = outcomes
            .iter()
            .map(|o| Curve { label: o.solver.clone(), points: o.points.iter().map(|p| (x(p), p.e_rms)).collect() })
            .collect();
        let spec =
            PlotSpec { title: format!("{scene}: e_rms against {x_label}"), x_label: x_label.into(), size: (800, 500) };
        let svg = out.join(format!("{stem}.svg"));
        write_svg(&curves, &spec, create(&svg)?).with_context(|| format!("cannot write {}", svg.display()))?;
        let png = out.join(format!("{stem}.png"));
        write_png(&curves, &spec, create(&png)?).with_context(|| format!("cannot write {}", png.display()))?;
        written.push((stem.to_string(), spec.title));
    }
    Ok(written)
}

fn cell(value: Option<Real>) -> String {
    value.map_or("—".into(), |v| round_significant(v, 3))
}

fn reached_cell(o: &Outcome, target: Real) -> String {
    o.reached(target).map_or("—".into(), |p| format!("{} / {:.3} s", p.columns, p.seconds))
}

/// The Markdown report.
fn report_markdown(
    experiment: &Experiment<'_>,
    report: &crate::scene_report::SceneReport,
    until: &str,
    outcomes: &[Outcome],
    plots: &[(String, String)],
    n: u64,
) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# Solver comparison on `{}`\n", report.scene);
    let _ = writeln!(
        md,
        "{} patches, mean reflectivity {:.3}; form factors `{}`; every solver run until `{until}`.\n",
        n,
        report.mean_reflectivity,
        experiment.spec.canonical()
    );
    let _ = writeln!(md, "- Left out by the scene analysis: {}.", left_out(&report.left_out));
    let _ = writeln!(
        md,
        "- Reference: {}; {} (F assembled in {:.2} s, solved in {:.2} s).\n",
        experiment.reference.method(),
        experiment.reference.certificate(),
        experiment.assembly_seconds,
        experiment.reference_seconds
    );
    let _ = writeln!(md, "## e_rms at n/4, n/2, n and 2n columns\n");
    let _ = writeln!(md, "| solver | n/4 | n/2 | n | 2n |\n|---|--:|--:|--:|--:|");
    for o in outcomes {
        let at = |c: u64| cell(o.at_columns(c));
        let _ = writeln!(md, "| `{}` | {} | {} | {} | {} |", o.solver, at(n / 4), at(n / 2), at(n), at(2 * n));
    }
    let _ = writeln!(md, "\n## Columns and seconds to reach e_rms 1e-2 and 1e-3\n");
    let _ = writeln!(md, "| solver | 1e-2 | 1e-3 |\n|---|--:|--:|");
    for o in outcomes {
        let _ = writeln!(md, "| `{}` | {} | {} |", o.solver, reached_cell(o, 1e-2), reached_cell(o, 1e-3));
    }
    let _ = writeln!(md, "\n## Where the time went\n");
    let _ = writeln!(
        md,
        "Form factors and solving are the run's own time; group solving is part of solving; \
         measurement (e_rms every step, all metrics at about 100 points) is outside the run.\n"
    );
    let _ = writeln!(
        md,
        "| solver | steps | columns (reused) | form factors | solving | of which groups | measurement | stopped |\n\
         |---|--:|--:|--:|--:|--:|--:|---|"
    );
    for o in outcomes {
        let s = &o.state;
        let _ = writeln!(
            md,
            "| `{}` | {} | {} ({}) | {:.3} s | {:.3} s | {:.3} s | {:.3} s | {} |",
            o.solver,
            s.step,
            s.columns,
            s.columns_reused,
            s.ff_seconds,
            s.solve_seconds,
            s.group_seconds,
            o.overhead,
            o.termination
        );
    }
    let _ = writeln!(md, "\n## Plots\n");
    for (stem, title) in plots {
        let _ = writeln!(md, "![{title}]({stem}.png)\n");
    }
    md
}

/// The compact table at the end of the output.
pub fn print_summary(outcomes: &[Outcome], n: u64) {
    println!(
        "{:<24} {:>8} {:>8} {:>10} {:>10} {:>10} {:>9}",
        "solver", "steps", "columns", "e_rms @n", "e_rms end", "1e-3 at", "seconds"
    );
    for o in outcomes {
        let last = o.points.last();
        println!(
            "{:<24} {:>8} {:>8} {:>10} {:>10} {:>10} {:>9.3}",
            o.solver,
            o.state.step,
            o.state.columns,
            cell(o.at_columns(n)),
            cell(last.map(|p| p.e_rms)),
            o.reached(1e-3).map_or("—".into(), |p| p.columns.to_string()),
            o.state.ff_seconds + o.state.solve_seconds
        );
    }
}
