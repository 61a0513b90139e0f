//! What a researcher reads and shows of a [`Comparison`]: `convergence.csv` (every metric at
//! the recorded steps), `report.md` (e_rms at n/4, n/2, n and 2n columns; columns and seconds
//! to reach e_rms 1e-2 and 1e-3; where the time went; what the scene analysis left out; the
//! reference, its kind and its certificate) and plots of e_rms against shooting steps (the
//! paper's axis), columns, every other unit of cost some solver spent (products, rays, links:
//! [`Unit`]) and seconds, as SVG and PNG, and a summary table for the terminal.
//!
//! **Plots and tables show what each run spent.** A plot against a unit of cost is drawn only
//! when some run spent that unit, and holds the runs that did (against columns, also a run
//! that spent nothing at all); the steps and seconds plots hold every run. Whoever a plot or
//! the table at n/4 … 2n columns leaves out is named, with why and what it spent instead, in
//! `report.md` and under the plot. A cost is always given in its run's own unit, named
//! (`659 columns`, `8,594,170 rays`), never as a bare count beside another unit's. Titles name
//! the scene by its short name (a file's name without its folders).
//!
//! **Solvers that sample transport** sit in the same table and plots as the others. Their
//! cost is counted in rays, and the rays plot is log–log with a reference slope of −½, the
//! rate at which a Monte Carlo estimate's error falls ([`crate::reports::plot`]'s module doc).
//! Their error bar is a standard error (the spread of independent replicates, summarised as
//! e_rms is), reported beside the certified bound of the deterministic solvers: a bound is a
//! promise that holds every time, a standard error a spread that the true error exceeds now
//! and then. The plots draw it as a shaded band up to twice the standard error
//! ([`crate::reports::plot`]'s module doc). Every one of them names the clock its seconds were counted on ([`Clock::name`]:
//! `measured`, columns computed and timed; `charged`, columns read from the stored matrix and
//! each charged the backend's modelled cost). Without a reference (`--reference none`) the
//! certified bound of every step takes e_rms's place in the tables and plots.

use crate::error::LabError;
use crate::lab::compare::Comparison;
use crate::lab::outcome::Outcome;
use crate::lab::recorder::Point;
use crate::lab::setup::ReferenceOrigin;
use crate::reports::plot::{AxisScale, Curve, MONTE_CARLO_SLOPE, PlotSpec, write_png, write_svg};
use crate::reports::report_text::sig;
use crate::reports::table::{ConvergenceTable, round_significant};
use radiosity_core::{Clock, Real};
use radiosity_solvers::Value;
use radiosity_solvers::{Cost, Unit};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The files a comparison wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct Written {
    /// The folder.
    pub dir: PathBuf,
    /// Every file, in the order written.
    pub files: Vec<PathBuf>,
}

impl Comparison {
    /// Every recorded row of every run.
    pub fn table(&self) -> ConvergenceTable {
        let mut table = ConvergenceTable::new().with_clock(self.clock);
        for row in self.outcomes.iter().flat_map(|o| &o.rows) {
            table.push(row.clone());
        }
        table
    }

    /// Writes `convergence.csv`, `report.md` and the plots into `dir` (created if needed).
    pub fn write(&self, dir: &Path) -> Result<Written, LabError> {
        std::fs::create_dir_all(dir).map_err(|e| LabError::write(dir, e))?;
        let mut files = Vec::new();
        let csv = dir.join("convergence.csv");
        self.table().write_csv(create(&csv)?).map_err(|e| LabError::write(&csv, e))?;
        files.push(csv);
        let plots = self.write_plots(dir, &mut files)?;
        let md = dir.join("report.md");
        std::fs::write(&md, self.report_markdown(&plots)).map_err(|e| LabError::write(&md, e))?;
        files.push(md);
        Ok(Written { dir: dir.to_path_buf(), files })
    }

    /// Writes the plots as SVG and PNG ([`Comparison::plots`]); returns their file stems and
    /// titles.
    fn write_plots(&self, dir: &Path, files: &mut Vec<PathBuf>) -> Result<Vec<(String, String)>, LabError> {
        let mut written = Vec::new();
        for plot in self.plots() {
            let spec = PlotSpec {
                title: plot.title,
                x_label: plot.x_label,
                size: (800, 500),
                certified_bound: !self.has_reference(),
                x_scale: plot.axis.scale(),
                slope: plot.axis.slope(),
                notes: left_out_sentence(&plot.left_out, |name| name.to_string()).into_iter().collect(),
            };
            let svg = dir.join(format!("{}.svg", plot.stem));
            write_svg(&plot.curves, &spec, create(&svg)?)?;
            let png = dir.join(format!("{}.png", plot.stem));
            write_png(&plot.curves, &spec, create(&png)?)?;
            files.extend([svg, png]);
            written.push((plot.stem, spec.title));
        }
        Ok(written)
    }

    /// The plots the comparison draws (module doc): against steps, every paid unit of cost
    /// some run spent, and seconds, each with the runs it shows and those it leaves out.
    fn plots(&self) -> Vec<Plot<'_>> {
        let seconds = format!("{} seconds (form factors and solving)", self.clock.name());
        let units = Unit::ALL.into_iter().filter(|u| u.paid()).map(Axis::Spent);
        let axes = std::iter::once(Axis::Steps).chain(units).chain([Axis::Seconds]);
        let what = if self.has_reference() { "e_rms" } else { "certified bound" };
        let mut plots = Vec::new();
        for axis in axes {
            // No plot against a unit nobody spent: it would be a line at 0.
            if let Axis::Spent(unit) = axis {
                if self.outcomes.iter().all(|o| o.state.cost[unit] == 0) {
                    continue;
                }
            }
            let label = match axis {
                Axis::Steps => "shooting steps",
                Axis::Spent(unit) => unit.spent(),
                Axis::Seconds => &seconds,
            };
            let mut curves = Vec::new();
            let mut left_out = Vec::new();
            for o in &self.outcomes {
                if let Some(why) = axis.absence(o) {
                    left_out.push((o.solver.as_str(), why));
                    continue;
                }
                let curve = self.curve(axis, o);
                if curve.points.is_empty() && curve.spread.is_empty() {
                    left_out.push((o.solver.as_str(), format!("no {what} to show")));
                } else {
                    curves.push(curve);
                }
            }
            if curves.is_empty() {
                continue;
            }
            let x_label = match axis.scale() {
                AxisScale::Linear => label.to_string(),
                AxisScale::Log => format!("{label} (log scale)"),
            };
            plots.push(Plot {
                axis,
                stem: format!("{}-{}", self.metric(), axis.key()),
                title: format!("{}: {what} against {label}", short_name(&self.scene.scene)),
                x_label,
                curves,
                left_out,
            });
        }
        plots
    }

    /// The curve of `o` against `axis`: its shown metric, and its standard errors beside e_rms.
    fn curve(&self, axis: Axis, o: &Outcome) -> Curve {
        Curve {
            label: o.solver.clone(),
            points: o.points.iter().map(|p| (axis.x(p), self.value(p))).filter(|(_, y)| y.is_finite()).collect(),
            // A band of standard errors belongs beside e_rms, never on an axis of certified
            // bounds (a comparison without a reference).
            spread: if self.has_reference() {
                o.points.iter().map(|p| (axis.x(p), p.std_error)).filter(|(_, s)| s.is_finite()).collect()
            } else {
                Vec::new()
            },
        }
    }

    /// The Markdown report, linking the plots `plots` (file stems and titles).
    pub fn report_markdown(&self, plots: &[(String, String)]) -> String {
        let n = self.n;
        let mut md = String::new();
        let _ = writeln!(md, "# Solver comparison on `{}`\n", self.scene.scene);
        let _ = writeln!(
            md,
            "{} patches, mean reflectivity {:.3}; form factors `{}`; every solver run until `{}`.\n",
            n, self.scene.mean_reflectivity, self.backend, self.rules
        );
        let _ = writeln!(md, "- Left out by the scene analysis: {}.", self.scene.left_out_phrase());
        let _ = writeln!(md, "- {}: {}.", capitalised(&self.clock.seconds_label()), self.seconds_phrase());
        if let Some(build) = &self.backend_build {
            let _ = writeln!(md, "- Form factors `{}`: {build}, outside every solver's seconds.", self.backend);
        }
        let origin = match &self.reference_origin {
            ReferenceOrigin::Solved { assembly_seconds, solve_seconds } if *assembly_seconds > 0.0 => {
                format!("F assembled in {assembly_seconds:.2} s, solved in {solve_seconds:.2} s")
            }
            ReferenceOrigin::Solved { solve_seconds, .. } => format!("solved in {solve_seconds:.2} s"),
            ReferenceOrigin::Cached { seconds, .. } => format!("read from the cache in {seconds:.2} s"),
            ReferenceOrigin::NotComputed => "not computed".into(),
        };
        let kind = &self.reference_kind;
        match (&self.reference_method, &self.reference_certificate) {
            (Some(method), Some(certificate)) => {
                let _ =
                    writeln!(md, "- Reference `{}` ({}): {method}; {certificate} ({origin}).\n", kind.kind, kind.why);
            }
            _ => {
                let _ = writeln!(
                    md,
                    "- Reference `none` ({}): no e_rms; the tables and plots show the certified bound on each step's \
                     relative L1 error, from what the solver knows without extra columns.\n",
                    kind.why
                );
            }
        }
        let metric = self.metric();
        let _ = writeln!(md, "## {metric} at n/4, n/2, n and 2n columns\n");
        // Only the runs that computed columns (or spent nothing): the others are named.
        let columns = Axis::Spent(Unit::Columns);
        let (at_n, left): (Vec<&Outcome>, Vec<&Outcome>) =
            self.outcomes.iter().partition(|o| columns.absence(o).is_none());
        let table = !at_n.is_empty();
        if table {
            let _ = writeln!(md, "| solver | n/4 | n/2 | n | 2n |\n|---|--:|--:|--:|--:|");
        }
        for o in at_n {
            let at = |c: u64| cell(o.at_columns_point(c).map(|p| self.value(&p)));
            let _ = writeln!(md, "| `{}` | {} | {} | {} | {} |", o.solver, at(n / 4), at(n / 2), at(n), at(2 * n));
        }
        let left: Vec<(&str, String)> =
            left.iter().filter_map(|o| Some((o.solver.as_str(), columns.absence(o)?))).collect();
        if let Some(sentence) = left_out_sentence(&left, |name| format!("`{name}`")) {
            // After the table, a paragraph of its own; in its place, the section's only line.
            let _ = writeln!(md, "{}{sentence}", if table { "\n" } else { "" });
        }
        let _ = writeln!(
            md,
            "\n## Columns (and products, rays or links) and {} seconds to reach {metric} 1e-2 and 1e-3\n",
            self.clock.name()
        );
        let _ = writeln!(md, "| solver | 1e-2 | 1e-3 |\n|---|--:|--:|");
        for o in &self.outcomes {
            let _ =
                writeln!(md, "| `{}` | {} | {} |", o.solver, self.reached_cell(o, 1e-2), self.reached_cell(o, 1e-3));
        }
        self.error_bars_markdown(&mut md);
        let _ = writeln!(md, "\n## Where the time went\n");
        let _ = writeln!(
            md,
            "Form factors and solving are the run's own time, the form factors' seconds {}; group solving is part \
             of solving; solving and measurement (e_rms every step, all metrics at about 100 points, outside the \
             run) are measured.\n",
            self.clock.name()
        );
        // Columns (with those reused) always, then every other paid unit some run spent.
        let units: Vec<Unit> = Unit::ALL
            .into_iter()
            .filter(|&u| u.paid() && u != Unit::Columns && self.outcomes.iter().any(|o| o.state.cost[u] > 0))
            .collect();
        if let Some(transport) = &self.transport {
            let _ = writeln!(md, "Rays: {transport}; a ray's seconds are form-factor seconds, measured.\n");
        }
        if units.contains(&Unit::Links) {
            let _ = writeln!(
                md,
                "Links: those of the hierarchy each solver touched, a column the links of its patch's leaf and \
                 ancestors, a product every link, a round of node shooting its nodes' links.\n"
            );
        }
        let heads: String = units.iter().map(|u| format!(" {} |", u.name())).collect();
        let rules = "--:|".repeat(units.len());
        let _ = writeln!(
            md,
            "| solver | steps | columns (reused) |{heads} form factors ({}) | solving | of which groups | \
             measurement | stopped |\n|---|--:|--:|{rules}--:|--:|--:|--:|---|",
            self.clock.name(),
        );
        for o in &self.outcomes {
            let s = &o.state.cost;
            let counts: String = units.iter().map(|&u| format!(" {} |", s[u])).collect();
            let _ = writeln!(
                md,
                "| `{}` | {} | {} ({}) |{counts} {:.3} s | {:.3} s | {:.3} s | {:.3} s | {} |",
                o.solver,
                o.state.step,
                s[Unit::Columns],
                s[Unit::Reused],
                s.ff_seconds,
                s.solve_seconds,
                s.group_seconds,
                o.overhead,
                o.termination
            );
        }
        if !self.notes.is_empty() {
            let _ = writeln!(md, "\n**Not as asked.** {}.", self.notes.join("; "));
        }
        let records: Vec<&Outcome> = self.outcomes.iter().filter(|o| !o.record.is_empty()).collect();
        if !records.is_empty() {
            let _ = writeln!(md, "\n## What the solvers recorded\n");
            for o in records {
                let items: Vec<String> = o.record.iter().map(|(k, v)| format!("{k} {}", value_cell(v))).collect();
                let _ = writeln!(md, "- `{}`: {}", o.solver, items.join(", "));
            }
        }
        let _ = writeln!(md, "\n## Plots\n");
        if self.outcomes.iter().all(|o| o.state.cost[Unit::Columns] == 0) {
            let _ = writeln!(md, "No plot against columns computed: no solver computed one.\n");
        }
        let drawn = self.plots();
        for (stem, title) in plots {
            let _ = writeln!(md, "![{title}]({stem}.png)\n");
            let left = drawn.iter().find(|p| &p.stem == stem).map_or(&[][..], |p| &p.left_out[..]);
            if let Some(sentence) = left_out_sentence(left, |name| format!("`{name}`")) {
                let _ = writeln!(md, "{sentence}\n");
            }
        }
        md
    }

    /// How the seconds of every run were counted, on its clock ([`Comparison::clock`]):
    /// columns computed and timed, or read from the stored matrix and charged
    /// ([`ColumnCharge`](crate::ColumnCharge)).
    pub fn seconds_phrase(&self) -> String {
        match (&self.charge, self.clock) {
            (Some(charge), Clock::Charged) => format!("solving timed, {}", charge.describe()),
            _ => "form factors and solving timed, every column computed when a solver asked for it".into(),
        }
    }

    /// The compact table for the terminal: with a reference, e_rms and the certified bound;
    /// without, the bound alone; when a solver cast rays or has a standard error, its rays and
    /// its standard error too. `@n` is at n columns, `no columns` for a run that computed none.
    /// `1e-3 at` counts what the run spent in the unit its cost is read in
    /// ([`radiosity_solvers::Cost::principal`]), named: `659 columns`, or `8,594,170 rays` for
    /// a solver that cast them, or links for a solver over a hierarchy that computed no column.
    pub fn summary(&self) -> String {
        let metric = self.metric();
        let bound = if self.has_reference() { format!(" {:>10}", "bound end") } else { String::new() };
        let sampled = self.casts_rays() || self.outcomes.iter().any(|o| o.last.standard_error.is_some());
        let rays = if sampled { format!(" {:>12} {:>10}", "rays", "std error") } else { String::new() };
        let seconds = self.clock.seconds_label();
        let width = seconds.len();
        // The solvers' names in a column wide enough for the longest.
        let names = self.outcomes.iter().map(|o| o.solver.chars().count()).max().unwrap_or(0).max(24);
        let mut out = format!(
            "{:<names$} {:>8} {:>8}{rays} {:>10} {:>10}{bound} {:>16} {seconds}\n",
            "solver",
            "steps",
            "columns",
            format!("{metric} @n"),
            format!("{metric} end"),
            "1e-3 at",
        );
        for o in &self.outcomes {
            let bound = if self.has_reference() { format!(" {:>10}", cell(o.last.bound)) } else { String::new() };
            let rays = if sampled {
                format!(" {:>12} {:>10}", o.state.cost[Unit::Rays], cell(o.last.standard_error))
            } else {
                String::new()
            };
            // At n columns; a run that computed none says so rather than `—`.
            let at_n = match Axis::Spent(Unit::Columns).absence(o) {
                Some(_) => "no columns".into(),
                None => cell(o.at_columns_point(self.n).map(|p| self.value(&p))),
            };
            let unit = o.state.cost.principal();
            let _ = writeln!(
                out,
                "{:<names$} {:>8} {:>8}{rays} {:>10} {:>10}{bound} {:>16} {:>width$.3}",
                o.solver,
                o.state.step,
                o.state.cost[Unit::Columns],
                at_n,
                cell(o.points.last().map(|p| self.value(p))),
                self.reached(o, 1e-3).map_or("—".into(), |p| format!("{} {}", count(p.cost[unit]), unit.name())),
                o.seconds()
            );
        }
        out
    }

    /// Whether some run cast rays.
    fn casts_rays(&self) -> bool {
        self.outcomes.iter().any(|o| o.state.cost[Unit::Rays] > 0)
    }

    /// `report.md`'s section on each run's error bar: the certified bound beside the standard
    /// error, and what each promises.
    fn error_bars_markdown(&self, md: &mut String) {
        let _ = writeln!(md, "\n## Error bars: certified bounds and standard errors\n");
        let _ = writeln!(
            md,
            "A certified bound is a promise: the final radiosity's area-weighted L1 error, relative to the \
             reference's, is at most the bound, every time (docs/design.md §6.3). A standard error is a spread: that \
             of independent replicates of a solver whose answer is an estimate, summarised as e_rms is, so the two \
             read side by side; an unbiased estimate's e_rms is expected near it, and exceeds it now and then (per \
             patch, within 2 standard errors about 70% of the time for 2 replicates, 95% as they grow). Neither \
             needs the reference. A solver that samples transport has no certified bound: its cell is empty even \
             where F is known. Its unshot power (relative to the emitted) is what its estimate still leaves out, a \
             bias no standard error sees: stochastic Jacobi shoots its incremental series whole in its first step, \
             so it is at most that series' threshold afterwards (docs/stochastic.md).\n"
        );
        let _ = writeln!(
            md,
            "| solver | {} end | certified bound | standard error (replicates) | unshot power | rays |\n\
             |---|--:|--:|--:|--:|--:|",
            self.metric()
        );
        for o in &self.outcomes {
            let spread = match (o.last.standard_error, o.last.replicates) {
                (Some(s), Some(r)) => format!("{} ({r})", cell(Some(s))),
                (Some(s), None) => cell(Some(s)),
                _ => "—".into(),
            };
            let _ = writeln!(
                md,
                "| `{}` | {} | {} | {spread} | {} | {} |",
                o.solver,
                cell(o.points.last().map(|p| self.value(p))),
                cell(o.last.bound),
                cell(o.record.real("unshot_power")),
                o.state.cost[Unit::Rays]
            );
        }
    }

    fn reached_cell(&self, o: &Outcome, target: Real) -> String {
        self.reached(o, target).map_or("—".into(), |p| format!("{} / {:.3} s", p.cost, p.cost.seconds()))
    }
}

/// The x axis of a plot: steps, a paid unit of cost, or seconds.
#[derive(Clone, Copy)]
enum Axis {
    Steps,
    Spent(Unit),
    Seconds,
}

impl Axis {
    /// The plot's file stem after the metric: `e_rms-rays`.
    fn key(self) -> &'static str {
        match self {
            Axis::Steps => "steps",
            Axis::Spent(unit) => unit.key(),
            Axis::Seconds => "seconds",
        }
    }

    /// Where `p` lies on this axis.
    fn x(self, p: &Point) -> Real {
        match self {
            Axis::Steps => p.step as Real,
            Axis::Spent(unit) => p.cost[unit] as Real,
            Axis::Seconds => p.cost.seconds(),
        }
    }

    /// Why the plot leaves `o` out, or `None` when it holds it: it holds every run against
    /// steps and seconds, the runs that spent a unit against it, and against columns also
    /// those that spent nothing at all (their error at 0 columns).
    fn absence(self, o: &Outcome) -> Option<String> {
        let cost = &o.state.cost;
        match self {
            Axis::Steps | Axis::Seconds => None,
            Axis::Spent(Unit::Columns) if cost.paid().next().is_none() => None,
            Axis::Spent(unit) if cost[unit] > 0 => None,
            Axis::Spent(unit) => Some(format!("no {}; its cost: {}", unit.spent(), principal_cost(cost))),
        }
    }

    /// The x axis's scale: logarithmic for rays, against which a Monte Carlo estimate's error
    /// falls as a power law; linear for the rest.
    fn scale(self) -> AxisScale {
        match self {
            Axis::Spent(Unit::Rays) => AxisScale::Log,
            _ => AxisScale::Linear,
        }
    }

    /// The reference slope drawn on the axis: a Monte Carlo estimate's against rays.
    fn slope(self) -> Option<Real> {
        (self.scale() == AxisScale::Log).then_some(MONTE_CARLO_SLOPE)
    }
}

/// A plot a comparison draws ([`Comparison::plots`]).
struct Plot<'c> {
    axis: Axis,
    /// The file stem: `e_rms-rays`.
    stem: String,
    title: String,
    x_label: String,
    /// One per run shown.
    curves: Vec<Curve>,
    /// Each run left out, by name, and why.
    left_out: Vec<(&'c str, String)>,
}

/// The sentence that names the runs `left` out of a plot or table and why, each name written
/// by `name`; `None` when none is.
fn left_out_sentence(left: &[(&str, String)], name: impl Fn(&str) -> String) -> Option<String> {
    let items: Vec<String> = left.iter().map(|(solver, why)| format!("{} ({why})", name(solver))).collect();
    (!items.is_empty()).then(|| format!("Left out: {}.", items.join(", ")))
}

/// What a run spent in the unit its cost is read in ([`radiosity_solvers::Cost::principal`]),
/// labelled: `659 columns computed`, `8,594,170 rays cast`.
fn principal_cost(cost: &Cost) -> String {
    let unit = cost.principal();
    format!("{} {}", count(cost[unit]), unit.spent())
}

/// A count as reports write one: with thousands separators from 10,000 (`8,594,170`), three
/// significant digits from 1e10 (as [`sig`] writes numbers).
fn count(k: u64) -> String {
    if k < 10_000 { k.to_string() } else { sig(k as Real, 3) }
}

/// A scene's name as a title gives it: a file's name without its folders (`office.glb`,
/// `classroom.mgf:size=0.1`), a built-in scene's as written (`cornell:res=16`).
pub(crate) fn short_name(scene: &str) -> &str {
    scene.rfind(['/', '\\']).map_or(scene, |k| &scene[k + 1..])
}

/// `text` with its first letter in capitals.
fn capitalised(text: &str) -> String {
    let mut chars = text.chars();
    chars.next().map_or_else(String::new, |first| first.to_uppercase().chain(chars).collect())
}

fn create(path: &Path) -> Result<std::fs::File, LabError> {
    std::fs::File::create(path).map_err(|e| LabError::write(path, e))
}

/// A recorded value: reals to 4 significant digits, everything else as it is.
pub fn value_cell(value: &Value) -> String {
    match value {
        Value::Real(v) => round_significant(*v, 4),
        other => other.to_string(),
    }
}

fn cell(value: Option<Real>) -> String {
    value.filter(|v| !v.is_nan()).map_or("—".into(), |v| round_significant(v, 3))
}
