//! The form-factor backend a [`BackendSpec`] names, built for a prepared scene: column
//! backends directly, stored matrices (`matrix:of=…`) assembled (and rebalanced when asked)
//! or loaded from the [`Cache`].
//!
//! A stored matrix is assembled by [`assemble_matrix`]: each unordered pair once, the other
//! entry by reciprocity, when the backend can give single entries (the analytic backend,
//! [`StoredMatrix::assemble_reciprocal`]); column by column otherwise (hemicube and Monte
//! Carlo columns are not reciprocal, so both entries of a pair must be computed). Both run on
//! rayon's threads and give the same matrix whatever their number.
//!
//! A stored matrix's cache key is [`scene_key`] with the canonical backend argument and the
//! way it was assembled, so a matrix is reused exactly when the geometry, every backend
//! parameter and the assembly agree. The hierarchical operator's links are cached the same way
//! (kind `hierarchical`, [`HierarchicalColumns::to_bytes`]), keyed by the scene and the
//! canonical argument: a second run over the same scene reads them instead of building.

use crate::error::LabError;
use crate::progress::Progress;
use crate::reference::cache::{Cache, Lookup, scene_key};
use radiosity_core::{ColumnSource, Real};
use radiosity_ff::guard::MatrixFigures;
use radiosity_ff::matrix::RebalanceReport;
use radiosity_ff::{Backend, BackendSpec, BuildProgress, HierarchicalColumns, StoredMatrix};
use radiosity_geom::PreparedScene;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// A stored matrix and where it came from.
#[derive(Debug)]
pub struct ObtainedMatrix {
    /// The matrix.
    pub matrix: StoredMatrix,
    /// Seconds to assemble (and rebalance) or load it.
    pub seconds: f64,
    /// Entries clamped while assembling; `None` when loaded from the cache.
    pub clamped: Option<u64>,
    /// Figures before rebalancing and what rebalancing did, when it was done now.
    pub rebalanced: Option<(MatrixFigures, RebalanceReport)>,
    /// How the cache was used, when one was.
    pub cache: Option<CacheUse>,
}

/// How the cache was used.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CacheUse {
    /// The entry's file.
    pub path: PathBuf,
    /// Loaded from the file (otherwise assembled and written to it).
    pub loaded: bool,
    /// Why the file could not be written, if it could not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub write_error: Option<String>,
}

/// The backend `spec` names; a `matrix` comes from `cache` when it holds it (and is written
/// to it otherwise), or is assembled fresh without a cache; so is the hierarchical operator's
/// links, whose reading or building is shown as a stage of `progress`.
pub fn backend<'p>(
    prepared: &'p PreparedScene,
    spec: &BackendSpec,
    cache: Option<&Cache>,
    progress: &dyn Progress,
) -> Result<Backend<'p>, LabError> {
    Ok(match spec {
        BackendSpec::Matrix { .. } => Backend::Matrix(obtain_matrix(prepared, spec, cache, progress)?.matrix),
        BackendSpec::Hierarchical(_) => {
            Backend::Hierarchical(Box::new(obtain_hierarchical(prepared, spec, cache, progress)))
        }
        _ => Backend::columns(spec, prepared.into()),
    })
}

/// The hierarchical operator `spec` names: read from `cache` when it holds it (a file that
/// cannot be read is replaced, with a warning), built otherwise and written to it.
fn obtain_hierarchical(
    prepared: &PreparedScene,
    spec: &BackendSpec,
    cache: Option<&Cache>,
    progress: &dyn Progress,
) -> HierarchicalColumns {
    let key = format!("{}; backend {}", scene_key(prepared.scene()), spec.canonical());
    if let Some(cache) = cache {
        progress.begin("reading the hierarchical operator", 0, "");
        let read = match cache.read("hierarchical", &key) {
            Lookup::Hit(bytes) => match HierarchicalColumns::from_bytes(&bytes, &key, prepared.scene()) {
                Ok(h) => Some(h),
                Err(e) => {
                    progress.warn(&format!("replacing cache file {}: {e}", cache.path("hierarchical", &key).display()));
                    None
                }
            },
            Lookup::Miss => None,
            Lookup::Unreadable(why) => {
                progress.warn(&why);
                None
            }
        };
        progress.end();
        if let Some(h) = read {
            return h;
        }
    }
    let BackendSpec::Hierarchical(params) = spec else { unreachable!("called with a hierarchical spec") };
    // The bar counts thousandths of the pairs of patches settled: links high in the tree
    // settle many at once, so it runs fast at first and slows down.
    progress.begin("building the hierarchical operator", 1000, "‰ pairs settled");
    let observe = |p: BuildProgress| progress.advance((p.settled * 1000.0) as u64, &format!("{} links", p.links));
    let built = HierarchicalColumns::new_observed(
        prepared.scene(),
        &prepared.visibility,
        &prepared.analysis,
        *params,
        &observe,
    );
    progress.end();
    if let Some(cache) = cache {
        if let Err(e) = cache.write("hierarchical", &key, &built.to_bytes(&key)) {
            progress.warn(&format!("the hierarchical operator was not cached: {e}"));
        }
    }
    built
}

/// The full matrix of `spec` (for `matrix:of=…`, of the backend it stores, rebalanced when it
/// says so), from `cache` when it holds it.
pub fn obtain_matrix(
    prepared: &PreparedScene,
    spec: &BackendSpec,
    cache: Option<&Cache>,
    progress: &dyn Progress,
) -> Result<ObtainedMatrix, LabError> {
    let rebalance = matches!(spec, BackendSpec::Matrix { rebalance: true, .. });
    let assemble_now = |cache: Option<CacheUse>| -> Result<ObtainedMatrix, LabError> {
        let start = Instant::now();
        let (matrix, clamped, rebalanced) = assemble_stored(prepared, spec, rebalance, progress)?;
        Ok(ObtainedMatrix { matrix, seconds: start.elapsed().as_secs_f64(), clamped: Some(clamped), rebalanced, cache })
    };
    let (BackendSpec::Matrix { .. }, Some(cache)) = (spec, cache) else { return assemble_now(None) };
    let key = format!("{}; backend {}; {}", scene_key(prepared.scene()), spec.canonical(), assembly_of(spec));
    let start = Instant::now();
    match cache.read("ff", &key) {
        Lookup::Hit(bytes) => match StoredMatrix::from_bytes(&bytes, &key) {
            Ok(matrix) => {
                let cache = Some(CacheUse { path: cache.path("ff", &key), loaded: true, write_error: None });
                let seconds = start.elapsed().as_secs_f64();
                return Ok(ObtainedMatrix { matrix, seconds, clamped: None, rebalanced: None, cache });
            }
            Err(e) => progress.warn(&format!("replacing cache file {}: {e}", cache.path("ff", &key).display())),
        },
        Lookup::Miss => {}
        Lookup::Unreadable(why) => progress.warn(&why),
    }
    let mut obtained = assemble_now(None)?;
    let (path, write_error) = match cache.write("ff", &key, &obtained.matrix.to_bytes(&key)) {
        Ok(path) => (path, None),
        Err(e) => {
            progress.warn(&format!("the matrix was not cached: {e}"));
            (cache.path("ff", &key), Some(e))
        }
    };
    obtained.cache = Some(CacheUse { path, loaded: false, write_error });
    Ok(obtained)
}

/// What [`assemble_stored`] gives: the matrix, the entries clamped, and the figures before
/// rebalancing with what rebalancing did.
pub type Assembled = (StoredMatrix, u64, Option<(MatrixFigures, RebalanceReport)>);

/// Assembles the full matrix of the backend `spec` names (for `matrix:of=…`, of the backend
/// it stores) with [`assemble_matrix`], reporting progress, and rebalances it when asked; no
/// cache.
pub fn assemble_stored(
    prepared: &PreparedScene,
    spec: &BackendSpec,
    rebalance: bool,
    progress: &dyn Progress,
) -> Result<Assembled, LabError> {
    let backend = Backend::columns(spec, prepared.into());
    let area: Vec<Real> = prepared.scene().patches().iter().map(|p| p.area()).collect();
    // Single entries, reciprocal by construction, only from the analytic backend.
    let pair = match &backend {
        Backend::Analytic(a) => Some(|i: usize, j: usize| a.pair(i, j)),
        _ => None,
    };
    let pair = pair.as_ref().map(|f| f as &(dyn Fn(usize, usize) -> Real + Sync));
    let (mut matrix, clamped) = assemble_matrix(&area, &backend, pair, progress)?;
    let rebalanced = if rebalance {
        let before = matrix.figures(&area);
        let report = matrix.rebalance(&area, prepared.analysis.closure.value.is_closed())?;
        Some((before, report))
    } else {
        None
    };
    Ok((matrix, clamped.unwrap_or_else(|| backend.clamped()), rebalanced))
}

/// How [`assemble_stored`] assembles the matrix of `spec`, as its cache key and reports name
/// it: "each pair once" for the analytic backend, "column by column" otherwise.
pub fn assembly_of(spec: &BackendSpec) -> &'static str {
    let of = match spec {
        BackendSpec::Matrix { of, .. } => of,
        other => other,
    };
    if matches!(of, BackendSpec::Analytic(_)) { "each pair once" } else { "column by column" }
}

/// Assembles the full matrix of `source` (areas `area`), reporting progress: with `pair`
/// (`F_ij` before clamping, for a source whose entries are reciprocal by construction), each
/// unordered pair once and the other entry by reciprocity
/// ([`StoredMatrix::assemble_reciprocal`]); without, column by column
/// ([`StoredMatrix::assemble`]). Both are parallel and give the same matrix whatever the
/// number of threads. Returns the matrix and, with `pair`, the entries clamped into `[0, 1]`
/// (a column source counts its own).
pub fn assemble_matrix<S: ColumnSource + ?Sized>(
    area: &[Real],
    source: &S,
    pair: Option<&(dyn Fn(usize, usize) -> Real + Sync)>,
    progress: &dyn Progress,
) -> Result<(StoredMatrix, Option<u64>), LabError> {
    assemble_matrix_dyn(area, &source, pair, progress)
}

fn assemble_matrix_dyn(
    area: &[Real],
    source: &dyn ColumnSource,
    pair: Option<&(dyn Fn(usize, usize) -> Real + Sync)>,
    progress: &dyn Progress,
) -> Result<(StoredMatrix, Option<u64>), LabError> {
    let n = source.patch_count() as u64;
    let done = AtomicU64::new(0);
    let assembled = match pair {
        Some(pair) => {
            progress.begin("assembling the matrix (each pair once)", n * (n + 1) / 2, "pairs");
            let m = StoredMatrix::assemble_reciprocal(area, pair, &|k| {
                let k = done.fetch_max(k as u64, Ordering::Relaxed).max(k as u64);
                progress.advance(k, "");
            });
            progress.end();
            let (m, clamped) = m?;
            (m, Some(clamped))
        }
        None => {
            progress.begin("assembling the matrix", n, "columns");
            let m = StoredMatrix::assemble(source, &|_| {
                let k = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress.advance(k, "");
            });
            progress.end();
            (m, None)
        }
    };
    Ok(assembled)
}

/// The backend `spec` names, with a `matrix` assembled now, never read from a cache: what
/// runs that time or stress the assembly itself need.
pub fn fresh_backend<'p>(
    prepared: &'p PreparedScene,
    spec: &BackendSpec,
    progress: &dyn Progress,
) -> Result<Backend<'p>, LabError> {
    backend(prepared, spec, None, progress)
}
