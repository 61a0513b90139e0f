//! Columns per second for each backend, on 1 and 2 threads, against the rate at which the same
//! rays are traced straight through the BVH.
//!
//! The columns are a fixed, seeded sample spread over the scene ([`sample`]), timed as computed
//! for the first time (the analytic backend's record of visible fractions is off, since the
//! passes repeat the sample). The rays are those the columns trace, listed by
//! [`radiosity_ff::ColumnRays`] without computing the columns, traced once through
//! [`Visibility`] (the exact `f64` queries the backends call) and once with obvhs's own `f32`
//! triangle test ([`RawTracer`]). Pipeline rays per second over raw rays per second is how
//! close the backend gets to the ray-tracing limit; the time to list the rays, which runs the
//! column's code without tracing, says where the rest goes.

use crate::error::LabError;
use crate::lab::timing::median;
use crate::progress::Progress;
use crate::reports::report_text::{duration, percent, sig};
use crate::suites::bench::json::ColumnsJson;
use radiosity_core::ColumnSource;
use radiosity_ff::pair_visibility::SamplingPath;
use radiosity_ff::{AnalyticColumns, AnalyticParams, BackendSpec, ColumnRays, FormFactorInput, TracedRays};
use radiosity_geom::PreparedScene;
use radiosity_geom::Visibility;
use radiosity_geom::visibility::RawTracer;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::hint::black_box;
use std::time::Instant;

/// The sample of columns every measurement here times (defined beside a lab's column charge,
/// which times the same kind of sample).
pub use crate::lab::timing::sample;

/// Rays traced per timed chunk: enough to amortise starting the pool's threads, few enough
/// to keep the rays of a chunk (under 200 MB) in memory.
const CHUNK_RAYS: usize = 2_000_000;

/// The seed of the column sample.
pub const SAMPLE_SEED: u64 = 0x5EED;

/// Seconds of the fastest call of `work`, called until `min_seconds` have passed (once at
/// least): short measurements are repeated, and the least disturbed pass is kept (on a busy
/// machine another process can take a core for a few milliseconds, which only ever slows a
/// pass down). Measurements longer than `min_seconds` are taken once.
fn per_pass<T>(min_seconds: f64, mut work: impl FnMut() -> T) -> (f64, T) {
    let start = Instant::now();
    let mut fastest = f64::INFINITY;
    loop {
        let pass = Instant::now();
        let out = black_box(work());
        fastest = fastest.min(pass.elapsed().as_secs_f64());
        if start.elapsed().as_secs_f64() >= min_seconds {
            return (fastest, out);
        }
    }
}

/// Seconds to compute every column of `sample` of `source`, in parallel over the current pool:
/// the fastest of the passes made until `min_seconds` have passed (one at least). A source
/// that makes later columns cheaper ([`ColumnSource::reset_memory`]) is not reset between
/// passes: time it with its memory off, as [`measure`] does, or in one pass.
pub fn time_parallel<S: ColumnSource + Sync + ?Sized>(source: &S, sample: &[usize], min_seconds: f64) -> f64 {
    let n = source.patch_count();
    per_pass(min_seconds, || {
        sample.par_iter().with_max_len(1).for_each_init(
            || vec![0.0; n],
            |column, &j| {
                source.fill_column(j, column);
                black_box(&column);
            },
        )
    })
    .0
}

/// Seconds to compute every column of `sample` of `source` one after another, as a solver asks
/// for them (a backend may still use the pool inside a column): the fastest pass, as
/// [`time_parallel`].
pub fn time_sequential<S: ColumnSource + ?Sized>(source: &S, sample: &[usize], min_seconds: f64) -> f64 {
    let mut column = vec![0.0; source.patch_count()];
    per_pass(min_seconds, || {
        for &j in sample {
            source.fill_column(j, &mut column);
            black_box(&column);
        }
    })
    .0
}

/// Rays per task when tracing in parallel: a plain loop inside, so that the per-ray cost is
/// the query's alone.
const TASK_RAYS: usize = 1024;

/// Traces `rays` over the current pool through `Visibility`: the seconds, and how many are
/// clear (segments) or hit something (rays).
fn trace_exact(vis: &Visibility, rays: &TracedRays, min_seconds: f64) -> (f64, usize) {
    per_pass(min_seconds, || match rays {
        TracedRays::Segments(s) => s
            .par_chunks(TASK_RAYS)
            .map(|c| c.iter().filter(|s| vis.unoccluded_between(s.p, s.from, s.q, s.to)).count())
            .sum(),
        TracedRays::Rays(r) => r
            .par_chunks(TASK_RAYS)
            .map(|c| c.iter().filter(|r| vis.first_hit(r.origin, r.direction, Some(r.skip)).is_some()).count())
            .sum(),
    })
}

/// Traces `rays` over the current pool with obvhs's `f32` test: the seconds and the count of
/// clear segments or rays that hit something.
fn trace_raw(raw: &RawTracer<'_>, rays: &TracedRays, min_seconds: f64) -> (f64, usize) {
    per_pass(min_seconds, || match rays {
        TracedRays::Segments(s) => s
            .par_chunks(TASK_RAYS)
            .map(|c| c.iter().filter(|s| raw.unoccluded_between(s.p, s.from, s.q, s.to)).count())
            .sum(),
        TracedRays::Rays(r) => r
            .par_chunks(TASK_RAYS)
            .map(|c| c.iter().filter(|r| raw.first_hit_patch(r.origin, r.direction, Some(r.skip)).is_some()).count())
            .sum(),
    })
}

/// One run's seconds for one backend.
#[derive(Clone, Debug, Default)]
pub struct ColumnRun {
    /// Columns: 1 thread; 2 threads, columns in parallel; 2 threads, one column at a time.
    pub columns: [f64; 3],
    /// Raw rays: `Visibility` on 1 and 2 threads, obvhs `f32` on 1 and 2 threads.
    pub raw: [f64; 4],
    /// Listing the rays (analytic: the kernel, sampling and bookkeeping of the columns
    /// without their tracing), on one thread.
    pub listing: f64,
    /// Analytic: the sample's columns again, one at a time on 2 threads, with every pair's
    /// visible fraction recorded by the first pass.
    pub recorded: f64,
    /// Rays in the sample.
    pub rays: usize,
    /// Segments found clear (or rays hitting a front) by `Visibility` and by obvhs.
    pub agree: (usize, usize),
    /// Analytic: the sample's pairs by how their visibility is sampled, each timed on its own
    /// on one thread.
    pub paths: Vec<PathFigures>,
}

/// The pairs of a column sample that take one sampling path ([`SamplingPath`]; `None`: the
/// pairs that trace no ray), each timed on its own on the calling thread.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathFigures {
    /// The path.
    pub path: Option<SamplingPath>,
    /// Its pairs.
    pub pairs: usize,
    /// The rays they traced.
    pub rays: usize,
    /// The seconds they took, kernel and quadrature included.
    pub seconds: f64,
}

/// Every pair of the columns of `sample`, timed one at a time on the calling thread and grouped
/// by sampling path (the path found first, untimed, which computes the pair's unoccluded factor
/// once more outside the timing; the pairs that trace no ray first).
pub fn time_by_sampling_path(analytic: &AnalyticColumns<'_>, sample: &[usize]) -> Vec<PathFigures> {
    let paths: Vec<Option<SamplingPath>> = std::iter::once(None).chain(SamplingPath::ALL.map(Some)).collect();
    let mut figures: Vec<PathFigures> =
        paths.iter().map(|&path| PathFigures { path, pairs: 0, rays: 0, seconds: 0.0 }).collect();
    for &j in sample {
        for i in 0..analytic.patch_count() {
            let path = analytic.sampling_path(i, j);
            let start = Instant::now();
            let (value, rays) = analytic.pair_counting_rays(i, j);
            let seconds = start.elapsed().as_secs_f64();
            black_box(value);
            let slot = &mut figures[paths.iter().position(|p| *p == path).unwrap_or(0)];
            slot.pairs += 1;
            slot.rays += rays;
            slot.seconds += seconds;
        }
    }
    figures
}

/// Measures the backend `spec` once on the columns of `sample`, with `pools` of 1 and 2
/// threads; timed measurements shorter than `min_seconds` are repeated and the fastest kept.
pub fn measure(
    spec: &BackendSpec,
    input: FormFactorInput<'_>,
    raw: &RawTracer<'_>,
    sample: &[usize],
    pools: &[rayon::ThreadPool; 2],
    min_seconds: f64,
) -> Result<ColumnRun, LabError> {
    // Columns are timed as computed for the first time: the passes repeat the sample, and
    // with its visible fractions recorded a repeated column traces nothing. The record
    // changes no entry, so the backend is the same one.
    let analytic = spec.params::<AnalyticParams>();
    let first_time = match analytic {
        Some(p) => BackendSpec::new(AnalyticParams { cache_mib: 0, ..*p }),
        None => spec.clone(),
    };
    let backend = first_time.build(input.clone())?;
    // One column untimed first: the BVH and the backend's tables paged in and cached.
    if let Some(&j) = sample.first() {
        pools[1].install(|| time_sequential(&backend, &[j], 0.0));
    }
    let mut run = ColumnRun::default();
    run.columns[0] = pools[0].install(|| time_parallel(&backend, sample, min_seconds));
    run.columns[1] = pools[1].install(|| time_parallel(&backend, sample, min_seconds));
    run.columns[2] = pools[1].install(|| time_sequential(&backend, sample, min_seconds));
    if let Some(p) = analytic {
        let analytic = AnalyticColumns::new(input.scene, &input.visibility, input.analysis, *p);
        run.paths = time_by_sampling_path(&analytic, sample);
        let recorded = spec.build(input.clone())?;
        pools[1].install(|| time_sequential(&recorded, sample, 0.0));
        run.recorded = pools[1].install(|| time_sequential(&recorded, sample, min_seconds));
    }
    let rays = ColumnRays::new(spec, input.clone())
        .ok_or_else(|| LabError::Invalid(format!("{} traces no rays to measure", spec.canonical())))?;
    let mut chunk = rays.empty();
    let flush = |chunk: &mut TracedRays, run: &mut ColumnRun| {
        run.rays += chunk.len();
        let (t, clear_exact) = pools[0].install(|| trace_exact(&input.visibility, chunk, min_seconds));
        run.raw[0] += t;
        run.raw[1] += pools[1].install(|| trace_exact(&input.visibility, chunk, min_seconds)).0;
        let (t, clear_raw) = pools[0].install(|| trace_raw(raw, chunk, min_seconds));
        run.raw[2] += t;
        run.raw[3] += pools[1].install(|| trace_raw(raw, chunk, min_seconds)).0;
        run.agree.0 += clear_exact;
        run.agree.1 += clear_raw;
        chunk.clear();
    };
    for &j in sample {
        let start = Instant::now();
        rays.rays(j, &mut chunk);
        run.listing += start.elapsed().as_secs_f64();
        if chunk.len() >= CHUNK_RAYS {
            flush(&mut chunk, &mut run);
        }
    }
    if !chunk.is_empty() {
        flush(&mut chunk, &mut run);
    }
    Ok(run)
}

/// What the columns section measures.
#[derive(Clone, Debug)]
pub struct ColumnsParams {
    /// The backends.
    pub backends: Vec<BackendSpec>,
    /// Columns in the sample ([`sample`]).
    pub columns: usize,
    /// Runs of every measurement; the figures are their medians.
    pub runs: usize,
    /// The shortest timed measurement: shorter ones are repeated and the fastest kept.
    pub min_seconds: f64,
}

/// The columns section: its Markdown, its JSON entries and what the targets are judged on.
#[derive(Debug)]
pub struct ColumnsSection {
    /// The section, headed `## 1. Columns per second against the ray-tracing limit`.
    pub markdown: String,
    /// One entry per backend.
    pub json: Vec<ColumnsJson>,
    /// Analytic with one ray at least per pair: pipeline rays/s over raw obvhs rays/s, and over
    /// raw `Visibility` rays/s, on 2 threads.
    pub analytic_ratio: Option<(f64, f64)>,
}

/// A rayon pool of `threads` threads.
fn pool(threads: usize) -> Result<rayon::ThreadPool, LabError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| LabError::Invalid(format!("cannot start a pool of {threads} threads: {e}")))
}

/// Measures every backend of `params` on `prepared` (named `scene` in the text) and writes the
/// section: `params.runs` runs of [`measure`] each, their medians.
pub fn run(
    prepared: &PreparedScene,
    scene: &str,
    params: &ColumnsParams,
    progress: &dyn Progress,
) -> Result<ColumnsSection, LabError> {
    let n = prepared.loaded.scene.len();
    let input = FormFactorInput::try_from(prepared)?;
    let visibility = prepared.visibility()?;
    let raw = visibility.raw_tracer();
    let columns = sample(n, params.columns, SAMPLE_SEED);
    let pools = [pool(1)?, pool(2)?];
    let specs = &params.backends;
    progress.begin("columns", (specs.len() * params.runs) as u64, "runs");
    let mut runs: Vec<Vec<ColumnRun>> = vec![Vec::new(); specs.len()];
    for r in 0..params.runs {
        for (b, spec) in specs.iter().enumerate() {
            progress.advance(
                (r * specs.len() + b) as u64,
                &format!("{} (run {}/{})", spec.canonical(), r + 1, params.runs),
            );
            runs[b].push(measure(spec, input.clone(), &raw, &columns, &pools, params.min_seconds)?);
        }
    }
    progress.end();
    let mut section = ColumnsSection { markdown: String::new(), json: Vec::new(), analytic_ratio: None };
    let mut out = String::from("## 1. Columns per second against the ray-tracing limit\n\n");
    let _ = writeln!(
        out,
        "{} columns of `{}` drawn one from each of {} equal index ranges (seed {SAMPLE_SEED:#x}). \"Pipeline\" \
         is the backend computing those columns; \"raw\" traces the very rays those columns trace (listed by \
         `radiosity_ff::ColumnRays`), straight through the BVH: through `Visibility` (the exact `f64` queries \
         the backends call) and with obvhs's own `f32` triangle test on the same tree. The ratio is pipeline \
         rays/s ÷ raw rays/s on the same threads. Dedicated rayon pools of 1 and 2 threads; \"one at a time\" \
         computes the columns one after another on 2 threads, as a solver asks for them.\n",
        columns.len(),
        scene,
        columns.len()
    );
    out += "| backend | threads | columns/s | rays/column | pipeline rays/s | raw `Visibility` rays/s | ratio | raw \
            obvhs rays/s | ratio |\n|---|---|--:|--:|--:|--:|--:|--:|--:|\n";
    let mut notes = String::new();
    for (spec, runs) in specs.iter().zip(&runs) {
        let rays = runs[0].rays as f64;
        let per_column = rays / columns.len() as f64;
        let rate = |f: &dyn Fn(&ColumnRun) -> f64| median(&runs.iter().map(f).collect::<Vec<_>>());
        let analytic = spec.params::<AnalyticParams>();
        let kind = if analytic.is_some() { "segments" } else { "rays" };
        for (row, label, raw_index) in [(0, "1", 0), (1, "2", 1), (2, "2, one at a time", 1)] {
            let cps = rate(&|r| columns.len() as f64 / r.columns[row]);
            let pipeline = rate(&|r| rays / r.columns[row]);
            let exact = rate(&|r| rays / r.raw[raw_index]);
            let obvhs = rate(&|r| rays / r.raw[raw_index + 2]);
            let _ = writeln!(
                out,
                "| `{}` | {label} | {} | {} {kind} | {} | {} | {} | {} | {} |",
                spec.canonical(),
                sig(cps, 3),
                sig(per_column, 4),
                sig(pipeline, 3),
                sig(exact, 3),
                percent(pipeline, exact),
                sig(obvhs, 3),
                percent(pipeline, obvhs),
            );
            if row == 1 && analytic.is_some_and(|p| p.rays == 1) && rays > 0.0 {
                section.analytic_ratio = Some((pipeline / obvhs, pipeline / exact));
            }
        }
        let per_second = |row: usize| rate(&|r| columns.len() as f64 / r.columns[row]);
        section.json.push(ColumnsJson {
            backend: spec.canonical(),
            columns_per_second: [("1".to_string(), per_second(0)), ("2".to_string(), per_second(1))].into(),
            rays_per_column: per_column,
            // As the table's ratio: the median pipeline rate over the median raw rate.
            raw_share: rate(&|r| rays / r.columns[1]) / rate(&|r| rays / r.raw[3]),
            recorded_columns_per_second: analytic.is_some().then(|| rate(&|r| columns.len() as f64 / r.recorded)),
        });
        let (exact, raw) = runs[0].agree;
        if exact != raw {
            let _ = writeln!(
                notes,
                "- `{}`: of {} {kind}, `Visibility` found {exact} {} and obvhs `f32` {raw} (grazing rays and shared \
                 edges, where the exact test decides differently).",
                spec.canonical(),
                runs[0].rays,
                if kind == "segments" { "clear" } else { "hitting a patch" },
            );
        }
        if analytic.is_some() {
            let column = rate(&|r| r.columns[0] / columns.len() as f64);
            let listing = rate(&|r| r.listing / columns.len() as f64);
            let tracing = rate(&|r| r.raw[0] / columns.len() as f64);
            let recorded = rate(&|r| r.recorded / columns.len() as f64);
            let _ = writeln!(
                notes,
                "- `{}` on 1 thread: a column takes {} ms; listing its segments, which runs the same code without \
                 tracing them (kernel, quadrature, sampling), {} ms; tracing them through `Visibility` {} ms. \
                 Computed again with every pair's visible fraction recorded (`radiosity_ff::visibility_cache`: a \
                 patch shot again, or one whose receivers were all shot before), a column takes {} ms one at a \
                 time on 2 threads, against {} ms the first time.",
                spec.canonical(),
                sig(1e3 * column, 3),
                sig(1e3 * listing, 3),
                sig(1e3 * tracing, 3),
                sig(1e3 * recorded, 3),
                sig(1e3 * rate(&|r| r.columns[2] / columns.len() as f64), 3),
            );
            let tracing_per_ray = rate(&|r| r.raw[0] / r.rays.max(1) as f64);
            notes += &path_table(runs, tracing_per_ray);
        }
    }
    out.push('\n');
    if !notes.is_empty() {
        out += &notes;
        out.push('\n');
    }
    section.markdown = out;
    Ok(section)
}

/// Where an analytic column's time goes, by sampling path: the medians over `runs` of each
/// path's pairs timed one by one, beside the time their rays take traced raw through
/// `Visibility` at `tracing_per_ray` seconds a ray.
fn path_table(runs: &[ColumnRun], tracing_per_ray: f64) -> String {
    let Some(first) = runs.first() else { return String::new() };
    let pairs: usize = first.paths.iter().map(|p| p.pairs).sum();
    let total = median(&runs.iter().map(|r| r.paths.iter().map(|p| p.seconds).sum()).collect::<Vec<_>>());
    let mut out = String::from(
        "\n  Where the column's time goes, each pair of the sample timed on its own on 1 thread (medians), by how \
         its visibility is sampled (`radiosity_ff::pair_visibility::SamplingPath`); \"tracing\" is its rays at the \
         raw `Visibility` rate of the same rays, the rest is kernel, quadrature and sampling:\n\n  \
         | pairs | share of pairs | rays per pair | share of the time | per ray | tracing | the rest |\n  \
         |---|--:|--:|--:|--:|--:|--:|\n",
    );
    for (k, path) in first.paths.iter().enumerate() {
        let seconds = median(&runs.iter().map(|r| r.paths.get(k).map_or(f64::NAN, |p| p.seconds)).collect::<Vec<_>>());
        let tracing = path.rays as f64 * tracing_per_ray;
        let per_ray = |s: f64| if path.rays > 0 { duration(s / path.rays as f64) } else { "—".to_string() };
        let _ = writeln!(
            out,
            "  | {} | {} | {} | {} | {} | {} | {} |",
            path.path.map_or("no ray traced", SamplingPath::name),
            percent(path.pairs as f64, pairs as f64),
            sig(path.rays as f64 / path.pairs.max(1) as f64, 3),
            percent(seconds, total),
            per_ray(seconds),
            per_ray(tracing),
            per_ray(seconds - tracing),
        );
    }
    out
}
