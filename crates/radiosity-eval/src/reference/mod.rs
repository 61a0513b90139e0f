//! References and certificates: the exact solution of the same discrete system
//! ([`solution`]), the choice of reference and its memory budget ([`kind`]), the shooting
//! reference that needs no matrix ([`shooting`]), the certified error bound and what it rests
//! on ([`certificate`]), the metrics of any vector against a reference ([`metrics`]), the
//! form-factor matrix held in memory ([`matrix`]) and the on-disk cache of stored matrices and
//! references ([`cache`]).
//!
//! Nothing here knows of a lab: the lab builds on these.

pub(crate) mod cache;
pub(crate) mod certificate;
pub(crate) mod kind;
pub(crate) mod matrix;
pub(crate) mod metrics;
pub(crate) mod shooting;
pub(crate) mod solution;
