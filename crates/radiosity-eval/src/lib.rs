//! Reference solutions, error metrics and convergence tables for radiosity solvers.
//!
//! Solvers are compared on one thing: how close they get to the exact solution `B*` of the
//! **same** discrete system `(I − diag(ρ) F) B = E` (docs/design.md §3 and §6), for the work they
//! did. The crate is in rooms by job; every module is private and this page is the whole
//! public API:
//!
//! - **the lab**: [`Lab`] sets a prepared scene up for measurement ([`LabOptions`], how
//!   columns are paid for: [`ColumnCost`], and so which [`Clock`] every run's seconds, stop
//!   rules and reports read; where the solvers that sample transport cast their rays:
//!   [`Transport`]), runs any solver with a [`Recorder`] into an
//!   [`Outcome`], and compares many into a [`Comparison`]; [`backend`] builds the backend a
//!   spec names, stored matrices from the [`Cache`];
//! - **references and certificates**: [`ReferenceSolution`], `B*` by dense LU or by certified
//!   Gauss–Seidel, with the method used and a [`Certificate`] of its own error; the choice of
//!   reference ([`ReferenceKind`], [`MemoryBudget`]) and the shooting reference
//!   ([`ShootingParams`]); the metrics `e_rms`, `e_max`, the residual power and the certified
//!   bound of any vector ([`evaluate`], [`Evaluator`], [`SolverBound`]); [`FormFactors`], the
//!   form-factor matrix fetched once from any [`ColumnSource`](radiosity_core::ColumnSource)
//!   and held in memory;
//! - **reports**: a comparison's `convergence.csv`, `report.md`, plots and terminal summary
//!   ([`Comparison::write`], [`Comparison::summary`]); [`ConvergenceTable`], rows written as
//!   CSV or Markdown with floats rounded to fixed significant digits; plots of e_rms against
//!   steps, columns, rays or seconds, standard errors as bands, log–log with a reference
//!   slope where a power law is expected ([`write_svg`], [`write_png`], [`PlotSpec`]);
//!   the paper's figures and claims
//!   ([`paper`]);
//! - **truth**: each object's area-mean radiosity by Monte Carlo path tracing
//!   ([`path_trace()`]), and those means beside the discrete reference at increasing mesh
//!   resolution ([`validate()`]), which separates discretization error from solver error; a
//!   fast operator against a trusted one by sampled rows and exact solutions
//!   ([`operator_distance()`]);
//! - **suites**: the stress suite ([`stress`]) and the performance measurements
//!   ([`bench`](mod@bench)): columns per second against the ray-tracing limit, matrix
//!   assembly, group solves, time and memory from scene load to accuracy, and the cost of a
//!   column as scenes grow;
//! - **view**: a picture of a solved scene ([`render()`], ray-cast, smoothly shaded with
//!   [`vertex_radiosity`], tone mapped, as PNG) and the scene as binary glTF with its
//!   radiosity as vertex colours ([`export_glb`]), which loads back as the same system.
//!
//! - **exchange**: the system in files other programs read ([`exchange`]): Matrix Market and
//!   NumPy's `.npz` (which `scipy.sparse.load_npz` reads), from [`exchange::SparseColumns`],
//!   a stored matrix's non-zeros column by column.
//!
//! `bench`, `stress`, `paper` and `exchange` stay public modules: each is a family whose members' short
//! names (`run`, `report`, `CASES`, `select`, `RULES`, `section`) clash at the root or say
//! nothing without the family's name.
//!
//! With `xtask`, it is the only crate that will write files; it writes to any
//! [`std::io::Write`] and leaves opening files to its callers.
//!
//! ```
//! use radiosity_core::{Channels, DenseColumns, LinearSystem};
//! use radiosity_eval::{ReferenceParams, ReferenceSolution, evaluate};
//!
//! // Two facing patches, each seeing half of its hemisphere covered by the other.
//! let f = DenseColumns::from_rows(2, &[0.0, 0.5, 0.5, 0.0]).unwrap();
//! let system = LinearSystem::new(Channels::Grey, vec![1.0, 1.0], vec![0.5, 0.5], vec![1.0, 0.0]).unwrap();
//! let reference = ReferenceSolution::solve(&system, &f, ReferenceParams::default()).unwrap();
//! // B1 = (E1 + ρ1 F12 E2) / (1 − ρ1 ρ2 F12 F21) = 1 / (1 − 1/16).
//! assert!((reference.get(0, 0) - 16.0 / 15.0).abs() < 1e-14);
//! assert!(reference.certificate().certified);
//!
//! // Emission alone (B = E) is 25% off in e_rms, and the certified bound covers its error.
//! let m = evaluate(&system, &f, &reference, &[1.0, 0.0]).unwrap();
//! assert!(m.bound.certified && m.l1_error <= m.bound.bound);
//! assert!((m.e_rms - 0.25).abs() < 1e-12);
//! ```

mod error;
pub mod exchange;
mod lab;
mod live;
mod memory;
mod phases;
mod progress;
mod reference;
mod reports;
mod suites;
mod truth;
mod view;

pub use error::{EvalError, LabError};
pub use lab::backends::{
    Assembled, CacheUse, ObtainedMatrix, assemble_matrix, assemble_stored, assembly_of, backend, fresh_backend,
    obtain_matrix,
};
pub use lab::calibration::Calibration;
pub use lab::compare::{Comparison, ComparisonWatch};
pub use lab::options::{ColumnCharge, ColumnCost, LabOptions, Transport};
pub use lab::outcome::{FinalMetrics, Outcome};
pub use lab::recorder::{Point, RecordPlan, Recorder, TableRow};
pub use lab::run::{check_rules, rgb};
pub use lab::setup::{ChosenReference, Lab, ReferenceOrigin, require_emitters};
pub use lab::summary::RankReport;
pub use lab::summary::{OperatorSummary, Reached, ReferenceSummary, RunSummary};
pub use lab::transport::TransportBuilt;
pub use live::feed::{FRAME_INTERVAL, Feed, FeedWatch, Frame, KEPT_FACTOR, KEPT_MOST, Sent};
pub use live::page::write_page;
pub use live::scene_view::{LiveHeader, LiveScene, PROBE_SIZE};
pub use live::server::Server;
pub use memory::return_freed_blocks;
pub use phases::{Phase, Phases, ReferenceMark};
pub use progress::{EVERY_SECONDS, Lines, NoProgress, Progress, QUIET_SECONDS};
pub use radiosity_core::Clock;
pub use reference::cache::{CACHE_DIR_VAR, Cache, Lookup, scene_key};
pub use reference::certificate::{Contraction, ErrorBound, Residual, SolverBound};
pub use reference::kind::{MEMORY_VARIABLE, MemoryBudget, ReferenceKind, matrix_bytes, parse_bytes};
pub use reference::matrix::{F32Columns, FormFactors};
pub use reference::metrics::{Errors, Evaluator, Metrics, errors, errors_against, evaluate};
pub use reference::shooting::{ShootingParams, solve_by_shooting};
pub use reference::solution::{Certificate, Method, ReferenceParams, ReferenceSolution, STORED_FORMAT_VERSION};
pub use reports::comparison::{Written, value_cell};
pub use reports::paper;
pub use reports::plot::{
    AxisScale, BAND_LABEL, BAND_STANDARD_ERRORS, BOUND_LABEL, BOUND_LABEL_SHORT, Curve, MONTE_CARLO_SLOPE, Marker,
    PlotSpec, Style, Variant, Y_LABEL, Y_LABEL_SHORT, slope_label, style_of, write_png, write_svg,
};
pub use reports::table::{ConvergenceTable, round_significant};
pub use suites::{bench, stress};
pub use truth::operator_distance::{OperatorDistance, OperatorDistanceParams, OperatorSolve, operator_distance};
pub use truth::path_trace::{
    DEFAULT_SAMPLES_PER_OBJECT, ObjectEstimate, PathTraceError, PathTraceParams, PathTraced, path_trace,
};
pub use truth::validate::{
    DiscreteMean, ObjectValidation, Refinement, Resolution, TraceSummary, ValidateError, ValidateParams, Validation,
    validate,
};
pub use view::framing::{Framing, INSIDE_FOV, default_view, up_axis};
pub use view::gltf_export::{ExportInfo, Glb, export_glb, exposure};
pub use view::png_image::{Rgb8, write_rgb8};
pub use view::render::{
    Camera, DEFAULT_FOV, ExposureProbe, Image, MAX_SIDE, RenderParams, corner_weights, render, srgb_byte,
};
pub use view::shading::{CornerTable, SMOOTH_COSINE, vertex_radiosity};
