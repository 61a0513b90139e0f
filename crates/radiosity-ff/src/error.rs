//! Typed errors of the form-factor crate.

use radiosity_geom::GeomError;
use thiserror::Error;

/// What can go wrong when choosing, building or storing form factors.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum FfError {
    /// A backend name that does not exist.
    #[error("unknown form-factor backend '{name}'; backends are {valid}")]
    UnknownBackend {
        /// The name given.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
    },
    /// A bad `key=value` parameter of a backend.
    #[error(transparent)]
    Params(#[from] GeomError),
    /// A stored matrix that cannot be decoded, or does not fit the scene.
    #[error("stored form-factor matrix is unusable: {0}")]
    StoredMatrix(String),
    /// A stored hierarchical operator that cannot be decoded, or does not fit the scene.
    #[error("stored hierarchical operator is unusable: {0}")]
    StoredOperator(String),
}
