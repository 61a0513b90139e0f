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
//! **Thin walls**: a wall modelled as two coincident faces back to back (the scene analysis
//! keeps both, each seeing the room) is met by a ray at two parameters equal up to rounding,
//! and `first_hit` returns whichever rounding put first. A ray that meets a back face first is
//! therefore traced once more, from `2m` before that hit (`m` the margin,
//! [`Visibility::ray_margin`]), skipping it: when the next hit is a front within `3m` of that
//! start, within `m` of the back face, the ray lands on that front. So light arriving on the
//! room side of a thin wall is received whichever face rounding put first, as the `analytic`
//! backend counts it (its segments end on the receiver and ignore hits within `1e-9` of the
//! end), where the `montecarlo` and `hemicube` backends lose such rays; the extra ray is
//! spent only on back hits.
//!
//! ## Global lines
//!
//! [`TransportSampler::global_line`] reads `u[0]`, `u[1]` as a direction uniform on the unit
//! sphere (`z = 1 − 2u₀`, azimuth `2π u₁`) and `u[2]`, `u[3]` as a point uniform on the disc of
//! radius `R` through the centre `c` of the scene's bounding sphere, perpendicular to that
//! direction (radius `R √u₂`, angle `2π u₃`). The line starts on the sphere, at `c + p − R d`,
//! and every crossing along it is found by repeated [`Visibility::first_hit`]s, each from `2m`
//! before the last crossing and skipping its patch, so that a thin wall's second face, within
//! the margin of the first, joins the same crossing (the query after it starts at the second
//! face, without stepping back). Two consecutive crossings `a`, `b` (in the order of `d`)
//! face each other when the line meets a patch of `a` from behind (its front faces `d`) and a
//! patch of `b` on its front; then both transfers between those two patches are pushed. Each
//! `first_hit` is a ray, the last one (which meets nothing) included.
//!
//! **The area each transfer stands for**, `W = 2π R²`. Oriented lines, measured by
//! `dL = dω dA⊥` (direction on the sphere, point on the plane perpendicular to it), are what
//! this samples: the lines meeting the bounding sphere have measure `4π · π R²`, and each is
//! drawn with density `1 / (4π² R²)`. The lines that leave `a`'s front and first reach `b`'s
//! front, in that direction, have measure `∫_{A_a} ∫ [first hit b's front] cos θ_a dω dA_a =
//! π A_a F_ab` (the integrand of `F_ab`; Santaló 1976, Sbert 1993). So a line gives the
//! transfer `(a, b)` with probability `π A_a F_ab / (4π² R²)` from the segment oriented `a → b`
//! and `π A_b F_ba / (4π² R²)` from the segment oriented `b → a` (which pushes `(a, b)` too):
//! with reciprocity, `E[#(a, b)] = 2π A_a F_ab / (4π² R²) = A_a F_ab / (2π R²)`, and
//! `E[#(a, b)] · W = A_a F_ab`. A check: in a closed convex box every line that meets it gives
//! two transfers, and with Cauchy's formula (mean projected area `S/4`) the expected
//! transfers times `W` sum to the box's area `S`, the sum of `A_a Σ_b F_ab` over `a`.
//!
//! ## Row sums and cost
//!
//! [`TransportSampler::row_sum`] is 1 only when the caller declares the scene closed
//! ([`SceneTransport::new`]; [`SceneTransport::from_prepared`] takes the scene analysis'
//! verdict, which samples rays from every patch): every ray in a closed scene lands on the front
//! of a patch, so every row of `F` sums to 1. Otherwise it is unknown (`None`).
//! [`TransportSampler::cost`]: one ray through the BVH, its candidate triangles tested
//! exactly in `f64`; its cost depends on where the ray goes. Memory: each patch's area sampler
//! (its fan triangles and their split, 152 bytes), made once, which saves a ray the triangles'
//! areas; the patches and the BVH are borrowed.
//!
//! ## References
//!
//! - M. Sbert, "An integral geometry based method for fast form-factor computation",
//!   Computer Graphics Forum 12(3) (Eurographics '93), 1993 (global lines).
//! - L. A. Santaló, *Integral Geometry and Geometric Probability*, Addison-Wesley, 1976 (the
//!   measure of lines, Cauchy's formula).
//! - P. Bekaert, *Hierarchical and Stochastic Algorithms for Radiosity*, PhD thesis,
//!   KU Leuven, 1999 (local and global lines in stochastic relaxation).
//! - G. Turk, "Generating random points in triangles", *Graphics Gems*, 1990.

use crate::montecarlo::AreaSampler;
use radiosity_core::math::cosine_direction;
use radiosity_core::{LineTransfers, Patch, Real, SampleCost, Scene, TransportSampler, Vec3};
use radiosity_geom::{PreparedScene, RayHit, Visibility};

/// Rays in a scene as a [`TransportSampler`] (module doc): the patches and the BVH borrowed.
#[derive(Debug)]
pub struct SceneTransport<'s> {
    patches: &'s [Patch],
    /// Each patch's origins, uniform by area.
    origins: Vec<AreaSampler>,
    visibility: Visibility,
    closed: bool,
    /// The centre of the bounding sphere of global lines: the centre of the scene's box.
    centre: Vec3,
    /// Its radius: half the box's diagonal.
    radius: Real,
}

impl<'s> SceneTransport<'s> {
    /// Rays in `scene`, traced through `visibility` (built over the same scene). `closed`
    /// declares that no ray escapes or meets a back face, so that every row of `F` sums to 1
    /// ([`TransportSampler::row_sum`]); pass `false` when that is not known.
    pub fn new(scene: &'s Scene, visibility: &Visibility, closed: bool) -> SceneTransport<'s> {
        let (lo, hi) = scene.bounds();
        SceneTransport {
            patches: scene.patches(),
            origins: scene.patches().iter().map(AreaSampler::new).collect(),
            visibility: visibility.clone(),
            closed,
            centre: (lo + hi) * 0.5,
            radius: 0.5 * (hi - lo).length(),
        }
    }

    /// Rays in a prepared scene, closed when its analysis found it closed; an error once its
    /// BVH is released.
    pub fn from_prepared(prepared: &'s PreparedScene) -> Result<SceneTransport<'s>, radiosity_geom::GeomError> {
        let closed = prepared.analysis.closure.value.is_closed();
        let visibility = prepared.visibility_for("sampling transport by rays")?;
        Ok(SceneTransport::new(prepared.scene(), &visibility, closed))
    }

    /// Whether the scene was declared closed.
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The ray `u` of [`TransportSampler::cast`] from `patch`: its origin and direction.
    pub fn ray(&self, from: usize, u: [Real; 4]) -> (Vec3, Vec3) {
        let patch = &self.patches[from];
        let origin = self.origins[from].point(u[0], u[1]);
        (origin, cosine_direction(patch.normal(), u[2], u[3]))
    }

    /// The global line `u` of [`TransportSampler::global_line`]: where it starts, on the
    /// bounding sphere, and its unit direction.
    pub fn line(&self, u: [Real; 4]) -> (Vec3, Vec3) {
        let z = 1.0 - 2.0 * u[0];
        let (sin, cos) = (std::f64::consts::TAU * u[1]).sin_cos();
        let across = (1.0 - z * z).max(0.0).sqrt();
        let direction = Vec3::new(across * cos, across * sin, z);
        let (e1, e2) = direction.any_orthonormal_pair();
        let r = self.radius * u[2].sqrt();
        let (sin, cos) = (std::f64::consts::TAU * u[3]).sin_cos();
        (self.centre + e1 * (r * cos) + e2 * (r * sin) - direction * self.radius, direction)
    }

    /// The area each transfer of a global line stands for, `2π R²` (module doc).
    pub fn line_area(&self) -> Real {
        std::f64::consts::TAU * self.radius * self.radius
    }

    /// The front of the other face of a thin wall, when the ray `origin + t · direction` met
    /// the back of one face first (`hit`) and a front lies within the margin of it (module
    /// doc).
    fn front_twin(&self, origin: Vec3, direction: Vec3, hit: RayHit) -> Option<usize> {
        let margin = self.visibility.ray_margin(direction);
        let start = origin + direction * (hit.t - 2.0 * margin);
        let twin = self.visibility.first_hit(start, direction, Some(hit.patch))?;
        (twin.front && twin.t <= 3.0 * margin).then_some(twin.patch)
    }
}

/// One crossing of a global line: the patch met on its front (which receives what arrives
/// along the line) and the one met from behind (which sends on along it); both where a thin
/// wall's two faces lie back to back.
#[derive(Clone, Copy, Debug, Default)]
struct Crossing {
    receiver: Option<usize>,
    emitter: Option<usize>,
}

impl Crossing {
    fn with(mut self, hit: RayHit) -> Crossing {
        self.add(hit);
        self
    }

    fn add(&mut self, hit: RayHit) {
        let side = if hit.front { &mut self.receiver } else { &mut self.emitter };
        side.get_or_insert(hit.patch);
    }

    /// Pushes the transfers between the last crossing's `emitter` and this crossing's
    /// receiver, both ways, and leaves this crossing's emitter in `emitter`.
    fn complete(self, emitter: &mut Option<usize>, transfers: &mut Vec<(usize, usize)>) {
        if let (Some(a), Some(b)) = (*emitter, self.receiver) {
            transfers.push((a, b));
            transfers.push((b, a));
        }
        *emitter = self.emitter;
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
        let hit = self.visibility.first_hit(origin, direction, Some(from))?;
        if hit.front { Some(hit.patch) } else { self.front_twin(origin, direction, hit) }
    }

    fn row_sum(&self, i: usize) -> Option<Real> {
        (self.closed && i < self.patches.len()).then_some(1.0)
    }

    fn global_line(&self, u: [Real; 4], line: &mut LineTransfers) -> bool {
        line.transfers.clear();
        line.area = self.line_area();
        line.rays = 0;
        let (mut origin, direction) = self.line(u);
        let margin = self.visibility.ray_margin(direction);
        // The emitter of the last crossing completed, and the crossing being gathered.
        let (mut emitter, mut crossing): (Option<usize>, Option<Crossing>) = (None, None);
        let (mut skip, mut back_off) = (None, 0.0);
        // Each query passes at least one patch, and a line crosses a planar patch at most once
        // (unless it lies in the patch's plane, a set of lines of measure zero): the bound only
        // makes termination certain.
        for _ in 0..=2 * self.patches.len() {
            line.rays += 1;
            let start = origin - direction * back_off;
            let Some(hit) = self.visibility.first_hit(start, direction, skip) else { break };
            origin = start + direction * hit.t;
            skip = Some(hit.patch);
            match crossing.as_mut() {
                // Within the margin of the last crossing's patch: its twin, the other face of
                // a thin wall. The next query starts from here, where the first face lies
                // within the margin, so neither is met again.
                Some(current) if back_off > 0.0 && hit.t <= 3.0 * margin => {
                    current.add(hit);
                    back_off = 0.0;
                }
                _ => {
                    if let Some(done) = crossing.replace(Crossing::default().with(hit)) {
                        done.complete(&mut emitter, &mut line.transfers);
                    }
                    back_off = 2.0 * margin;
                }
            }
        }
        if let Some(done) = crossing {
            done.complete(&mut emitter, &mut line.transfers);
        }
        true
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
