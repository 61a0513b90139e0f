//! Radiosity at patch vertices, for smooth shading in [`render`](crate::view::render) and
//! [`gltf_export`](crate::view::gltf_export).
//!
//! Radiosity is constant over a patch. A viewer expects it to vary smoothly over a surface, so
//! each patch corner gets the area-weighted mean radiosity of the patches that meet there:
//! those of the same object, at the same position (to 1e-9 of the scene diagonal), whose
//! normals agree to within about 25° (`n · n' > 0.9`). Creases and separate objects keep
//! their edges; a flat wall meshed into a grid shades smoothly. Means of non-negative
//! values, so nothing new appears: every vertex value lies between its patches' values.

use crate::error::EvalError;
use radiosity_core::{Real, Scene, Vec3};
use std::collections::HashMap;

/// Normals closer than this (cosine) are smoothed together.
pub const SMOOTH_COSINE: Real = 0.9;

/// Which patches each patch corner averages, and with what weights: corner `v` of patch `i`
/// (slot `4 i + v`; a triangle's fourth slot is empty) is the mean of `patches[k]` weighted by
/// `areas[k]` over `k` in `starts[4 i + v] .. starts[4 i + v + 1]`, divided by the slot's
/// summed area. The rule of [`vertex_radiosity`], kept so that it can be applied to many
/// radiosity vectors of one scene (the live page of [`crate::live`] applies it in the browser).
#[derive(Clone, Debug, PartialEq)]
pub struct CornerTable {
    /// Where each corner slot's list starts in `patches` and `areas`; `4 n + 1` entries.
    pub starts: Vec<u32>,
    /// The patches averaged, slot by slot.
    pub patches: Vec<u32>,
    /// Their areas, the weights of the mean.
    pub areas: Vec<Real>,
}

impl CornerTable {
    /// The table of `scene`.
    pub fn new(scene: &Scene) -> CornerTable {
        let scale = scene.diagonal().max(Real::MIN_POSITIVE) * 1e-9;
        let key = |object: u32, p: Vec3| {
            let q = (p / scale).round();
            (object, q.x as i64, q.y as i64, q.z as i64)
        };
        // Every patch corner, grouped by object and position.
        let mut corners: HashMap<(u32, i64, i64, i64), Vec<usize>> = HashMap::new();
        for (i, patch) in scene.patches().iter().enumerate() {
            for &v in patch.vertices() {
                corners.entry(key(patch.object.0, v)).or_default().push(i);
            }
        }
        let patches = scene.patches();
        let mut table = CornerTable { starts: vec![0], patches: Vec::new(), areas: Vec::new() };
        for patch in patches {
            let normal = patch.normal();
            for slot in 0..4 {
                // The patch itself is among those met at its own corner, so the weight is at
                // least its area.
                if let Some(&v) = patch.vertices().get(slot) {
                    for &j in corners.get(&key(patch.object.0, v)).into_iter().flatten() {
                        if patches[j].normal().dot(normal) > SMOOTH_COSINE {
                            table.patches.push(j as u32);
                            table.areas.push(patches[j].area());
                        }
                    }
                }
                table.starts.push(table.patches.len() as u32);
            }
        }
        table
    }

    /// The area-weighted mean of `radiosity` (one RGB triple per patch) at corner `slot` of
    /// patch `i`.
    pub fn corner(&self, i: usize, slot: usize, radiosity: &[[Real; 3]]) -> [Real; 3] {
        let range = self.starts[4 * i + slot] as usize..self.starts[4 * i + slot + 1] as usize;
        let (mut sum, mut weight) = ([0.0; 3], 0.0);
        for (&j, &a) in self.patches[range.clone()].iter().zip(&self.areas[range]) {
            for c in 0..3 {
                sum[c] += a * radiosity[j as usize][c];
            }
            weight += a;
        }
        sum.map(|s| s / weight)
    }
}

/// The RGB radiosity at each corner of each patch: `result[i][v]` for vertex `v` of patch `i`,
/// from the per-patch RGB radiosity `radiosity` (one triple per patch of `scene`).
pub fn vertex_radiosity(scene: &Scene, radiosity: &[[Real; 3]]) -> Result<Vec<Vec<[Real; 3]>>, EvalError> {
    if radiosity.len() != scene.len() {
        return Err(EvalError::SizeMismatch {
            what: "the radiosity vector",
            expected: scene.len(),
            found: radiosity.len(),
        });
    }
    let table = CornerTable::new(scene);
    Ok(scene
        .patches()
        .iter()
        .enumerate()
        .map(|(i, patch)| (0..patch.vertices().len()).map(|v| table.corner(i, v, radiosity)).collect())
        .collect())
}
