//! Vertex radiosity: corners are means of the patches that meet there on one smooth surface,
//! so they lie within those patches' values, and creases keep their edges.

use radiosity_core::Real;
use radiosity_eval::EvalError;
use radiosity_eval::vertex_radiosity;

#[test]
fn grids_are_smoothed_within_the_patch_values_and_creases_kept() {
    // The furnace box: 6 faces of 2 × 2 patches, distinct values per patch.
    let scene = radiosity_geom::load_scene("furnace:res=2").unwrap().scene;
    let b: Vec<[Real; 3]> = (0..scene.len()).map(|i| [i as Real; 3]).collect();
    let v = vertex_radiosity(&scene, &b).unwrap();
    assert_eq!(v.len(), scene.len());
    for (i, corners) in v.iter().enumerate() {
        assert_eq!(corners.len(), scene.patches()[i].vertices().len());
        for corner in corners {
            // A corner's value is a mean of patches that touch it, so it lies within them.
            assert!(corner[0] >= 0.0 && corner[0] <= (scene.len() - 1) as Real);
            assert_eq!(corner[0], corner[1]);
        }
        // Each patch of a 2 × 2 face touches the other three at the face's centre, and
        // only patches of its own face (perpendicular faces meet at a crease).
        let values = corners.iter().map(|c| c[0]).collect::<Vec<_>>();
        assert!(values.iter().any(|&c| c != i as Real), "patch {i} is smoothed somewhere");
        let face: Vec<usize> =
            (0..scene.len()).filter(|&j| scene.patches()[j].normal().dot(scene.patches()[i].normal()) > 0.9).collect();
        let (lo, hi) = (face.iter().min().unwrap(), face.iter().max().unwrap());
        assert!(values.iter().all(|&c| c >= *lo as Real && c <= *hi as Real), "patch {i}: {values:?}");
    }
}

#[test]
fn a_uniform_radiosity_stays_uniform_at_every_corner() {
    // A mean of equal values is that value, whatever the weights.
    let scene = radiosity_geom::load_scene("cornell:res=2").unwrap().scene;
    let b = vec![[0.25, 0.5, 2.0]; scene.len()];
    for corners in vertex_radiosity(&scene, &b).unwrap() {
        for corner in corners {
            for (c, expected) in corner.iter().zip([0.25, 0.5, 2.0]) {
                assert!((c - expected).abs() <= 1e-15 * expected, "{corner:?}");
            }
        }
    }
}

#[test]
fn a_radiosity_vector_of_the_wrong_length_is_refused() {
    let scene = radiosity_geom::load_scene("furnace:res=2").unwrap().scene;
    let e = vertex_radiosity(&scene, &[[1.0; 3]; 5]).unwrap_err();
    assert_eq!(e, EvalError::SizeMismatch { what: "the radiosity vector", expected: scene.len(), found: 5 });
}
