//! Setting a lab up: the prepared scene's linear system, the column source solvers read, the
//! reference decided (`auto` weighed against the memory budget), read from the cache or solved,
//! and the stored matrix when it is kept (module doc of [`crate::lab`]).

use crate::error::LabError;
use crate::lab::backends::{assemble_matrix, backend, obtain_matrix};
use crate::lab::charged::ChargedColumns;
use crate::lab::options::{ColumnCharge, ColumnCost, LabOptions, Transport};
use crate::progress::Progress;
use crate::reference::cache::{Lookup, checksum, scene_key};
use crate::reference::certificate::Contraction;
use crate::reference::kind::{MEMORY_VARIABLE, MemoryBudget, ReferenceKind, gib, matrix_bytes};
use crate::reference::matrix::{F32Columns, FormFactors};
use crate::reference::metrics::Evaluator;
use crate::reference::shooting::solve_by_shooting;
use crate::reference::solution::ReferenceSolution;
use radiosity_core::{Clock, Collective, ColumnSource, LinearSystem, Real};
use radiosity_ff::{BackendFigures, BackendSpec, FormFactorBackend};
use radiosity_geom::{PreparedScene, SceneReport};
use std::sync::Arc;
use std::time::Instant;

/// Where the reference came from.
#[derive(Clone, Debug, PartialEq)]
pub enum ReferenceOrigin {
    /// Solved now, after assembling the matrix (`matrix`), or by a long run (`shooting`, no
    /// assembly).
    Solved {
        /// Seconds to assemble the matrix (0 without one).
        assembly_seconds: Real,
        /// Seconds to solve once the matrix was assembled.
        solve_seconds: Real,
    },
    /// Read from the cache.
    Cached {
        /// The cache file.
        path: String,
        /// Seconds to read it.
        seconds: Real,
    },
    /// There is no reference (`none`).
    NotComputed,
}

/// The reference a lab measures against, once `auto` is decided, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct ChosenReference {
    /// `matrix`, `shooting` or `none`.
    pub kind: ReferenceKind,
    /// Why: asked for, or what `auto` weighed.
    pub why: String,
}

/// A prepared scene with everything solvers are measured against.
pub struct Lab<'p> {
    pub(super) prepared: &'p PreparedScene,
    pub(super) report: SceneReport,
    pub(super) backend: String,
    pub(super) system: LinearSystem,
    pub(super) source: Box<dyn ColumnSource + 'p>,
    pub(super) serves_rows: bool,
    pub(super) matrix: Option<Arc<FormFactors>>,
    pub(super) reference: Option<ReferenceSolution>,
    pub(super) origin: ReferenceOrigin,
    pub(super) chosen: ChosenReference,
    pub(super) contraction: Contraction,
    pub(super) order: Vec<usize>,
    /// The source that serves and charges the columns, when columns are charged
    /// ([`ColumnCost::Charged`]).
    pub(super) charged: Option<Arc<ChargedColumns>>,
    /// What building the backend found and cost, when it says
    /// ([`radiosity_ff::FormFactorBackend::figures`]).
    pub(super) figures: Option<BackendFigures>,
    /// Where the solvers that sample transport cast their rays ([`LabOptions::transport`]).
    pub(super) transport: Transport,
    /// The ranks the lab's runs are solved over when its source is not split itself
    /// ([`Lab::over_ranks`]).
    pub(super) ranks: Option<Arc<dyn Collective>>,
}

/// How the matrix of a lab's source is obtained, when a `matrix` reference needs it.
enum Assembly<'s> {
    /// The backend is a stored matrix: it is the matrix.
    Stored(Arc<FormFactors>),
    /// Each unordered pair once (`F_rs` for the smaller patch `r`), the other by reciprocity.
    Reciprocal(&'s (dyn Fn(usize, usize) -> Real + Sync)),
    /// Column by column from the source.
    Columns,
}

/// What [`Lab::setup`] works out.
struct Setup {
    system: LinearSystem,
    matrix: Option<Arc<FormFactors>>,
    reference: Option<ReferenceSolution>,
    origin: ReferenceOrigin,
    chosen: ChosenReference,
    contraction: Contraction,
    /// A fresh column's mean cost, from the matrix assembled here: its seconds over `n / 2`
    /// columns when each pair was computed once, over `n` when column by column.
    assembled_column: Option<Real>,
}

impl<'p> Lab<'p> {
    /// Builds the backend `spec` (a stored matrix from the options' cache when it is there),
    /// and sets the lab up with it. `spec` may come from any [`radiosity_ff::BackendRegistry`]:
    /// a backend of one's own runs here as a built-in does. A `matrix` reference of a backend
    /// that gives single entries (the analytic one) is assembled by reciprocity (each pair
    /// once); of a stored matrix, it is that matrix.
    pub fn new(
        prepared: &'p PreparedScene,
        spec: &BackendSpec,
        options: LabOptions,
        progress: &dyn Progress,
    ) -> Result<Lab<'p>, LabError> {
        // Before the backend: a stored matrix would be assembled for nothing.
        require_emitters(prepared)?;
        let label = spec.canonical();
        if spec.stores().is_some() {
            let stored = obtain_matrix(prepared, spec, options.cache.as_ref(), progress)?.matrix;
            let serves_rows = stored.serves_rows();
            let matrix = Arc::new(FormFactors::from_stored(stored));
            // The backend and the lab's matrix, held once.
            let source = matrix.clone();
            let setup = Lab::setup(prepared, &label, &source, Assembly::Stored(matrix), &options, progress)?;
            // The backend is the matrix: its columns cost what they cost.
            let columns = ColumnCost::Computed;
            return Ok(Lab::finish(prepared, &label, Box::new(source), serves_rows, setup, columns, options.transport));
        }
        let built = backend(prepared, spec, options.cache.as_ref(), progress)?;
        let (serves_rows, figures) = (built.serves_rows(), built.figures());
        let source = F32Columns(built);
        // A backend that gives single entries is assembled each pair once.
        let pair = source.0.pairs().map(|entries| move |i: usize, j: usize| entries.pair(i, j));
        let assembly = match &pair {
            Some(pair) => Assembly::Reciprocal(pair),
            None => Assembly::Columns,
        };
        let setup = Lab::setup(prepared, &label, &source, assembly, &options, progress)?;
        let lab =
            Lab::finish(prepared, &label, Box::new(source), serves_rows, setup, options.columns, options.transport);
        Ok(Lab { figures, ..lab })
    }

    /// Sets a lab up with any column source, labelled `backend` in reports and in cache keys
    /// (which also hold a fingerprint of three of its columns, so an edited source is not
    /// taken for the old one). `serves_rows` says
    /// whether [`ColumnSource::fill_row`] gives exact rows of the matrix its columns assemble.
    /// Solvers read its columns rounded to `f32`, as a stored matrix holds them, so that a
    /// `matrix` reference solves exactly their system.
    pub fn with_source(
        prepared: &'p PreparedScene,
        backend: &str,
        source: Box<dyn ColumnSource + 'p>,
        serves_rows: bool,
        options: LabOptions,
        progress: &dyn Progress,
    ) -> Result<Lab<'p>, LabError> {
        require_emitters(prepared)?;
        let scene = prepared.scene();
        if source.patch_count() != scene.len() {
            return Err(LabError::Invalid(format!(
                "the form factors of '{backend}' have {} patches, the scene {}",
                source.patch_count(),
                scene.len()
            )));
        }
        let source = F32Columns(source);
        let setup = Lab::setup(prepared, backend, &source, Assembly::Columns, &options, progress)?;
        Ok(Lab::finish(prepared, backend, Box::new(source), serves_rows, setup, options.columns, options.transport))
    }

    fn finish(
        prepared: &'p PreparedScene,
        backend: &str,
        source: Box<dyn ColumnSource + 'p>,
        serves_rows: bool,
        setup: Setup,
        columns: ColumnCost,
        transport: Transport,
    ) -> Lab<'p> {
        let scene = prepared.scene();
        // Charged columns: the stored matrix serves them (exact rows too), at the backend's
        // measured price.
        let (source, charged) = match (&setup.matrix, columns) {
            (Some(matrix), ColumnCost::Charged) => {
                let charge = ColumnCharge::measure(&*source, setup.assembled_column);
                let charged =
                    Arc::new(ChargedColumns::new(matrix.clone(), serves_rows, source.reciprocity_bound(), charge));
                (Box::new(charged.clone()) as Box<dyn ColumnSource + 'p>, Some(charged))
            }
            _ => (source, None),
        };
        Lab {
            prepared,
            report: prepared.report(),
            backend: backend.to_string(),
            system: setup.system,
            source,
            serves_rows,
            matrix: setup.matrix,
            reference: setup.reference,
            origin: setup.origin,
            chosen: setup.chosen,
            contraction: setup.contraction,
            order: radiosity_geom::spatial_order(scene),
            charged,
            figures: None,
            transport,
            ranks: None,
        }
    }

    /// Decides the reference (module doc of [`crate::reference::kind`]), reads it from the
    /// cache or computes it.
    fn setup(
        prepared: &PreparedScene,
        backend: &str,
        source: &dyn ColumnSource,
        assembly: Assembly<'_>,
        options: &LabOptions,
        progress: &dyn Progress,
    ) -> Result<Setup, LabError> {
        let scene = prepared.scene();
        let system = LinearSystem::from_scene(scene);
        let stored = match &assembly {
            Assembly::Stored(m) => Some(m.clone()),
            _ => None,
        };
        let chosen = choose(source, stored.is_some(), options)?;
        let none = |chosen| {
            let contraction = match &stored {
                Some(m) => Contraction::from_matrix(&system, m)?,
                None => Contraction::from_products(&system, source)?.unwrap_or_else(|| Contraction::assumed(&system)),
            };
            Ok::<_, LabError>(Setup {
                system: system.clone(),
                matrix: stored.clone(),
                reference: None,
                origin: ReferenceOrigin::NotComputed,
                chosen,
                contraction,
                assembled_column: None,
            })
        };
        if chosen.kind == ReferenceKind::None {
            return none(chosen);
        }
        let params = options.reference.clone();
        let kind = chosen.kind;
        // The key costs three columns: only worked out when there is a cache to look in.
        let key = match &options.cache {
            Some(_) => {
                let how = match kind {
                    ReferenceKind::Shooting => format!("shooting {:?}", options.shooting),
                    _ => format!("matrix {params:?}"),
                };
                format!(
                    "{}; backend {backend}; columns {:016x}; reference {how}",
                    scene_key(scene),
                    source_fingerprint(source)
                )
            }
            None => String::new(),
        };
        let start = Instant::now();
        let mut cached = None;
        if let Some(cache) = &options.cache {
            progress.begin("reading the reference", 0, "");
            match cache.read("reference", &key) {
                Lookup::Hit(bytes) => match ReferenceSolution::from_bytes(&bytes, &key, &system) {
                    Ok(r) => cached = Some(r),
                    Err(e) => progress.warn(&format!("replacing {}: {e}", cache.path("reference", &key).display())),
                },
                Lookup::Miss => {}
                Lookup::Unreadable(why) => progress.warn(&why),
            }
            progress.end();
        }
        // A matrix that rays sample is kept too, so that it never depends on the cache.
        let keep_matrix = kind == ReferenceKind::Matrix
            && (options.residuals || options.transport == Transport::Matrix || cached.is_none());
        let n = system.len() as Real;
        let (matrix, assembly_seconds, assembled_column) = match (keep_matrix, assembly) {
            (false, _) => (stored, 0.0, None),
            (true, Assembly::Stored(m)) => (Some(m), 0.0, None),
            (true, Assembly::Reciprocal(pair)) => {
                let start = Instant::now();
                let m = assemble(&system, source, Some(pair), progress)?;
                let seconds = start.elapsed().as_secs_f64();
                (Some(Arc::new(m)), seconds, Some(2.0 * seconds / n))
            }
            (true, Assembly::Columns) => {
                let start = Instant::now();
                let m = assemble(&system, source, None, progress)?;
                let seconds = start.elapsed().as_secs_f64();
                (Some(Arc::new(m)), seconds, Some(seconds / n))
            }
        };
        let (reference, origin) = match cached {
            Some(reference) => {
                let path = options.cache.as_ref().map(|c| c.path("reference", &key).display().to_string());
                (
                    reference,
                    ReferenceOrigin::Cached { path: path.unwrap_or_default(), seconds: start.elapsed().as_secs_f64() },
                )
            }
            None => {
                let solve_start = Instant::now();
                let reference = match &matrix {
                    Some(m) if kind == ReferenceKind::Matrix => {
                        progress.begin("reference (matrix)", 0, "");
                        let r = ReferenceSolution::solve_matrix(&system, m, params);
                        progress.end();
                        r?
                    }
                    _ => solve_by_shooting(&system, source, &options.shooting, progress)?,
                };
                if let Some(cache) = &options.cache {
                    if let Err(e) = cache.write("reference", &key, &reference.to_bytes(&key)) {
                        progress.warn(&format!("the reference was not cached: {e}"));
                    }
                }
                let solve_seconds = solve_start.elapsed().as_secs_f64();
                (reference, ReferenceOrigin::Solved { assembly_seconds, solve_seconds })
            }
        };
        let contraction = reference.certificate().contraction.clone();
        Ok(Setup { system, matrix, reference: Some(reference), origin, chosen, contraction, assembled_column })
    }

    /// The prepared scene.
    pub fn prepared(&self) -> &'p PreparedScene {
        self.prepared
    }

    /// The report of the scene.
    pub fn report(&self) -> &SceneReport {
        &self.report
    }

    /// The backend's label (for built-in backends, the canonical argument).
    pub fn backend(&self) -> &str {
        &self.backend
    }

    /// The linear system.
    pub fn system(&self) -> &LinearSystem {
        &self.system
    }

    /// The column source solvers read.
    pub fn source(&self) -> &dyn ColumnSource {
        &*self.source
    }

    /// What each column a solver fetches is charged, when the lab serves them from its stored
    /// matrix ([`ColumnCost::Charged`]); `None` when solvers compute their columns.
    pub fn charge(&self) -> Option<&ColumnCharge> {
        self.charged.as_deref().map(ChargedColumns::charge)
    }

    /// The stored matrix, when it is kept ([`LabOptions::residuals`], assembled for the
    /// reference, or the backend itself).
    pub fn matrix(&self) -> Option<&FormFactors> {
        self.matrix.as_deref()
    }

    /// The exact solution of the same discrete system, unless the reference is `none`.
    pub fn reference(&self) -> Option<&ReferenceSolution> {
        self.reference.as_ref()
    }

    /// Where the reference came from.
    pub fn origin(&self) -> &ReferenceOrigin {
        &self.origin
    }

    /// The reference measured against, once `auto` is decided, and why.
    pub fn chosen(&self) -> &ChosenReference {
        &self.chosen
    }

    /// The contraction every certified bound of this lab rests on: measured on the stored
    /// matrix when there is one, the hypothesis of docs/design.md §6.3 otherwise
    /// ([`Contraction::assumed`]).
    pub fn contraction(&self) -> &Contraction {
        &self.contraction
    }

    /// Measures against the reference with F, when both are kept; the contraction is the one
    /// measured on the same F.
    pub(super) fn evaluator(&self) -> Result<Option<Evaluator<'_>>, LabError> {
        let (Some(m), Some(reference)) = (&self.matrix, &self.reference) else { return Ok(None) };
        Ok(Some(Evaluator::with_contraction(&self.system, m, reference, self.contraction.clone())?))
    }

    /// The number of patches.
    pub fn n(&self) -> usize {
        self.system.len()
    }

    /// What building the lab's backend found and cost, when it says (the hierarchical
    /// operator's tree and links).
    pub fn backend_figures(&self) -> Option<&BackendFigures> {
        self.figures.as_ref()
    }
}

/// Decides the reference: as asked, or for `auto` a stored backend's matrix, else `matrix`
/// when its estimated size fits the budget and `shooting` when it does not. An explicit
/// `matrix` that does not fit is refused before anything is assembled.
fn choose(source: &dyn ColumnSource, stored: bool, options: &LabOptions) -> Result<ChosenReference, LabError> {
    let asked = |kind| ChosenReference { kind, why: "asked for".into() };
    match options.kind {
        ReferenceKind::None => return Ok(asked(ReferenceKind::None)),
        ReferenceKind::Shooting => return Ok(asked(ReferenceKind::Shooting)),
        ReferenceKind::Matrix | ReferenceKind::Auto if stored => {
            let why = match options.kind {
                ReferenceKind::Auto => "auto: the backend is a stored matrix".to_string(),
                _ => "asked for; the backend is a stored matrix".to_string(),
            };
            return Ok(ChosenReference { kind: ReferenceKind::Matrix, why });
        }
        _ => {}
    }
    let mut budget = match &options.memory {
        Some(b) => b.clone(),
        None => MemoryBudget::from_env()?,
    };
    if let Some(ranks) = source.collective() {
        // Over a source split over ranks, every rank decides by rank 0's budget (ranks may
        // run on machines of different memory): the columns the estimate samples, and the
        // reference chosen, are then the same on every rank.
        budget.bytes = ranks.gather(&[budget.bytes as Real])[0][0] as u64;
    }
    let (bytes, _) = matrix_bytes(source, budget.bytes);
    let fits = bytes <= budget.bytes;
    let n = source.patch_count();
    let weighed = format!("the matrix of {n} patches needs about {} of the {budget}", gib(bytes));
    match (options.kind, fits) {
        (ReferenceKind::Matrix, true) => {
            Ok(ChosenReference { kind: ReferenceKind::Matrix, why: format!("asked for; {weighed}") })
        }
        (ReferenceKind::Matrix, false) => Err(LabError::Invalid(format!(
            "--reference matrix: {weighed}; raise {MEMORY_VARIABLE} (e.g. {MEMORY_VARIABLE}=16G) or use --reference \
             shooting or none"
        ))),
        (_, true) => Ok(ChosenReference { kind: ReferenceKind::Matrix, why: format!("auto: {weighed}") }),
        (_, false) => Ok(ChosenReference {
            kind: ReferenceKind::Shooting,
            why: format!("auto: {weighed}, so a long shooting run stands in for it"),
        }),
    }
}

/// The xxh3 of three columns of `source` (the first, the middle and the last), bit for bit:
/// part of the reference's cache key, so that a backend whose numbers change (another build,
/// an edited source of one's own) never reads an entry computed by the old one.
fn source_fingerprint(source: &dyn ColumnSource) -> u64 {
    let n = source.patch_count();
    let mut column = vec![0.0; n];
    let mut bytes = Vec::with_capacity(3 * 8 * n);
    for j in [0, n / 2, n.saturating_sub(1)] {
        source.fill_column(j, &mut column);
        bytes.extend(column.iter().flat_map(|v| v.to_bits().to_le_bytes()));
    }
    checksum(&bytes)
}

/// Refuses a scene that emits nothing: its radiosity is zero everywhere, so there is no error
/// relative to the reference to measure.
pub fn require_emitters(prepared: &PreparedScene) -> Result<(), LabError> {
    if prepared.analysis.emitters.value.is_empty() {
        return Err(LabError::NoEmitters(prepared.scene().name().to_string()));
    }
    Ok(())
}

/// Assembles the stored matrix of `source` for a `matrix` reference: each pair once by
/// reciprocity when the backend can give single entries, column by column otherwise.
fn assemble(
    system: &LinearSystem,
    source: &dyn ColumnSource,
    pair: Option<&(dyn Fn(usize, usize) -> Real + Sync)>,
    progress: &dyn Progress,
) -> Result<FormFactors, LabError> {
    let (matrix, _) = assemble_matrix(system.areas(), source, pair, progress)?;
    Ok(FormFactors::from_stored(matrix))
}

impl<'p> Lab<'p> {
    /// The lab with its columns charged at `charge`'s prices instead of those it measured,
    /// so that a run's charged seconds are known in advance (a test of what reads the clock,
    /// or a comparison priced as another machine measured); the same lab when its columns are
    /// computed ([`Lab::clock`] is [`Clock::Measured`]).
    pub fn with_charge(mut self, charge: ColumnCharge) -> Lab<'p> {
        if let Some(old) = &self.charged {
            let charged = Arc::new(old.repriced(charge));
            self.source = Box::new(charged.clone());
            self.charged = Some(charged);
        }
        self
    }

    /// The clock the lab's runs are counted on: [`Clock::Charged`] when its solvers read their
    /// columns from its stored matrix and are charged for them, [`Clock::Measured`] otherwise.
    pub fn clock(&self) -> Clock {
        if self.charged.is_some() { Clock::Charged } else { Clock::Measured }
    }
}
