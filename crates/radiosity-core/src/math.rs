//! Shared scalar and vector aliases, so every crate computes in the same precision.
//!
//! Geometry and radiosity are computed in `f64`: scenes span many orders of magnitude
//! (the stress suite uses coordinate scales of 1e-4 and 1e4 and area ratios of 1e6), and
//! `f32` round-off would show in reciprocity and closure checks. Storage-bound code (a stored
//! form-factor matrix, the BVH) may narrow to `f32` on purpose, and says so where it does.
//!
//! `Vec3` is glam's `DVec3`, exposed here on purpose as the project's point and vector type.

/// The scalar type of all geometric and radiometric quantities.
pub type Real = f64;

/// A point or vector in scene space.
pub type Vec3 = glam::DVec3;

/// The length of the diagonal of the axis-aligned box around `points`; zero when empty.
///
/// Used as the scale against which tolerances are made relative, so no test in the workspace
/// depends on an absolute epsilon.
pub fn bounding_diagonal(points: impl IntoIterator<Item = Vec3>) -> Real {
    let mut lo = Vec3::splat(Real::INFINITY);
    let mut hi = Vec3::splat(Real::NEG_INFINITY);
    let mut any = false;
    for p in points {
        lo = lo.min(p);
        hi = hi.max(p);
        any = true;
    }
    if any { (hi - lo).length() } else { 0.0 }
}

/// A direction about the unit `normal`, cosine-distributed when `(u1, u2)` is uniform on the
/// unit square (Malley's method: a uniform point of the unit disc lifted to the hemisphere).
pub fn cosine_direction(normal: Vec3, u1: Real, u2: Real) -> Vec3 {
    let (tangent, bitangent) = normal.any_orthonormal_pair();
    let r = u1.sqrt();
    let (sin, cos) = (std::f64::consts::TAU * u2).sin_cos();
    tangent * (r * cos) + bitangent * (r * sin) + normal * (1.0 - u1).max(0.0).sqrt()
}
