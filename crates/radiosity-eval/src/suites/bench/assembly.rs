//! Matrix assembly: the full analytic matrix with each pair computed once (reciprocity), at
//! k = 1 and k = 4 shadow rays per pair, beside column-by-column assembly. [`measure`] times
//! every assembly and keeps the figures of the matrix it gave (storage, bytes, row sums,
//! reciprocity, clamped entries), not the matrix; [`report`] writes the section from them.

use crate::error::LabError;
use crate::lab::timing::median;
use crate::progress::Progress;
use crate::reports::report_text::{human_bytes, sig};
use radiosity_core::Real;
use radiosity_ff::guard::MatrixFigures;
use radiosity_ff::matrix::Storage;
use radiosity_ff::{AnalyticColumns, AnalyticParams, StoredMatrix};
use radiosity_geom::PreparedScene;
use std::fmt::Write as _;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// What the assembly section measures.
#[derive(Clone, Debug, PartialEq)]
pub struct AssemblyParams {
    /// Shadow rays per pair of each assembly by reciprocity; one column-by-column assembly at
    /// k = 1 follows them.
    pub rays: Vec<usize>,
    /// Runs of every assembly; the figures are their medians.
    pub runs: usize,
}

/// How a matrix was assembled, and what came out.
#[derive(Clone, Debug)]
pub struct Assembly {
    /// "each pair once (reciprocity)" or "column by column".
    pub label: String,
    /// Shadow rays per pair.
    pub rays: usize,
    /// Seconds of every run.
    pub seconds: Vec<f64>,
    /// Pairs computed: each unordered pair once, or every ordered pair.
    pub pairs: f64,
    /// How the matrix is stored.
    pub storage: Storage,
    /// Bytes of the stored entries.
    pub bytes: usize,
    /// Stored non-zeros.
    pub nonzeros: usize,
    /// Its row sums and reciprocity.
    pub figures: MatrixFigures,
    /// Every row sum.
    pub row_sums: Vec<Real>,
    /// Entries clamped into `[0, 1]`.
    pub clamped: u64,
}

/// Assembles the analytic backend's full matrix of `prepared` as `params` says, `params.runs`
/// times each, and keeps the figures of the last matrix of each (the matrices of a large scene
/// are hundreds of MB each); `progress` follows every assembly.
pub fn measure(
    prepared: &PreparedScene,
    params: &AssemblyParams,
    progress: &dyn Progress,
) -> Result<Vec<Assembly>, LabError> {
    let scene = &prepared.loaded.scene;
    let n = scene.len();
    let area: Vec<Real> = scene.patches().iter().map(|p| p.area()).collect();
    let total_pairs = (n * (n + 1) / 2) as u64;
    let mut assemblies: Vec<Assembly> = Vec::new();
    // (label, rays, by reciprocity)
    let mut cases: Vec<(String, usize, bool)> =
        params.rays.iter().map(|&k| ("each pair once (reciprocity)".to_string(), k, true)).collect();
    cases.push(("column by column".to_string(), 1, false));
    for (label, rays, reciprocal) in cases {
        let analytic = AnalyticParams { rays, ..AnalyticParams::default() };
        let analytic = AnalyticColumns::new(scene, &prepared.visibility()?, &prepared.analysis, analytic);
        let mut seconds = Vec::new();
        let mut last = None;
        for r in 0..params.runs {
            let (len, unit) = if reciprocal { (total_pairs, "pairs") } else { (n as u64, "columns") };
            progress.begin("assembly", len, unit);
            progress.advance(0, &format!("k = {rays}, {label}, run {}/{}", r + 1, params.runs));
            let done = AtomicU64::new(0);
            let start = Instant::now();
            let assembled = if reciprocal {
                StoredMatrix::assemble_reciprocal(&area, &|i, j| analytic.pair(i, j), &|k| {
                    progress.advance(done.fetch_max(k as u64, Ordering::Relaxed).max(k as u64), "")
                })
            } else {
                let before = analytic.clamped();
                let m = StoredMatrix::assemble(&analytic, &|_| {
                    progress.advance(done.fetch_add(1, Ordering::Relaxed) + 1, "")
                });
                Ok((m, analytic.clamped() - before))
            };
            seconds.push(start.elapsed().as_secs_f64());
            progress.end();
            last = Some(assembled?);
        }
        let Some((matrix, clamped)) = last else { return Err(LabError::Invalid("--runs must be at least 1".into())) };
        // Pairs computed: each unordered pair once, or every ordered pair.
        let pairs = if reciprocal { (n * (n + 1) / 2) as f64 } else { (n * n) as f64 };
        // Only the figures are kept: the matrices of a large scene are hundreds of MB each.
        assemblies.push(Assembly {
            label,
            rays,
            seconds,
            pairs,
            storage: matrix.storage(),
            bytes: matrix.bytes(),
            nonzeros: matrix.nonzeros(),
            figures: matrix.figures(&area),
            row_sums: matrix.row_sums(),
            clamped,
        });
    }
    Ok(assemblies)
}

/// The section, headed `## 2. Matrix assembly`, from [`measure`]'s assemblies of the matrix of
/// `scene` (its argument as written), `n` patches.
pub fn report(scene: &str, n: usize, assemblies: &[Assembly]) -> String {
    let threads = rayon::current_num_threads();
    let mut out = String::from("## 2. Matrix assembly\n\n");
    let _ = writeln!(
        out,
        "The analytic backend's full matrix of `{}` ({n} patches, {} entries), assembled on {threads} threads \
         (the global rayon pool). \"Each pair once\" computes the entry whose receiver is the smaller patch and \
         derives the other by reciprocity (`StoredMatrix::assemble_reciprocal`, what `--ff matrix` does); \"column by \
         column\" computes every column, so every pair twice. Bytes are those of the stored entries.\n",
        scene,
        sig((n * n) as f64, 4),
    );
    out += "| assembly | k | seconds | pairs/s | storage | bytes | non-zeros | row sums min / mean / max | \
            reciprocity error | clamped |\n|---|--:|--:|--:|---|--:|--:|---|--:|--:|\n";
    for a in assemblies {
        let f = &a.figures;
        let s = median(&a.seconds);
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} f32 | {} | {} ({:.1}%) | {:.4} / {:.4} / {:.4} | {:.1e} | {} |",
            a.label,
            a.rays,
            sig(s, 3),
            sig(a.pairs / s, 3),
            a.storage,
            human_bytes(a.bytes as u64),
            sig(a.nonzeros as f64, 4),
            100.0 * a.nonzeros as f64 / (n * n).max(1) as f64,
            f.row_sum_min,
            f.row_sum_mean,
            f.row_sum_max,
            f.max_reciprocity_error,
            a.clamped,
        );
    }
    // The two k = 1 matrices side by side: what computing each pair once changed.
    let first = assemblies.iter().position(|a| a.rays == 1);
    if let (Some(k1), Some(columns)) = (first, assemblies.len().checked_sub(1)) {
        if k1 != columns {
            let (a, b) = (&assemblies[k1].row_sums, &assemblies[columns].row_sums);
            let largest = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, Real::max);
            let mean = a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<Real>() / n.max(1) as Real;
            let speedup = median(&assemblies[columns].seconds) / median(&assemblies[k1].seconds);
            let _ = writeln!(
                out,
                "\nAt k = 1, computing each pair once is {speedup:.2}× faster than column by column; the row sums \
                 of the two matrices differ by {largest:.2e} at most ({mean:.2e} on average): the quadrature error of \
                 the larger receiver of each pair, which the derived entries no longer carry."
            );
        }
    }
    out.push('\n');
    out
}
