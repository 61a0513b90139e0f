//! `export`: the binary glTF it writes reads back with the scene's patches, normals facing the
//! way triangles wind, colours in `[0, 1]` brightest on the light, and unlit materials, and it
//! loads back as a scene with the same patches.

use super::{failure, stdout_json, xtask};
use std::path::PathBuf;

/// A file in the temporary directory, removed when dropped.
struct TempFile(PathBuf);

impl TempFile {
    fn new(name: &str) -> TempFile {
        TempFile(std::env::temp_dir().join(format!("radiosity-export-{}-{name}", std::process::id())))
    }

    fn path(&self) -> &str {
        self.0.to_str().unwrap()
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

#[test]
fn cornell_round_trips_with_one_vertex_set_per_patch() {
    let file = TempFile::new("cornell.glb");
    let out = xtask(&["export", "--scene", "cornell:res=2", "--solver", "reference", "--out", file.path()])
        .success()
        .get_output()
        .stdout
        .clone();
    let line = String::from_utf8(out).unwrap();
    assert_eq!(line.lines().count(), 1, "{line}");
    assert!(line.contains(file.path()) && line.contains("exposure"), "{line}");

    let scene = radiosity_geom::load_scene("cornell:res=2").unwrap().scene;
    // Patches material by material (in the scene's material order), each material's in the
    // scene's order: one primitive per material used.
    let mut order: Vec<usize> = (0..scene.len()).collect();
    order.sort_by_key(|&i| scene.patches()[i].material);
    let corners: Vec<usize> = order.iter().map(|&i| scene.patches()[i].vertices().len()).collect();
    let glb = gltf::Gltf::from_slice(&std::fs::read(&file.0).unwrap()).unwrap();
    let buffers = [glb.blob.clone().expect("the binary chunk")];
    let document = glb.document;
    assert_eq!(document.meshes().count(), 1);
    assert_eq!(document.nodes().count(), 1);
    let mesh = document.meshes().next().unwrap();
    let primitives: Vec<_> = mesh.primitives().collect();
    let used: std::collections::BTreeSet<_> = scene.patches().iter().map(|p| p.material).collect();
    assert_eq!(primitives.len(), used.len());
    // The primitives' vertices one after the other, indices offset to match.
    let (mut positions, mut normals, mut colours, mut indices) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for primitive in &primitives {
        assert_eq!(primitive.mode(), gltf::mesh::Mode::Triangles);
        let reader = primitive.reader(|b| Some(&buffers[b.index()][..]));
        let first = positions.len() as u32;
        indices.extend(reader.read_indices().expect("indices").into_u32().map(|i| first + i));
        positions.extend(reader.read_positions().expect("POSITION"));
        normals.extend(reader.read_normals().expect("NORMAL"));
        colours.extend(reader.read_colors(0).expect("COLOR_0").into_rgb_f32());
    }

    // One vertex per patch corner, patch after patch; corners − 2 triangles per patch.
    assert_eq!(positions.len(), corners.iter().sum::<usize>());
    assert_eq!(normals.len(), positions.len());
    assert_eq!(colours.len(), positions.len());
    assert_eq!(indices.len() / 3, corners.iter().map(|k| k - 2).sum::<usize>());
    assert_eq!(indices.len() % 3, 0);
    // (patch, corner) of every vertex.
    let owner: Vec<(usize, usize)> =
        order.iter().zip(&corners).flat_map(|(&i, &k)| (0..k).map(move |c| (i, c))).collect();
    let patch_of: Vec<usize> = owner.iter().map(|&(i, _)| i).collect();
    for (v, p) in positions.iter().enumerate() {
        let patch = &scene.patches()[owner[v].0];
        let corner = patch.vertices()[owner[v].1];
        assert!((corner - radiosity_core::Vec3::from(p.map(f64::from))).length() < 1e-3, "vertex {v}");
        let n = patch.normal();
        assert!((n - radiosity_core::Vec3::from(normals[v].map(f64::from))).length() < 1e-6, "normal {v}");
    }
    // Each triangle lies in one patch and winds counter-clockwise about its normal.
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as usize);
        assert!(patch_of[a] == patch_of[b] && patch_of[b] == patch_of[c], "{t:?} spans patches");
        let p = |i: usize| radiosity_core::Vec3::from(positions[i].map(f64::from));
        let n = radiosity_core::Vec3::from(normals[a].map(f64::from));
        assert!((p(b) - p(a)).cross(p(c) - p(a)).dot(n) > 0.0, "{t:?} winds clockwise");
    }

    // Colours are finite, in [0, 1]; the largest channel is 1, and the brightest vertex is on
    // an emitter (the light saturates).
    assert!(colours.iter().flatten().all(|c| c.is_finite() && (0.0..=1.0).contains(c)));
    let top = colours.iter().flatten().fold(0.0f32, |m, &c| m.max(c));
    assert_eq!(top, 1.0);
    let brightest =
        (0..colours.len()).max_by(|&a, &b| luminance(colours[a]).total_cmp(&luminance(colours[b]))).unwrap();
    assert!(scene.emission(patch_of[brightest]).is_positive(), "vertex {brightest} is not on the light");
    // The light is more than 1% of the vertices at res=2, so the exposure is its luminance and
    // every other vertex stays below 1.
    for (v, c) in colours.iter().enumerate() {
        if !scene.emission(patch_of[v]).is_positive() {
            assert!(luminance(*c) < 1.0, "vertex {v} off the light saturates: {c:?}");
        }
    }

    // The materials are unlit, white and single-sided, one per primitive.
    let bytes = std::fs::read(&file.0).unwrap();
    let glb = gltf::binary::Glb::from_slice(&bytes).unwrap();
    assert_eq!(bytes.len() % 4, 0);
    assert_eq!(glb.header.length as usize, bytes.len());
    let json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
    assert!(document.extensions_used().any(|e| e == "KHR_materials_unlit"));
    for primitive in &primitives {
        let material = primitive.material();
        assert!(!material.double_sided());
        assert_eq!(material.pbr_metallic_roughness().base_color_factor(), [1.0; 4]);
        let k = material.index().unwrap();
        assert!(json["materials"][k]["extensions"]["KHR_materials_unlit"].is_object(), "{}", json["materials"]);
    }
    // The exposure is stored, and the light's colour times the exposure is its radiosity,
    // which is at least its emission.
    let exposure = json["asset"]["extras"]["radiosity_exposure"].as_f64().unwrap();
    assert!(exposure > 0.0);
    let light = scene.emission(patch_of[brightest]);
    let g = colours[brightest][1] as f64 * exposure;
    assert!(g >= light.channel(1) * (1.0 - 1e-6), "{g} against emission {light:?}");
}

#[test]
fn bad_export_arguments_fail_cleanly() {
    let e = failure(&["export", "--scene", "cornell:res=2", "--solver", "prr", "--out", "/tmp/never.glb"]);
    assert!(e.contains("unknown solver 'prr'"), "{e}");
    let e = failure(&["export", "--scene", "cornell:res=2", "--solver", "pr", "--out", "/tmp/never.png"]);
    assert!(e.contains("never.png") && e.contains(".glb"), "{e}");
    let e = failure(&["export", "--scene", "cornell:res=2", "--solver", "pr", "--out", "/tmp/never.gltf"]);
    assert!(e.contains("binary glTF only") && e.contains("never.glb"), "{e}");
    let e = failure(&[
        "export",
        "--scene",
        "cornell:res=2",
        "--solver",
        "pr",
        "--until",
        "often",
        "--out",
        "/tmp/never.glb",
    ]);
    assert!(e.contains("'often'"), "{e}");
    let e = failure(&["export", "--scene", "nowhere", "--solver", "reference", "--out", "/tmp/never.glb"]);
    assert!(e.contains("unknown scene 'nowhere'"), "{e}");
}

#[test]
fn an_exported_scene_loads_back_with_the_same_patches() {
    let file = TempFile::new("explain.glb");
    xtask(&["export", "--scene", "cornell:res=2", "--solver", "reference", "--out", file.path()]).success();
    let original = stdout_json(&["scenes", "--explain", "cornell:res=2", "--json"]);
    let back = stdout_json(&["scenes", "--explain", file.path(), "--json"]);
    for key in ["patches", "quads", "triangles", "emitters", "channels"] {
        assert_eq!(back[key], original[key], "{key}");
    }
    for key in ["total_area", "mean_reflectivity", "max_reflectivity"] {
        let (a, b) = (original[key].as_f64().unwrap(), back[key].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-6 * a, "{key}: {b} against {a}");
    }
}
