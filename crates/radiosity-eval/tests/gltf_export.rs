//! Binary glTF export: the exposure rule, a solved Cornell box that loads back as the same
//! radiosity system (patches, areas, reflectivities and emissions), the file's materials and
//! primitives, and clean refusals of bad input.

use radiosity_core::{Channels, LinearSystem, Real, Scene};
use radiosity_eval::EvalError;
use radiosity_eval::{ExportInfo, Glb, export_glb, exposure};
use radiosity_eval::{ReferenceParams, ReferenceSolution};
use radiosity_ff::{BackendSpec, FormFactorInput};
use radiosity_geom::{SceneAnalysis, Visibility, load_scene};

#[test]
fn exposure_is_the_99th_percentile_of_luminance() {
    // 200 grey vertices of luminance 1..=200: the 198th is the 99th percentile.
    let values: Vec<[Real; 3]> = (1..=200).map(|i| [i as Real; 3]).collect();
    assert!((exposure(&values) - 198.0).abs() < 1e-9);
    // Mostly black: the brightest sets the exposure; all black: 1.
    let mut values = vec![[0.0; 3]; 200];
    values[7] = [0.0, 2.0, 0.0];
    assert!((exposure(&values) - 1.4304).abs() < 1e-12);
    assert_eq!(exposure(&[[0.0; 3]; 5]), 1.0);
    assert_eq!(exposure(&[]), 1.0);
}

/// `arg` loaded, with its exact radiosity for analytic form factors, as RGB per patch.
fn solved(arg: &str) -> (Scene, Vec<[Real; 3]>) {
    let scene = load_scene(arg).unwrap().scene;
    let visibility = Visibility::new(&scene);
    let analysis = SceneAnalysis::new(&scene, &visibility);
    let spec = BackendSpec::parse("analytic").unwrap();
    let backend =
        spec.build(FormFactorInput { scene: &scene, visibility: visibility.clone(), analysis: &analysis }).unwrap();
    let system = LinearSystem::from_scene(&scene);
    let reference = ReferenceSolution::solve(&system, &backend, ReferenceParams::default()).unwrap();
    let channel = |c: usize| if system.channels() == Channels::Grey { 0 } else { c };
    let rgb = (0..scene.len()).map(|i| std::array::from_fn(|c| reference.get(i, channel(c)))).collect();
    drop(backend);
    (scene, rgb)
}

fn about(scene: &str) -> ExportInfo {
    ExportInfo { scene: scene.into(), solver: "reference".into(), ff: "analytic".into() }
}

/// Writes `glb` to a scratch file and loads it back as a scene argument. Each call has a
/// folder of its own: tests run in parallel, and two of them may load back the same scene.
fn load_back(glb: &Glb, name: &str) -> radiosity_geom::LoadedScene {
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("radiosity-eval-export-{}-{call}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.glb"));
    glb.save(&path).unwrap();
    let loaded = load_scene(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{name} does not load back: {e}"));
    std::fs::remove_dir_all(&dir).unwrap();
    loaded
}

#[test]
fn a_solved_cornell_box_loads_back_as_the_same_system() {
    let (scene, rgb) = solved("cornell:res=2");
    let glb = export_glb(&scene, &rgb, &about("cornell:res=2")).unwrap();
    let loaded = load_back(&glb, "cornell");
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let back = &loaded.scene;

    // The same patches, quads still quads, in the order the export lists.
    assert_eq!(back.len(), scene.len());
    let mut order = glb.patch_order.clone();
    order.sort_unstable();
    assert_eq!(order, (0..scene.len()).collect::<Vec<_>>(), "the patch order is a permutation");
    let (original, reloaded) = (LinearSystem::from_scene(&scene), LinearSystem::from_scene(back));
    assert_eq!(reloaded.channels(), original.channels());
    let k = original.channels().count();
    let diagonal = scene.diagonal();
    for (j, &i) in glb.patch_order.iter().enumerate() {
        let (a, b) = (&scene.patches()[i], &back.patches()[j]);
        assert_eq!(a.shape(), b.shape(), "patch {i}");
        // Coordinates are f32 in glTF: corners move by at most 2^-24 of the largest coordinate.
        let eps = Real::from(f32::EPSILON) * scene.bounds().1.abs().max_element();
        for (p, q) in a.vertices().iter().zip(b.vertices()) {
            assert!((*p - *q).length() <= eps, "patch {i}: {p} against {q}");
        }
        assert!(
            (a.area() - b.area()).abs() <= 8.0 * eps * diagonal,
            "patch {i}: area {} against {}",
            a.area(),
            b.area()
        );
        assert!((a.area() - b.area()).abs() <= 1e-6 * a.area(), "patch {i}: area {} against {}", a.area(), b.area());
        assert!(a.normal().dot(b.normal()) > 1.0 - 1e-12, "patch {i}");
        // Reflectivity and emission are JSON numbers that read back to the same f64.
        assert_eq!(scene.material_of(i).name, back.material_of(j).name);
        for c in 0..k {
            assert_eq!(reloaded.rho(j, c), original.rho(i, c), "patch {i} channel {c}");
            assert_eq!(reloaded.e(j, c), original.e(i, c), "patch {i} channel {c}");
        }
        assert!((reloaded.areas()[j] - original.areas()[i]).abs() <= 1e-6 * original.areas()[i]);
    }
    assert!((back.total_area() - scene.total_area()).abs() <= 1e-6 * scene.total_area());
    assert_eq!(back.emitters().len(), scene.emitters().len());
}

#[test]
fn every_built_in_kind_of_patch_survives_the_round_trip() {
    // The closed furnace with its block (grey, one channel) and the closed Cornell box.
    for arg in ["furnace:res=2:block=true", "cornell:res=1:front=true"] {
        let scene = load_scene(arg).unwrap().scene;
        let rgb: Vec<[Real; 3]> = (0..scene.len()).map(|i| scene.emission(i).0).collect();
        let glb = export_glb(&scene, &rgb, &about(arg)).unwrap();
        let back = load_back(&glb, arg.split(':').next().unwrap()).scene;
        assert_eq!(back.len(), scene.len(), "{arg}");
        assert_eq!(back.channels(), scene.channels(), "{arg}");
        for (j, &i) in glb.patch_order.iter().enumerate() {
            assert_eq!(back.patches()[j].shape(), scene.patches()[i].shape(), "{arg} patch {i}");
            assert_eq!(back.reflectivity(j), scene.reflectivity(i), "{arg} patch {i}");
            assert_eq!(back.emission(j), scene.emission(i), "{arg} patch {i}");
            let (a, b) = (scene.patches()[i].area(), back.patches()[j].area());
            assert!((a - b).abs() <= 1e-6 * a, "{arg} patch {i}: {a} against {b}");
        }
    }
}

#[test]
fn the_file_has_one_unlit_white_material_and_one_primitive_per_scene_material() {
    let (scene, rgb) = solved("cornell:res=2");
    let glb = export_glb(&scene, &rgb, &about("cornell:res=2")).unwrap();
    let file = gltf::Gltf::from_slice(&glb.bytes).unwrap();
    let (document, buffers) = (file.document, [file.blob.expect("the binary chunk")]);
    assert_eq!((document.meshes().count(), document.nodes().count()), (1, 1));
    let mesh = document.meshes().next().unwrap();
    let used: Vec<usize> =
        (0..scene.materials().len()).filter(|&m| scene.patches().iter().any(|p| p.material.0 as usize == m)).collect();
    assert_eq!(mesh.primitives().count(), used.len());
    let json: serde_json::Value =
        serde_json::from_slice(&gltf::binary::Glb::from_slice(&glb.bytes).unwrap().json).unwrap();
    let (mut vertices, mut triangles) = (0, 0);
    for (primitive, &m) in mesh.primitives().zip(&used) {
        let material = primitive.material();
        let k = material.index().unwrap();
        let expected = &scene.materials()[m];
        assert_eq!(material.name(), Some(expected.name.as_str()));
        assert_eq!(material.pbr_metallic_roughness().base_color_factor(), [1.0; 4]);
        assert!(!material.double_sided());
        assert!(json["materials"][k]["extensions"]["KHR_materials_unlit"].is_object());
        let extras = &json["materials"][k]["extras"];
        assert_eq!(extras["radiosity_reflectivity"], serde_json::json!(expected.reflectivity.0));
        assert_eq!(extras["radiosity_emission"], serde_json::json!(expected.emission.0));
        assert!(primitive.extension_value("FB_ngon_encoding").is_some());
        let reader = primitive.reader(|b| Some(&buffers[b.index()][..]));
        let colours: Vec<[f32; 3]> = reader.read_colors(0).unwrap().into_rgb_f32().collect();
        assert!(colours.iter().flatten().all(|c| (0.0..=1.0).contains(c)));
        vertices += colours.len();
        triangles += reader.read_indices().unwrap().into_u32().count() / 3;
    }
    assert_eq!((vertices, triangles), (glb.vertices, glb.triangles));
    let corners: usize = scene.patches().iter().map(|p| p.vertices().len()).sum();
    assert_eq!(glb.vertices, corners);
    assert_eq!(glb.triangles, corners - 2 * scene.len());
    for extension in ["KHR_materials_unlit", "FB_ngon_encoding"] {
        assert!(document.extensions_used().any(|e| e == extension), "{extension}");
    }
    assert_eq!(document.extensions_required().count(), 0);
    // serde_json's default float parser may miss the last bit of the written shortest form.
    let written = json["asset"]["extras"]["radiosity_exposure"].as_f64().unwrap();
    assert!((written - glb.exposure).abs() <= 4.0 * f64::EPSILON * glb.exposure, "{written} vs {}", glb.exposure);
}

#[test]
fn bad_radiosity_is_refused() {
    let scene = load_scene("furnace:res=2").unwrap().scene;
    let mut rgb = vec![[1.0; 3]; scene.len()];
    let e = export_glb(&scene, &rgb[1..], &ExportInfo::default()).unwrap_err();
    assert!(matches!(e, EvalError::SizeMismatch { .. }), "{e}");
    rgb[3][1] = Real::INFINITY;
    assert_eq!(
        export_glb(&scene, &rgb, &ExportInfo::default()).unwrap_err(),
        EvalError::NonFiniteRadiosity { patch: 3 }
    );
}

#[test]
fn a_stiff_closed_box_with_a_block_read_from_gltf_gives_its_exact_answer() {
    // The block furnace at ρ = 0.99, written as glTF and read back: a closed box with an
    // occluder, where an error δ in the mean row sum of F moves the answer by about 99 δ.
    // The exact answer is E / (1 − ρ) = 100 everywhere; the default backend's reference must
    // be within 1% (its visibility budget grows with the scene's stiffness; at the plain budget of a
    // scene with ρ ≤ 0.8 this box misses by more).
    let arg = "furnace:res=2:block=true:rho=0.99";
    let scene = load_scene(arg).unwrap().scene;
    let emission: Vec<[Real; 3]> = (0..scene.len()).map(|i| scene.emission(i).0).collect();
    let glb = export_glb(&scene, &emission, &about(arg)).unwrap();
    let prepared = load_back(&glb, "stiff-furnace").prepare();
    assert_eq!(prepared.scene().len(), scene.len());
    assert!(prepared.analysis.occlusion.value && prepared.analysis.closure.value.is_closed());
    let input = FormFactorInput {
        scene: prepared.scene(),
        visibility: prepared.visibility().unwrap(),
        analysis: &prepared.analysis,
    };
    let backend = BackendSpec::parse("analytic").unwrap().build(input).unwrap();
    let system = LinearSystem::from_scene(prepared.scene());
    let reference = ReferenceSolution::solve(&system, &backend, ReferenceParams::default()).unwrap();
    for i in 0..system.len() {
        let b = reference.get(i, 0);
        assert!((b / 100.0 - 1.0).abs() < 1e-2, "patch {i}: {b}, not within 1% of 100");
    }
}
