//! The form-factor backend a [`BackendSpec`] names (whichever registry parsed it), built for a prepared scene: column
//! backends directly, stored matrices (`matrix:of=…`) assembled (and rebalanced when asked)
//! or loaded from the [`Cache`].
//!
//! A stored matrix is assembled by [`assemble_matrix`]: each unordered pair once, the other
//! entry by reciprocity, when the backend can give single entries
//! ([`FormFactorBackend::pairs`]: the analytic backend, [`StoredMatrix::assemble_reciprocal`]);
//! column by column otherwise (hemicube and Monte
//! Carlo columns are not reciprocal, so both entries of a pair must be computed). Both run on
//! rayon's threads and give the same matrix whatever their number.
//!
//! A stored matrix's cache key is [`scene_key`] with the canonical backend argument and the
//! way it was assembled, so a matrix is reused exactly when the geometry, every backend
//! parameter and the assembly agree. A backend that keeps its build
//! ([`radiosity_ff::BackendArgument::cache_kind`]: the hierarchical operator's links, kind
//! `hierarchical`) is cached the same way ([`FormFactorBackend::persist`]), keyed by the scene
//! and the canonical argument: a second run over the same scene reads it instead of building.

use crate::error::LabError;
use crate::progress::Progress;
use crate::reference::cache::{Cache, Lookup, scene_key};
use radiosity_core::{ColumnSource, Real};
use radiosity_ff::guard::MatrixFigures;
use radiosity_ff::matrix::RebalanceReport;
use radiosity_ff::{BackendSpec, BuildObserver, FormFactorBackend, FormFactorInput, StoredMatrix};
use radiosity_geom::PreparedScene;
use std::path::PathBuf;
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

/// A [`Progress`] that a backend reports its build to.
#[derive(Clone, Copy)]
pub struct Observed<'a>(pub &'a dyn Progress);

impl BuildObserver for Observed<'_> {
    fn begin(&self, stage: &str, total: u64, unit: &str) {
        self.0.begin(stage, total, unit)
    }

    fn advance(&self, done: u64, note: &str) {
        self.0.advance(done, note)
    }

    fn end(&self) {
        self.0.end()
    }

    fn warn(&self, message: &str) {
        self.0.warn(message)
    }
}

/// The backend `spec` names; a stored matrix comes from `cache` when it holds it (and is
/// written to it otherwise), or is assembled fresh without a cache; so is a backend that keeps
/// its build ([`radiosity_ff::BackendArgument::cache_kind`], the hierarchical operator's
/// links), whose reading or building is shown as a stage of `progress`.
pub fn backend<'p>(
    prepared: &'p PreparedScene,
    spec: &BackendSpec,
    cache: Option<&Cache>,
    progress: &dyn Progress,
) -> Result<Box<dyn FormFactorBackend + 'p>, LabError> {
    if spec.stores().is_some() {
        return Ok(Box::new(obtain_matrix(prepared, spec, cache, progress)?.matrix));
    }
    match (spec.argument().cache_kind(), cache) {
        (Some(kind), Some(cache)) => obtain_kept(prepared, spec, kind, cache, progress),
        _ => Ok(spec.build_observed(FormFactorInput::try_from(prepared)?, &Observed(progress))?),
    }
}

/// The backend `spec` names, whose build is kept under `kind`: read from `cache` when it holds
/// it (a file that cannot be read is replaced, with a warning), built otherwise and written to
/// it.
fn obtain_kept<'p>(
    prepared: &'p PreparedScene,
    spec: &BackendSpec,
    kind: &str,
    cache: &Cache,
    progress: &dyn Progress,
) -> Result<Box<dyn FormFactorBackend + 'p>, LabError> {
    let key = format!("{}; backend {}", scene_key(prepared.scene()), spec.canonical());
    progress.begin(&format!("reading the {} backend", spec.name()), 0, "");
    let read = match cache.read(kind, &key) {
        Lookup::Hit(bytes) => match spec.argument().load(&bytes, &key, FormFactorInput::try_from(prepared)?) {
            Ok(built) => Some(built),
            Err(e) => {
                progress.warn(&format!("replacing cache file {}: {e}", cache.path(kind, &key).display()));
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
    if let Some(built) = read {
        return Ok(built);
    }
    let built = spec.build_observed(FormFactorInput::try_from(prepared)?, &Observed(progress))?;
    // Turned into bytes only where they can be written: at a million patches they are 0.7 GB.
    let written = cache.prepare().and_then(|()| match built.persist(&key) {
        Some(bytes) => cache.write(kind, &key, &bytes).map(|_| ()),
        None => Ok(()),
    });
    if let Err(e) = written {
        progress.warn(&format!("the {} backend was not cached: {e}", spec.name()));
    }
    Ok(built)
}

/// The full matrix of `spec` (for `matrix:of=…`, of the backend it stores, rebalanced when it
/// says so), from `cache` when it holds it.
pub fn obtain_matrix(
    prepared: &PreparedScene,
    spec: &BackendSpec,
    cache: Option<&Cache>,
    progress: &dyn Progress,
) -> Result<ObtainedMatrix, LabError> {
    let rebalance = spec.stores().is_some_and(|(_, rebalance)| rebalance);
    let assemble_now = |cache: Option<CacheUse>| -> Result<ObtainedMatrix, LabError> {
        let start = Instant::now();
        let (matrix, clamped, rebalanced) = assemble_stored(prepared, spec, rebalance, progress)?;
        Ok(ObtainedMatrix { matrix, seconds: start.elapsed().as_secs_f64(), clamped: Some(clamped), rebalanced, cache })
    };
    let (Some(_), Some(cache)) = (spec.stores(), cache) else { return assemble_now(None) };
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
    let backend = spec.columns().build_observed(FormFactorInput::try_from(prepared)?, &Observed(progress))?;
    let area: Vec<Real> = prepared.scene().patches().iter().map(|p| p.area()).collect();
    let (mut matrix, clamped) = StoredMatrix::assemble_backend(&area, backend.as_ref(), &Observed(progress))?;
    let rebalanced = if rebalance {
        let before = matrix.figures(&area);
        let report = matrix.rebalance(&area, prepared.analysis.closure.value.is_closed())?;
        Some((before, report))
    } else {
        None
    };
    Ok((matrix, clamped, rebalanced))
}

/// How [`assemble_stored`] assembles the matrix of `spec`, as its cache key and reports name
/// it: "each pair once" for a backend that gives single entries
/// ([`BackendSpec::pairs_once`], the analytic backend), "column by column" otherwise.
pub fn assembly_of(spec: &BackendSpec) -> &'static str {
    if spec.pairs_once() { "each pair once" } else { "column by column" }
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
    Ok(StoredMatrix::assemble_observed(area, &source, pair, &Observed(progress))?)
}

/// The backend `spec` names, with a `matrix` assembled now, never read from a cache: what
/// runs that time or stress the assembly itself need.
pub fn fresh_backend<'p>(
    prepared: &'p PreparedScene,
    spec: &BackendSpec,
    progress: &dyn Progress,
) -> Result<Box<dyn FormFactorBackend + 'p>, LabError> {
    backend(prepared, spec, None, progress)
}
