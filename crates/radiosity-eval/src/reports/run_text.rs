//! A run's summary as text, one labelled line a figure, as `cargo xtask solve` prints it
//! ([`RunSummary::text`]).

use crate::lab::summary::RunSummary;
use crate::reports::report_text::human_bytes;
use crate::reports::table::round_significant;
use radiosity_solvers::Unit;
use std::fmt::Write as _;

impl RunSummary {
    /// The summary as text: the scene (`scene`, its `patches`) and the backend (`backend`)
    /// head it; then how the run stopped, its work, its error and bound, its spread, where it
    /// reached each power of ten, what the solver recorded, each rank's part, what the operator
    /// cost and holds (where the backend says: its build stage by stage, its bytes a patch part
    /// by part), and the reference.
    pub fn text(&self, scene: &str, patches: usize, backend: &str) -> String {
        let mut out = String::new();
        let mut line = |label: &str, text: String| {
            let _ = writeln!(out, "{label:<12} {text}");
        };
        line("scene", format!("{scene}: {patches} patches"));
        line(
            "solver",
            match &self.transport {
                // A solver that samples transport casts rays; the backend only serves the reference.
                Some(transport) => format!("{} with rays ({transport}; the reference over {backend})", self.solver),
                None => format!("{} with {backend}", self.solver),
            },
        );
        line("stopped", self.termination.clone());
        let c = &self.cost;
        let mut work = format!("{} steps, {} columns", self.steps, c[Unit::Columns]);
        for (unit, k) in Unit::ALL.into_iter().map(|u| (u, c[u])).filter(|&(u, k)| u != Unit::Columns && k > 0) {
            let _ = match unit {
                Unit::Reused => write!(work, " (and {k} served again from memory)"),
                Unit::Rays => write!(work, ", {k} rays ({})", self.transport.as_deref().unwrap_or_default()),
                other => write!(work, ", {k} {}", other.name()),
            };
        }
        let in_ff = if c[Unit::Rays] > 0 { "in form factors and rays" } else { "in form factors" };
        line("work", format!("{work}, {:.3} s ({:.3} s {in_ff}; {} seconds)", c.seconds(), c.ff_seconds, c.clock));
        if c.group_seconds > 0.0 {
            let share = 100.0 * c.group_seconds / c.seconds();
            line("groups", format!("{:.3} s solving groups, {share:.2}% of the run", c.group_seconds));
        }
        let residual = match self.residual {
            Some(r) if self.residual_of == "displayed radiosity" => format!("residual power {r:.4e}"),
            Some(r) => format!("residual power {r:.4e}, {}", self.residual_of),
            None => format!("residual {}", self.residual_of),
        };
        let errors = match (self.e_rms, self.e_max) {
            (Some(r), Some(m)) => format!("e_rms {r:.4e}, e_max {m:.4e}, "),
            _ => "no e_rms (no reference), ".into(),
        };
        line("error", format!("{errors}{residual}"));
        line(
            "bound",
            match self.bound {
                Some(b) => format!("certified relative L1 error ≤ {b:.4e}"),
                None => "none: the solver knows no bound on its residual".into(),
            },
        );
        if let Some(s) = self.standard_error {
            let replicates = self.replicates.map_or(String::new(), |r| format!(" of {r} independent replicates"));
            line("spread", format!("standard error {s:.4e}, relative as e_rms is{replicates} (a spread, not a bound)"));
        }
        for r in &self.reached {
            let text = format!("e_rms {:.0e} after {} steps, {}, {:.3} s", r.e_rms, r.steps, r.cost, r.cost.seconds());
            line("reached", text);
        }
        if !self.record.is_empty() {
            let cell = |v: &serde_json::Value| match v {
                serde_json::Value::Number(n) if n.is_f64() => round_significant(n.as_f64().unwrap_or_default(), 4),
                serde_json::Value::String(s) => s.clone(),
                other => other.to_string(),
            };
            let items: Vec<String> = self.record.iter().map(|(k, v)| format!("{k} {}", cell(v))).collect();
            line("recorded", items.join(", "));
        }
        for r in self.ranks.iter().flatten() {
            // A rank's part of the operator, where the operator is split between the ranks.
            let built = (r.tasks > 0 || r.links > 0).then(|| {
                let stages: Vec<String> = r.build_stages.iter().map(|(stage, t)| format!("{stage} {t:.2} s")).collect();
                let stages = if stages.is_empty() { String::new() } else { format!(" ({})", stages.join(", ")) };
                format!(
                    "{} links ({} tasks, {:.1}% of the estimated cost), {} operator ({} of links) built in {:.2} s{stages}; ",
                    r.links,
                    r.tasks,
                    100.0 * r.estimated_share,
                    human_bytes(r.operator_bytes),
                    human_bytes(r.link_bytes),
                    r.build_seconds,
                )
            });
            let rays = if r.run_rays > 0 { format!("{} rays cast, ", r.run_rays) } else { String::new() };
            line(
                &format!("rank {}", r.rank),
                format!(
                    "{}peak memory {}; the run: {rays}{:.3} s in the operator, {:.3} s in {} sums, {} sent",
                    built.unwrap_or_default(),
                    r.peak_rss.map_or("n/a".into(), human_bytes),
                    r.run_operator_seconds,
                    r.run_sum_seconds,
                    r.run_sums,
                    human_bytes(r.run_bytes_sent)
                ),
            );
        }
        if let Some(o) = &self.operator {
            let stages: Vec<String> = o.stages.iter().map(|(stage, t)| format!("{stage} {t:.2} s")).collect();
            let stages = if stages.is_empty() { String::new() } else { format!(": {}", stages.join(", ")) };
            let built = if o.loaded { "read from the cache, built in" } else { "built in" };
            line("operator", format!("{}; {built} {:.2} s{stages}", o.summary, o.build_seconds));
            let per = |bytes: usize| bytes as f64 / patches.max(1) as f64;
            let parts: Vec<String> = o.parts.iter().map(|(part, b)| format!("{part} {:.0}", per(*b))).collect();
            let parts = if parts.is_empty() { String::new() } else { format!(" ({})", parts.join(", ")) };
            line(
                "held",
                format!("{} by the operator, {:.0} bytes a patch{parts}", human_bytes(o.bytes as u64), per(o.bytes)),
            );
        }
        let r = &self.reference;
        line(
            "reference",
            match (&r.method, &r.certificate) {
                (Some(method), Some(certificate)) => format!("{} ({}): {method}; {certificate}", r.kind, r.why),
                _ => format!("none ({})", r.why),
            },
        );
        out
    }
}
