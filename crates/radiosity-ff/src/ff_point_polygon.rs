//! The form factor from a differential area to a polygon: Lambert's formula, with the polygon
//! clipped to the hemisphere above the differential area.
//!
//! For a point `x` with unit normal `n` and a polygon with vertices `v_k`, write
//! `R_k = v_k − x`. The unoccluded form factor is (Lambert 1760; Baum, Rushmeier & Winget
//! 1989, "Improving radiosity solutions through the use of analytically determined
//! form-factors", eq. 4):
//!
//! `F(dA_x → P) = 1/(2π) · Σ_k β_k · n · (R_k × R_{k+1}) / |R_k × R_{k+1}|`,
//!
//! where `β_k` is the angle between `R_k` and `R_{k+1}`. The sum's sign depends on which way
//! round the polygon is seen from `x`; its magnitude is the projected solid angle over `π`.
//!
//! The formula holds only for the part of the polygon above the tangent plane of `x`, so the
//! polygon is first clipped to `n · (y − x) ≥ 0` (Sutherland–Hodgman against one plane). A
//! polygon touching `x`'s patch along an edge keeps that edge in the tangent plane; its terms
//! stay finite because `x` is never on the edge itself (quadrature points are interior).

use radiosity_core::{Real, Vec3};

/// At most this many vertices after clipping a quad by one plane.
const MAX_CLIPPED: usize = 5;

/// The unoccluded form factor from the differential area at `x` with unit normal `n` to the
/// convex polygon `polygon` (3 or 4 vertices, either orientation).
pub fn point_to_polygon(x: Vec3, n: Vec3, polygon: &[Vec3]) -> Real {
    let mut clipped = [Vec3::ZERO; MAX_CLIPPED];
    let count = clip_above(x, n, polygon, &mut clipped);
    if count < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for k in 0..count {
        let a = clipped[k] - x;
        let b = clipped[(k + 1) % count] - x;
        let cross = a.cross(b);
        let sin = cross.length();
        if sin > 0.0 {
            let beta = sin.atan2(a.dot(b));
            sum += beta * n.dot(cross) / sin;
        }
    }
    (sum / (2.0 * std::f64::consts::PI)).abs()
}

/// Clips `polygon` to the closed half-space `n · (y − x) ≥ 0`, writing the result into `out`;
/// returns the vertex count.
fn clip_above(x: Vec3, n: Vec3, polygon: &[Vec3], out: &mut [Vec3; MAX_CLIPPED]) -> usize {
    let height = |p: Vec3| n.dot(p - x);
    let k = polygon.len();
    if polygon.iter().all(|p| height(*p) >= 0.0) {
        out[..k].copy_from_slice(polygon);
        return k;
    }
    let mut count = 0;
    for i in 0..k {
        let (a, b) = (polygon[i], polygon[(i + 1) % k]);
        let (ha, hb) = (height(a), height(b));
        if ha >= 0.0 {
            out[count] = a;
            count += 1;
        }
        if (ha >= 0.0) != (hb >= 0.0) {
            out[count] = a + (b - a) * (ha / (ha - hb));
            count += 1;
        }
    }
    count
}
