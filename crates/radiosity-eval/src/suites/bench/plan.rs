//! What a bench run measures and how it is judged: the sections and their defaults
//! ([`BenchConfig`] from a command line's [`BenchOptions`]), the cases each section runs, the
//! report's header ([`header`]) and the performance targets beside the measurements
//! ([`targets`], from the [`Findings`] of the sections).
//!
//! A command line parses its arguments into [`BenchOptions`], runs the sections (the heavy
//! cases in child processes, [`crate::bench::children`]) and prints; everything it decides is
//! here, so a researcher's crate runs the same bench with the same judgement.

use crate::error::LabError;
use crate::reports::report_text::{duration, human_bytes, sig};
use crate::suites::bench::assembly::AssemblyParams;
use crate::suites::bench::columns::ColumnsParams;
use crate::suites::bench::json::BenchJson;
use crate::suites::bench::lu::LuParams;
use crate::suites::bench::peer::Peer;
use crate::suites::bench::{scale, stochastic};
use radiosity_core::Real;
use radiosity_ff::BackendSpec;
use radiosity_solvers::SolverRegistry;
use std::fmt::Write as _;

/// The sections, in report order.
pub const SECTIONS: [&str; 6] = ["columns", "assembly", "lu", "e2e", "scale", "stochastic"];

/// The sections a plain bench runs (`scale` and `stochastic` are asked for by name).
pub const DEFAULT_SECTIONS: [&str; 4] = ["columns", "assembly", "lu", "e2e"];

/// `analytic`'s columns per second on `office`, 2 threads, before the throughput work
/// (`docs/bench-office.md` of that time): its target is twice as many.
pub const COLUMNS_BEFORE: Real = 58.8;

/// Which sections to run, from a comma-separated list (`memory` is `e2e`); all the default
/// ones without a list. An error names an unknown section.
pub fn sections(only: Option<&str>) -> Result<Vec<&'static str>, LabError> {
    let Some(only) = only else { return Ok(DEFAULT_SECTIONS.to_vec()) };
    let mut chosen = Vec::new();
    for name in only.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let Some(section) = SECTIONS.iter().find(|s| **s == name || (name == "memory" && **s == "e2e")) else {
            return Err(LabError::Invalid(format!(
                "unknown bench section '{name}'; the sections are {}",
                SECTIONS.join(", ")
            )));
        };
        if !chosen.contains(section) {
            chosen.push(*section);
        }
    }
    if chosen.is_empty() {
        return Err(LabError::Invalid(format!("--only names no section; the sections are {}", SECTIONS.join(", "))));
    }
    Ok(SECTIONS.iter().copied().filter(|s| chosen.contains(s)).collect())
}

/// What a command line gives the bench: `None` for every default.
#[derive(Clone, Debug, Default)]
pub struct BenchOptions {
    /// A smoke test: a small scene, few columns, small backends, few runs.
    pub quick: bool,
    /// Runs per measurement.
    pub runs: Option<usize>,
    /// The scene (and the stochastic section's).
    pub scene: Option<String>,
    /// Columns in the sample of the columns section.
    pub columns: Option<usize>,
    /// Solvers, comma-separated.
    pub solvers: Option<String>,
    /// Longest solver time of one run, in seconds.
    pub max_seconds: Option<Real>,
    /// A RenderPark executable to time beside the stochastic section.
    pub peer: Option<Peer>,
}

/// What every section is run with.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    /// A smoke test whose figures mean nothing.
    pub quick: bool,
    /// The bench scene.
    pub scene: String,
    /// Runs of the cheap sections (columns, lu).
    pub runs_cheap: usize,
    /// Runs of the heavy sections (assembly, e2e, scale, stochastic).
    pub runs_heavy: usize,
    /// Columns in the sample of the columns section.
    pub columns: usize,
    /// Backends of the columns section.
    pub backends: Vec<String>,
    /// Shadow rays per pair of the assembly section.
    pub assembly_rays: Vec<usize>,
    /// Group sizes of the lu section.
    pub group_sizes: Vec<usize>,
    /// Solvers of the end-to-end and scale sections, besides the full-matrix alternative.
    pub solvers: Vec<String>,
    /// Wall-time cap of one end-to-end run.
    pub max_seconds: Real,
    /// Solver-time cap of one scale run.
    pub scale_seconds: Real,
    /// The scene of the stochastic section.
    pub stochastic_scene: String,
    /// The solvers of the stochastic section.
    pub stochastic_solvers: Vec<String>,
    /// Solver-time cap of one stochastic run.
    pub sampled_seconds: Real,
    /// The shortest timed measurement of the columns section: shorter ones are repeated.
    pub min_seconds: Real,
    /// The peer timed beside the stochastic section.
    pub peer: Option<Peer>,
}

impl BenchConfig {
    /// The configuration of `options`, each default filled in; an error for a count of 0, a
    /// time that is not a positive number or a solver that does not exist.
    pub fn new(options: &BenchOptions) -> Result<BenchConfig, LabError> {
        let quick = options.quick;
        if options.runs == Some(0) {
            return Err(LabError::Invalid("--runs must be at least 1".into()));
        }
        if options.columns == Some(0) {
            return Err(LabError::Invalid("--columns must be at least 1".into()));
        }
        if let Some(s) = options.max_seconds {
            if !(s.is_finite() && s > 0.0) {
                return Err(LabError::Invalid(format!("--max-seconds must be a positive number of seconds, not {s}")));
            }
        }
        let default_solvers = if quick { "pr,xu,xu-g10-m40" } else { "pr,xu,xu-g50-m500" };
        let solvers: Vec<String> = options
            .solvers
            .as_deref()
            .unwrap_or(default_solvers)
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect();
        for s in &solvers {
            SolverRegistry::builtin().build(s)?;
        }
        let backends = if quick {
            ["analytic", "hemicube:res=32", "montecarlo:rays=2000"]
        } else {
            ["analytic", "hemicube", "montecarlo"]
        };
        let pick =
            |quick_value: Real, value: Real| options.max_seconds.unwrap_or(if quick { quick_value } else { value });
        Ok(BenchConfig {
            quick,
            scene: options.scene.clone().unwrap_or_else(|| if quick { "cornell:res=4" } else { "office" }.to_string()),
            runs_cheap: options.runs.unwrap_or(if quick { 2 } else { 5 }),
            runs_heavy: options.runs.unwrap_or(if quick { 1 } else { 3 }),
            columns: options.columns.unwrap_or(if quick { 12 } else { 200 }),
            backends: backends.iter().map(|s| s.to_string()).collect(),
            assembly_rays: vec![1, 4],
            group_sizes: if quick { vec![20, 50] } else { vec![20, 50, 100, 200, 500] },
            solvers: solvers.clone(),
            max_seconds: pick(60.0, 300.0),
            scale_seconds: pick(5.0, 120.0),
            stochastic_scene: options
                .scene
                .clone()
                .unwrap_or_else(|| if quick { "cornell:res=4" } else { stochastic::SCENE }.to_string()),
            stochastic_solvers: match &options.solvers {
                Some(_) => solvers,
                None => stochastic::SOLVERS.iter().map(|s| s.to_string()).collect(),
            },
            sampled_seconds: pick(5.0, 60.0),
            min_seconds: if quick { 0.05 } else { 0.2 },
            peer: options.peer.clone(),
        })
    }

    /// The parameters of the columns section.
    pub fn columns_params(&self) -> Result<ColumnsParams, LabError> {
        Ok(ColumnsParams {
            backends: self.backends.iter().map(|b| BackendSpec::parse(b)).collect::<Result<_, _>>()?,
            columns: self.columns,
            runs: self.runs_cheap,
            min_seconds: self.min_seconds,
        })
    }

    /// The parameters of the assembly section.
    pub fn assembly_params(&self) -> AssemblyParams {
        AssemblyParams { rays: self.assembly_rays.clone(), runs: self.runs_heavy }
    }

    /// The parameters of the lu section.
    pub fn lu_params(&self) -> LuParams {
        LuParams {
            group_sizes: self.group_sizes.clone(),
            runs: self.runs_cheap,
            budget: if self.quick { 0.002 } else { 0.05 },
        }
    }

    /// The end-to-end cases, (solver, backend): every solver over the analytic backend, then
    /// the full-matrix alternative, `gauss-seidel` over `matrix`.
    pub fn e2e_cases(&self) -> Vec<(String, String)> {
        let mut cases: Vec<(String, String)> =
            self.solvers.iter().map(|s| (s.clone(), "analytic".to_string())).collect();
        cases.push(("gauss-seidel".to_string(), "matrix".to_string()));
        cases
    }

    /// The stochastic cases: every solver with rays in the scene (`None`), then every
    /// comparator over its backend ([`stochastic::COMPARATORS`]).
    pub fn stochastic_cases(&self) -> Vec<(String, Option<String>)> {
        let mut cases: Vec<(String, Option<String>)> =
            self.stochastic_solvers.iter().map(|s| (s.clone(), None)).collect();
        cases.extend(stochastic::COMPARATORS.iter().map(|(s, ff)| (s.to_string(), Some(ff.to_string()))));
        cases
    }

    /// The scale section's scenes ([`scale::SCENES`]; with `quick`, two small Cornell boxes).
    pub fn scale_scenes(&self) -> Vec<String> {
        let scenes: &[&str] = if self.quick { &["cornell:res=4", "cornell:res=8"] } else { &scale::SCENES };
        scenes.iter().map(|s| s.to_string()).collect()
    }

    /// The scale cases, (backend, solver): the solvers over the analytic backend, then the
    /// hierarchical operator's methods ([`scale::HIERARCHICAL_SOLVERS`]).
    pub fn scale_cases(&self) -> Vec<(String, String)> {
        let mut cases: Vec<(String, String)> =
            self.solvers.iter().map(|s| ("analytic".to_string(), s.clone())).collect();
        cases.extend(scale::HIERARCHICAL_SOLVERS.iter().map(|s| ("hierarchical".to_string(), s.to_string())));
        cases
    }
}

/// What the sections found that the performance targets are judged on.
#[derive(Debug, Default)]
pub struct Findings {
    /// Analytic k = 1: pipeline rays/s ÷ raw obvhs rays/s, and ÷ raw `Visibility` rays/s, on
    /// 2 threads.
    pub analytic_ratio: Option<(Real, Real)>,
    /// The fastest method to each e_rms threshold: (threshold, method, seconds).
    pub fastest: Vec<(Real, String, Option<Real>)>,
    /// The largest peak resident memory of an end-to-end run, and its method.
    pub peak_memory: Option<(u64, String)>,
    /// Everything `--json` writes.
    pub json: BenchJson,
}

/// The title, the machine and how the figures were taken; `patches`, the bench scene's, when
/// a section measured on it.
pub fn header(config: &BenchConfig, patches: Option<usize>, sections: &[&str]) -> String {
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mut out = String::from("# Benchmarks (`cargo xtask bench`)\n\n");
    if config.quick {
        out += "**Smoke test (`--quick`): small scene and backends, figures mean nothing.**\n\n";
    }
    let scene = patches.map_or_else(String::new, |p| format!("Scene `{}`: {p} patches. ", config.scene));
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

/// The performance targets beside the measurements on `scene`; empty when no section measured
/// what they are judged on.
pub fn targets(findings: &Findings, scene: &str) -> String {
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
        let rate = c.columns_per_second.get("2").copied().unwrap_or(Real::NAN);
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
