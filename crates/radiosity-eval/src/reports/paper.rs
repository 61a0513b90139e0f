//! The paper's figures 1–3 (Rousselle & Renaud, *Group Accelerated Shooting Methods for
//! Radiosity*, §5) as comparisons, and each of its claims set beside our measurement.
//!
//! Multi-cubes with groups of 30 and a memory of 480; the labyrinth and the office with groups
//! of 50 and a memory of 500; every run to n shooting steps (the paper's axis), with the
//! automatic group frequency. [`section`] writes one figure's part of the report.

use crate::lab::compare::Comparison;
use radiosity_core::Real;
use radiosity_solvers::Unit;
use std::fmt::Write as _;

/// The stop rule of every run: n shooting steps, the paper's axis.
pub const RULES: &str = "steps=n";

/// One of the paper's figures: the scene and its six methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Figure {
    /// The scene.
    pub scene: &'static str,
    /// The figure's number in the paper.
    pub figure: &'static str,
    /// The six methods, comma-separated.
    pub solvers: &'static str,
}

/// The paper's three figures.
pub const FIGURES: [Figure; 3] = [
    Figure { scene: "multi-cubes", figure: "Fig. 1", solvers: "pr,pr-g30,pr-g30-m480,xu,xu-g30,xu-g30-m480" },
    Figure { scene: "labyrinth", figure: "Fig. 2", solvers: "pr,pr-g50,pr-g50-m500,xu,xu-g50,xu-g50-m500" },
    Figure { scene: "office", figure: "Fig. 3", solvers: "pr,pr-g50,pr-g50-m500,xu,xu-g50,xu-g50-m500" },
];

/// A claim of the paper: `better` ends below `worse` at n steps.
fn beats(c: &Comparison, better: &str, worse: &str) -> (String, String, bool) {
    let e = |name: &str| c.outcome(name).and_then(|o| c.at_step(o, c.n));
    let (b, w) = (e(better), e(worse));
    let holds = matches!((b, w), (Some(b), Some(w)) if b < w);
    (format!("`{better}` beats `{worse}` at n steps"), format!("{} against {}", sci(b), sci(w)), holds)
}

fn sci(v: Option<Real>) -> String {
    v.map_or("—".into(), |v| format!("{v:.2e}"))
}

/// The paper's claims about `figure`, with our measurement and whether it holds.
pub fn claims(figure: &Figure, c: &Comparison) -> Vec<(String, String, bool)> {
    match figure.scene {
        "multi-cubes" => vec![
            beats(c, "pr-g30", "pr"),
            beats(c, "pr-g30-m480", "pr-g30"),
            beats(c, "xu", "pr"),
            beats(c, "xu-g30", "xu"),
            beats(c, "xu-g30-m480", "xu-g30"),
        ],
        "labyrinth" => {
            let within = c.outcome("xu-g50-m500").and_then(|o| c.reached(o, 1e-2)).map(|p| p.cost[Unit::Columns]);
            vec![
                (
                    format!("`xu-g50-m500` reaches {} ≤ 1e-2 within n columns", c.metric()),
                    within.map_or("not reached".into(), |k| format!("after {k} of {} columns", c.n)),
                    within.is_some_and(|k| k <= c.n),
                ),
                beats(c, "xu-g50-m500", "xu"),
                beats(c, "pr-g50-m500", "pr"),
            ]
        }
        _ => {
            // "Group accelerated PR converges faster than PR, but the difference appears to
            // be very small"; "group accelerated Xu does not provide any acceleration".
            // "Little" is read as less than a factor 2 in e_rms at n steps.
            let e = |name: &str| c.outcome(name).and_then(|o| c.at_step(o, c.n));
            let gain = |claim: &str, a: &str, b: &str| match (e(a), e(b)) {
                (Some(x), Some(y)) => (
                    claim.to_string(),
                    format!("{:.2}× lower {} ({} against {})", y / x, c.metric(), sci(Some(x)), sci(Some(y))),
                    y / x < 2.0,
                ),
                _ => (claim.to_string(), "—".into(), false),
            };
            vec![
                gain("`pr-g50-m500` gains little (< 2×) over `pr`", "pr-g50-m500", "pr"),
                gain("`xu-g50-m500` gains little or nothing (< 2×) over `xu`", "xu-g50-m500", "xu"),
            ]
        }
    }
}

/// The report's section on `figure`, whose comparison is `c`: the step plot (in the folder
/// named after the scene), a table of every method, its seconds labelled with the run's clock,
/// and the claims with their verdicts.
pub fn section(figure: &Figure, c: &Comparison) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "## {} ({}, n = {})\n", figure.scene, figure.figure, c.n);
    let metric = c.metric();
    let _ = writeln!(md, "![{metric} against shooting steps]({}/{metric}-steps.png)\n", figure.scene);
    // Every seconds figure names its clock: `charged` when the columns came from the stored
    // matrix at the backend's measured cost, `measured` when each was computed.
    let clock = c.clock.name();
    let _ = writeln!(md, "Seconds on the `{clock}` clock: {}.\n", c.seconds_phrase());
    let _ = writeln!(
        md,
        "| method | {metric} at n steps | columns | to 1e-2 (columns / {clock} s) | to 1e-3 (columns / {clock} s) | \
         group share |"
    );
    let _ = writeln!(md, "|---|--:|--:|--:|--:|--:|");
    for o in &c.outcomes {
        let reach = |t: Real| {
            c.reached(o, t).map_or("—".into(), |p| format!("{} / {:.2} s", p.cost[Unit::Columns], p.cost.seconds()))
        };
        let _ = writeln!(
            md,
            "| `{}` | {} | {} | {} | {} | {:.1}% |",
            o.solver,
            sci(c.at_step(o, c.n)),
            o.columns_at_step(c.n).map_or("—".into(), |k| k.to_string()),
            reach(1e-2),
            reach(1e-3),
            100.0 * o.group_share()
        );
    }
    let _ = writeln!(md, "\n| the paper says | we measure | holds |\n|---|---|---|");
    for (claim, measured, holds) in claims(figure, c) {
        let _ = writeln!(md, "| {claim} | {measured} | {} |", if holds { "yes" } else { "**no**" });
    }
    md.push('\n');
    md
}

/// The report's opening, naming the form-factor backend every run used (`backend`, its
/// canonical argument).
pub fn header(backend: &str) -> String {
    format!(
        "# The paper's figures and claims, measured\n\nRousselle & Renaud, *Group Accelerated Shooting Methods \
         for Radiosity*, §5. Every method runs to n shooting steps with the form factors `{backend}` and the \
         automatic group frequency (group steps as often as keeps their counted operations near 5% of the \
         columns' modelled cost). Each scene's folder holds its full comparison report.\n\n"
    )
}
