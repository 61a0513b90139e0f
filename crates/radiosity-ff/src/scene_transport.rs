//! [`SceneTransport`]: transport sampled by rays in the scene ([`TransportSampler`]), over the
//! BVH and exact `f64` ray tests the backends already use ([`Visibility::first_hit`]).
//!
//! ## A ray from a patch
//!
//! [`TransportSampler::cast`] reads its point `u` of `[0, 1)^4` as:
//!
//! - `u[0]`, `u[1]`: the origin, uniform by area on patch `from` (`u[0]` picks one of its fan
//!   triangles in proportion to area and is rescaled inside it; `(1 − √s) v₀ + √s (1 − t) v₁ +
//!   √s t v₂` on that triangle, Turk 1990), as the `montecarlo` backend draws them, so a
//!   non-parallelogram quad is sampled uniformly too;
//! - `u[2]`, `u[3]`: the direction, cosine-distributed about the patch's normal
//!   ([`cosine_direction`], Malley's method).
//!
//! The ray lands on the patch [`Visibility::first_hit`] finds when it arrives on that patch's
//! **front**; a ray that first meets the back of a patch is absorbed there (`None`), and one
//! that meets nothing escapes (`None`). This is how `F` counts light: the kernel of `F_ij`
//! holds the receiver's cosine, and a patch is one-sided, so `F_ij = 0` wherever `i`'s cosine
//! is `≤ 0`: light that reaches the back of a patch reaches no receiver, and the patch still
//! stops it (it is an occluder from both sides, as in every backend's shadow test). The
//! probability that a ray from `j` lands on `i` is then exactly
//! `(1/(π A_j)) ∫_{A_j} ∫ [first hit is i's front] cos θ dω dA = F_ji = A_i F_ij / A_j`, the
//! `T_ij` of [`radiosity_core::transport`], and `1 − Σ_i T_ij` is what escapes or is absorbed.
//!
//! **Margins**: the origin lies on patch `from` itself, without an offset. `first_hit` skips
//! `from` by index and ignores hits closer than `1e-9` scene diagonals, so neither the patch
//! nor a neighbour sharing an edge with the origin stops the ray at `t ≈ 0`: the conventions
//! of the `montecarlo` and `hemicube` backends and of the scene analysis' closure test, which
//! trace the same rays.
//!
//! ## Row sums and cost
//!
//! [`TransportSampler::row_sum`] is 1 only when the caller declares the scene closed
//! ([`SceneTransport::new`]; [`SceneTransport::from_prepared`] takes the scene analysis'
//! verdict, which samples rays from every patch): every ray in a closed scene lands on the front
//! of a patch, so every row of `F` sums to 1. Otherwise it is unknown (`None`).
//! [`TransportSampler::cost`]: one ray through the BVH, its candidate triangles tested
//! exactly in `f64`; its cost depends on where the ray goes.
//!
//! ## References
//!
//! - P. Bekaert, *Hierarchical and Stochastic Algorithms for Radiosity*, PhD thesis,
//!   KU Leuven, 1999 (local lines in stochastic relaxation).
//! - G. Turk, "Generating random points in triangles", *Graphics Gems*, 1990.

use crate::montecarlo::AreaSampler;
use radiosity_core::math::cosine_direction;
use radiosity_core::{Patch, Real, SampleCost, Scene, TransportSampler, Vec3};
use radiosity_geom::{PreparedScene, Visibility};

/// Rays in a scene as a [`TransportSampler`] (module doc): the patches and the BVH borrowed.
#[derive(Debug)]
pub struct SceneTransport<'s> {
    patches: &'s [Patch],
    visibility: &'s Visibility,
    closed: bool,
}

impl<'s> SceneTransport<'s> {
    /// Rays in `scene`, traced through `visibility` (built over the same scene). `closed`
    /// declares that no ray escapes or meets a back face, so that every row of `F` sums to 1
    /// ([`TransportSampler::row_sum`]); pass `false` when that is not known.
    pub fn new(scene: &'s Scene, visibility: &'s Visibility, closed: bool) -> SceneTransport<'s> {
        SceneTransport { patches: scene.patches(), visibility, closed }
    }

    /// Rays in a prepared scene, closed when its analysis found it closed.
    pub fn from_prepared(prepared: &'s PreparedScene) -> SceneTransport<'s> {
        let closed = prepared.analysis.closure.value.is_closed();
        SceneTransport::new(prepared.scene(), &prepared.visibility, closed)
    }

    /// Whether the scene was declared closed.
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The ray `u` of [`TransportSampler::cast`] from `patch`: its origin and direction.
    pub fn ray(&self, from: usize, u: [Real; 4]) -> (Vec3, Vec3) {
        let patch = &self.patches[from];
        let origin = AreaSampler::new(patch).point(u[0], u[1]);
        (origin, cosine_direction(patch.normal(), u[2], u[3]))
    }
}

/// `n` with a comma between groups of three digits (`12,345`).
fn grouped(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (k, c) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

impl TransportSampler for SceneTransport<'_> {
    fn patch_count(&self) -> usize {
        self.patches.len()
    }

    fn cast(&self, from: usize, u: [Real; 4]) -> Option<usize> {
        let (origin, direction) = self.ray(from, u);
        self.visibility.first_hit(origin, direction, Some(from)).filter(|hit| hit.front).map(|hit| hit.patch)
    }

    fn row_sum(&self, i: usize) -> Option<Real> {
        (self.closed && i < self.patches.len()).then_some(1.0)
    }

    fn cost(&self) -> SampleCost {
        SampleCost {
            ray: format!(
                "one ray through a BVH of {} triangles (exact f64 tests)",
                grouped(self.visibility.triangle_count())
            ),
            constant: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::grouped;

    #[test]
    fn counts_are_grouped_by_thousands() {
        assert_eq!(grouped(0), "0");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(1000), "1,000");
        assert_eq!(grouped(12_345), "12,345");
        assert_eq!(grouped(1_234_567), "1,234,567");
    }
}
