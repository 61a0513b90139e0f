//! Core types shared by every radiosity crate: math aliases, spectra, patches, the scene
//! description, the discrete radiosity system and the [`ColumnSource`] trait.
//!
//! This crate knows nothing about how geometry is built or how form factors are computed.
//! It fixes the vocabulary the other crates agree on:
//!
//! - [`Patch`]: a planar convex triangle or quad with its area, centroid and normal, and the
//!   object and material it came from;
//! - [`Scene`]: patches plus the materials and objects they reference;
//! - [`LinearSystem`]: areas, reflectivities and emissions per channel, the data of
//!   `B_i = E_i + ρ_i Σ_j F_ij B_j`;
//! - [`ColumnSource`]: "fill column j of F", the only thing a solver knows about form factors;
//! - [`TransportSampler`]: "where does a ray leaving patch j land?", the seam of the solvers
//!   that estimate transport with rays and never form F; [`ColumnTransport`] samples any
//!   column source's matrix exactly;
//! - [`Collective`]: ranks that sum vectors in rank order, the seam of a computation split
//!   over processes (MPI) or threads ([`InProcessRanks`]);
//! - [`Clock`]: whether a run's seconds are measured or charged by its source;
//! - [`RadiosityOperator`]: `F·x`, `(I − diag(ρ) F)·x` and the residual over any source, also
//!   as faer's `LinOp` (scipy's `LinearOperator`, in Rust).
//!
//! ```
//! use radiosity_core::{ColumnSource, CountingColumns, DenseColumns};
//!
//! // Two facing patches: row i holds F_ij, the fraction of i's power that reaches j.
//! let f = DenseColumns::from_rows(2, &[0.0, 0.2, 0.2, 0.0]).unwrap();
//! let counted = CountingColumns::new(&f);
//! let mut column = vec![0.0; counted.patch_count()];
//! counted.fill_column(1, &mut column);
//! assert_eq!(column, [0.2, 0.0]);
//! assert_eq!(counted.stats().columns, 1);
//! ```

pub mod channel_groups;
pub mod clock;
pub mod collective;
pub mod column;
pub mod column_transport;
pub mod dense_lu;
pub mod error;
pub mod faer_operator;
pub mod ids;
pub mod link_source;
pub mod math;
pub mod operator;
pub mod patch;
pub mod scene;
pub mod sobol;
pub mod spectrum;
pub mod suggest;
pub mod system;
pub mod transport;

pub use channel_groups::{channel_groups, pick_channels, put_channels};
pub use clock::Clock;
pub use collective::{Collective, InProcessRanks, Traffic};
pub use column::{ColumnSource, ColumnStats, CountingColumns, DenseColumns, measured_reciprocity};
pub use column_transport::{AliasTable, ColumnTransport};
pub use error::CoreError;
pub use faer_operator::SymmetrizedOperator;
pub use ids::{MaterialId, ObjectId};
pub use link_source::{LinkSource, NO_PARENT};
pub use math::{Real, Vec3};
pub use operator::{
    Product, RadiosityOperator, apply_from_product, multiply, multiply_by_columns, residual_from_product,
};
pub use patch::{Patch, PatchShape};
pub use scene::{Material, Scene};
pub use spectrum::{Channels, Spectrum};
pub use system::LinearSystem;
pub use transport::{LineTransfers, SampleCost, TransportSampler};
