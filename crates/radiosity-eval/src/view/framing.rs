//! The default view of a scene: which way is up, and a camera that shows the inside of an
//! enclosure rather than its outer walls.
//!
//! ## Up
//!
//! Every built-in scene is y-up, and so is glTF (glTF 2.0, §3.4: "+Y is up"). MGF states no up
//! axis, and RenderPark's scenes are z-up; so for any file the luminaires decide when they
//! agree: lights hang from ceilings and shine down, so when the area-weighted sum of the
//! emitters' normals points within 30° of a coordinate axis, up is the opposite of that axis
//! ([`up_axis`]). Otherwise glTF files are +y and MGF files +z. The reason is kept, for the
//! caller to print.
//!
//! ## Framing
//!
//! A built-in scene keeps its preset ([`Camera::default_for`]). For a file, a camera inside
//! the scene is tried first ([`default_view`]): from candidate eyes high in the bounding box
//! (near each upper corner, then the upper middle), looking across and down at the opposite
//! lower part, with a 75° field of view. An eye counts as inside an enclosure when every one of
//! 26 probe rays (the axes, the face diagonals and the cube diagonals) hits the front of a
//! patch: it sees walls all round, and is not inside furniture or outside an open scene. The
//! first eye inside wins; when none is, the scene is seen from outside, from the horizontal
//! side whose view shows the most fronts of patches (an open box from its open side), framed
//! to its bounding sphere.

use crate::view::render::{Camera, DEFAULT_FOV};
use radiosity_core::{Real, Scene, Vec3};
use radiosity_geom::spec::FileFormat;
use radiosity_geom::{SceneSource, SceneSpec, Visibility};

/// The field of view of a camera placed inside an enclosure, in degrees.
pub const INSIDE_FOV: Real = 75.0;

/// The default view of a scene ([`default_view`]): the camera and why it was chosen.
#[derive(Clone, Debug, PartialEq)]
pub struct Framing {
    /// The camera.
    pub camera: Camera,
    /// Which way is up, and why (`+z, from the luminaires`).
    pub up: String,
    /// Whether the eye is inside an enclosure (every probe ray hits a front face).
    pub inside: bool,
}

/// The scene's up axis (module doc), and the reason in words.
pub fn up_axis(spec: &SceneSpec, scene: &Scene) -> (Vec3, &'static str) {
    let format = match spec.source() {
        SceneSource::Builtin(_) => return (Vec3::Y, "+y, as every built-in scene"),
        SceneSource::File(format) => format,
    };
    let emitted: Vec3 = scene.emitters().iter().map(|&i| scene.patches()[i].normal() * scene.patches()[i].area()).sum();
    let length = emitted.length();
    if length > 0.0 && length.is_finite() {
        let axis = dominant_axis(-emitted / length);
        if axis.dot(-emitted / length) >= 30f64.to_radians().cos() {
            let reason = match axis.to_array() {
                [x, _, _] if x > 0.5 => "+x, from the luminaires, which shine along -x",
                [x, _, _] if x < -0.5 => "-x, from the luminaires, which shine along +x",
                [_, y, _] if y > 0.5 => "+y, from the luminaires, which shine down along -y",
                [_, y, _] if y < -0.5 => "-y, from the luminaires, which shine along +y",
                [_, _, z] if z > 0.5 => "+z, from the luminaires, which shine down along -z",
                _ => "-z, from the luminaires, which shine along +z",
            };
            return (axis, reason);
        }
    }
    match format {
        FileFormat::Gltf => (Vec3::Y, "+y, glTF's convention (the luminaires do not say)"),
        FileFormat::Mgf => (Vec3::Z, "+z, as RenderPark's MGF scenes (the luminaires do not say)"),
    }
}

/// The signed coordinate axis nearest to the unit vector `v`.
fn dominant_axis(v: Vec3) -> Vec3 {
    let a = v.abs();
    if a.x >= a.y && a.x >= a.z {
        Vec3::X * v.x.signum()
    } else if a.y >= a.z {
        Vec3::Y * v.y.signum()
    } else {
        Vec3::Z * v.z.signum()
    }
}

/// The default camera for the scene `spec` names, loaded as `scene` with its BVH
/// `visibility`, for an image of aspect ratio `aspect` (module doc).
pub fn default_view(spec: &SceneSpec, scene: &Scene, visibility: &Visibility, aspect: Real) -> Framing {
    let (up, why) = up_axis(spec, scene);
    let framing = |camera: Camera, inside| Framing { camera: camera.with_up(up), up: why.to_string(), inside };
    if spec.builtin().is_some() {
        let camera = Camera::default_for(spec, scene, aspect);
        let inside = encloses(visibility, camera.eye());
        return framing(camera, inside);
    }
    let (lo, hi) = scene.bounds();
    let (h1, h2) = horizontal(up);
    // The point of the box at fractions `f1`, `f2` along the horizontal axes and `fu` of the
    // way from floor to ceiling.
    let at = |f1: Real, f2: Real, fu: Real| {
        let along = |axis: Vec3, f: Real| {
            let (a, b) = (axis.abs().dot(lo), axis.abs().dot(hi));
            axis.abs() * if axis.dot(Vec3::ONE) > 0.0 { a + f * (b - a) } else { b - f * (b - a) }
        };
        along(h1, f1) + along(h2, f2) + along(up, fu)
    };
    let candidates = [(0.12, 0.12), (0.88, 0.12), (0.12, 0.88), (0.88, 0.88), (0.5, 0.5)];
    for (f1, f2) in candidates {
        let eye = at(f1, f2, 0.85);
        if encloses(visibility, eye) {
            // Across and down to the opposite lower part; from the middle, towards one side.
            let target = if (f1, f2) == (0.5, 0.5) { at(1.0, 0.5, 0.25) } else { at(1.0 - f1, 1.0 - f2, 0.25) };
            if let Ok(camera) = Camera::new(eye, target, INSIDE_FOV) {
                return framing(camera, true);
            }
        }
    }
    framing(outside(spec, scene, visibility, up, aspect), false)
}

/// Two unit horizontal axes for the up axis `up` (a signed coordinate axis or any direction).
fn horizontal(up: Vec3) -> (Vec3, Vec3) {
    let a = dominant_axis(up);
    if a.x != 0.0 {
        (Vec3::Y, Vec3::Z)
    } else if a.y != 0.0 {
        (Vec3::X, Vec3::Z)
    } else {
        (Vec3::X, Vec3::Y)
    }
}

/// Whether every probe ray from `eye` hits the front of a patch (module doc).
fn encloses(visibility: &Visibility, eye: Vec3) -> bool {
    let mut directions = Vec::with_capacity(26);
    for x in -1..=1 {
        for y in -1..=1 {
            for z in -1..=1 {
                if (x, y, z) != (0, 0, 0) {
                    directions.push(Vec3::new(Real::from(x), Real::from(y), Real::from(z)).normalize());
                }
            }
        }
    }
    directions.iter().all(|&d| visibility.first_hit(eye, d, None).is_some_and(|hit| hit.front))
}

/// The scene seen from outside: from the horizontal side that shows the most fronts of patches
/// (an open box from its open side), 15° above, far enough back for its bounding sphere to fit
/// the narrower of the two fields of view.
fn outside(spec: &SceneSpec, scene: &Scene, visibility: &Visibility, up: Vec3, aspect: Real) -> Camera {
    let (lo, hi) = scene.bounds();
    let (c, radius) = ((lo + hi) * 0.5, (0.5 * (hi - lo).length()).max(Real::MIN_POSITIVE));
    let (h1, h2) = horizontal(up);
    let half_v = (DEFAULT_FOV * 0.5).to_radians();
    let half = half_v.min((half_v.tan() * aspect).atan());
    let distance = radius / half.sin();
    let elevation = 15f64.to_radians();
    let mut best: Option<(Real, Camera)> = None;
    for back in [h2, -h2, h1, -h1] {
        let eye = c + (back * elevation.cos() + up * elevation.sin()) * distance;
        let Ok(camera) = Camera::new(eye, c, DEFAULT_FOV) else { continue };
        let camera = camera.with_up(up);
        let share = camera.front_share(visibility, 16, 12);
        if best.is_none_or(|(b, _)| share > b) {
            best = Some((share, camera));
        }
    }
    best.map_or_else(|| Camera::default_for(spec, scene, aspect), |(_, camera)| camera)
}
