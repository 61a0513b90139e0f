//! Typed errors of the form-factor crate.

use radiosity_geom::GeomError;
use thiserror::Error;

/// What can go wrong when choosing, building or storing form factors.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum FfError {
    /// A backend name that does not exist.
    #[error("unknown form-factor backend '{name}'{}; backends are {valid}", suggestion.as_ref().map(|s| format!(" (did you mean '{s}'?)")).unwrap_or_default())]
    UnknownBackend {
        /// The name given.
        name: String,
        /// The valid names, comma-separated ([`crate::BackendRegistry::names`]).
        valid: String,
        /// The known name nearest to the one given, when one is near enough to be a typo.
        suggestion: Option<String>,
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
    /// A backend asked to read back a built source it does not keep.
    #[error("form-factor backend '{0}' keeps nothing to read back")]
    NotPersistent(String),
    /// A backend of one's own that could not be built.
    #[error("form-factor backend '{name}' cannot be built: {reason}")]
    Build {
        /// The backend's name.
        name: String,
        /// Why, in a few words.
        reason: String,
    },
}
