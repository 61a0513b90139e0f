//! Directions drawn uniformly in the solid angle a planar polygon subtends at a point, and
//! the solid angle itself.
//!
//! The solid angle of the triangle with unit directions `A`, `B`, `C` from the point is
//! Van Oosterom & Strackee's (1983, "The solid angle of a plane triangle", IEEE Trans.
//! Biomed. Eng. 30(2)):
//!
//! `tan(Ω/2) = |A · (B × C)| / (1 + A·B + B·C + C·A)`,
//!
//! accurate for small triangles, where the angle-excess formula `α + β + γ − π` cancels.
//! Directions uniform in `Ω` come from Arvo's map of the unit square onto the spherical
//! triangle (1995, "Stratified sampling of spherical triangles", SIGGRAPH, Fig. 2): the first
//! coordinate picks the sub-triangle `A B C'` of area `ξ₁ Ω`, the second a point on the arc
//! from `B` to `C'` at `cos = 1 − ξ₂ (1 − C'·B)`. The map preserves area, so stratified
//! `(ξ₁, ξ₂)` give stratified directions. A polygon is fanned into triangles, chosen in
//! proportion to their solid angles.

use radiosity_core::{Real, Vec3};

/// Triangles below this solid angle (steradians) are sampled by area: there Arvo's map loses
/// digits, and area and solid angle agree to the triangle's size over its distance.
const TINY: Real = 1e-7;

/// The solid angle of the triangle whose vertices lie in the unit directions `a`, `b`, `c`.
pub fn triangle(a: Vec3, b: Vec3, c: Vec3) -> Real {
    let numerator = a.dot(b.cross(c)).abs();
    // `1 + p·q + r·(p + q) = |p + q|² / 2 + r·(p + q)` for unit vectors, with `p, q` the pair
    // nearest opposite: seen from a point near an edge, its two ends are, and `1 + p·q`
    // cancels to the square of the distance while `|p + q|` keeps its digits.
    let (ab, bc, ca) = (a.dot(b), b.dot(c), c.dot(a));
    let (p, q, r) = if ab <= bc && ab <= ca {
        (a, b, c)
    } else if bc <= ca {
        (b, c, a)
    } else {
        (c, a, b)
    };
    let sum = p + q;
    let denominator = 0.5 * sum.length_squared() + r.dot(sum);
    2.0 * numerator.atan2(denominator)
}

/// The polygon `vertices` (convex, planar, at most five vertices, not containing `x`) as seen
/// from `x`: its fan triangles' solid angles, to draw directions from.
#[derive(Clone, Copy, Debug)]
pub struct SphericalPolygon {
    /// Unit directions from `x` to the vertices.
    directions: [Vec3; 5],
    /// The vertices.
    vertices: [Vec3; 5],
    count: usize,
    /// `cumulative[t]`: the solid angle of fan triangles `0..=t`.
    cumulative: [Real; 3],
}

impl SphericalPolygon {
    /// `vertices` seen from `x`; at most five vertices are used.
    pub fn new(x: Vec3, vertices: &[Vec3]) -> SphericalPolygon {
        let count = vertices.len().min(5);
        let mut polygon =
            SphericalPolygon { directions: [Vec3::ZERO; 5], vertices: [Vec3::ZERO; 5], count, cumulative: [0.0; 3] };
        for (k, v) in vertices.iter().take(count).enumerate() {
            polygon.vertices[k] = *v;
            polygon.directions[k] = (*v - x).normalize_or_zero();
        }
        let mut total = 0.0;
        for t in 0..count.saturating_sub(2) {
            let d = &polygon.directions;
            total += triangle(d[0], d[t + 1], d[t + 2]);
            polygon.cumulative[t] = total;
        }
        polygon
    }

    /// The solid angle.
    pub fn solid_angle(&self) -> Real {
        if self.count < 3 { 0.0 } else { self.cumulative[self.count - 3] }
    }

    /// The largest `n · d` over the directions `d` of the polygon (`n` a unit vector): at a
    /// vertex, inside an edge's arc, or 1 when `n` itself points into the polygon. It bounds
    /// the cosine for drawing directions in proportion to `n · d` by rejection.
    pub fn max_cosine(&self, n: Vec3) -> Real {
        let d = &self.directions[..self.count];
        let mut best = d.iter().map(|v| n.dot(*v)).fold(Real::NEG_INFINITY, Real::max);
        let mut sides = (0, 0);
        for k in 0..self.count {
            let (p, q) = (d[k], d[(k + 1) % self.count]);
            let m = p.cross(q);
            let side = m.dot(n);
            if side > 0.0 {
                sides.0 += 1;
            } else if side < 0.0 {
                sides.1 += 1;
            }
            let Some(m) = m.try_normalize() else { continue };
            // The point of the edge's great circle nearest n, if it lies on the arc.
            let Some(nearest) = (n - m * n.dot(m)).try_normalize() else { continue };
            if m.dot(p.cross(nearest)) >= 0.0 && m.dot(nearest.cross(q)) >= 0.0 {
                best = best.max(n.dot(nearest));
            }
        }
        if sides.0 == 0 || sides.1 == 0 { 1.0 } else { best }
    }

    /// The point of the polygon hit by the direction at `(u, v) ∈ [0, 1)²` from `x`, uniform
    /// in solid angle when `(u, v)` is uniform. `None` when the polygon subtends nothing.
    pub fn point_at(&self, x: Vec3, u: Real, v: Real) -> Option<Vec3> {
        let total = self.solid_angle();
        if total <= 0.0 || !total.is_finite() {
            return None;
        }
        let (t, s, width) = pick_fan_triangle(&self.cumulative[..self.count - 2], u);
        let (a, b, c) = (self.vertices[0], self.vertices[t + 1], self.vertices[t + 2]);
        if width < TINY {
            // Shirley's square-to-triangle warp, uniform by area.
            let r = s.sqrt();
            return Some(a * (1.0 - r) + b * (r * (1.0 - v)) + c * (r * v));
        }
        let (da, db, dc) = (self.directions[0], self.directions[t + 1], self.directions[t + 2]);
        let direction = arvo(da, db, dc, width, s, v)?;
        // Where the direction meets the triangle's plane.
        let normal = (b - a).cross(c - a);
        let along = normal.dot(direction);
        if along == 0.0 {
            return None;
        }
        let distance = normal.dot(a - x) / along;
        (distance > 0.0 && distance.is_finite()).then(|| x + direction * distance)
    }
}

/// The fan triangle `t` that `u ∈ [0, 1)` falls in when the triangles' cumulative measures
/// are `cumulative` (at least one), `u` rescaled within it, and its own measure: what draws a
/// point of a fanned polygon in proportion to area or solid angle.
pub fn pick_fan_triangle(cumulative: &[Real], u: Real) -> (usize, Real, Real) {
    let last = cumulative.len() - 1;
    let target = u * cumulative[last];
    let t = (0..last).find(|&t| target < cumulative[t]).unwrap_or(last);
    let below = if t == 0 { 0.0 } else { cumulative[t - 1] };
    let width = cumulative[t] - below;
    let s = if width > 0.0 { ((target - below) / width).clamp(0.0, 1.0) } else { 0.5 };
    (t, s, width)
}

/// Arvo's area-preserving map from `(u, v)` to the spherical triangle `a b c` (unit vectors)
/// of solid angle `area`.
fn arvo(a: Vec3, b: Vec3, c: Vec3, area: Real, u: Real, v: Real) -> Option<Vec3> {
    // The angle at `a` between the great circles through `a b` and `a c`.
    let (nab, nac) = (a.cross(b).normalize_or_zero(), a.cross(c).normalize_or_zero());
    if nab == Vec3::ZERO || nac == Vec3::ZERO {
        return None;
    }
    let cos_alpha = nab.dot(nac).clamp(-1.0, 1.0);
    let alpha = cos_alpha.acos();
    let sin_alpha = alpha.sin();
    let cos_c = a.dot(b);
    let sub = u * area;
    let (s, t) = (sub - alpha).sin_cos();
    let (p, q) = (t - cos_alpha, s + sin_alpha * cos_c);
    let denominator = (q * s + p * t) * sin_alpha;
    if denominator == 0.0 {
        return None;
    }
    let w = (((q * t - p * s) * cos_alpha - q) / denominator).clamp(-1.0, 1.0);
    let towards_c = (c - a * c.dot(a)).normalize_or_zero();
    let c_hat = a * w + towards_c * (1.0 - w * w).max(0.0).sqrt();
    let z = 1.0 - v * (1.0 - c_hat.dot(b));
    let towards = (c_hat - b * c_hat.dot(b)).normalize_or_zero();
    Some((b * z + towards * (1.0 - z * z).max(0.0).sqrt()).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ff_point_polygon::point_to_polygon;

    #[test]
    fn the_solid_angle_of_an_octant_is_half_pi() {
        let omega = triangle(Vec3::X, Vec3::Y, Vec3::Z);
        assert!((omega - std::f64::consts::FRAC_PI_2).abs() < 1e-14, "{omega}");
    }

    #[test]
    fn a_triangle_seen_from_near_its_edge_keeps_its_digits() {
        // a and b on the equator, an arc of π − 2 atan δ apart through +y, and c the pole:
        // the triangle is that slice of the hemisphere, of solid angle π − 2 atan δ. Seen
        // from a point δ from the edge a b, `1 + a·b` is 2δ² and lost to rounding.
        for delta in [1e-5, 1e-7, 1e-9] {
            let (a, b) = (Vec3::new(1.0, delta, 0.0).normalize(), Vec3::new(-1.0, delta, 0.0).normalize());
            let exact = std::f64::consts::PI - 2.0 * delta.atan();
            for (p, q, r) in [(a, b, Vec3::Z), (b, Vec3::Z, a), (Vec3::Z, a, b)] {
                let omega = triangle(p, q, r);
                assert!((omega - exact).abs() < 1e-14, "δ = {delta}: {omega} against {exact}");
            }
        }
    }

    #[test]
    fn the_largest_cosine_is_found_on_vertices_edges_and_inside() {
        let square = |z: Real| {
            [Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(1.0, 1.0, z), Vec3::new(-1.0, 1.0, z)]
        };
        let polygon = SphericalPolygon::new(Vec3::ZERO, &square(1.0));
        // Straight up lies inside.
        assert_eq!(polygon.max_cosine(Vec3::Z), 1.0);
        // Along +x the best direction is the middle of the edge x = 1: (1, 0, 1)/√2.
        let along_x = polygon.max_cosine(Vec3::X);
        assert!((along_x - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12, "{along_x}");
        // Along a diagonal, a vertex: (1, 1, 1)/√3 · (1, 1, 0)/√2.
        let diagonal = polygon.max_cosine(Vec3::new(1.0, 1.0, 0.0).normalize());
        assert!((diagonal - (2.0 / 6.0_f64.sqrt())).abs() < 1e-12, "{diagonal}");
        // Brute force over a fine grid of the square never beats the bound.
        for n in [Vec3::new(1.0, 0.3, -0.2), Vec3::new(-0.4, 0.9, 0.1), Vec3::new(0.1, 0.1, 1.0)] {
            let n = n.normalize();
            let bound = polygon.max_cosine(n);
            let mut best = Real::NEG_INFINITY;
            for i in 0..=200 {
                for j in 0..=200 {
                    let y = Vec3::new(-1.0 + i as Real / 100.0, -1.0 + j as Real / 100.0, 1.0);
                    best = best.max(n.dot(y.normalize()));
                }
            }
            assert!(best <= bound + 1e-12 && best >= bound - 1e-4, "{best} against {bound}");
        }
    }

    #[test]
    fn directions_are_uniform_in_solid_angle() {
        // The mean cosine at x over uniform directions, times Ω/π, is the point-to-polygon
        // form factor: check it against Lambert's formula for a near and a far quad, a
        // tilted one and a tiny distant one (sampled by area). A 256 × 256 grid of stratified
        // samples; the stratified error is below a fifth of the tolerance.
        let x = Vec3::ZERO;
        let n = Vec3::Z;
        let quads: [[Vec3; 4]; 4] = [
            [
                Vec3::new(-1.0, -1.0, 0.3),
                Vec3::new(1.0, -1.0, 0.3),
                Vec3::new(1.0, 1.0, 0.3),
                Vec3::new(-1.0, 1.0, 0.3),
            ],
            [Vec3::new(0.0, 0.0, 5.0), Vec3::new(1.0, 0.0, 5.0), Vec3::new(1.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 5.0)],
            [Vec3::new(0.2, -0.5, 0.0), Vec3::new(0.2, 0.5, 0.0), Vec3::new(0.7, 0.5, 1.0), Vec3::new(0.7, -0.5, 1.0)],
            [Vec3::new(0.0, 0.0, 1e3), Vec3::new(0.1, 0.0, 1e3), Vec3::new(0.1, 0.1, 1e3), Vec3::new(0.0, 0.1, 1e3)],
        ];
        for quad in quads {
            let polygon = SphericalPolygon::new(x, &quad);
            let k = 256;
            let mut sum = 0.0;
            for i in 0..k {
                for j in 0..k {
                    let (u, v) = ((i as Real + 0.5) / k as Real, (j as Real + 0.5) / k as Real);
                    let y = polygon.point_at(x, u, v).expect("a point");
                    // On the quad's plane and inside it (within round-off).
                    let normal = (quad[1] - quad[0]).cross(quad[3] - quad[0]).normalize();
                    assert!(normal.dot(y - quad[0]).abs() < 1e-9 * (1.0 + y.length()), "{y}");
                    sum += n.dot((y - x).normalize());
                }
            }
            let estimate = polygon.solid_angle() * sum / (k * k) as Real / std::f64::consts::PI;
            let exact = point_to_polygon(x, n, &quad);
            assert!((estimate - exact).abs() <= 1e-3 * exact, "{estimate} against {exact}");
        }
    }
}
