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
    Ok(patches
        .iter()
        .map(|patch| {
            let normal = patch.normal();
            patch
                .vertices()
                .iter()
                .map(|&v| {
                    // The patch itself is among those met at its own corner, so the weight is
                    // at least its area.
                    let (mut sum, mut weight) = ([0.0; 3], 0.0);
                    for &j in corners.get(&key(patch.object.0, v)).into_iter().flatten() {
                        if patches[j].normal().dot(normal) > SMOOTH_COSINE {
                            let a = patches[j].area();
                            for c in 0..3 {
                                sum[c] += a * radiosity[j][c];
                            }
                            weight += a;
                        }
                    }
                    sum.map(|s| s / weight)
                })
                .collect()
        })
        .collect())
}
