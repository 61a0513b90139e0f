//! Reference solutions, error metrics and convergence tables for radiosity solvers.
//!
//! Solvers are compared on one thing: how close they get to the exact solution `B*` of the
//! **same** discrete system `(I − diag(ρ) F) B = E` (DESIGN §3 and §5), for the work they
//! did. This crate provides:
//!
//! - [`ReferenceSolution`] ([`reference`](mod@reference)): `B*` by dense LU or by certified Gauss–Seidel,
//!   with the method used and a [`Certificate`] of its own error;
//! - [`metrics`]: `e_rms`, `e_max`, the residual power `R` and the certified bound on the
//!   area-weighted L1 error of any vector, set beside the true error;
//! - [`ConvergenceTable`] ([`table`]): rows of measured points written as CSV or Markdown
//!   with floats rounded to fixed significant digits;
//! - [`FormFactors`] ([`matrix`]): the form-factor matrix fetched once from any
//!   [`ColumnSource`](radiosity_core::ColumnSource) and held in memory;
//! - [`plot`]: e_rms against steps, columns or seconds, as SVG and PNG;
//! - [`render`]: a picture of a solved scene (ray-cast, smoothly shaded with [`shading`],
//!   tone mapped), as PNG;
//! - [`gltf_export`]: a solved scene as binary glTF with its radiosity as vertex colours and
//!   its materials in the extras, so it loads back as the same system;
//! - [`path_trace`](mod@path_trace): each object's area-mean radiosity estimated by Monte Carlo
//!   path tracing over the BVH, with its standard error: a truth of the continuous problem;
//! - [`validate`](mod@validate): those path-traced means beside the discrete reference at
//!   increasing mesh resolution, which separates discretization error from solver error;
//! - [`bench`]: columns per second against the ray-tracing limit, time and memory from scene
//!   load to accuracy, and the cost of a column as scenes grow, with their medians, Markdown
//!   sections and the JSON keys of `cargo xtask bench --json`.
//!
//! With `xtask`, it is the only crate that will write files; it writes to any
//! [`std::io::Write`] and leaves opening files to its callers.
//!
//! ```
//! use radiosity_core::{Channels, DenseColumns, LinearSystem};
//! use radiosity_eval::{ReferenceParams, ReferenceSolution, metrics};
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
//! let m = metrics::evaluate(&system, &f, &reference, &[1.0, 0.0]).unwrap();
//! assert!(m.bound.certified && m.l1_error <= m.bound.bound);
//! assert!((m.e_rms - 0.25).abs() < 1e-12);
//! ```

pub mod backends;
pub mod bench;
pub mod cache;
pub mod certificate;
pub mod compare;
pub mod error;
pub mod gltf_export;
pub mod lab;
pub mod matrix;
pub mod metrics;
pub mod paper;
pub mod path_trace;
pub mod plot;
pub mod png_image;
pub mod progress;
pub mod reference;
pub mod reference_kind;
pub mod reference_shooting;
pub mod render;
pub mod shading;
pub mod stress;
pub mod table;
pub mod validate;

pub use cache::Cache;
pub use compare::Comparison;
pub use error::{EvalError, LabError};
pub use lab::{ChosenReference, ColumnCharge, ColumnCost, FinalMetrics, Lab, LabOptions, Outcome, Point, RecordPlan, ReferenceOrigin};
pub use matrix::FormFactors;
pub use certificate::{Contraction, ErrorBound, Residual, SolverBound};
pub use metrics::{Errors, Evaluator, Metrics};
pub use path_trace::{ObjectEstimate, PathTraceError, PathTraceParams, PathTraced, path_trace};
pub use progress::{NoProgress, Progress};
pub use reference::{Certificate, Method, ReferenceParams, ReferenceSolution};
pub use reference_kind::{MemoryBudget, ReferenceKind};
pub use reference_shooting::ShootingParams;
pub use table::{ConvergenceTable, TableRow};
pub use validate::{ValidateError, ValidateParams, Validation, validate};
