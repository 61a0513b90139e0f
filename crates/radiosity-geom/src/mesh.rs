//! Meshing: subdividing quads and triangles into patches, and the [`SceneBuilder`] that
//! built-in scenes and file loaders use to emit patches.
//!
//! Subdivision is deterministic, so the same input gives the same patches in the same order:
//!
//! - a planar convex quad with corners `v0 v1 v2 v3` is cut into an `nu × nv` grid of
//!   bilinear cells (`nu` along `v0→v1`, `nv` along `v0→v3`); for a planar quad every cell is
//!   itself a planar convex quad, and the cells tile the quad exactly;
//! - a triangle is cut into `k²` similar triangles by the `k`-fold barycentric grid;
//! - a quad that is not planar (the red wall of the published Cornell box is one, by 3.2 mm)
//!   is split along its shorter diagonal into two triangles first.
//!
//! "To a target size" picks the smallest division whose cells have edges no longer than the
//! target: `ceil(edge / target)`.

use crate::error::GeomError;
use radiosity_core::{CoreError, Material, MaterialId, ObjectId, Patch, Real, Scene, Vec3};

/// The number of divisions of an edge of length `length` so that pieces are at most `target`.
///
/// A non-positive or non-finite target means "no subdivision" (one piece).
pub fn divisions(length: Real, target: Real) -> usize {
    if !(target > 0.0 && target.is_finite()) {
        return 1;
    }
    ((length / target) * (1.0 - 1e-12)).ceil().max(1.0) as usize
}

/// The `nu × nv` bilinear cells of a quad, row by row from `v0`, each counter-clockwise like
/// the quad.
pub fn subdivide_quad(v: [Vec3; 4], nu: usize, nv: usize) -> Vec<[Vec3; 4]> {
    let at = |a: usize, b: usize| {
        let s = a as Real / nu as Real;
        let t = b as Real / nv as Real;
        v[0].lerp(v[1], s).lerp(v[3].lerp(v[2], s), t)
    };
    let mut cells = Vec::with_capacity(nu * nv);
    for b in 0..nv {
        for a in 0..nu {
            cells.push([at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)]);
        }
    }
    cells
}

/// The `k²` triangles of the `k`-fold barycentric grid of a triangle, with its orientation.
pub fn subdivide_triangle(v: [Vec3; 3], k: usize) -> Vec<[Vec3; 3]> {
    let at =
        |a: usize, b: usize| v[0] + (v[1] - v[0]) * (a as Real / k as Real) + (v[2] - v[0]) * (b as Real / k as Real);
    let mut tris = Vec::with_capacity(k * k);
    for b in 0..k {
        for a in 0..k - b {
            tris.push([at(a, b), at(a + 1, b), at(a, b + 1)]);
            if a + b + 1 < k {
                tris.push([at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)]);
            }
        }
    }
    tris
}

/// Which way the faces of a box point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Facing {
    /// Normals point out of the box (a solid object).
    Outward,
    /// Normals point into the box (a room).
    Inward,
}

/// The six faces of an axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoxFace {
    /// The face at minimum x.
    MinX,
    /// The face at maximum x.
    MaxX,
    /// The face at minimum y (the floor or bottom; y is up).
    MinY,
    /// The face at maximum y (the ceiling or top).
    MaxY,
    /// The face at minimum z.
    MinZ,
    /// The face at maximum z.
    MaxZ,
}

impl BoxFace {
    /// All six faces.
    pub const ALL: [BoxFace; 6] =
        [BoxFace::MinX, BoxFace::MaxX, BoxFace::MinY, BoxFace::MaxY, BoxFace::MinZ, BoxFace::MaxZ];

    /// The face's corners, counter-clockwise seen from outside the box.
    pub fn corners(self, lo: Vec3, hi: Vec3) -> [Vec3; 4] {
        let p = |x: Real, y: Real, z: Real| Vec3::new(x, y, z);
        match self {
            BoxFace::MinX => [p(lo.x, lo.y, lo.z), p(lo.x, lo.y, hi.z), p(lo.x, hi.y, hi.z), p(lo.x, hi.y, lo.z)],
            BoxFace::MaxX => [p(hi.x, lo.y, lo.z), p(hi.x, hi.y, lo.z), p(hi.x, hi.y, hi.z), p(hi.x, lo.y, hi.z)],
            BoxFace::MinY => [p(lo.x, lo.y, lo.z), p(hi.x, lo.y, lo.z), p(hi.x, lo.y, hi.z), p(lo.x, lo.y, hi.z)],
            BoxFace::MaxY => [p(lo.x, hi.y, lo.z), p(lo.x, hi.y, hi.z), p(hi.x, hi.y, hi.z), p(hi.x, hi.y, lo.z)],
            BoxFace::MinZ => [p(lo.x, lo.y, lo.z), p(lo.x, hi.y, lo.z), p(hi.x, hi.y, lo.z), p(hi.x, lo.y, lo.z)],
            BoxFace::MaxZ => [p(lo.x, lo.y, hi.z), p(hi.x, lo.y, hi.z), p(hi.x, hi.y, hi.z), p(lo.x, hi.y, hi.z)],
        }
    }
}

/// Reverses a polygon's orientation, keeping its first vertex.
fn flipped(v: [Vec3; 4]) -> [Vec3; 4] {
    [v[0], v[3], v[2], v[1]]
}

/// Collects materials, objects and patches, and builds a validated [`Scene`].
#[derive(Debug)]
pub struct SceneBuilder {
    name: String,
    patches: Vec<Patch>,
    materials: Vec<Material>,
    objects: Vec<String>,
}

impl SceneBuilder {
    /// An empty builder for a scene called `name`.
    pub fn new(name: impl Into<String>) -> Self {
        SceneBuilder { name: name.into(), patches: Vec::new(), materials: Vec::new(), objects: Vec::new() }
    }

    /// Adds a material, validating it, and returns its id.
    pub fn material(&mut self, material: Material) -> Result<MaterialId, GeomError> {
        material.validate().map_err(|e| GeomError::core("material", e))?;
        self.materials.push(material);
        Ok(MaterialId(self.materials.len() as u32 - 1))
    }

    /// Adds an object name and returns its id.
    pub fn object(&mut self, name: impl Into<String>) -> ObjectId {
        self.objects.push(name.into());
        ObjectId(self.objects.len() as u32 - 1)
    }

    /// The patches added so far.
    pub fn patch_count(&self) -> usize {
        self.patches.len()
    }

    fn context(&self, object: ObjectId) -> String {
        format!("object '{}'", self.objects.get(object.0 as usize).map_or("?", String::as_str))
    }

    /// Adds one patch as given (3 or 4 vertices).
    pub fn polygon(&mut self, v: &[Vec3], material: MaterialId, object: ObjectId) -> Result<(), GeomError> {
        let patch = match *v {
            [a, b, c] => Patch::triangle([a, b, c], material, object),
            [a, b, c, d] => Patch::quad([a, b, c, d], material, object),
            _ => unreachable!("patches have 3 or 4 vertices"),
        };
        self.patches.push(patch.map_err(|e| GeomError::core(self.context(object), e))?);
        Ok(())
    }

    /// Adds a quad cut into `nu × nv` patches. A non-planar quad is split into two triangles
    /// along its shorter diagonal, each cut `max(nu, nv)`-fold.
    pub fn quad_grid(
        &mut self,
        v: [Vec3; 4],
        nu: usize,
        nv: usize,
        material: MaterialId,
        object: ObjectId,
    ) -> Result<(), GeomError> {
        match Patch::quad(v, material, object) {
            Ok(_) => {
                for cell in subdivide_quad(v, nu.max(1), nv.max(1)) {
                    self.polygon(&cell, material, object)?;
                }
                Ok(())
            }
            Err(CoreError::NonPlanarQuad { .. }) => {
                let k = nu.max(nv).max(1);
                for tri in split_quad(v) {
                    self.triangle_grid(tri, k, material, object)?;
                }
                Ok(())
            }
            Err(e) => Err(GeomError::core(self.context(object), e)),
        }
    }

    /// Adds a quad cut so that patch edges are at most `target` long.
    pub fn quad_sized(
        &mut self,
        v: [Vec3; 4],
        target: Real,
        material: MaterialId,
        object: ObjectId,
    ) -> Result<(), GeomError> {
        let nu = divisions((v[1] - v[0]).length().max((v[2] - v[3]).length()), target);
        let nv = divisions((v[3] - v[0]).length().max((v[2] - v[1]).length()), target);
        self.quad_grid(v, nu, nv, material, object)
    }

    /// Adds a triangle cut into `k²` patches.
    pub fn triangle_grid(
        &mut self,
        v: [Vec3; 3],
        k: usize,
        material: MaterialId,
        object: ObjectId,
    ) -> Result<(), GeomError> {
        for tri in subdivide_triangle(v, k.max(1)) {
            self.polygon(&tri, material, object)?;
        }
        Ok(())
    }

    /// Adds a triangle cut so that patch edges are at most `target` long.
    pub fn triangle_sized(
        &mut self,
        v: [Vec3; 3],
        target: Real,
        material: MaterialId,
        object: ObjectId,
    ) -> Result<(), GeomError> {
        let longest = (0..3).map(|i| (v[(i + 1) % 3] - v[i]).length()).fold(0.0, Real::max);
        self.triangle_grid(v, divisions(longest, target), material, object)
    }

    /// Adds the given faces of the axis-aligned box with corners `[lo, hi]`, each cut to patches
    /// of at most `target` edge length, facing out of the box or into it.
    pub fn axis_box(
        &mut self,
        [lo, hi]: [Vec3; 2],
        faces: &[BoxFace],
        facing: Facing,
        target: Real,
        material: MaterialId,
        object: ObjectId,
    ) -> Result<(), GeomError> {
        for &face in faces {
            let c = face.corners(lo, hi);
            let c = if facing == Facing::Inward { flipped(c) } else { c };
            self.quad_sized(c, target, material, object)?;
        }
        Ok(())
    }

    /// Builds the scene, validating it as a whole.
    pub fn build(self) -> Result<Scene, GeomError> {
        let name = self.name.clone();
        Scene::new(self.name, self.patches, self.materials, self.objects)
            .map_err(|e| GeomError::core(format!("scene '{name}'"), e))
    }
}

/// The two triangles of a quad, split along the shorter diagonal.
fn split_quad(v: [Vec3; 4]) -> [[Vec3; 3]; 2] {
    if (v[2] - v[0]).length_squared() <= (v[3] - v[1]).length_squared() {
        [[v[0], v[1], v[2]], [v[0], v[2], v[3]]]
    } else {
        [[v[0], v[1], v[3]], [v[1], v[2], v[3]]]
    }
}
