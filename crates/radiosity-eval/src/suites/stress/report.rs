//! The stress suite's writers: `stress.md` (deterministic: no timings, so it is
//! snapshot-tested), `stress.csv` (every run) and the terminal summary, from a
//! [`StressReport`].

use crate::error::LabError;
use crate::reports::table::round_significant;
use crate::suites::stress::cases::{
    CONVERGED, RESIDUAL_TARGET, STEP_CAP, STOCHASTIC_RAYS_PER_PATCH, STOCHASTIC_SPREADS, STOCHASTIC_TOLERANCE,
};
use crate::suites::stress::judge::{BackendResult, CaseResult, Outcome, StressReport, Unsettled};
use radiosity_core::Real;
use radiosity_solvers::TerminationReason;
use radiosity_solvers::Unit;
use std::fmt::Write as _;
use std::path::Path;

impl StressReport {
    /// The Markdown report (deterministic: no timings), as `stress.md`.
    pub fn markdown(&self) -> String {
        report_markdown(&self.results, &self.solvers)
    }

    /// Writes every run as CSV to `path`.
    pub fn write_csv(&self, path: &Path) -> Result<(), LabError> {
        write_csv(path, &self.results).map_err(|e| LabError::write(path, e))
    }

    /// Writes `stress.md` and `stress.csv` into `dir` (created if needed).
    pub fn write(&self, dir: &Path) -> Result<(), LabError> {
        std::fs::create_dir_all(dir).map_err(|e| LabError::write(dir, e))?;
        let md = dir.join("stress.md");
        std::fs::write(&md, self.markdown()).map_err(|e| LabError::write(&md, e))?;
        self.write_csv(&dir.join("stress.csv"))
    }

    /// Per case and backend: how many runs converged, and which did not.
    pub fn summary(&self) -> String {
        summary(&self.results)
    }
}

/// Errors below this are shown as round-off, so that the snapshot of the report does not
/// move with the order of a sum.
const ROUND_OFF: Real = 1e-12;

/// `v` to `digits` significant digits, or `<1e-12` below [`ROUND_OFF`].
fn small(v: Real, digits: usize) -> String {
    if v.abs() < ROUND_OFF { format!("<{ROUND_OFF:e}") } else { round_significant(v, digits) }
}

/// Two significant digits (round-off shown as such), or `—`.
fn sig(v: Option<Real>) -> String {
    v.map_or_else(|| "—".into(), |v| small(v, 2))
}

/// A number for the CSV: full precision, empty when unknown.
fn raw(v: Option<Real>) -> String {
    v.map_or_else(String::new, |v| format!("{v:e}"))
}

fn count(v: Option<u64>) -> String {
    v.map_or_else(String::new, |v| v.to_string())
}

/// A short name for how a run ended.
fn stop_kind(t: &TerminationReason) -> &'static str {
    match t {
        TerminationReason::Spent(..) | TerminationReason::Steps(_) => "budget",
        TerminationReason::Rms(_) => "rms",
        TerminationReason::Residual(_) => "residual",
        TerminationReason::StdError(_) => "standard error",
        TerminationReason::Time(_) => "time",
        TerminationReason::RoundOff => "round-off",
        TerminationReason::StepCap(_) => "step cap",
        TerminationReason::Diverged { .. } => "diverged",
        TerminationReason::Stopped { .. } => "stopped",
        TerminationReason::Breakdown { .. } => "breakdown",
    }
}

/// One grid cell: status, then the final error against the exact answer (or the reference).
fn cell(outcome: &Outcome) -> String {
    match outcome {
        Outcome::Failed(_) => "**failed**".into(),
        Outcome::Ended(e) => {
            let status = if e.non_finite > 0 {
                "NaN"
            } else if e.converged() {
                "✓"
            } else {
                match e.termination {
                    TerminationReason::StepCap(_) => "cap",
                    TerminationReason::Diverged { .. } => "div",
                    _ => "✗",
                }
            };
            // A stochastic run is judged against the reference of the system it sampled, with
            // its standard error beside.
            let error = if e.sampled { e.e_reference } else { e.e_exact.or(e.e_reference) };
            let mut s = format!("{status} {}", error.map_or_else(|| "—".into(), |v| small(v, 1)));
            if let Some((spread, _)) = e.spread.filter(|_| e.sampled) {
                write!(s, " ±{}", small(spread, 1)).ok();
            }
            if e.negative > 0 {
                s.push_str(" neg");
            }
            if e.record.count("group_fallbacks").unwrap_or(0) > 0 {
                s.push_str(" fb");
            }
            s
        }
    }
}

/// Why a run did not converge: its reason in words, and its certified error bound (`None`
/// for a run that failed or whose system is not certifiable).
fn why(result: &BackendResult, outcome: &Outcome) -> Option<(String, Option<Real>)> {
    let e = match outcome {
        Outcome::Failed(message) => return Some((message.clone(), None)),
        Outcome::Ended(e) if e.converged() => return None,
        Outcome::Ended(e) => e,
    };
    let mut why = e.termination.to_string();
    match e.unsettled().filter(|_| e.sampled) {
        Some(Unsettled::Unmeasured) => why.push_str("; no standard error or no reference to judge it by"),
        Some(Unsettled::Noisy(spread)) => {
            write!(
                why,
                "; standard error {} above the tolerance {STOCHASTIC_TOLERANCE:e}",
                round_significant(spread, 2)
            )
            .ok();
        }
        Some(Unsettled::Inaccurate(e_rms)) => {
            write!(
                why,
                "; e_rms {} against the reference above the tolerance {STOCHASTIC_TOLERANCE:e}",
                round_significant(e_rms, 2)
            )
            .ok();
        }
        Some(Unsettled::Off { e_rms, spread }) => {
            write!(
                why,
                "; e_rms {} against the reference is more than {STOCHASTIC_SPREADS} standard errors ({}): biased, \
                 or its bar too narrow",
                round_significant(e_rms, 2),
                round_significant(spread, 2)
            )
            .ok();
        }
        None => {}
    }
    if result.contraction >= 1.0 {
        write!(
            why,
            "; not certifiable: ρ times some row sum of F reaches {}, so the system need not have a non-negative \
             solution nor any iteration converge",
            round_significant(result.contraction, 4)
        )
        .ok();
    }
    if e.negative > 0 {
        write!(why, "; {} negative radiosities", e.negative).ok();
    }
    // A stochastic run is judged by its spread, not by a certified bound.
    Some((why, (result.contraction < 1.0 && !e.sampled).then_some(e.bound)))
}

/// The runs of one case that did not converge, one line per solver and reason, naming the
/// backends and the range of their certified error bounds.
fn failures(case: &CaseResult, solvers: &[String]) -> Vec<String> {
    let shown: Vec<&BackendResult> = case.runs.iter().filter(|b| b.left_out.is_none()).collect();
    let mut lines = Vec::new();
    for (s, name) in solvers.iter().enumerate() {
        let mut groups: Vec<(String, Vec<&str>, Vec<Real>)> = Vec::new();
        for b in &shown {
            let Some((reason, bound)) = why(b, &b.solvers[s].outcome) else { continue };
            let at = match groups.iter().position(|g| g.0 == reason) {
                Some(at) => at,
                None => {
                    groups.push((reason, Vec::new(), Vec::new()));
                    groups.len() - 1
                }
            };
            groups[at].1.push(b.backend.label);
            groups[at].2.extend(bound);
        }
        for (reason, backends, bounds) in groups {
            let mut line = format!("- `{name}` on {}: {reason}", backends.join(", "));
            if !bounds.is_empty() {
                let lo = bounds.iter().copied().fold(Real::INFINITY, Real::min);
                let hi = bounds.iter().copied().fold(0.0, Real::max);
                let range = if round_significant(lo, 2) == round_significant(hi, 2) {
                    round_significant(lo, 2)
                } else {
                    format!("{} to {}", round_significant(lo, 2), round_significant(hi, 2))
                };
                write!(line, "; certified error bound {range}").ok();
            }
            lines.push(line);
        }
    }
    lines
}

/// Whether some run of `results` sampled transport.
fn any_sampled(results: &[CaseResult]) -> bool {
    results.iter().flat_map(|c| &c.runs).flat_map(|b| &b.solvers).any(|r| match &r.outcome {
        Outcome::Ended(e) => e.sampled,
        Outcome::Failed(_) => false,
    })
}

fn report_markdown(results: &[CaseResult], solvers: &[String]) -> String {
    let mut md = String::new();
    writeln!(md, "# Stress suite: stiff and extreme scenes\n").ok();
    writeln!(
        md,
        "Every solver on every backend. A run stops at residual power {RESIDUAL_TARGET:e}, at round-off, on divergence \
         or after {STEP_CAP}n steps. Cells give the status and the final e_rms against the exact answer (the furnace \
         identity where the scene is closed and uniform, otherwise the reference of the same system):\n\n\
         - `✓`: converged, the certified relative L1 error bound is at most {CONVERGED:e};\n\
         - `cap`: the step cap came first; `div`: the residual diverged; `✗`: stopped otherwise without a certified bound;\n\
         - `NaN`: non-finite values; `neg`: negative radiosities; `fb`: group systems fell back to point shots;\n\
         - `**failed**`: the run stopped with an error.\n\n\
         Each case's first table describes the systems: row sums of F, the contraction `q` the certificate needs \
         below 1, the condition number `κ_∞` of `I − diag(ρ) F` (— where it is not an M-matrix), the reference and its \
         distance from the furnace identity. Details of every run are in `stress.csv`.\n"
    )
    .ok();
    if any_sampled(results) {
        writeln!(
            md,
            "Solvers that sample transport cast their rays on the same F, each column sampled exactly, for \
             {STOCHASTIC_RAYS_PER_PATCH} rays per patch. No bound is certified for an estimate: such a run is `✓` when \
             its standard error (the spread of its replicates, relative as e_rms is, shown after `±`) is at most \
             {STOCHASTIC_TOLERANCE:e} and its e_rms against the reference of the system it sampled (its exact answer) \
             is at most {STOCHASTIC_TOLERANCE:e} too and at most {STOCHASTIC_SPREADS} standard errors: as accurate as \
             asked, and unbiased as far as its noise shows.\n"
        )
        .ok();
    }
    for case in results {
        writeln!(md, "## `{}`: {}\n", case.case.key, case.case.what).ok();
        writeln!(md, "`{}`, {} patches.\n", case.case.scene, case.patches).ok();
        writeln!(md, "| backend | row sums | q | κ_∞ | reference | reference vs exact |").ok();
        writeln!(md, "|---|---|--:|--:|---|--:|").ok();
        for b in &case.runs {
            if let Some(why) = &b.left_out {
                writeln!(md, "| {} | left out: {why} | | | | |", b.backend.label).ok();
                continue;
            }
            let reference = match &b.reference {
                Ok(r) if r.certified => format!("certified to {}", small(r.relative_bound, 1)),
                Ok(_) => "not certified".into(),
                Err(e) => format!("failed: {e}"),
            };
            let closure = b
                .closure_factors
                .map(|(lo, hi)| {
                    format!(" (after closing rows by {}–{})", round_significant(lo, 6), round_significant(hi, 6))
                })
                .unwrap_or_default();
            writeln!(
                md,
                "| {} | {}–{}{closure} | {} | {} | {reference} | {} |",
                b.backend.label,
                round_significant(b.row_sums.0, 6),
                round_significant(b.row_sums.1, 6),
                round_significant(b.contraction, 6),
                sig(b.condition),
                sig(b.reference_vs_exact),
            )
            .ok();
        }
        let shown: Vec<&BackendResult> = case.runs.iter().filter(|b| b.left_out.is_none()).collect();
        writeln!(md).ok();
        write!(md, "| solver |").ok();
        for b in &shown {
            write!(md, " {} |", b.backend.label).ok();
        }
        writeln!(md).ok();
        writeln!(md, "|---|{}", "---|".repeat(shown.len())).ok();
        for (s, name) in solvers.iter().enumerate() {
            write!(md, "| `{name}` |").ok();
            for b in &shown {
                write!(md, " {} |", cell(&b.solvers[s].outcome)).ok();
            }
            writeln!(md).ok();
        }
        let failures = failures(case, solvers);
        if !failures.is_empty() {
            writeln!(md, "\nRuns that did not converge:\n").ok();
            for f in failures {
                writeln!(md, "{f}").ok();
            }
        }
        writeln!(md).ok();
    }
    md
}

fn write_csv(path: &Path, results: &[CaseResult]) -> Result<(), csv::Error> {
    let mut w = csv::Writer::from_path(path)?;
    w.write_record([
        "case",
        "scene",
        "backend",
        "solver",
        "stop",
        "detail",
        "converged",
        "steps",
        "columns",
        "columns_to_1e-3",
        "columns_to_1e-6",
        "e_rms_reference",
        "e_rms_exact",
        "certified_bound",
        "non_finite",
        "negative",
        "energy",
        "group_condition",
        "group_fallbacks",
        "rays",
        "standard_error",
        "replicates",
    ])?;
    for case in results {
        for b in case.runs.iter().filter(|b| b.left_out.is_none()) {
            for r in &b.solvers {
                let head = [case.case.key, case.case.scene, b.backend.label, r.solver.as_str()];
                let record: Vec<String> = match &r.outcome {
                    Outcome::Failed(message) => {
                        let mut v: Vec<String> = head.iter().map(|s| s.to_string()).collect();
                        v.extend(["failed".to_string(), message.clone()]);
                        v.resize(22, String::new());
                        v
                    }
                    Outcome::Ended(e) => {
                        let mut v: Vec<String> = head.iter().map(|s| s.to_string()).collect();
                        v.extend([
                            stop_kind(&e.termination).to_string(),
                            e.termination.to_string(),
                            e.converged().to_string(),
                            e.state.step.to_string(),
                            e.state.cost[Unit::Columns].to_string(),
                            count(e.reached[0]),
                            count(e.reached[1]),
                            raw(e.e_reference),
                            raw(e.e_exact),
                            raw(Some(e.bound)),
                            e.non_finite.to_string(),
                            e.negative.to_string(),
                            raw(e.energy),
                            raw(e.record.real("group_condition").or(Some(0.0))),
                            e.record.count("group_fallbacks").unwrap_or(0).to_string(),
                            e.state.cost[Unit::Rays].to_string(),
                            raw(e.spread.map(|(s, _)| s)),
                            e.spread.map_or_else(String::new, |(_, r)| r.to_string()),
                        ]);
                        v
                    }
                };
                w.write_record(&record)?;
            }
        }
    }
    w.flush()?;
    Ok(())
}

/// Per case and backend: how many runs converged, and which did not.
fn summary(results: &[CaseResult]) -> String {
    let mut out = String::new();
    for case in results {
        for b in case.runs.iter().filter(|b| b.left_out.is_none()) {
            let failed: Vec<&str> = b
                .solvers
                .iter()
                .filter(|r| !matches!(&r.outcome, Outcome::Ended(e) if e.converged()))
                .map(|r| r.solver.as_str())
                .collect();
            let total = b.solvers.len();
            let _ = write!(
                out,
                "{:<15} {:<22} {:>2}/{total} converged",
                case.case.key,
                b.backend.label,
                total - failed.len()
            );
            if failed.is_empty() {
                out.push('\n');
            } else {
                let _ = writeln!(out, "; not: {}", failed.join(", "));
            }
        }
    }
    out
}
