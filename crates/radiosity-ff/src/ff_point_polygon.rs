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
//!
//! ## Four points at once
//!
//! [`point_to_polygon_x4`] evaluates the formula for four points with the same normal (the
//! quadrature points of a receiver, the corners of a sampling cell) in a structure-of-arrays
//! layout, one SIMD lane per point (the `wide` crate's `f64x4`): the polygon's vertices are
//! shared, each edge is one pass over the lanes. A lane whose tangent plane cuts the polygon
//! is clipped and computed on its own. The lanes run the very operations of the one-point
//! [`point_to_polygon`], in the same order and without fused multiply-adds, so each lane is
//! bit for bit the value [`point_to_polygon`] gives for its point (tested).
//!
//! ## The angle
//!
//! `β_k = atan2(|R_k × R_{k+1}|, R_k · R_{k+1}) ∈ [0, π]` is computed without the library's
//! `atan2` (a fifth of the analytic backend's time once, and not vectorisable). Seen from a
//! distant point every edge subtends a small angle, and for `s / c ≤ 1/8` the Taylor series
//! of `atan(s / c)` to the 15th power is exact to `2^-52` relative. Otherwise the ratio
//! `t = min(s, |c|) / max(s, |c|) ∈ [0, 1]` is reduced to `|x| ≤ tan(π/8)` by
//! `atan t = π/4 + atan((t − 1)/(t + 1))`, where Cephes' rational approximation of degree
//! 4/5 (Moshier 1989, `atan.c`) is accurate to about one unit in the last place; then
//! `π/2 − ·` when `s > |c|` and `π − ·` when `c < 0`. Measured against `atan2` over the
//! whole range, the largest difference is a few units in the last place (tested); Howell's
//! closed forms are met as before.

use radiosity_core::{Real, Vec3};
use wide::{CmpGt, CmpLe, CmpLt, f64x4};

/// At most this many vertices after clipping a quad by one plane.
pub const MAX_CLIPPED: usize = 5;

/// The unoccluded form factor from the differential area at `x` with unit normal `n` to the
/// convex polygon `polygon` (3 or 4 vertices, either orientation).
pub fn point_to_polygon(x: Vec3, n: Vec3, polygon: &[Vec3]) -> Real {
    if polygon.iter().all(|p| n.dot(*p - x) >= 0.0) {
        return lambert(x, n, polygon);
    }
    let mut clipped = [Vec3::ZERO; MAX_CLIPPED];
    let count = clip_above(x, n, polygon, &mut clipped);
    if count < 3 {
        return 0.0;
    }
    lambert(x, n, &clipped[..count])
}

/// `out[k] = point_to_polygon(x[k], n, polygon)` for every point (`out` as long as `x`):
/// four at a time with [`point_to_polygon_x4`], the last few one at a time, so bit for bit
/// the one-point values.
pub fn point_to_polygon_each(x: &[Vec3], n: Vec3, polygon: &[Vec3], out: &mut [Real]) {
    let mut points = x.chunks_exact(4);
    let mut values = out.chunks_exact_mut(4);
    for (four, value) in (&mut points).zip(&mut values) {
        value.copy_from_slice(&point_to_polygon_x4([four[0], four[1], four[2], four[3]], n, polygon));
    }
    for (&p, value) in points.remainder().iter().zip(values.into_remainder()) {
        *value = point_to_polygon(p, n, polygon);
    }
}

/// The form factors from the differential areas at the four points `x`, all with unit
/// normal `n`, to the convex polygon `polygon` (3 or 4 vertices, either orientation): lane
/// `l` is bit for bit `point_to_polygon(x[l], n, polygon)` (module documentation, "Four
/// points at once").
pub fn point_to_polygon_x4(x: [Vec3; 4], n: Vec3, polygon: &[Vec3]) -> [Real; 4] {
    let above = x.map(|x| polygon.iter().all(|p| n.dot(*p - x) >= 0.0));
    if above.iter().all(|&a| !a) {
        return x.map(|x| point_to_polygon(x, n, polygon));
    }
    let mut out = lambert_x4(x, n, polygon);
    for l in 0..4 {
        if !above[l] {
            out[l] = point_to_polygon(x[l], n, polygon);
        }
    }
    out
}

/// Lambert's sum for a polygon wholly above the tangent plane of `x`.
fn lambert(x: Vec3, n: Vec3, polygon: &[Vec3]) -> Real {
    let count = polygon.len();
    let mut sum = 0.0;
    for k in 0..count {
        let a = polygon[k] - x;
        let b = polygon[(k + 1) % count] - x;
        let cross = a.cross(b);
        let sin = cross.length();
        if sin > 0.0 {
            sum += angle(sin, a.dot(b)) * n.dot(cross) / sin;
        }
    }
    (sum / (2.0 * std::f64::consts::PI)).abs()
}

/// [`lambert`] for four points at once, one lane each, with the same operations in the same
/// order (`glam`'s `cross`, `dot` and `length` written out).
fn lambert_x4(x: [Vec3; 4], n: Vec3, polygon: &[Vec3]) -> [Real; 4] {
    let lanes = |f: fn(&Vec3) -> Real| f64x4::new([f(&x[0]), f(&x[1]), f(&x[2]), f(&x[3])]);
    let (px, py, pz) = (lanes(|v| v.x), lanes(|v| v.y), lanes(|v| v.z));
    let (nx, ny, nz) = (f64x4::splat(n.x), f64x4::splat(n.y), f64x4::splat(n.z));
    let count = polygon.len();
    let mut sum = f64x4::splat(0.0);
    for k in 0..count {
        let (v, w) = (polygon[k], polygon[(k + 1) % count]);
        let (ax, ay, az) = (f64x4::splat(v.x) - px, f64x4::splat(v.y) - py, f64x4::splat(v.z) - pz);
        let (bx, by, bz) = (f64x4::splat(w.x) - px, f64x4::splat(w.y) - py, f64x4::splat(w.z) - pz);
        let cx = ay * bz - by * az;
        let cy = az * bx - bz * ax;
        let cz = ax * by - bx * ay;
        let sin = (cx * cx + cy * cy + cz * cz).sqrt();
        let cos = ax * bx + ay * by + az * bz;
        let term = angle_x4(sin, cos) * (nx * cx + ny * cy + nz * cz) / sin;
        sum += sin.cmp_gt(f64x4::splat(0.0)).blend(term, f64x4::splat(0.0));
    }
    (sum / f64x4::splat(2.0 * std::f64::consts::PI)).abs().to_array()
}

/// `tan(π/8)`: above it, `atan t` is taken as `π/4 + atan((t − 1)/(t + 1))`.
const TAN_PI_8: Real = 0.414_213_562_373_095_03;
/// Cephes' `atan.c` numerator `P(z)`, highest power first, digits as published
/// (they round to the same `f64`s as 17-digit literals would).
#[allow(clippy::excessive_precision)]
const ATAN_P: [Real; 5] = [
    -8.750_608_600_031_904_122_785e-1,
    -1.615_753_718_733_365_076_637e1,
    -7.500_855_792_314_704_667_340e1,
    -1.228_866_684_490_136_173_410e2,
    -6.485_021_904_942_025_371_773e1,
];
/// Cephes' denominator `Q(z)` (leading coefficient 1), highest power first.
#[allow(clippy::excessive_precision)]
const ATAN_Q: [Real; 5] = [
    2.485_846_490_142_306_297_962e1,
    1.650_270_098_316_988_542_046e2,
    4.328_810_604_912_902_668_951e2,
    4.853_903_996_359_136_964_868e2,
    1.945_506_571_482_613_964_425e2,
];

/// The angle `atan2(sin, cos)` for `sin ≥ 0` (module documentation, "The angle").
fn angle(sin: Real, cos: Real) -> Real {
    if cos > 0.0 && sin <= SERIES_LIMIT * cos {
        return small_angle(sin / cos);
    }
    let c = cos.abs();
    let t = sin.min(c) / sin.max(c);
    let big = t > TAN_PI_8;
    let x = if big { (t - 1.0) / (t + 1.0) } else { t };
    let z = x * x;
    let p = (((ATAN_P[0] * z + ATAN_P[1]) * z + ATAN_P[2]) * z + ATAN_P[3]) * z + ATAN_P[4];
    let q = ((((z + ATAN_Q[0]) * z + ATAN_Q[1]) * z + ATAN_Q[2]) * z + ATAN_Q[3]) * z + ATAN_Q[4];
    let mut r = x + x * (z * p / q);
    if big {
        r += std::f64::consts::FRAC_PI_4;
    }
    if sin > c {
        r = std::f64::consts::FRAC_PI_2 - r;
    }
    if cos < 0.0 {
        r = std::f64::consts::PI - r;
    }
    r
}

/// `atan x` for `0 ≤ x ≤ 1/8` by its Taylor series to the 15th power, whose next term is below
/// `2^-52` relative there: one division fewer than the rational form, for the small angles
/// every edge subtends from a distant point.
fn small_angle(x: Real) -> Real {
    let x2 = x * x;
    let series = 1.0
        - x2 * (1.0 / 3.0
            - x2 * (1.0 / 5.0
                - x2 * (1.0 / 7.0 - x2 * (1.0 / 9.0 - x2 * (1.0 / 11.0 - x2 * (1.0 / 13.0 - x2 / 15.0))))));
    x * series
}

/// [`small_angle`] on four lanes, with the same operations.
fn small_angle_x4(x: f64x4) -> f64x4 {
    let s = f64x4::splat;
    let x2 = x * x;
    let series = s(1.0)
        - x2 * (s(1.0 / 3.0)
            - x2 * (s(1.0 / 5.0)
                - x2 * (s(1.0 / 7.0)
                    - x2 * (s(1.0 / 9.0) - x2 * (s(1.0 / 11.0) - x2 * (s(1.0 / 13.0) - x2 / s(15.0)))))));
    x * series
}

/// Below this `sin / cos` (and for `cos > 0`) the angle is [`small_angle`].
const SERIES_LIMIT: Real = 0.125;

/// [`angle`] on four lanes, with the same operations: both forms are computed and each lane
/// takes the one [`angle`] would.
fn angle_x4(sin: f64x4, cos: f64x4) -> f64x4 {
    let splat = f64x4::splat;
    let series = cos.cmp_gt(splat(0.0)) & sin.cmp_le(splat(SERIES_LIMIT) * cos);
    let small = small_angle_x4(sin / cos);
    let c = cos.abs();
    let t = sin.min(c) / sin.max(c);
    let big = t.cmp_gt(splat(TAN_PI_8));
    let x = big.blend((t - splat(1.0)) / (t + splat(1.0)), t);
    let z = x * x;
    let p = (((splat(ATAN_P[0]) * z + splat(ATAN_P[1])) * z + splat(ATAN_P[2])) * z + splat(ATAN_P[3])) * z
        + splat(ATAN_P[4]);
    let q = ((((z + splat(ATAN_Q[0])) * z + splat(ATAN_Q[1])) * z + splat(ATAN_Q[2])) * z + splat(ATAN_Q[3])) * z
        + splat(ATAN_Q[4]);
    let mut r = x + x * (z * p / q);
    r = big.blend(splat(std::f64::consts::FRAC_PI_4) + r, r);
    r = sin.cmp_gt(c).blend(splat(std::f64::consts::FRAC_PI_2) - r, r);
    r = cos.cmp_lt(splat(0.0)).blend(splat(std::f64::consts::PI) - r, r);
    series.blend(small, r)
}

/// Clips `polygon` to the closed half-space `n · (y − x) ≥ 0`, writing the result into `out`;
/// returns the vertex count.
pub fn clip_above(x: Vec3, n: Vec3, polygon: &[Vec3], out: &mut [Vec3; MAX_CLIPPED]) -> usize {
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

/// The distance from `x` to the planar convex polygon `polygon` (its interior included), whose
/// unit normal is `normal` (either orientation).
pub fn distance_to_polygon(x: Vec3, polygon: &[Vec3], normal: Vec3) -> Real {
    let k = polygon.len();
    let height = normal.dot(x - polygon[0]);
    let foot = x - normal * height;
    let inside = (0..k).all(|i| (polygon[(i + 1) % k] - polygon[i]).cross(foot - polygon[i]).dot(normal) >= 0.0);
    if inside {
        return height.abs();
    }
    (0..k)
        .map(|i| {
            let (a, b) = (polygon[i], polygon[(i + 1) % k]);
            let ab = b - a;
            let t = (ab.dot(x - a) / ab.length_squared()).clamp(0.0, 1.0);
            (a + ab * t - x).length()
        })
        .fold(Real::INFINITY, Real::min)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    #[test]
    fn the_angle_matches_atan2_to_a_few_ulp() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        let mut worst: Real = 0.0;
        for k in 0..200_000 {
            // Every direction of the upper half-plane, and ratios from 1e-12 to 1e12.
            let (sin, cos) = if k % 2 == 0 {
                let theta = std::f64::consts::PI * rng.random::<Real>();
                (theta.sin().abs(), theta.cos())
            } else {
                let scale = 10f64.powf(24.0 * rng.random::<Real>() - 12.0);
                (scale * rng.random::<Real>(), if rng.random::<bool>() { 1.0 } else { -1.0 })
            };
            if sin <= 0.0 {
                continue;
            }
            let exact = sin.atan2(cos);
            let ulp = (exact.abs() * Real::EPSILON).max(Real::MIN_POSITIVE);
            worst = worst.max((angle(sin, cos) - exact).abs() / ulp);
        }
        assert!(worst <= 4.0, "the angle is {worst} units in the last place from atan2");
    }

    #[test]
    fn four_lanes_give_the_one_point_values_bit_for_bit() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(2);
        let quad =
            [Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.2), Vec3::new(1.0, 1.0, 1.4), Vec3::new(0.0, 1.0, 1.2)];
        let triangle = [Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.5), Vec3::new(0.0, 2.0, 0.25)];
        for k in 0..5_000 {
            let n = Vec3::new(rng.random::<Real>() - 0.5, rng.random::<Real>() - 0.5, 1.0).normalize();
            // Points near and far, some whose tangent plane cuts the polygon (clipped alone).
            let x: [Vec3; 4] = std::array::from_fn(|_| {
                let spread = if k % 3 == 0 { 0.1 } else { 3.0 };
                Vec3::new(rng.random::<Real>(), rng.random::<Real>(), 0.0) * spread - Vec3::new(0.0, 0.0, spread)
            });
            for polygon in [&quad[..], &triangle[..]] {
                let four = point_to_polygon_x4(x, n, polygon);
                for l in 0..4 {
                    let one = point_to_polygon(x[l], n, polygon);
                    assert_eq!(four[l].to_bits(), one.to_bits(), "lane {l} of {x:?}: {} against {one}", four[l]);
                }
            }
        }
    }
}
