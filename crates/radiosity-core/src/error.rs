//! Typed errors of the core crate: invalid patches, materials and system data.

use crate::math::Real;
use thiserror::Error;

/// What can be wrong with core data. Messages are single sentences meant for end users.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum CoreError {
    /// A vertex coordinate is NaN or infinite.
    #[error("a patch vertex has a non-finite coordinate")]
    NonFiniteVertex,
    /// A patch has (numerically) zero area.
    #[error("a patch is degenerate (area {area:e} against a squared edge length of {scale:e})")]
    DegeneratePatch {
        /// The computed area.
        area: Real,
        /// The squared longest edge, the scale the area was compared with.
        scale: Real,
    },
    /// A quad's fourth vertex lies off the plane of the other three.
    #[error("a quad is not planar (relative deviation {deviation:e})")]
    NonPlanarQuad {
        /// Distance of the farthest vertex from the mean plane, over the longest diagonal.
        deviation: Real,
    },
    /// A quad is not convex (or its vertices are not in order around it).
    #[error("a quad is not convex")]
    NonConvexQuad,
    /// A reflectivity outside `[0, 1)`, or not finite.
    #[error("material '{material}' has reflectivity {value} in a channel; it must be at least 0 and below 1")]
    InvalidReflectivity {
        /// The material's name.
        material: String,
        /// The offending channel value.
        value: Real,
    },
    /// A negative or non-finite emission.
    #[error("material '{material}' has emission {value} in a channel; it must be finite and at least 0")]
    InvalidEmission {
        /// The material's name.
        material: String,
        /// The offending channel value.
        value: Real,
    },
    /// A patch refers to a material or object that the scene does not have.
    #[error("patch {patch} refers to {what} {index}, but the scene has only {count}")]
    DanglingReference {
        /// The patch index.
        patch: usize,
        /// "material" or "object".
        what: &'static str,
        /// The index referred to.
        index: usize,
        /// How many the scene has.
        count: usize,
    },
    /// A scene with no patches.
    #[error("the scene has no patches")]
    EmptyScene,
    /// Arrays that must agree in length do not.
    #[error("{what} has length {found}, expected {expected}")]
    SizeMismatch {
        /// What was measured.
        what: &'static str,
        /// The expected length.
        expected: usize,
        /// The length found.
        found: usize,
    },
    /// A non-positive or non-finite patch area in a linear system.
    #[error("patch {patch} has area {area}; areas must be finite and positive")]
    InvalidArea {
        /// The patch index.
        patch: usize,
        /// The offending area.
        area: Real,
    },
    /// Weights that are not a distribution: empty, negative, not finite or all zero.
    #[error(
        "{len} weights summing to {total} are not a distribution: they must be finite, non-negative and not all zero"
    )]
    InvalidDistribution {
        /// How many weights.
        len: usize,
        /// Their sum.
        total: Real,
    },
    /// A form factor that is negative or not finite.
    #[error("F[{row}][{column}] is {value}; form factors must be finite and non-negative")]
    InvalidEntry {
        /// The row.
        row: usize,
        /// The column.
        column: usize,
        /// The entry.
        value: Real,
    },
}
