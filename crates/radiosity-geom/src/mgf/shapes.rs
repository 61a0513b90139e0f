//! Tessellation of MGF's curved primitives (`cone`, `cyl`, `sph`, `ring`, `torus`) and
//! extrusion of `prism`, as RenderPark's MGF library does it.
//!
//! With `div` divisions per quarter circle (RenderPark's "curved surface division", default
//! 4), every circle is cut into `4 div` segments:
//!
//! - `cone` and `cyl`: `4 div` quads between the two end circles (triangles where a radius
//!   is 0). Cones and cylinders are open: MGF has no end caps.
//! - `sph`: `2 div` bands from pole to pole of `4 div` faces each, so `8 div²` faces (the two
//!   polar bands are triangles). RenderPark builds spheres from the same cones.
//! - `ring`: `4 div` faces around the centre, with no radial division: triangles for a disc
//!   (`r0 = 0`), quads for an annulus.
//! - `torus`: `4 div` faces around the tube times `4 div` around the axis, `16 div²` quads.
//!
//! Surfaces face outwards (rings towards the centre vertex's normal); negative radii turn
//! them inwards, as the MGF specification says. A `prism` is its polygon extruded by the given
//! length along the polygon's right-hand normal: the polygon reversed as the base, the moved
//! polygon as the top, and one quad per edge; all of them face away from the solid for a
//! positive length.

use radiosity_core::{Real, Vec3};
use std::f64::consts::FRAC_PI_2;

/// Two unit axes `u`, `v` across `axis` with `u × v = axis` (normalised).
fn axes(axis: Vec3) -> (Vec3, Vec3) {
    let a = axis.normalize();
    let helper = if a.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let u = helper.cross(a).normalize();
    // u × (a × u) = a for unit perpendicular u and a.
    let v = a.cross(u);
    (u, v)
}

fn reversed(mut polygons: Vec<Vec<Vec3>>) -> Vec<Vec<Vec3>> {
    for p in &mut polygons {
        p.reverse();
    }
    polygons
}

/// A truncated cone between circles of radius `r1` at `p1` and `r2` at `p2` (both ≥ 0),
/// facing outwards.
fn frustum(p1: Vec3, r1: Real, p2: Vec3, r2: Real, div: usize) -> Vec<Vec<Vec3>> {
    let (u, v) = axes(p2 - p1);
    let n = 4 * div;
    let at = |c: Vec3, r: Real, i: usize| {
        let t = i as Real * FRAC_PI_2 / div as Real;
        c + r * (u * t.cos() + v * t.sin())
    };
    (0..n)
        .map(|i| {
            let (a, b) = (i, (i + 1) % n);
            if r1 == 0.0 {
                vec![p1, at(p2, r2, b), at(p2, r2, a)]
            } else if r2 == 0.0 {
                vec![at(p1, r1, a), at(p1, r1, b), p2]
            } else {
                vec![at(p1, r1, a), at(p1, r1, b), at(p2, r2, b), at(p2, r2, a)]
            }
        })
        .collect()
}

/// `cone p1 r1 p2 r2`: radii of one sign (or zero); negative radii face inwards.
pub fn cone(p1: Vec3, r1: Real, p2: Vec3, r2: Real, div: usize) -> Result<Vec<Vec<Vec3>>, String> {
    if r1 * r2 < 0.0 || (r1 == 0.0 && r2 == 0.0) {
        return Err(format!("cone radii {r1} and {r2} must have one sign and not both be 0"));
    }
    if (p2 - p1).length() == 0.0 {
        return Err("cone end points coincide".into());
    }
    let faces = frustum(p1, r1.abs(), p2, r2.abs(), div);
    Ok(if r1 < 0.0 || r2 < 0.0 { reversed(faces) } else { faces })
}

/// `sph p r`: a negative radius faces inwards.
pub fn sphere(centre: Vec3, r: Real, div: usize) -> Result<Vec<Vec<Vec3>>, String> {
    if r == 0.0 {
        return Err("sphere radius must not be 0".into());
    }
    let bands = 2 * div;
    let mut faces = Vec::new();
    for k in 0..bands {
        let (phi1, phi2) = (k as Real * FRAC_PI_2 / div as Real, (k + 1) as Real * FRAC_PI_2 / div as Real);
        let r1 = if k == 0 { 0.0 } else { r.abs() * phi1.sin() };
        let r2 = if k + 1 == bands { 0.0 } else { r.abs() * phi2.sin() };
        let c1 = centre + Vec3::Z * (r.abs() * phi1.cos());
        let c2 = centre + Vec3::Z * (r.abs() * phi2.cos());
        faces.extend(frustum(c1, r1, c2, r2, div));
    }
    Ok(if r < 0.0 { reversed(faces) } else { faces })
}

/// `ring p r0 r1` around `normal`: a disc when `r0 = 0`.
pub fn ring(centre: Vec3, normal: Vec3, r0: Real, r1: Real, div: usize) -> Result<Vec<Vec<Vec3>>, String> {
    if normal.length() == 0.0 {
        return Err("ring centre vertex needs a normal (n)".into());
    }
    if !(r0 >= 0.0 && r1 > r0) {
        return Err(format!("ring radii must satisfy 0 <= r0 < r1, got {r0} and {r1}"));
    }
    let (u, v) = axes(normal);
    let n = 4 * div;
    let dir = |i: usize| {
        let t = i as Real * FRAC_PI_2 / div as Real;
        u * t.cos() + v * t.sin()
    };
    Ok((0..n)
        .map(|i| {
            let (a, b) = (dir(i), dir((i + 1) % n));
            if r0 == 0.0 {
                vec![centre, centre + r1 * a, centre + r1 * b]
            } else {
                vec![centre + r0 * a, centre + r1 * a, centre + r1 * b, centre + r0 * b]
            }
        })
        .collect())
}

/// `torus p r0 r1` around `normal`: the tube between radii `r0` and `r1`; negative radii face
/// inwards.
pub fn torus(centre: Vec3, normal: Vec3, r0: Real, r1: Real, div: usize) -> Result<Vec<Vec<Vec3>>, String> {
    if normal.length() == 0.0 {
        return Err("torus centre vertex needs a normal (n)".into());
    }
    if r0 == 0.0 || r0 * r1 < 0.0 || (r1 - r0).abs() == 0.0 || (r1.abs() < r0.abs()) {
        return Err(format!("torus radii must have one sign with 0 < |r0| < |r1|, got {r0} and {r1}"));
    }
    let (r0a, r1a) = (r0.abs(), r1.abs());
    let (big, tube) = (0.5 * (r0a + r1a), 0.5 * (r1a - r0a));
    let (u, v) = axes(normal);
    let w = normal.normalize();
    let n = 4 * div;
    let step = FRAC_PI_2 / div as Real;
    let at = |i: usize, j: usize| {
        let (theta, phi) = ((i % n) as Real * step, (j % n) as Real * step);
        centre + (big + tube * theta.cos()) * (u * phi.cos() + v * phi.sin()) + tube * theta.sin() * w
    };
    let mut faces = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            faces.push(vec![at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    Ok(if r0 < 0.0 { reversed(faces) } else { faces })
}

/// `prism v1 … vn length`.
pub fn prism(base: &[Vec3], length: Real) -> Result<Vec<Vec<Vec3>>, String> {
    let mut newell = Vec3::ZERO;
    for i in 1..base.len().saturating_sub(1) {
        newell += (base[i] - base[0]).cross(base[i + 1] - base[0]);
    }
    if base.len() < 3 || newell.length() == 0.0 {
        return Err("prism base polygon has no area".into());
    }
    if length == 0.0 {
        return Err("prism length must not be 0".into());
    }
    let offset = newell.normalize() * length;
    let mut faces = vec![base.iter().rev().copied().collect::<Vec<_>>(), base.iter().map(|p| *p + offset).collect()];
    for i in 0..base.len() {
        let (a, b) = (base[i], base[(i + 1) % base.len()]);
        faces.push(vec![a, b, b + offset, a + offset]);
    }
    Ok(faces)
}
