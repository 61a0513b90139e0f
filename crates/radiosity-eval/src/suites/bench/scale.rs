//! The cost of a column and of a certified answer as the scene grows, with no
//! matrix anywhere (`--reference none`).
//!
//! For `office` at `size` 0.186, 0.093 and 0.05 (10 990, 33 179 and 95 832 patches) and the
//! largest third-party scene (the scenes folder, [`radiosity_geom::third_party`]) cut finer (`office.mgf` at `size=0.007`, 114 042
//! patches), [`scale_run`] runs one method for a given solver time (`cargo xtask bench --only
//! scale` runs each case in a process of its own, so that its peak memory is its own): from scene load, its setup (load, BVH, analysis, backend),
//! seconds per column and columns per second, its peak resident memory (`VmHWM`), the
//! certified bound at the end, and the wall time from scene load to a certified bound of 1e-1
//! and 1e-2 and 1e-3 ([`SolverBound`](crate::SolverBound), the bound every recorded step
//! carries). The growth of the time per column with `n` is fitted over the office sizes (least
//! squares of `log(seconds per column)` against `log n`): a column computes `n` pairs, so the
//! exponent should be about 1.
//!
//! The same scenes run over the hierarchical operator (`--ff hierarchical`, its defaults) with
//! [`HIERARCHICAL_SOLVERS`]: the operator's build seconds, links and memory, the seconds of a
//! product, and the same wall times from scene load, the build included; the growth of the
//! build with `n` is fitted the same way (its links grow about as `n`).

use crate::error::LabError;
use crate::lab::options::LabOptions;
use crate::lab::recorder::RecordPlan;
use crate::lab::setup::Lab;
use crate::lab::timing::median;
use crate::memory::peak_rss;
use crate::progress::NoProgress;
use crate::reference::kind::ReferenceKind;
use crate::reports::report_text::{duration, human_bytes, sig};
use radiosity_core::Real;
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::Unit;
use radiosity_solvers::{Solver, StopRules};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::time::Instant;

/// The scenes of the section: three office sizes, then the largest real scene.
pub const SCENES: [&str; 4] =
    ["office:size=0.186", "office:size=0.093", "office:size=0.05", "mgf/office3/office.mgf:size=0.007"];

/// The certified bounds timed.
pub const BOUNDS: [Real; 3] = [1e-1, 1e-2, 1e-3];

/// The residual power a run stops at before its time is up: the Krylov runs over the
/// hierarchical operator get there in a few products, at a bound far below the last of
/// [`BOUNDS`], and the rest of their time would measure nothing.
pub const STOP_RESIDUAL: Real = 1e-6;

/// The methods run over the hierarchical operator: a Krylov solver, the gathering sweep, the
/// best point shooting method and its group-accelerated variant.
pub const HIERARCHICAL_SOLVERS: [&str; 4] = ["cg", "gauss-seidel", "xu", "xu-g50-m500"];

/// What building the hierarchical operator cost, in a run over it.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct OperatorFigures {
    /// Seconds to build the tree and the links.
    pub seconds: Real,
    /// Far links (between clusters).
    pub far_links: usize,
    /// Near links (patch to patch).
    pub near_links: usize,
    /// Bytes held by the tree and the links.
    pub bytes: usize,
}

/// What one run reports.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ScaleReport {
    /// The scene's patches.
    pub patches: usize,
    /// Load, BVH and analysis.
    pub scene_seconds: Real,
    /// The lab's setup (backend, no reference).
    pub backend_seconds: Real,
    /// Columns computed.
    pub columns: u64,
    /// Products by F computed by the source itself.
    #[serde(default)]
    pub products: u64,
    /// The hierarchical operator's figures, in a run over it.
    #[serde(default)]
    pub operator: Option<OperatorFigures>,
    /// The run's seconds (form factors and solving).
    pub seconds: Real,
    /// Of which form factors.
    pub ff_seconds: Real,
    /// The certified relative bound at the end.
    pub bound: Real,
    /// Wall seconds from scene load to each bound of [`BOUNDS`] reached, and the columns then.
    pub reached: Vec<(Real, Real, u64)>,
    /// Peak resident memory in bytes.
    pub peak_rss: Option<u64>,
}

/// Runs `solver` over the backend `ff` on `prepared` with no reference and no matrix for
/// `max_seconds` of solver time or to residual power [`STOP_RESIDUAL`], timing from `start`, the instant the caller began loading the scene, which took
/// `scene_seconds`.
pub fn scale_run(
    prepared: &PreparedScene,
    start: Instant,
    scene_seconds: Real,
    solver: &mut dyn Solver,
    ff: &BackendSpec,
    max_seconds: Real,
) -> Result<ScaleReport, LabError> {
    let rules = StopRules::parse(&format!("time={}ms,residual={STOP_RESIDUAL:e}", (max_seconds * 1e3).ceil() as u64))?;
    let options = LabOptions::default().with_reference(ReferenceKind::None).with_residuals(false);
    let lab = Lab::new(prepared, ff, options, &NoProgress)?;
    let operator = lab.backend_figures().map(|f| OperatorFigures {
        seconds: f.seconds,
        far_links: f.count("far links").unwrap_or(0.0) as usize,
        near_links: f.count("near links").unwrap_or(0.0) as usize,
        bytes: f.bytes,
    });
    let backend_seconds = start.elapsed().as_secs_f64() - scene_seconds;
    let setup = start.elapsed().as_secs_f64();
    let o = lab.run(solver, &rules, &RecordPlan::errors_only(), &NoProgress)?;
    let reached =
        BOUNDS.iter().filter_map(|&b| o.bound_reached(b).map(|p| (b, setup + p.wall, p.cost[Unit::Columns]))).collect();
    Ok(ScaleReport {
        patches: lab.n(),
        scene_seconds,
        backend_seconds,
        columns: o.state.cost[Unit::Columns],
        products: o.state.cost[Unit::Products],
        operator,
        seconds: o.seconds(),
        ff_seconds: o.state.cost.ff_seconds,
        bound: o.last.bound.unwrap_or(Real::NAN),
        reached,
        peak_rss: peak_rss(),
    })
}

/// One case's runs: its scene, its backend, its solver and each run's report.
pub type ScaleCase = (String, String, String, Vec<ScaleReport>);

/// The section from every case's runs, each stopped after `max_seconds` of solver time; the
/// growth exponent is fitted for each solver over the office sizes.
pub fn report(rows: &[ScaleCase], max_seconds: Real) -> String {
    let mut out = String::from("## Scale: columns and certified bounds without a matrix\n\n");
    let _ = writeln!(
        out,
        "Each run is a child process with `--reference none`, stopped after {} of solver time or at residual \
         power {STOP_RESIDUAL:e}; wall times count from scene load. Seconds per column are the run's form-factor \
         seconds over its columns. Medians of {} run(s).\n",
        duration(max_seconds),
        rows.first().map_or(0, |r| r.3.len())
    );
    let _ = writeln!(
        out,
        "| scene | n | setup | method | columns | s/column | columns/s | peak memory | bound at end | to bound 1e-1 | \
         to bound 1e-2 | to bound 1e-3 |\n|---|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|"
    );
    let mut per_column: Vec<(String, f64, f64)> = Vec::new();
    for (scene, _, solver, runs) in rows.iter().filter(|r| r.1 != "hierarchical") {
        let m = |f: &dyn Fn(&ScaleReport) -> f64| median(&runs.iter().map(f).collect::<Vec<_>>());
        let n = runs.first().map_or(0, |r| r.patches);
        let spc = m(&|r| r.ff_seconds / r.columns.max(1) as f64);
        per_column.push((solver.clone(), n as f64, if scene.starts_with("office:") { spc } else { f64::NAN }));
        let _ = writeln!(
            out,
            "| `{scene}` | {} | {} | `{solver}` | {} | {} | {} | {} | {} | {} | {} | {} |",
            sig(n as f64, 3),
            duration(m(&|r| r.scene_seconds + r.backend_seconds)),
            sig(m(&|r| r.columns as f64), 3),
            duration(spc),
            sig(m(&|r| r.columns as f64 / r.seconds.max(1e-12)), 3),
            memory(m(&|r| r.peak_rss.map_or(f64::NAN, |b| b as f64))),
            sig(m(&|r| r.bound), 3),
            to(runs, 1e-1),
            to(runs, 1e-2),
            to(runs, 1e-3)
        );
    }
    out.push('\n');
    fits(&mut out, &per_column, "seconds per column", "a column computes n pairs");

    let hierarchical: Vec<&ScaleCase> = rows.iter().filter(|r| r.1 == "hierarchical").collect();
    if hierarchical.is_empty() {
        return out;
    }
    out.push_str(
        "### Over the hierarchical operator\n\nThe same scenes over `--ff hierarchical` (its defaults), the operator \
         built in each run, from scene load: the wall times include it. A product is `F·x` for the three channels.\n\n\
         | scene | n | operator built | far + near links | operator memory | method | products | columns | \
         s/product | peak memory | bound at end | to bound 1e-2 | to bound 1e-3 |\n\
         |---|--:|--:|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    let mut builds: Vec<(String, f64, f64)> = Vec::new();
    for (scene, _, solver, runs) in hierarchical {
        let m = |f: &dyn Fn(&ScaleReport) -> f64| median(&runs.iter().map(f).collect::<Vec<_>>());
        let n = runs.first().map_or(0, |r| r.patches);
        let op = |f: &dyn Fn(&OperatorFigures) -> f64| m(&|r| r.operator.as_ref().map_or(f64::NAN, f));
        let built = op(&|o| o.seconds);
        if scene.starts_with("office:") && !builds.iter().any(|b| b.1 == n as f64) {
            builds.push(("hierarchical".to_string(), n as f64, built));
        }
        let products = m(&|r| r.products as f64);
        let _ = writeln!(
            out,
            "| `{scene}` | {} | {} | {} + {} | {} | `{solver}` | {} | {} | {} | {} | {} | {} | {} |",
            sig(n as f64, 3),
            duration(built),
            sig(op(&|o| o.far_links as f64), 3),
            sig(op(&|o| o.near_links as f64), 3),
            memory(op(&|o| o.bytes as f64)),
            sig(products, 3),
            sig(m(&|r| r.columns as f64), 3),
            if products > 0.0 { duration(m(&|r| r.ff_seconds / r.products.max(1) as f64)) } else { "—".into() },
            memory(m(&|r| r.peak_rss.map_or(f64::NAN, |b| b as f64))),
            sig(m(&|r| r.bound), 3),
            to(runs, 1e-2),
            to(runs, 1e-3)
        );
    }
    out.push('\n');
    fits(&mut out, &builds, "operator's build seconds", "its links grow about as n");
    out
}

/// The median wall time from scene load to bound `b` over `runs`, or how many runs missed it.
fn to(runs: &[ScaleReport], b: Real) -> String {
    let times: Vec<f64> = runs.iter().map(|r| r.reached.iter().find(|x| x.0 == b).map_or(f64::NAN, |x| x.1)).collect();
    match times.iter().filter(|t| !t.is_nan()).count() {
        0 => "not reached".to_string(),
        k if k == runs.len() => duration(median(&times)),
        k => format!("{} ({k} of {} runs)", duration(median(&times)), runs.len()),
    }
}

/// Bytes as text, or a dash when unknown.
fn memory(bytes: f64) -> String {
    if bytes.is_nan() { "—".into() } else { human_bytes(bytes as u64) }
}

/// Appends the growth exponent in `n` of `what`, fitted per name over `points` (name, n,
/// value; values that are not finite left out), with `why` it should be about 1.
fn fits(out: &mut String, points: &[(String, f64, f64)], what: &str, why: &str) {
    let mut names: Vec<&String> = points.iter().map(|p| &p.0).collect();
    names.sort();
    names.dedup();
    let mut found = Vec::new();
    for name in names {
        let logs: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| &p.0 == name && p.2.is_finite() && p.2 > 0.0)
            .map(|p| (p.1.ln(), p.2.ln()))
            .collect();
        if logs.len() >= 2 {
            found.push(format!("`{name}` {}", sig(slope(&logs), 3)));
        }
    }
    if !found.is_empty() {
        let _ = writeln!(
            out,
            "Growth of the {what} with n over the office sizes (the slope of log–log least squares; 1 is linear, \
             and {why}): {}.\n",
            found.join(", ")
        );
    }
}

/// The least-squares slope of `points` (x, y): the exponent of a power law fitted in log–log.
pub fn slope(points: &[(f64, f64)]) -> f64 {
    let k = points.len() as f64;
    let (sx, sy) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
    let (mx, my) = (sx / k, sy / k);
    let (num, den) =
        points.iter().fold((0.0, 0.0), |(n, d), (x, y)| (n + (x - mx) * (y - my), d + (x - mx) * (x - mx)));
    if den > 0.0 { num / den } else { f64::NAN }
}

#[cfg(test)]
mod tests {
    use super::slope;

    #[test]
    fn the_slope_of_a_power_law_is_its_exponent() {
        let points: Vec<(f64, f64)> =
            [1e4, 3e4, 1e5].iter().map(|n: &f64| (n.ln(), (2e-6 * n.powf(1.1)).ln())).collect();
        assert!((slope(&points) - 1.1).abs() < 1e-12);
    }
}
