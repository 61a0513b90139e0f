//! Quadrature rules on patches: Gauss–Legendre points with weights summing to the area.
//!
//! Order `q` uses the `q`-point Gauss–Legendre rule in each of the two parameters of the
//! patch (Golub & Welsch 1969; nodes by Newton's iteration on the Legendre recurrence, as in
//! Press et al., *Numerical Recipes*, `gauleg`):
//!
//! - a quad is parametrised bilinearly, `P(s, t)`, with area element `|P_s × P_t| ds dt`, exact
//!   for planar convex quads of any shape;
//! - a triangle by the collapsed square (Duffy 1982), `P(s, t) = v0 + s((v1 − v0) + t(v2 − v1))`,
//!   with area element `2A s ds dt`.
//!
//! For `q ≥ 2` each parameter is first mapped through `u = 3ξ² − 2ξ³`, whose derivative
//! vanishes at both ends. The form-factor integrand of two patches that touch along an edge
//! has a logarithmic singularity in its derivative at that edge; the map moves points away
//! from edges and flattens the singularity, so the touching cases converge like the smooth
//! ones (measured in the tests against Howell's closed forms). Order 1 is the centroid rule.

use radiosity_core::{Patch, PatchShape, Real, Vec3};

/// Gauss–Legendre nodes and weights on `[0, 1]` (weights sum to 1).
pub fn gauss_legendre(order: usize) -> Vec<(Real, Real)> {
    let n = order.max(1);
    let mut rule = Vec::with_capacity(n);
    for i in 0..n {
        // Initial guess (Tricomi), then Newton on P_n.
        let mut x = (std::f64::consts::PI * (i as Real + 0.75) / (n as Real + 0.5)).cos();
        let mut derivative = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let k = k as Real;
                let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { x } else { p1 };
            let pn_1 = if n == 1 { 1.0 } else { p0 };
            derivative = n as Real * (x * pn - pn_1) / (x * x - 1.0);
            let dx = pn / derivative;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * derivative * derivative);
        rule.push((0.5 * (1.0 - x), 0.5 * w));
    }
    rule.sort_by(|a, b| a.0.total_cmp(&b.0));
    rule
}

/// The edge-smoothing map `u = 3ξ² − 2ξ³` and its derivative.
fn smooth(xi: Real) -> (Real, Real) {
    (xi * xi * (3.0 - 2.0 * xi), 6.0 * xi * (1.0 - xi))
}

/// A one-dimensional rule on `[0, 1]` for order `q`: Gauss–Legendre composed with the
/// smoothing map for `q ≥ 2`.
pub fn interval_rule(order: usize) -> Vec<(Real, Real)> {
    if order <= 1 {
        return vec![(0.5, 1.0)];
    }
    gauss_legendre(order)
        .into_iter()
        .map(|(xi, w)| {
            let (u, du) = smooth(xi);
            (u, w * du)
        })
        .collect()
}

/// Points on `patch` with weights summing to its area: `order²` points, or the centroid for
/// order 1.
pub fn patch_rule(patch: &Patch, order: usize) -> Vec<(Vec3, Real)> {
    if order <= 1 {
        return vec![(patch.centroid(), patch.area())];
    }
    let rule = interval_rule(order);
    let v = patch.vertices();
    let mut points = Vec::with_capacity(rule.len() * rule.len());
    for &(s, ws) in &rule {
        for &(t, wt) in &rule {
            let (p, jacobian) = match patch.shape() {
                PatchShape::Quad => {
                    let p = v[0].lerp(v[1], s).lerp(v[3].lerp(v[2], s), t);
                    let ps = (v[1] - v[0]) * (1.0 - t) + (v[2] - v[3]) * t;
                    let pt = (v[3] - v[0]) * (1.0 - s) + (v[2] - v[1]) * s;
                    (p, ps.cross(pt).length())
                }
                PatchShape::Triangle => {
                    let p = v[0] + ((v[1] - v[0]) + (v[2] - v[1]) * t) * s;
                    (p, 2.0 * patch.area() * s)
                }
            };
            points.push((p, ws * wt * jacobian));
        }
    }
    points
}
