//! Rendering: corner weights that reproduce points of quads and triangles, the camera syntax,
//! the sRGB curve, and a picture of the Cornell box whose walls come out on the published
//! sides, with clean refusals of bad input.

use radiosity_core::{MaterialId, ObjectId, Patch, Real, Vec3};
use radiosity_eval::EvalError;
use radiosity_eval::{Camera, DEFAULT_FOV, Image, MAX_SIDE, RenderParams, corner_weights, render, srgb_byte};
use radiosity_geom::SceneSpec;
use radiosity_geom::Visibility;

fn reproduce(patch: &Patch, s: Real, t: Real) {
    let p = patch.point_at(s, t);
    let w = corner_weights(patch, p);
    let back = patch.vertices().iter().zip(w).fold(Vec3::ZERO, |acc, (&v, w)| acc + v * w);
    assert!((back - p).length() < 1e-9 * patch.area().sqrt(), "{s} {t}: {back} against {p}");
    assert!((w.iter().sum::<Real>() - 1.0).abs() < 1e-12);
    assert!(w.iter().all(|&w| w >= 0.0));
}

#[test]
fn corner_weights_reproduce_points_of_quads_and_triangles() {
    let (m, o) = (MaterialId(0), ObjectId(0));
    let trapezoid = Patch::quad(
        [Vec3::new(0.0, 0.0, 5.0), Vec3::new(4.0, 0.0, 5.0), Vec3::new(3.0, 1.0, 5.5), Vec3::new(0.5, 2.0, 6.0)],
        m,
        o,
    )
    .unwrap();
    let square = Patch::quad([Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y], m, o).unwrap();
    let triangle = Patch::triangle([Vec3::ZERO, Vec3::new(2.0, 0.0, 1.0), Vec3::new(0.0, 3.0, 0.0)], m, o).unwrap();
    for patch in [&trapezoid, &square, &triangle] {
        for i in 0..=6 {
            for j in 0..=6 {
                reproduce(patch, i as Real / 6.0, j as Real / 6.0);
            }
        }
    }
    // On a quad the weights are bilinear in (s, t), so (s, t) itself comes back:
    // s = w1 + w2 and t = w2 + w3.
    let w = corner_weights(&trapezoid, trapezoid.point_at(0.3, 0.7));
    let (s, t) = (w[1] + w[2], w[2] + w[3]);
    assert!((s - 0.3).abs() < 1e-12 && (t - 0.7).abs() < 1e-12, "{s} {t}");
    // A triangle's fourth weight is zero.
    assert_eq!(corner_weights(&triangle, triangle.centroid())[3], 0.0);
}

#[test]
fn camera_syntax() {
    let c: Camera = "1,2,3:4,5,6".parse().unwrap();
    assert_eq!((c.eye(), c.target(), c.fov()), (Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0), DEFAULT_FOV));
    assert_eq!("1,2,3:4,5,6:30".parse::<Camera>().unwrap().fov(), 30.0);
    for bad in ["1,2:4,5,6", "1,2,3", "a,b,c:4,5,6", "1,2,3:4,5,6:200", "1,2,3:1,2,3", "1,2,3:4,5,6:30:1", ""] {
        let e = bad.parse::<Camera>().unwrap_err();
        assert!(matches!(e, EvalError::InvalidCamera { .. }), "{bad}: {e}");
        assert!(e.to_string().starts_with(&format!("invalid camera '{bad}': ")), "{e}");
    }
    let e = "1,2:3,4,5".parse::<Camera>().unwrap_err().to_string();
    assert!(e.contains("x,y,z:tx,ty,tz"), "{e}");
    let e = "1,2,3:3,4,5:180".parse::<Camera>().unwrap_err().to_string();
    assert!(e.contains("field of view"), "{e}");
    // The same rules for a camera given in numbers.
    assert!(Camera::new(Vec3::ZERO, Vec3::X, 0.0).is_err());
    assert!(Camera::new(Vec3::ZERO, Vec3::ZERO, 40.0).is_err());
    assert!(Camera::new(Vec3::splat(Real::NAN), Vec3::X, 40.0).is_err());
    assert_eq!(Camera::new(Vec3::ZERO, Vec3::X, 40.0).unwrap(), "0,0,0:1,0,0:40".parse().unwrap());
}

#[test]
fn srgb_curve_ends() {
    assert_eq!((srgb_byte(0.0), srgb_byte(1.0), srgb_byte(2.0), srgb_byte(-1.0)), (0, 255, 255, 0));
    // Mid grey: 0.2 linear is 0.4845 encoded.
    assert_eq!(srgb_byte(0.2), 124);
    // The linear segment near black: 0.001 × 12.92 × 255 = 3.29.
    assert_eq!(srgb_byte(0.001), 3);
}

/// The Cornell box at res=2 with its BVH, and a radiosity equal to each patch's reflectivity
/// (its colour) plus its emission.
fn cornell() -> (radiosity_core::Scene, Visibility, Vec<[Real; 3]>) {
    let scene = radiosity_geom::load_scene("cornell:res=2").unwrap().scene;
    let visibility = Visibility::new(&scene);
    let rgb = (0..scene.len()).map(|i| (scene.reflectivity(i) + scene.emission(i)).0).collect();
    (scene, visibility, rgb)
}

#[test]
fn the_default_cornell_camera_shows_the_red_wall_left_and_the_green_wall_right() {
    let (scene, visibility, rgb) = cornell();
    let camera = Camera::default_for(&SceneSpec::parse("cornell:res=2").unwrap(), &scene, 4.0 / 3.0);
    let params = RenderParams { width: 96, height: 72, ..RenderParams::new(camera) };
    let image = render(&scene, &visibility, &rgb, &params).unwrap();
    assert_eq!((image.width, image.height, image.pixels.len()), (96, 72, 96 * 72 * 3));
    assert!(image.exposure > 0.0 && image.exposure.is_finite());
    let (w, h) = (96usize, 72usize);
    let redness = |from: usize, to: usize| {
        let (sum, n) = (0..h).flat_map(|y| (from..to).map(move |x| (x, y))).fold((0.0, 0), |(s, n), (x, y)| {
            let p = &image.pixels[3 * (y * w + x)..3 * (y * w + x) + 3];
            (s + Real::from(p[0]) - Real::from(p[1]), n + 1)
        });
        sum / Real::from(n)
    };
    let (left, right) = (redness(0, w / 3), redness(w - w / 3, w));
    assert!(left > right + 20.0 && right < 0.0, "left third red-green {left}, right third {right}");
    // The same picture whatever the thread count: rendering again gives the same bytes.
    assert_eq!(render(&scene, &visibility, &rgb, &params).unwrap(), image);
}

#[test]
fn png_bytes_decode_to_the_image() {
    let (scene, visibility, rgb) = cornell();
    let camera = Camera::default_for(&SceneSpec::parse("cornell:res=2").unwrap(), &scene, 1.0);
    let image = render(&scene, &visibility, &rgb, &RenderParams { width: 40, height: 40, ..RenderParams::new(camera) })
        .unwrap();
    let mut png = Vec::new();
    image.write_png(&mut png).unwrap();
    let decoded = radiosity_eval::Rgb8::decode(&png).unwrap();
    assert_eq!((decoded.width, decoded.height), (40, 40));
    assert_eq!(decoded.pixels, image.pixels);
    // A pixel buffer that does not match the size is refused, not written.
    let short = Image { pixels: vec![0; 10], ..image };
    assert!(matches!(short.write_png(Vec::new()), Err(EvalError::SizeMismatch { .. })));
}

#[test]
fn bad_input_is_refused_before_rendering() {
    let (scene, visibility, rgb) = cornell();
    let camera = Camera::default_for(&SceneSpec::parse("cornell:res=2").unwrap(), &scene, 1.0);
    for (width, height) in [(0, 10), (10, 0), (MAX_SIDE + 1, 10)] {
        let e = render(&scene, &visibility, &rgb, &RenderParams { width, height, ..RenderParams::new(camera) })
            .unwrap_err();
        assert!(matches!(e, EvalError::InvalidParameter { .. }) && e.to_string().contains("8192"), "{e}");
    }
    let params = RenderParams { width: 8, height: 8, ..RenderParams::new(camera) };
    let e = render(&scene, &visibility, &rgb[1..], &params).unwrap_err();
    assert!(matches!(e, EvalError::SizeMismatch { .. }), "{e}");
    let mut nan = rgb.clone();
    nan[7][2] = Real::NAN;
    assert_eq!(render(&scene, &visibility, &nan, &params).unwrap_err(), EvalError::NonFiniteRadiosity { patch: 7 });
    // A BVH over another scene.
    let other = Visibility::new(&radiosity_geom::load_scene("furnace:res=2").unwrap().scene);
    assert!(matches!(render(&scene, &other, &rgb, &params), Err(EvalError::SizeMismatch { .. })));
}

/// `built` (a built-in scene argument) exported to binary glTF and loaded back as a file scene,
/// with its spec and BVH.
fn as_file(built: &str, name: &str) -> (SceneSpec, radiosity_core::Scene, Visibility) {
    let scene = radiosity_geom::load_scene(built).unwrap().scene;
    let rgb: Vec<[Real; 3]> = (0..scene.len()).map(|i| scene.emission(i).0).collect();
    let about = radiosity_eval::ExportInfo { scene: built.into(), solver: "none".into(), ff: "none".into() };
    let dir = std::env::temp_dir().join(format!("radiosity-framing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    radiosity_eval::export_glb(&scene, &rgb, &about).unwrap().save(&path).unwrap();
    let spec = SceneSpec::parse(path.to_str().unwrap()).unwrap();
    let loaded = spec.load().unwrap().scene;
    std::fs::remove_file(&path).unwrap();
    let visibility = Visibility::new(&loaded);
    (spec, loaded, visibility)
}

#[test]
fn a_file_scene_is_framed_from_inside_its_enclosure_and_an_open_box_from_its_open_side() {
    // A closed room as a file: the default eye is inside, and every ray of the picture sees the
    // front of a wall (from outside, every one would see a back or nothing).
    let (spec, scene, visibility) = as_file("furnace:res=3:block=true", "furnace.glb");
    let framing = radiosity_eval::default_view(&spec, &scene, &visibility, 4.0 / 3.0);
    assert!(framing.inside, "{framing:?}");
    assert_eq!(framing.camera.up(), Vec3::Y, "glTF is y-up: {framing:?}");
    assert!(framing.camera.front_share(&visibility, 32, 24) > 0.999, "{framing:?}");
    // The Cornell box, open at its front: no eye is enclosed, and the view from outside is
    // the one through the opening, which sees more fronts than any other side.
    let (spec, scene, visibility) = as_file("cornell:res=2", "cornell.glb");
    let framing = radiosity_eval::default_view(&spec, &scene, &visibility, 4.0 / 3.0);
    assert!(!framing.inside, "{framing:?}");
    let share = framing.camera.front_share(&visibility, 32, 24);
    let side = Camera::new(Vec3::new(3000.0, 300.0, 280.0), Vec3::new(278.0, 274.0, 280.0), DEFAULT_FOV).unwrap();
    assert!(share > 0.3 && share > side.front_share(&visibility, 32, 24) + 0.2, "{share}: {framing:?}");
}

#[test]
fn the_up_axis_of_a_file_follows_its_luminaires() {
    // The furnace's every patch emits, in every direction: the luminaires do not say, and a
    // glTF file is y-up. The Cornell box's light faces down (-y): up is +y.
    let (spec, scene, _) = as_file("furnace:res=2", "furnace-up.glb");
    assert_eq!(radiosity_eval::up_axis(&spec, &scene), (Vec3::Y, "+y, glTF's convention (the luminaires do not say)"));
    let (spec, scene, _) = as_file("cornell:res=2", "cornell-up.glb");
    assert_eq!(radiosity_eval::up_axis(&spec, &scene).0, Vec3::Y);
    // Built-in scenes are y-up.
    let spec = SceneSpec::parse("cornell:res=2").unwrap();
    assert_eq!(radiosity_eval::up_axis(&spec, &scene).0, Vec3::Y);
}
