//! The cost of a column and of a certified answer as the scene grows, with no
//! matrix anywhere (`--reference none`).
//!
//! For `office` at `size` 0.186, 0.093 and 0.05 (10 990, 33 179 and 95 832 patches) and the
//! largest real scene of `../shared/scenes` cut finer (`office.mgf` at `size=0.007`, 114 042
//! patches), [`scale_run`] runs one method for a given solver time (`cargo xtask bench --only
//! scale` runs each case in a process of its own, so that its peak memory is its own): from scene load, its setup (load, BVH, analysis, backend),
//! seconds per column and columns per second, its peak resident memory (`VmHWM`), the
//! certified bound at the end, and the wall time from scene load to a certified bound of 1e-1
//! and 1e-2 ([`SolverBound`](crate::SolverBound), the bound every recorded step carries). The
//! growth of the time per column with `n` is fitted over the office sizes (least squares of
//! `log(seconds per column)` against `log n`): a column computes `n` pairs, so the exponent
//! should be about 1.

use crate::error::LabError;
use crate::lab::options::LabOptions;
use crate::lab::recorder::RecordPlan;
use crate::lab::setup::Lab;
use crate::lab::timing::median;
use crate::progress::NoProgress;
use crate::reference::kind::ReferenceKind;
use crate::suites::bench::memory::peak_rss;
use crate::suites::bench::report_text::{duration, human_bytes, sig};
use radiosity_core::Real;
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::{Solver, StopRules};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::time::Instant;

/// The scenes of the section: three office sizes, then the largest real scene.
pub const SCENES: [&str; 4] = [
    "office:size=0.186",
    "office:size=0.093",
    "office:size=0.05",
    "../shared/scenes/mgf/office3/office.mgf:size=0.007",
];

/// The certified bounds timed.
pub const BOUNDS: [Real; 2] = [1e-1, 1e-2];

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

/// Runs `solver` on `prepared` with no reference and no matrix for `max_seconds` of solver
/// time, timing from `start`, the instant the caller began loading the scene, which took
/// `scene_seconds`.
pub fn scale_run(
    prepared: &PreparedScene,
    start: Instant,
    scene_seconds: Real,
    solver: &mut dyn Solver,
    max_seconds: Real,
) -> Result<ScaleReport, LabError> {
    let rules = StopRules::parse(&format!("time={}ms", (max_seconds * 1e3).ceil() as u64))?;
    let options = LabOptions::default().with_reference(ReferenceKind::None).with_residuals(false);
    let lab = Lab::new(prepared, &BackendSpec::parse("analytic")?, options, &NoProgress)?;
    let backend_seconds = start.elapsed().as_secs_f64() - scene_seconds;
    let setup = start.elapsed().as_secs_f64();
    let o = lab.run(solver, &rules, &RecordPlan::errors_only(), &NoProgress)?;
    let reached = BOUNDS.iter().filter_map(|&b| o.bound_reached(b).map(|p| (b, setup + p.wall, p.columns))).collect();
    Ok(ScaleReport {
        patches: lab.n(),
        scene_seconds,
        backend_seconds,
        columns: o.state.columns,
        seconds: o.seconds(),
        ff_seconds: o.state.ff_seconds,
        bound: o.last.bound.unwrap_or(Real::NAN),
        reached,
        peak_rss: peak_rss(),
    })
}

/// One case's runs: its scene, its solver and each run's report.
pub type ScaleCase = (String, String, Vec<ScaleReport>);

/// The section from every case's runs, each stopped after `max_seconds` of solver time; the
/// growth exponent is fitted for each of `solvers` over the office sizes.
pub fn report(rows: &[ScaleCase], solvers: &[String], max_seconds: Real) -> String {
    let mut out = String::from("## Scale: columns and certified bounds without a matrix\n\n");
    let _ = writeln!(
        out,
        "Each run is a child process with `--reference none`, stopped after {} of solver time; wall times \
         count from scene load. Seconds per column are the run's form-factor seconds over its columns. \
         Medians of {} run(s).\n",
        duration(max_seconds),
        rows.first().map_or(0, |r| r.2.len())
    );
    let _ = writeln!(
        out,
        "| scene | n | setup | method | columns | s/column | columns/s | peak memory | bound at end | to bound 1e-1 | \
         to bound 1e-2 |\n|---|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|"
    );
    let mut per_column: Vec<(String, f64, f64)> = Vec::new();
    for (scene, solver, runs) in rows {
        let m = |f: &dyn Fn(&ScaleReport) -> f64| median(&runs.iter().map(f).collect::<Vec<_>>());
        let n = runs.first().map_or(0, |r| r.patches);
        let setup = m(&|r| r.scene_seconds + r.backend_seconds);
        let columns = m(&|r| r.columns as f64);
        let spc = m(&|r| r.ff_seconds / r.columns.max(1) as f64);
        let cps = m(&|r| r.columns as f64 / r.seconds.max(1e-12));
        let rss = m(&|r| r.peak_rss.map_or(f64::NAN, |b| b as f64));
        let bound = m(&|r| r.bound);
        let to = |b: Real| {
            let times: Vec<f64> =
                runs.iter().map(|r| r.reached.iter().find(|x| x.0 == b).map_or(f64::NAN, |x| x.1)).collect();
            let reached = times.iter().filter(|t| !t.is_nan()).count();
            match reached {
                0 => "not reached".to_string(),
                k if k == runs.len() => duration(median(&times)),
                k => format!("{} ({k} of {} runs)", duration(median(&times)), runs.len()),
            }
        };
        per_column.push((solver.clone(), n as f64, spc));
        let _ = writeln!(
            out,
            "| `{scene}` | {} | {} | `{solver}` | {} | {} | {} | {} | {} | {} | {} |",
            sig(n as f64, 3),
            duration(setup),
            sig(columns, 3),
            duration(spc),
            sig(cps, 3),
            if rss.is_nan() { "—".into() } else { human_bytes(rss as u64) },
            sig(bound, 3),
            to(1e-1),
            to(1e-2)
        );
    }
    out.push('\n');
    // The growth exponent over the office sizes, per method.
    let mut fits = Vec::new();
    for solver in solvers {
        let points: Vec<(f64, f64)> = per_column
            .iter()
            .zip(rows)
            .filter(|((s, _, spc), (scene, _, _))| s == solver && scene.starts_with("office:") && spc.is_finite())
            .map(|((_, n, spc), _)| (n.ln(), spc.ln()))
            .collect();
        if points.len() >= 2 {
            fits.push(format!("`{solver}` {}", sig(slope(&points), 3)));
        }
    }
    if !fits.is_empty() {
        let _ = writeln!(
            out,
            "Growth of the seconds per column with n over the office sizes (the slope of log–log least squares; \
             1 is linear): {}.\n",
            fits.join(", ")
        );
    }
    out
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
