//! Splitting an MGF face (any planar polygon, possibly non-convex, possibly with holes joined
//! to the outline by seam edges) into convex triangles and quads, by ear clipping.
//!
//! - Consecutive repeated vertices (including the last equal to the first) are merged.
//! - A face with more than three vertices whose vertices lie within `1e-5` of its extent from
//!   its mean plane is projected onto that plane. MGF files carry about six significant digits,
//!   so quads written as planar are rarely planar to the `1e-9` that patches require; moving
//!   vertices by less than the file's precision keeps them one patch each, as in RenderPark.
//!   Faces further from planar are ear-clipped into triangles without being moved.
//! - A triangle is kept as it is; a valid (planar, convex) quad too.
//! - A convex polygon with more vertices, with no vertex repeated, is cut into a fan of quads
//!   `(v0, v_i, v_i+1, v_i+2)` (and one triangle when the count is odd), each convex because
//!   it is part of a convex polygon.
//! - Anything else is triangulated by ear clipping in the plane of the face (the Newell normal;
//!   the polygon is projected on the two axes across it). An ear is a convex corner whose
//!   triangle contains no other vertex, inside or on an edge; vertices at the same position as a
//!   corner of the candidate ear (the two ends of a seam) do not block it. Collinear corners
//!   and the tips of zero-width spikes are removed without a triangle: they enclose no area.
//!   If no ear is found (a self-intersecting face), the most convex corner is clipped anyway,
//!   so the loop always ends.
//!
//! Pieces whose area is zero within round-off are left out; they carry no light.

use radiosity_core::{MaterialId, ObjectId, Patch, Real, Vec3};

/// Relative tolerance for areas (in units of the squared extent of the face).
const EPS: Real = 1e-12;
/// Largest distance from the mean plane, relative to the face's extent, at which a face with
/// more than three vertices counts as planar and is projected onto that plane.
const FLATTEN: Real = 1e-5;

/// Why a face gives no patch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Degenerate;

/// The convex pieces (3 or 4 vertices, with the face's orientation) of a planar polygon.
pub fn split(points: &[Vec3]) -> Result<Vec<Vec<Vec3>>, Degenerate> {
    let mut v: Vec<Vec3> = Vec::with_capacity(points.len());
    for &p in points {
        if v.last() != Some(&p) {
            v.push(p);
        }
    }
    while v.len() > 1 && v.first() == v.last() {
        v.pop();
    }
    if v.len() < 3 {
        return Err(Degenerate);
    }
    let origin = v[0];
    let extent2 = v.iter().map(|p| (*p - origin).length_squared()).fold(0.0, Real::max);
    let newell = newell(&v);
    if newell.length().is_nan() || newell.length() <= 2.0 * EPS * extent2 {
        return Err(Degenerate);
    }
    let normal = newell.normalize();
    let keep = |piece: &[Vec3]| newell_area(piece) > EPS * extent2;
    let mean = v.iter().copied().sum::<Vec3>() / v.len() as Real;
    let deviation = v.iter().map(|p| (*p - mean).dot(normal).abs()).fold(0.0, Real::max);
    if v.len() > 3 && deviation > FLATTEN * extent2.sqrt() {
        let pieces: Vec<Vec<Vec3>> =
            ear_clip(&v, normal, extent2).into_iter().map(|t| t.to_vec()).filter(|p| keep(p)).collect();
        return if pieces.is_empty() { Err(Degenerate) } else { Ok(pieces) };
    }
    if v.len() > 3 {
        for p in &mut v {
            *p -= normal * (*p - mean).dot(normal);
        }
    }
    let whole =
        v.len() == 3 || (v.len() == 4 && Patch::quad([v[0], v[1], v[2], v[3]], MaterialId(0), ObjectId(0)).is_ok());
    let pieces: Vec<Vec<Vec3>> = if whole {
        vec![v.clone()]
    } else if is_convex(&v, normal, extent2) {
        let mut pieces = Vec::new();
        let mut i = 1;
        while i + 1 < v.len() {
            if i + 2 < v.len() {
                pieces.push(vec![v[0], v[i], v[i + 1], v[i + 2]]);
                i += 2;
            } else {
                pieces.push(vec![v[0], v[i], v[i + 1]]);
                i += 1;
            }
        }
        pieces
    } else {
        ear_clip(&v, normal, extent2).into_iter().map(|t| t.to_vec()).collect()
    };
    let pieces: Vec<Vec<Vec3>> = pieces.into_iter().filter(|p| keep(p)).collect();
    if pieces.is_empty() { Err(Degenerate) } else { Ok(pieces) }
}

/// Twice the vector area of a polygon, relative to its first vertex.
fn newell(v: &[Vec3]) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for i in 1..v.len() - 1 {
        sum += (v[i] - v[0]).cross(v[i + 1] - v[0]);
    }
    sum
}

fn newell_area(v: &[Vec3]) -> Real {
    0.5 * newell(v).length()
}

/// Every corner turning the same way, no vertex repeated (the polygon is planar already).
fn is_convex(v: &[Vec3], normal: Vec3, extent2: Real) -> bool {
    let n = v.len();
    for i in 0..n {
        let turn = (v[(i + 1) % n] - v[i]).cross(v[(i + 2) % n] - v[(i + 1) % n]);
        if turn.dot(normal) <= EPS * extent2 {
            return false;
        }
        if v[i + 1..].contains(&v[i]) {
            return false;
        }
    }
    true
}

/// Triangles of a simple polygon (holes joined by seams allowed), by ear clipping.
fn ear_clip(v: &[Vec3], normal: Vec3, extent2: Real) -> Vec<[Vec3; 3]> {
    // Axes across the normal, so that the polygon runs counter-clockwise in (u, w).
    let helper = if normal.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let u = normal.cross(helper).normalize();
    let w = normal.cross(u);
    let p: Vec<[Real; 2]> = v.iter().map(|q| [(*q - v[0]).dot(u), (*q - v[0]).dot(w)]).collect();
    let cross =
        |a: [Real; 2], b: [Real; 2], c: [Real; 2]| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    let tol = EPS * extent2;
    let mut idx: Vec<usize> = (0..v.len()).collect();
    let mut out = Vec::new();
    while idx.len() > 3 {
        let m = idx.len();
        let mut clipped = false;
        let mut best: Option<(Real, usize)> = None;
        for k in 0..m {
            let (a, b, c) = (idx[(k + m - 1) % m], idx[k], idx[(k + 1) % m]);
            let turn = cross(p[a], p[b], p[c]);
            if turn.abs() <= tol {
                idx.remove(k);
                clipped = true;
                break;
            }
            if turn < 0.0 {
                continue;
            }
            if best.is_none_or(|(t, _)| turn > t) {
                best = Some((turn, k));
            }
            let blocked = idx.iter().any(|&j| {
                if p[j] == p[a] || p[j] == p[b] || p[j] == p[c] {
                    return false;
                }
                cross(p[a], p[b], p[j]) >= -tol && cross(p[b], p[c], p[j]) >= -tol && cross(p[c], p[a], p[j]) >= -tol
            });
            if !blocked {
                out.push([v[a], v[b], v[c]]);
                idx.remove(k);
                clipped = true;
                break;
            }
        }
        if !clipped {
            let Some((_, k)) = best else { break };
            let m = idx.len();
            out.push([v[idx[(k + m - 1) % m]], v[idx[k]], v[idx[(k + 1) % m]]]);
            idx.remove(k);
        }
    }
    if idx.len() == 3 && cross(p[idx[0]], p[idx[1]], p[idx[2]]) > tol {
        out.push([v[idx[0]], v[idx[1]], v[idx[2]]]);
    }
    out
}
