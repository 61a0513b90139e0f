//! Tests: glTF input. Hand-made fixtures in `test_data/` check the mapping (transforms,
//! winding, materials, primitive modes, subdivision) against coordinates worked out by hand,
//! and one fixture per bad input checks the error says what is wrong. The real Cornell box
//! export, a file written by someone else, is tested in `third_party_scenes.rs`.

use radiosity_core::{Patch, PatchShape, Real, Spectrum, Vec3};
use radiosity_geom::gltf_input::{self, PARAMS};
use radiosity_geom::{GeomError, KeyValueParams, LoadedScene};
use std::path::Path;

use crate::{fixture, load, load_err};

fn close(a: Vec3, b: Vec3, tol: Real) -> bool {
    (a - b).length() <= tol
}

/// Whether the patch is the triangle `expected`, up to a cyclic shift of its vertices (same
/// winding).
fn is_triangle(patch: &Patch, expected: [Vec3; 3]) -> bool {
    let v = patch.vertices();
    v.len() == 3 && (0..3).any(|s| (0..3).all(|i| close(v[(i + s) % 3], expected[i], 1e-12)))
}

fn v(x: Real, y: Real, z: Real) -> Vec3 {
    Vec3::new(x, y, z)
}

/// The patches of the object called `name`.
fn object_patches<'a>(loaded: &'a LoadedScene, name: &str) -> Vec<&'a Patch> {
    let scene = &loaded.scene;
    let id = scene.objects().iter().position(|o| o == name).unwrap_or_else(|| panic!("no object {name}"));
    scene.patches().iter().filter(|p| p.object.0 as usize == id).collect()
}

/// The unit quad of `quad.gltf`: two triangles, front side +z.
fn check_unit_quad(loaded: &LoadedScene) {
    let scene = &loaded.scene;
    assert_eq!(scene.len(), 2);
    let expected = [[v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.)], [v(0., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)]];
    for (patch, tri) in scene.patches().iter().zip(expected) {
        assert!(is_triangle(patch, tri), "{:?} is not {tri:?}", patch.vertices());
        assert!(close(patch.normal(), Vec3::Z, 1e-15));
    }
    assert!((scene.total_area() - 1.0).abs() < 1e-15);
    assert!(scene.emitters().is_empty());
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
}

#[test]
fn indexed_quad_is_two_patches_facing_its_counter_clockwise_side() {
    let loaded = load(&fixture("quad.gltf"));
    check_unit_quad(&loaded);
    assert_eq!(loaded.scene.objects(), ["quad"]);
    assert_eq!(loaded.scene.materials().len(), 1);
    assert_eq!(loaded.scene.materials()[0].name, "grey");
    assert_eq!(loaded.scene.materials()[0].reflectivity, Spectrum::grey(0.5));
}

#[test]
fn unindexed_quad_gives_the_same_triangles_and_its_base_colour() {
    let loaded = load(&fixture("quad_unindexed.gltf"));
    check_unit_quad(&loaded);
    // The node has no name, so the object takes the mesh's.
    assert_eq!(loaded.scene.objects(), ["unindexed"]);
    assert_eq!(loaded.scene.materials()[0].reflectivity, Spectrum::rgb(0.25, 0.5, 0.75));
    assert_eq!(loaded.scene.materials()[0].emission, Spectrum::ZERO);
}

#[test]
fn position_bounds_may_be_missing() {
    check_unit_quad(&load(&fixture("no_minmax.gltf")));
}

#[test]
fn node_transforms_compose_through_the_hierarchy_of_the_default_scene_only() {
    let loaded = load(&fixture("hierarchy.gltf"));
    // Scene 1's node "elsewhere" is not loaded.
    assert_eq!(loaded.scene.len(), 3);
    assert_eq!(loaded.scene.objects(), ["child", "tri", "node 3"]);
    // Triangle a = (1,0,0), b = (0,1,0), c = (0,0,0). "child": rotate 90° about z
    // ((x,y,z) -> (-y,x,z)), add (0,0,1); then its parent: scale 2, add (1,2,3).
    // a -> (0,1,1) -> (1,4,5); b -> (-1,0,1) -> (-1,2,5); c -> (0,0,1) -> (1,2,5).
    let child = object_patches(&loaded, "child");
    assert!(is_triangle(child[0], [v(1., 4., 5.), v(-1., 2., 5.), v(1., 2., 5.)]), "{:?}", child[0].vertices());
    assert!((child[0].area() - 2.0).abs() < 1e-12);
    // Node 2: column-major matrix scaling by (1,2,3) then translating by (10,0,0).
    let matrix = object_patches(&loaded, "tri");
    assert!(is_triangle(matrix[0], [v(11., 0., 0.), v(10., 2., 0.), v(10., 0., 0.)]), "{:?}", matrix[0].vertices());
    assert!((matrix[0].area() - 1.0).abs() < 1e-12);
    // Node 3: neither node nor mesh has a name; translated by (0,0,-5).
    let plain = object_patches(&loaded, "node 3");
    assert!(is_triangle(plain[0], [v(1., 0., -5.), v(0., 1., -5.), v(0., 0., -5.)]), "{:?}", plain[0].vertices());
    for p in loaded.scene.patches() {
        assert!(close(p.normal(), Vec3::Z, 1e-12), "{:?}", p.normal());
    }
}

#[test]
fn file_without_scenes_loads_its_root_nodes_once() {
    let loaded = load(&fixture("no_scene.gltf"));
    assert_eq!(loaded.scene.len(), 2);
    assert_eq!(loaded.scene.objects(), ["leaf"]);
    for p in loaded.scene.patches() {
        assert!(p.vertices().iter().all(|q| q.z == 5.0), "{:?}", p.vertices());
    }
}

#[test]
fn mirroring_transforms_flip_the_winding_so_fronts_stay_on_the_same_side() {
    let loaded = load(&fixture("mirror.gltf"));
    assert_eq!(loaded.scene.len(), 6);
    // The mesh is the unit quad in z = 1, facing +z, away from the origin.
    for (object, z, normal) in [("plain", 1.0, Vec3::Z), ("mirrored", -1.0, -Vec3::Z), ("turned", 1.0, Vec3::Z)] {
        let patches = object_patches(&loaded, object);
        assert_eq!(patches.len(), 2);
        let area: Real = patches.iter().map(|p| p.area()).sum();
        assert!((area - 1.0).abs() < 1e-15, "{object}");
        for p in patches {
            assert!(p.vertices().iter().all(|q| q.z == z), "{object}: {:?}", p.vertices());
            assert!(close(p.normal(), normal, 1e-15), "{object}: normal {:?}", p.normal());
        }
    }
    // The half turn maps x to -x and y to -y.
    for p in object_patches(&loaded, "turned") {
        assert!(p.vertices().iter().all(|q| (-1.0..=0.0).contains(&q.x) && (-1.0..=0.0).contains(&q.y)));
    }
}

/// `emissive.gltf` and `emissive.glb`: three quads in z = 0, 1, 2 with materials lamp, glow,
/// lamp; "unused" is never referenced.
fn check_emissive(loaded: &LoadedScene) {
    let scene = &loaded.scene;
    assert_eq!(scene.len(), 6);
    let names: Vec<&str> = scene.materials().iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["lamp", "glow"]);
    // emissiveFactor (1, 0.5, 0.25) times emissiveStrength 4.
    assert_eq!(scene.materials()[0].emission, Spectrum::rgb(4.0, 2.0, 1.0));
    assert_eq!(scene.materials()[0].reflectivity, Spectrum::grey(0.5));
    // No strength extension: the factor as it is.
    assert_eq!(scene.materials()[1].emission, Spectrum::grey(0.5));
    assert_eq!(scene.materials()[1].reflectivity, Spectrum::grey(0.25));
    assert_eq!(scene.emitters().len(), 6);
    for (i, p) in scene.patches().iter().enumerate() {
        let expected = if (p.centroid().z - 1.0).abs() < 1e-12 { "glow" } else { "lamp" };
        assert_eq!(scene.material_of(i).name, expected, "patch {i} at {:?}", p.centroid());
    }
}

#[test]
fn emission_is_the_emissive_factor_times_the_emissive_strength() {
    check_emissive(&load(&fixture("emissive.gltf")));
}

#[test]
fn binary_gltf_loads_like_text_gltf() {
    check_emissive(&load(&fixture("emissive.glb")));
    let direct = gltf_input::load(Path::new(&fixture("emissive.glb")), &KeyValueParams::default()).unwrap();
    check_emissive(&direct);
}

#[test]
fn triangle_strips_and_fans_are_converted_with_their_winding() {
    let loaded = load(&fixture("strip_fan.gltf"));
    assert_eq!(loaded.scene.len(), 4);
    for z in [0.0, 1.0] {
        let level: Vec<&Patch> = loaded.scene.patches().iter().filter(|p| (p.centroid().z - z).abs() < 1e-12).collect();
        assert_eq!(level.len(), 2, "z = {z}");
        let area: Real = level.iter().map(|p| p.area()).sum();
        assert!((area - 1.0).abs() < 1e-15, "z = {z}: area {area}");
        assert!(level.iter().all(|p| close(p.normal(), Vec3::Z, 1e-15)));
    }
}

#[test]
fn degenerate_triangles_are_dropped_with_one_warning() {
    let loaded = load(&fixture("degenerate.gltf"));
    check_unit_quad(&LoadedScene { scene: loaded.scene.clone(), warnings: Vec::new() });
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(loaded.warnings[0].contains("dropped 2 degenerate triangles"), "{}", loaded.warnings[0]);
}

#[test]
fn base_colour_textures_are_ignored_with_one_warning_counting_the_materials() {
    // The image file does not exist: it must not be read.
    let loaded = load(&fixture("textured.gltf"));
    assert_eq!(loaded.scene.len(), 6);
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    // "moss" is textured but unused, so 2 materials of the 3 used, not 3 of 4.
    assert!(loaded.warnings[0].contains("2 materials"), "{}", loaded.warnings[0]);
    assert!(loaded.warnings[0].contains("texture"), "{}", loaded.warnings[0]);
    assert_eq!(loaded.scene.materials()[0].reflectivity, Spectrum::rgb(0.5, 0.25, 0.25));
}

#[test]
fn size_cuts_triangles_relative_to_the_bounding_box_diagonal() {
    // Diagonal √2, so size=0.25 asks for edges ≤ √2/4: each triangle's longest edge is √2,
    // so it is cut 4-fold into 16 triangles.
    let loaded = load(&format!("{}:size=0.25", fixture("quad.gltf")));
    assert_eq!(loaded.scene.len(), 32);
    assert!((loaded.scene.total_area() - 1.0).abs() < 1e-12);
    let target = 0.25 * 2.0_f64.sqrt();
    for p in loaded.scene.patches() {
        assert!(close(p.normal(), Vec3::Z, 1e-12));
        let vs = p.vertices();
        let longest = (0..3).map(|i| (vs[(i + 1) % 3] - vs[i]).length()).fold(0.0, Real::max);
        assert!(longest <= target * (1.0 + 1e-12), "edge {longest} > {target}");
    }
    // size=0 is the default: one patch per triangle.
    assert_eq!(load(&format!("{}:size=0", fixture("quad.gltf"))).scene.len(), 2);
}

#[test]
fn size_must_be_a_finite_non_negative_number() {
    for bad in ["-0.1", "abc", "nan", "inf"] {
        let (e, message) = load_err(&format!("{}:size={bad}", fixture("quad.gltf")));
        assert!(matches!(e, GeomError::BadParameter { .. }), "size={bad}: {message}");
        assert!(message.contains("size"), "{message}");
    }
}

#[test]
fn unknown_parameters_are_errors_listing_the_valid_keys() {
    assert!(PARAMS.iter().any(|p| p.key == "size"));
    let (e, message) = load_err(&format!("{}:foo=1", fixture("quad.gltf")));
    assert!(matches!(e, GeomError::UnknownParameter { .. }), "{message}");
    assert!(message.contains("'foo'") && message.contains("size"), "{message}");
}

#[test]
fn a_missing_file_is_an_io_error() {
    let (e, message) = load_err(&fixture("no-such-file.gltf"));
    assert!(matches!(e, GeomError::Io { .. }), "{message}");
    assert!(message.contains("no-such-file.gltf"), "{message}");
}

/// Loads a bad fixture and checks the error is a `Gltf` error whose message contains every
/// one of `needles`.
fn check_gltf_error(name: &str, needles: &[&str]) {
    let (e, message) = load_err(&fixture(name));
    assert!(matches!(e, GeomError::Gltf { .. }), "{name}: {message}");
    assert!(message.contains(name), "{message}");
    for needle in needles {
        assert!(message.contains(needle), "{name}: '{needle}' not in: {message}");
    }
}

#[test]
fn garbage_and_truncated_files_are_clear_errors() {
    check_gltf_error("garbage.gltf", &["not glTF JSON"]);
    check_gltf_error("truncated.gltf", &["truncated"]);
    check_gltf_error("truncated.glb", &["truncated"]);
    check_gltf_error("short_buffer.gltf", &["buffer 0 is truncated", "76 bytes"]);
}

#[test]
fn unsupported_required_extensions_are_named() {
    check_gltf_error("required_ext.gltf", &["requires the extension KHR_draco_mesh_compression"]);
}

#[test]
fn reflectivity_of_one_is_an_error_naming_the_material_and_file() {
    let (e, message) = load_err(&fixture("white.gltf"));
    assert!(matches!(e, GeomError::Core { .. }), "{message}");
    assert!(message.contains("white.gltf") && message.contains("'snow'"), "{message}");
    assert!(message.contains("reflectivity 1"), "{message}");
}

#[test]
fn primitives_without_material_get_the_white_default_material_which_is_refused() {
    let (e, message) = load_err(&fixture("no_material.gltf"));
    assert!(matches!(e, GeomError::Core { .. }), "{message}");
    assert!(message.contains("no_material.gltf"), "{message}");
    assert!(message.contains("mesh 'bare' primitive 0 has no material"), "{message}");
    assert!(message.contains("'default material'"), "{message}");
}

#[test]
fn bad_geometry_is_an_error_naming_the_mesh() {
    check_gltf_error("nan.gltf", &["mesh 'broken'", "NaN or infinite", "vertex 2"]);
    check_gltf_error("no_position.gltf", &["mesh 'normals only'", "no POSITION"]);
    check_gltf_error("lines.gltf", &["mesh 'wire'", "LINES"]);
    check_gltf_error("bad_index.gltf", &["mesh 'holey'", "vertex 7", "only 4"]);
    check_gltf_error("cycle.gltf", &["cycle"]);
}

#[test]
fn a_node_reached_twice_is_an_error_not_a_second_instance() {
    // `leaf` is a child of both `left` and `right`: glTF nodes must form disjoint trees.
    check_gltf_error("shared_child.gltf", &["node 'leaf'", "reached twice", "disjoint trees"]);
}

/// `quad.gltf` with its nodes replaced by `nodes`, as JSON text.
fn quad_with_nodes(nodes: serde_json::Value) -> Vec<u8> {
    let mut json: serde_json::Value = serde_json::from_slice(&std::fs::read(fixture("quad.gltf")).unwrap()).unwrap();
    json["nodes"] = nodes;
    serde_json::to_vec(&json).unwrap()
}

#[test]
fn a_node_shared_at_every_level_is_refused_at_once_rather_than_visited_exponentially() {
    // Node i lists node i + 1 twice, 64 levels deep: walked as a tree, the quad at the bottom
    // would be instanced 2^64 times. The walk is depth-first, so the quad is the first node
    // met twice.
    let mut nodes: Vec<serde_json::Value> = (1..=64).map(|i| serde_json::json!({ "children": [i, i] })).collect();
    nodes.push(serde_json::json!({ "name": "quad", "mesh": 0 }));
    let bytes = quad_with_nodes(nodes.into());
    let e = gltf_input::load_slice(&bytes, Path::new("doubling.gltf"), &KeyValueParams::default()).unwrap_err();
    let message = e.to_string();
    assert!(matches!(e, GeomError::Gltf { .. }), "{message}");
    assert!(message.contains("doubling.gltf") && message.contains("node 'quad' is reached twice"), "{message}");
}

#[test]
fn a_deep_node_hierarchy_loads_without_overflowing_the_stack() {
    // A chain of 100 000 nodes, each the only child of the one before, with the quad at the
    // bottom; the test thread's stack is far smaller than a recursive walk would need.
    const DEPTH: usize = 100_000;
    let mut nodes: Vec<serde_json::Value> = (1..=DEPTH).map(|i| serde_json::json!({ "children": [i] })).collect();
    nodes.push(serde_json::json!({ "name": "quad", "mesh": 0 }));
    let bytes = quad_with_nodes(nodes.into());
    let loaded = gltf_input::load_slice(&bytes, Path::new("deep.gltf"), &KeyValueParams::default()).unwrap();
    check_unit_quad(&loaded);
}

#[test]
fn bytes_in_memory_load_like_the_file_they_came_from() {
    for name in ["quad.gltf", "emissive.glb"] {
        let path = fixture(name);
        let params = KeyValueParams::parse("test", ["size=0.3"], PARAMS).unwrap();
        let from_file = gltf_input::load(Path::new(&path), &params).unwrap();
        let from_memory = gltf_input::load_slice(&std::fs::read(&path).unwrap(), Path::new(&path), &params).unwrap();
        assert_eq!(from_memory.scene.name(), from_file.scene.name());
        assert_eq!(from_memory.scene.len(), from_file.scene.len());
        for (a, b) in from_memory.scene.patches().iter().zip(from_file.scene.patches()) {
            assert_eq!(a.vertices(), b.vertices());
        }
        assert_eq!(from_memory.warnings, from_file.warnings);
    }
}

#[test]
fn bytes_in_memory_cannot_refer_to_external_buffers() {
    let text = std::fs::read_to_string(fixture("quad.gltf")).unwrap();
    let start = text.find("data:application").unwrap();
    let end = start + text[start..].find('"').unwrap();
    let external = format!("{}quad.bin{}", &text[..start], &text[end..]);
    let e =
        gltf_input::load_slice(external.as_bytes(), Path::new("memory.gltf"), &KeyValueParams::default()).unwrap_err();
    let message = e.to_string();
    assert!(matches!(e, GeomError::Gltf { .. }), "{message}");
    assert!(message.contains("memory.gltf") && message.contains("buffer 0 is stored in 'quad.bin'"), "{message}");
    assert!(message.contains("loaded from memory"), "{message}");
}

#[test]
fn accessors_without_storage_cannot_declare_billions_of_elements() {
    // Zeros except for one sparse element: the count is not bounded by the file, and two
    // billion positions would be a 48 GB allocation.
    let text = r#"{
      "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
      "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
      "buffers": [{"byteLength": 16, "uri": "data:application/octet-stream;base64,AAAAAAAAgD8AAIA/AACAPw=="}],
      "bufferViews": [{"buffer": 0, "byteLength": 4}, {"buffer": 0, "byteOffset": 4, "byteLength": 12}],
      "accessors": [{"componentType": 5126, "type": "VEC3", "count": 2000000000,
                     "min": [0, 0, 0], "max": [1, 1, 1],
                     "sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5125},
                                "values": {"bufferView": 1}}}]
    }"#;
    let e = gltf_input::load_slice(text.as_bytes(), Path::new("huge.gltf"), &KeyValueParams::default()).unwrap_err();
    let message = e.to_string();
    assert!(message.contains("huge.gltf") && message.contains("no buffer view"), "{message}");
    assert!(message.contains("2000000000 elements"), "{message}");
}

#[test]
fn scenes_without_usable_triangles_are_empty_file_errors() {
    for (name, why) in [("empty_scene.gltf", "no node of its scene has a mesh"), ("all_degenerate.gltf", "degenerate")]
    {
        let (e, message) = load_err(&fixture(name));
        assert!(matches!(e, GeomError::EmptyFile { .. }), "{name}: {message}");
        assert!(message.contains(name) && message.contains(why), "{message}");
    }
}

/// Loads `bytes` written to a scratch file named `name`, returning whether it loaded, and
/// failing the test (with `what`) if the loader panicked.
fn load_bytes(dir: &Path, name: &str, bytes: &[u8], what: &str) -> bool {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let result = std::panic::catch_unwind(|| gltf_input::load(&path, &KeyValueParams::default()).is_ok());
    result.unwrap_or_else(|_| panic!("the loader panicked on {what}"))
}

#[test]
fn damaged_files_give_errors_not_panics() {
    let dir = std::env::temp_dir().join(format!("radiosity-geom-gltf-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Truncations of a binary file, as cut (the header's length is then too long) and with
    // the header's length patched to match, so that the chunk lengths are too long instead.
    let glb = std::fs::read(fixture("emissive.glb")).unwrap();
    for len in (0..glb.len()).filter(|&len| len < 64 || len % 16 == 0) {
        let mut cut = glb[..len].to_vec();
        assert!(!load_bytes(&dir, "cut.glb", &cut, &format!("emissive.glb cut to {len} bytes")));
        if len >= 12 {
            cut[8..12].copy_from_slice(&(len as u32).to_le_bytes());
            assert!(!load_bytes(&dir, "cut.glb", &cut, &format!("emissive.glb cut to {len} bytes, length patched")));
        }
    }
    // Every digit of a text file (indices, counts, offsets, strides, base64 data, fan
    // indices, material extras) set to 9 and to 0: out-of-range references and lengths must
    // be caught before reading.
    for name in ["emissive.gltf", "ngon_extras.gltf"] {
        let mut loaded = 0;
        let text = std::fs::read(fixture(name)).unwrap();
        for i in (0..text.len()).filter(|&i| text[i].is_ascii_digit()) {
            for digit in [b'9', b'0'] {
                let mut damaged = text.clone();
                damaged[i] = digit;
                loaded += usize::from(load_bytes(
                    &dir,
                    "damaged.gltf",
                    &damaged,
                    &format!("{name} byte {i} set to '{}'", digit as char),
                ));
            }
        }
        // Some changes are harmless (a vertex coordinate in the base64 data, say).
        assert!(loaded > 0, "{name}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The patches of `ngon_extras.gltf`, loaded without refinement.
fn ngon_extras() -> LoadedScene {
    load(&fixture("ngon_extras.gltf"))
}

#[test]
fn ngon_encoded_fans_of_planar_convex_quads_are_one_patch_each() {
    let loaded = ngon_extras();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    // The unit square at z = 0, written as the fan (0, 1, 2), (0, 2, 3): one quad, its corners
    // in fan order.
    let square = object_patches(&loaded, "ngon")[0];
    assert_eq!(square.shape(), PatchShape::Quad);
    assert_eq!(square.vertices(), &[v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)]);
    assert!(close(square.normal(), Vec3::Z, 1e-15) && (square.area() - 1.0).abs() < 1e-15);
    // The same square under a mirroring node (x ↦ 10 − x): still one quad, still facing +z.
    let mirrored = object_patches(&loaded, "mirrored");
    assert_eq!(mirrored.len(), 1);
    assert_eq!(mirrored[0].shape(), PatchShape::Quad);
    assert!(close(mirrored[0].normal(), Vec3::Z, 1e-15) && (mirrored[0].area() - 1.0).abs() < 1e-15);
    assert!(close(mirrored[0].centroid(), v(9.5, 0.5, 0.0), 1e-15));
}

#[test]
fn ngon_quads_from_f32_coordinates_of_a_tilted_plane_are_planar_patches() {
    // The parallelogram o, o + w, o + u + w, o + u with o = (552.8, 300.3, 280.7),
    // u = (−0.32, 0.01, 5.592), w = (0.31, 5.488, 0.02): planar in exact arithmetic, but its
    // f32 corners lie 5.5e-8 diagonals off their mean plane, beyond the 1e-9 a patch allows.
    let loaded = ngon_extras();
    let (o, u, w) = (v(552.8, 300.3, 280.7), v(-0.32, 0.01, 5.592), v(0.31, 5.488, 0.02));
    let wall: Vec<&Patch> = object_patches(&loaded, "ngon").into_iter().filter(|p| p.centroid().x > 500.0).collect();
    assert_eq!(wall.len(), 1);
    assert_eq!(wall[0].shape(), PatchShape::Quad);
    // Rounding to f32 moves each coordinate near 553 by at most 3.05e-5, so each corner by at
    // most 5.3e-5: 1e-5 of the 5.5-long sides, 2e-5 of the area.
    for (corner, exact) in wall[0].vertices().iter().zip([o, o + w, o + u + w, o + u]) {
        assert!(close(*corner, exact, 5.3e-5), "{corner} against {exact}");
    }
    let area = w.cross(u).length();
    assert!((wall[0].area() - area).abs() < 2e-5 * area, "{} against {area}", wall[0].area());
    assert!(close(wall[0].normal(), w.cross(u).normalize(), 2e-5));
}

#[test]
fn ngon_fans_that_are_not_planar_quads_stay_one_patch_per_triangle() {
    let loaded = ngon_extras();
    let patches = object_patches(&loaded, "ngon");
    // The square, the bent quad (a corner 0.1 off the plane) as 2 triangles, the pentagon as 3,
    // and the tilted wall.
    assert_eq!(patches.len(), 1 + 2 + 3 + 1);
    let triangles: Vec<&&Patch> = patches.iter().filter(|p| p.shape() == PatchShape::Triangle).collect();
    assert_eq!(triangles.len(), 5);
    let bent = triangles.iter().filter(|p| p.centroid().x < 3.5).count();
    assert_eq!(bent, 2);
    let pentagon: Real = triangles.iter().filter(|p| p.centroid().x > 3.5).map(|p| p.area()).sum();
    assert!((pentagon - 1.25).abs() < 1e-12, "{pentagon}");
}

#[test]
fn ngon_quads_are_refined_as_quad_grids() {
    // `quad.gltf`'s triangles (0, 1, 2), (0, 2, 3) are the fan of its square. With edges of at
    // most 0.3 diagonals (0.42), each side is cut in 3.
    let mut json: serde_json::Value = serde_json::from_slice(&std::fs::read(fixture("quad.gltf")).unwrap()).unwrap();
    json["meshes"][0]["primitives"][0]["extensions"] = serde_json::json!({ "FB_ngon_encoding": {} });
    let bytes = serde_json::to_vec(&json).unwrap();
    let params = KeyValueParams::parse("test", ["size=0.3"], PARAMS).unwrap();
    let scene = gltf_input::load_slice(&bytes, Path::new("ngon.gltf"), &params).unwrap().scene;
    assert_eq!(scene.len(), 9);
    assert!(scene.patches().iter().all(|p| p.shape() == PatchShape::Quad));
    assert!(scene.patches().iter().all(|p| (p.area() - 1.0 / 9.0).abs() < 1e-15));
}

#[test]
fn radiosity_extras_give_reflectivity_and_emission_before_the_pbr_factors() {
    let loaded = ngon_extras();
    let scene = &loaded.scene;
    let material = |name: &str| scene.materials().iter().find(|m| m.name == name).unwrap().clone();
    // "painted" is white with emissive factor 1: its extras say otherwise, and win.
    let painted = material("painted");
    assert_eq!(painted.reflectivity, Spectrum::rgb(0.5, 0.25, 0.125));
    assert_eq!(painted.emission, Spectrum::rgb(3.0, 2.0, 1.0));
    // "grey" has extras that are not an object: someone else's, ignored.
    let grey = material("grey");
    assert_eq!(grey.reflectivity, Spectrum::grey(0.5));
    assert_eq!(grey.emission, Spectrum::ZERO);
}

#[test]
fn radiosity_extras_that_are_not_three_numbers_are_errors_naming_the_material() {
    for bad in [
        serde_json::json!({ "radiosity_reflectivity": [0.5, 0.5] }),
        serde_json::json!({ "radiosity_reflectivity": "red" }),
        serde_json::json!({ "radiosity_emission": [1, null, 1] }),
    ] {
        let mut json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(fixture("quad.gltf")).unwrap()).unwrap();
        json["materials"][0]["extras"] = bad.clone();
        let bytes = serde_json::to_vec(&json).unwrap();
        let e = gltf_input::load_slice(&bytes, Path::new("extras.gltf"), &KeyValueParams::default()).unwrap_err();
        let message = e.to_string();
        assert!(matches!(e, GeomError::Gltf { .. }), "{message}");
        assert!(message.contains("extras.gltf") && message.contains("material 'grey'"), "{bad}: {message}");
        assert!(message.contains("three numbers"), "{bad}: {message}");
    }
    // Reflectivity 1 from the extras is refused like a white base colour.
    let mut json: serde_json::Value = serde_json::from_slice(&std::fs::read(fixture("quad.gltf")).unwrap()).unwrap();
    json["materials"][0]["extras"] = serde_json::json!({ "radiosity_reflectivity": [1, 0.5, 0.5] });
    let bytes = serde_json::to_vec(&json).unwrap();
    let message =
        gltf_input::load_slice(&bytes, Path::new("extras.gltf"), &KeyValueParams::default()).unwrap_err().to_string();
    assert!(message.contains("'grey'") && message.contains("reflectivity 1"), "{message}");
}
