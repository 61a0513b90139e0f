//! Planar convex patches (triangles and quads): the unknowns of the radiosity system.
//!
//! A patch is one-sided: it emits and receives on the side its normal points to. Vertices are
//! ordered counter-clockwise seen from that side. The normal comes from Newell's method, the
//! area and centroid from the fan of triangles, so both are exact for planar convex polygons.
//!
//! Validation uses tolerances relative to the patch's own size (never absolute), so the same
//! patch is accepted or refused at any coordinate scale:
//!
//! - degenerate: area below `1e-12` times the squared longest edge;
//! - non-planar quad: a vertex farther than `1e-9` diagonals from the mean plane;
//! - non-convex quad: consecutive edge turns that disagree in sign with the normal.

use crate::error::CoreError;
use crate::ids::{MaterialId, ObjectId};
use crate::math::{Real, Vec3};

/// Relative area below which a patch counts as degenerate.
const DEGENERATE_AREA: Real = 1e-12;
/// Relative out-of-plane distance above which a quad counts as non-planar.
const PLANARITY: Real = 1e-9;

/// The polygon kind of a patch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PatchShape {
    /// Three vertices.
    Triangle,
    /// Four vertices, planar and convex.
    Quad,
}

/// A planar convex polygon with its derived quantities and provenance.
#[derive(Clone, Debug, PartialEq)]
pub struct Patch {
    vertices: [Vec3; 4],
    shape: PatchShape,
    area: Real,
    centroid: Vec3,
    normal: Vec3,
    /// The material (reflectivity and emission) of the patch.
    pub material: MaterialId,
    /// The object the patch was meshed from.
    pub object: ObjectId,
}

impl Patch {
    /// A triangle patch; vertices counter-clockwise around the front side.
    pub fn triangle(v: [Vec3; 3], material: MaterialId, object: ObjectId) -> Result<Patch, CoreError> {
        Self::build(&v, material, object)
    }

    /// A quad patch; vertices counter-clockwise around the front side, planar and convex.
    pub fn quad(v: [Vec3; 4], material: MaterialId, object: ObjectId) -> Result<Patch, CoreError> {
        Self::build(&v, material, object)
    }

    fn build(v: &[Vec3], material: MaterialId, object: ObjectId) -> Result<Patch, CoreError> {
        if v.iter().any(|p| !p.is_finite()) {
            return Err(CoreError::NonFiniteVertex);
        }
        let k = v.len();
        let longest_edge2 = (0..k).map(|i| (v[(i + 1) % k] - v[i]).length_squared()).fold(0.0, Real::max);
        // Newell's normal: twice the vector area, exact for planar polygons. Computed relative
        // to the first vertex, so far from the origin the products do not cancel.
        let mut twice_area = Vec3::ZERO;
        for i in 1..k - 1 {
            twice_area += (v[i] - v[0]).cross(v[i + 1] - v[0]);
        }
        let area = 0.5 * twice_area.length();
        if area.is_nan() || area <= DEGENERATE_AREA * longest_edge2 {
            return Err(CoreError::DegeneratePatch { area, scale: longest_edge2 });
        }
        let normal = twice_area / (2.0 * area);
        if k == 4 {
            let mean = (v[0] + v[1] + v[2] + v[3]) * 0.25;
            let diagonal = (v[2] - v[0]).length().max((v[3] - v[1]).length());
            let deviation = v.iter().map(|p| (*p - mean).dot(normal).abs()).fold(0.0, Real::max) / diagonal;
            if deviation > PLANARITY {
                return Err(CoreError::NonPlanarQuad { deviation });
            }
            for i in 0..4 {
                let turn = (v[(i + 1) % 4] - v[i]).cross(v[(i + 2) % 4] - v[(i + 1) % 4]);
                if turn.dot(normal) <= DEGENERATE_AREA * longest_edge2 {
                    return Err(CoreError::NonConvexQuad);
                }
            }
        }
        // Area-weighted centroid of the fan (v0, v_i, v_{i+1}).
        let mut weighted = Vec3::ZERO;
        let mut total = 0.0;
        for i in 1..k - 1 {
            let a = 0.5 * (v[i] - v[0]).cross(v[i + 1] - v[0]).dot(normal);
            weighted += (v[0] + v[i] + v[i + 1]) * (a / 3.0);
            total += a;
        }
        let mut vertices = [Vec3::ZERO; 4];
        vertices[..k].copy_from_slice(v);
        Ok(Patch {
            vertices,
            shape: if k == 3 { PatchShape::Triangle } else { PatchShape::Quad },
            area,
            centroid: weighted / total,
            normal,
            material,
            object,
        })
    }

    /// The vertices, counter-clockwise around the front side (3 or 4 of them).
    pub fn vertices(&self) -> &[Vec3] {
        match self.shape {
            PatchShape::Triangle => &self.vertices[..3],
            PatchShape::Quad => &self.vertices[..4],
        }
    }

    /// Triangle or quad.
    pub fn shape(&self) -> PatchShape {
        self.shape
    }

    /// The area.
    pub fn area(&self) -> Real {
        self.area
    }

    /// The area centroid.
    pub fn centroid(&self) -> Vec3 {
        self.centroid
    }

    /// The unit normal of the front side.
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    /// The triangles of the patch as a fan from the first vertex (one or two).
    pub fn triangles(&self) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        let v = self.vertices();
        (1..v.len() - 1).map(move |i| [v[0], v[i], v[i + 1]])
    }

    /// The point at parameters `(s, t)` in the unit square: bilinear on a quad, and on a
    /// triangle the square folded onto it (`t` collapses towards the third vertex), so uniform
    /// `(s, t)` in the square maps to a sample set covering the whole patch.
    pub fn point_at(&self, s: Real, t: Real) -> Vec3 {
        let v = &self.vertices;
        match self.shape {
            PatchShape::Quad => {
                let bottom = v[0].lerp(v[1], s);
                let top = v[3].lerp(v[2], s);
                bottom.lerp(top, t)
            }
            PatchShape::Triangle => {
                // Square-to-triangle warp with uniform density (Shirley): u = 1 - sqrt(s).
                let r = s.sqrt();
                v[0] * (1.0 - r) + v[1] * (r * (1.0 - t)) + v[2] * (r * t)
            }
        }
    }
}
