//! Radiosity at patch vertices, for smooth shading in `render` and `export`.
//!
//! Radiosity is constant over a patch. A viewer expects it to vary smoothly over a surface, so
//! each patch corner gets the area-weighted mean radiosity of the patches that meet there:
//! those of the same object, at the same position (to 1e-9 of the scene diagonal), whose
//! normals agree to within about 25° (`n · n' > 0.9`). Creases and separate objects keep
//! their edges; a flat wall meshed into a grid shades smoothly. Means of non-negative
//! values, so nothing new appears: every vertex value lies between its patches' values.

use radiosity_core::{Real, Scene, Vec3};
use std::collections::HashMap;

/// Normals closer than this (cosine) are smoothed together.
const SMOOTH_COSINE: Real = 0.9;

/// The RGB radiosity at each corner of each patch: `result[i][v]` for vertex `v` of patch `i`.
pub fn vertex_radiosity(scene: &Scene, radiosity: &[[Real; 3]]) -> Vec<Vec<[Real; 3]>> {
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
    patches
        .iter()
        .map(|patch| {
            let normal = patch.normal();
            patch
                .vertices()
                .iter()
                .map(|&v| {
                    let (mut sum, mut weight) = ([0.0; 3], 0.0);
                    for &j in &corners[&key(patch.object.0, v)] {
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
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_are_smoothed_within_the_patch_values_and_creases_kept() {
        // The furnace box: 6 faces of 2 × 2 patches, distinct values per patch.
        let scene = radiosity_geom::load_scene("furnace:res=2").unwrap().scene;
        let b: Vec<[Real; 3]> = (0..scene.len()).map(|i| [i as Real; 3]).collect();
        let v = vertex_radiosity(&scene, &b);
        for (i, corners) in v.iter().enumerate() {
            for corner in corners {
                // A corner's value is a mean of patches that touch it, so it lies within them.
                assert!(corner[0] >= 0.0 && corner[0] <= (scene.len() - 1) as Real);
                assert_eq!(corner[0], corner[1]);
            }
            // Each patch of a 2 × 2 face touches the other three at the face's centre, and
            // only patches of its own face (perpendicular faces meet at a crease).
            let values = corners.iter().map(|c| c[0]).collect::<Vec<_>>();
            assert!(values.iter().any(|&c| c != i as Real), "patch {i} is smoothed somewhere");
            let face: Vec<usize> = (0..scene.len())
                .filter(|&j| scene.patches()[j].normal().dot(scene.patches()[i].normal()) > 0.9)
                .collect();
            let (lo, hi) = (face.iter().min().unwrap(), face.iter().max().unwrap());
            assert!(values.iter().all(|&c| c >= *lo as Real && c <= *hi as Real), "patch {i}: {values:?}");
        }
    }
}
