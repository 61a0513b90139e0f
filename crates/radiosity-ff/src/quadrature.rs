//! Quadrature on patches: Gauss–Legendre points with weights summing to the area, and the
//! per-pair choice of order used by the analytic backend.
//!
//! Order `q` uses the `q`-point Gauss–Legendre rule in each of the two parameters of the
//! patch (nodes by Newton's iteration on the Legendre recurrence, as in Press et al.,
//! *Numerical Recipes*, `gauleg`; Golub & Welsch 1969 for the theory):
//!
//! - a quad is parametrised bilinearly, `P(s, t)`, with area element `|P_s × P_t| ds dt`, exact
//!   for planar convex quads of any shape;
//! - a triangle by the collapsed square (Duffy 1982), `P(s, t) = v0 + s((v1 − v0) + t(v2 − v1))`,
//!   with area element `2A s ds dt`.
//!
//! Order 1 is the centroid rule.
//!
//! ## Choosing the order per pair
//!
//! The analytic backend integrates `F(dA_x → P_j)` over the receiver `i`. That integrand
//! varies on the length scale of the distance `d` between the patches, so the error of the
//! `q`-point rule falls like `(h/d)^{2q}`, `h` the receiver's longest edge. Fitted to the
//! measured errors on opposed unit squares at distances 0.5 to 8 (plain Gauss–Legendre,
//! orders 1 to 4):
//!
//! `error(q, r) ≈ 0.33 · 0.08^{q−1} · r^{−2q}`, `r = d / h`.
//!
//! [`order_for`] picks the smallest order whose predicted error is below a tolerance. Plain
//! Gauss–Legendre is used throughout: a smoothing substitution that clusters points away from
//! the edges (`u = 3ξ² − 2ξ³`) measured worse everywhere, even for patches touching along an
//! edge, where the integrand's derivative has a logarithmic singularity (docs/form-factors.md,
//! "Accuracy of the analytic and hemicube backends").

use radiosity_core::{Patch, PatchShape, Real, Vec3};

/// Gauss–Legendre nodes and weights on `[0, 1]` (weights sum to 1), nodes ascending.
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
            let (pn, pn_1) = if n == 1 { (x, 1.0) } else { (p1, p0) };
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

/// A rectangle `[s0, s1] × [t0, t1]` of a patch's parameter square.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Panel {
    /// Lower corner `(s0, t0)`.
    pub lo: (Real, Real),
    /// Upper corner `(s1, t1)`.
    pub hi: (Real, Real),
}

impl Panel {
    /// The whole parameter square.
    pub const WHOLE: Panel = Panel { lo: (0.0, 0.0), hi: (1.0, 1.0) };

    /// The four quarters.
    pub fn quarters(&self) -> [Panel; 4] {
        let mid = (0.5 * (self.lo.0 + self.hi.0), 0.5 * (self.lo.1 + self.hi.1));
        [
            Panel { lo: self.lo, hi: mid },
            Panel { lo: (mid.0, self.lo.1), hi: (self.hi.0, mid.1) },
            Panel { lo: (self.lo.0, mid.1), hi: (mid.0, self.hi.1) },
            Panel { lo: mid, hi: self.hi },
        ]
    }

    /// The larger side, as a fraction of the parameter square.
    pub fn extent(&self) -> Real {
        (self.hi.0 - self.lo.0).max(self.hi.1 - self.lo.1)
    }
}

/// The point of `patch` at parameters `(s, t)` and the area element there (see the module
/// documentation for the two parametrisations).
pub fn parametrisation(patch: &Patch, s: Real, t: Real) -> (Vec3, Real) {
    let v = patch.vertices();
    match patch.shape() {
        PatchShape::Quad => {
            let p = v[0].lerp(v[1], s).lerp(v[3].lerp(v[2], s), t);
            let ps = (v[1] - v[0]) * (1.0 - t) + (v[2] - v[3]) * t;
            let pt = (v[3] - v[0]) * (1.0 - s) + (v[2] - v[1]) * s;
            (p, ps.cross(pt).length())
        }
        PatchShape::Triangle => (v[0] + ((v[1] - v[0]) + (v[2] - v[1]) * t) * s, 2.0 * patch.area() * s),
    }
}

/// Calls `f(point, weight)` for the points of the tensor rule built from the 1-D rule `nodes`
/// on `panel` of `patch`; over the whole square the weights sum to the patch's area. A single
/// node on the whole square means the centroid rule.
pub fn for_each_point_in(patch: &Patch, panel: Panel, nodes: &[(Real, Real)], mut f: impl FnMut(Vec3, Real)) {
    if nodes.len() <= 1 && panel == Panel::WHOLE {
        f(patch.centroid(), patch.area());
        return;
    }
    let (ds, dt) = (panel.hi.0 - panel.lo.0, panel.hi.1 - panel.lo.1);
    for &(a, wa) in nodes {
        for &(b, wb) in nodes {
            let (p, jacobian) = parametrisation(patch, panel.lo.0 + a * ds, panel.lo.1 + b * dt);
            f(p, wa * wb * ds * dt * jacobian);
        }
    }
}

/// [`for_each_point_in`] over the whole patch.
pub fn for_each_point(patch: &Patch, nodes: &[(Real, Real)], f: impl FnMut(Vec3, Real)) {
    for_each_point_in(patch, Panel::WHOLE, nodes, f)
}

/// The points and weights of the order-`order` rule on `patch` (see [`for_each_point`]).
pub fn patch_rule(patch: &Patch, order: usize) -> Vec<(Vec3, Real)> {
    let mut points = Vec::with_capacity(order * order);
    for_each_point(patch, &gauss_legendre(order), |p, w| points.push((p, w)));
    points
}

/// The smallest order up to `max_order` whose predicted relative error for a receiver of
/// size `h` at distance `d` from the shooter is at most `tolerance` (see the module
/// documentation), or `None` when even `max_order` is not predicted to reach it, or when `d`
/// is not positive.
pub fn order_for(d: Real, h: Real, tolerance: Real, max_order: usize) -> Option<usize> {
    // A bound at or below zero says nothing about the distance (a receiver within the reach of
    // a long shooter); squared, it would pass for a large one.
    if d <= 0.0 {
        return None;
    }
    let r = d / h;
    let mut predicted = 0.33 / (r * r);
    for q in 1..=max_order {
        if predicted <= tolerance {
            return Some(q);
        }
        predicted *= 0.08 / (r * r);
    }
    None
}
