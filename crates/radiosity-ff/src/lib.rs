//! Form factors: kernels and backends that implement [`radiosity_core::ColumnSource`].
//!
//! This is the only crate that turns geometry into form factors. Backends are chosen by a
//! [`BackendSpec`] ([`spec`]) that a [`BackendRegistry`] parses from `NAME[:key=value…]`
//! ([`registry`]); a built backend is a [`FormFactorBackend`], asked what it can do
//! ([`backend`]). The built-ins, registered by [`builtins`]:
//!
//! - `analytic` ([`analytic`]): Lambert's point-to-polygon formula integrated over the
//!   receiver, times each pair's visible fraction, estimated with shadow rays drawn as the
//!   kernel weighs them ([`pair_visibility`]) when something can occlude;
//! - `hemicube` ([`hemicube`]): a ray-cast hemicube at the shooter, giving its row;
//! - `montecarlo` ([`montecarlo`]): cosine-weighted rays from the shooter, giving its row;
//! - `hierarchical` ([`hierarchical`]): links between clusters of a tree over the patches, so
//!   that a product `F x` costs `O(links + n)` and a column `O(n)`; exactly reciprocal,
//!   non-negative, its rows held to at most 1 (docs/design.md §5);
//! - `matrix` ([`matrix`], [`matrix_backend`]): the full matrix of another backend, assembled
//!   once and stored.
//!
//! Every backend clamps its entries into `[0, 1]` and counts what it clamped ([`guard`]).
//!
//! Beside the backends, [`SceneTransport`] ([`scene_transport`]) samples transport with rays in
//! the scene for the solvers that never form `F` ([`radiosity_core::TransportSampler`]).
//!
//! ```
//! use radiosity_core::ColumnSource;
//! use radiosity_ff::{BackendSpec, FormFactorInput};
//! use radiosity_geom::{SceneAnalysis, Visibility, load_scene};
//!
//! let scene = load_scene("furnace:res=2").unwrap().scene;
//! let visibility = Visibility::new(&scene);
//! let analysis = SceneAnalysis::new(&scene, &visibility);
//! let input = FormFactorInput { scene: &scene, visibility: visibility.clone(), analysis: &analysis };
//! let backend = BackendSpec::parse("analytic").unwrap().build(input).unwrap();
//! let mut column = vec![0.0; backend.patch_count()];
//! backend.fill_column(0, &mut column);
//! // Every patch of the closed box sees the whole box: Σ_j F_0j = 1, and by reciprocity
//! // (equal areas) column 0 holds row 0.
//! assert!((column.iter().sum::<f64>() - 1.0).abs() < 1e-3);
//! ```

pub mod analytic;
pub mod backend;
pub mod builtins;
pub mod error;
pub mod ff_point_polygon;
mod framing;
pub mod guard;
pub mod hemicube;
pub mod hierarchical;
pub mod matrix;
pub mod matrix_backend;
pub mod montecarlo;
pub mod pair_visibility;
pub mod quadrature;
pub mod rays;
pub mod registry;
pub mod row_comparison;
pub mod row_diagnosis;
pub mod scene_transport;
pub mod sobol;
pub mod solid_angle;
pub mod spec;
pub mod traced;
pub mod visibility_cache;

pub use analytic::{AnalyticColumns, AnalyticParams};

/// The revision of the backends' entries: raised whenever a backend computes different
/// entries for the same canonical argument (a change of rule, not of parameters), so that
/// caches keyed by the canonical argument ([`BackendSpec::canonical`]) and this revision are
/// not read across it. What each revision changed: docs/form-factors.md, "Entries revisions".
pub const ENTRIES_REVISION: u32 = 6;
pub use backend::{BackendFigures, BuildObserver, FormFactorBackend, FormFactorInput, PairEntries, Unobserved};
pub use builtins::MatrixParams;
pub use error::FfError;
pub use hemicube::{HemicubeColumns, HemicubeParams};
pub use hierarchical::{
    BuildProgress, BuildStages, Distribution, HeldBytes, HierarchicalColumns, HierarchicalParams, HierarchyFigures,
    HierarchyLink, Oracle, RankFigures, TASKS_PER_RANK,
};
pub use matrix::StoredMatrix;
pub use montecarlo::{MonteCarloColumns, MonteCarloParams, RayTally};
pub use rays::{HitRay, ShadowSegment, TracedRays};
pub use registry::BackendRegistry;
pub use scene_transport::SceneTransport;
pub use spec::{BackendArgument, BackendParams, BackendSpec};
pub use traced::ColumnRays;
