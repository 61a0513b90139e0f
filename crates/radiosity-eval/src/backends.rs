//! The form-factor backend a [`BackendSpec`] names, built for a prepared scene: column
//! backends directly, stored matrices (`matrix:of=…`) assembled column by column (and
//! rebalanced when asked) or loaded from the [`Cache`].
//!
//! A stored matrix's cache key is [`scene_key`] with the canonical backend argument, so a
//! matrix is reused exactly when the geometry and every backend parameter agree.

use crate::cache::{Cache, Lookup, scene_key};
use crate::lab::LabError;
use crate::progress::Progress;
use radiosity_core::ColumnSource;
use radiosity_ff::guard::MatrixFigures;
use radiosity_ff::matrix::RebalanceReport;
use radiosity_ff::{Backend, BackendSpec, StoredMatrix};
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
/// to it otherwise), or is assembled fresh without a cache.
pub fn backend<'p>(
    prepared: &'p PreparedScene,
    spec: &BackendSpec,
    cache: Option<&Cache>,
    progress: &dyn Progress,
) -> Result<Backend<'p>, LabError> {
    Ok(match spec {
        BackendSpec::Matrix { .. } => Backend::Matrix(obtain_matrix(prepared, spec, cache, progress)?.matrix),
        _ => Backend::columns(spec, prepared.into()),
    })
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
    let key = format!("{}; backend {}", scene_key(prepared.scene()), spec.canonical());
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
/// it stores) column by column, reporting progress, and rebalances it when asked; no cache.
pub fn assemble_stored(
    prepared: &PreparedScene,
    spec: &BackendSpec,
    rebalance: bool,
    progress: &dyn Progress,
) -> Result<Assembled, LabError> {
    let backend = Backend::columns(spec, prepared.into());
    let n = backend.patch_count() as u64;
    progress.begin("assembling", n, "columns");
    let done = AtomicU64::new(0);
    let mut matrix = StoredMatrix::assemble(&backend, &|_| {
        let k = done.fetch_add(1, Ordering::Relaxed) + 1;
        progress.advance(k, "");
    });
    progress.end();
    let rebalanced = if rebalance {
        let area: Vec<f64> = prepared.scene().patches().iter().map(|p| p.area()).collect();
        let before = matrix.figures(&area);
        let report = matrix.rebalance(&area, prepared.analysis.closure.value.is_closed())?;
        Some((before, report))
    } else {
        None
    };
    Ok((matrix, backend.clamped(), rebalanced))
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
