//! Form factors: kernels and backends that implement [`radiosity_core::ColumnSource`].
//!
//! This is the only crate that turns geometry into form factors. Four backends, chosen by a
//! [`BackendSpec`] parsed from `NAME[:key=value…]`:
//!
//! - `analytic` ([`analytic`]): Lambert's point-to-polygon formula integrated over the
//!   receiver, with jittered shadow rays when something can occlude;
//! - `hemicube` ([`hemicube`]): a ray-cast hemicube at the shooter, giving its row;
//! - `montecarlo` ([`montecarlo`]): cosine-weighted rays from the shooter, giving its row;
//! - `matrix` ([`matrix`]): the full matrix of another backend, assembled once and stored.
//!
//! Every backend clamps its entries into `[0, 1]` and counts what it clamped ([`guard`]).

pub mod analytic;
pub mod backend;
pub mod error;
pub mod ff_point_polygon;
pub mod guard;
pub mod hemicube;
pub mod matrix;
pub mod montecarlo;
pub mod quadrature;
pub mod spec;

pub use analytic::AnalyticColumns;
pub use backend::{Backend, FormFactorInput};
pub use error::FfError;
pub use hemicube::HemicubeColumns;
pub use matrix::StoredMatrix;
pub use montecarlo::MonteCarloColumns;
pub use spec::{AnalyticParams, BackendSpec, HemicubeParams, MonteCarloParams};
