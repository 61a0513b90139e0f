//! `cornell`: the Cornell box as published by the Cornell Program of Computer Graphics.
//!
//! Geometry: the measured coordinates (millimetres, y up) of the "Cornell Box Data" page,
//! <https://www.graphics.cornell.edu/online/box/data.html>: floor, ceiling, back wall, red
//! left wall (x ≈ 556), green right wall (x = 0), the 130 × 105 light, and the short and tall
//! blocks (their five visible faces each). The front is open, as published, unless
//! `front=true` adds a white front wall to close the box.
//!
//! Two facts of the published data we keep rather than "fix":
//! - the walls are not exact rectangles (549.6 to 556.0 in x), and the red wall is not planar
//!   (by 3.2 mm); the mesher splits a non-planar quad into two triangles first;
//! - the light lies in the ceiling plane (both at y = 548.8); the ceiling is cut around it,
//!   so no surface hides behind another.
//!
//! Orientation is not taken from the published vertex order: room surfaces are turned to face
//! the inside of the box, block faces to face out of their block.
//!
//! Colours: the usual RGB reductions of the measured spectra (as in the pbrt and Mitsuba
//! versions of the scene): white (0.725, 0.71, 0.68), red (0.63, 0.065, 0.05), green
//! (0.14, 0.45, 0.091); the light emits (17, 12, 4) and reflects 0.78.
//!
//! `res` is the number of patches along the longest wall edge (559.2 mm); every surface is
//! cut to patches of at most `559.2 / res` mm.

use crate::LoadedScene;
use crate::error::GeomError;
use crate::mesh::SceneBuilder;
use crate::scenes::camera::CameraPreset;
use crate::spec::{KeyValueParams, ParamDoc};
use radiosity_core::{Material, MaterialId, ObjectId, Scene, Spectrum, Vec3};

/// One line for scene listings.
pub const SUMMARY: &str = "the published Cornell box (mm, open front), light in the ceiling, two blocks";

/// Parameters.
pub const PARAMS: &[ParamDoc] = &[
    ParamDoc { key: "res", default: "8", doc: "patches along the longest wall edge" },
    ParamDoc { key: "front", default: "false", doc: "close the box with a white front wall" },
];

type Quad = [[f64; 3]; 4];

const FLOOR: Quad = [[552.8, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 559.2], [549.6, 0.0, 559.2]];
const BACK: Quad = [[549.6, 0.0, 559.2], [0.0, 0.0, 559.2], [0.0, 548.8, 559.2], [556.0, 548.8, 559.2]];
const GREEN_WALL: Quad = [[0.0, 0.0, 559.2], [0.0, 0.0, 0.0], [0.0, 548.8, 0.0], [0.0, 548.8, 559.2]];
const RED_WALL: Quad = [[552.8, 0.0, 0.0], [549.6, 0.0, 559.2], [556.0, 548.8, 559.2], [556.0, 548.8, 0.0]];
const FRONT: Quad = [[552.8, 0.0, 0.0], [556.0, 548.8, 0.0], [0.0, 548.8, 0.0], [0.0, 0.0, 0.0]];
const LIGHT: Quad = [[343.0, 548.8, 227.0], [343.0, 548.8, 332.0], [213.0, 548.8, 332.0], [213.0, 548.8, 227.0]];
/// The ceiling (556.0 × 559.2 at y = 548.8) cut around the light's rectangle.
const CEILING: [Quad; 4] = [
    [[0.0, 548.8, 0.0], [213.0, 548.8, 0.0], [213.0, 548.8, 559.2], [0.0, 548.8, 559.2]],
    [[343.0, 548.8, 0.0], [556.0, 548.8, 0.0], [556.0, 548.8, 559.2], [343.0, 548.8, 559.2]],
    [[213.0, 548.8, 0.0], [343.0, 548.8, 0.0], [343.0, 548.8, 227.0], [213.0, 548.8, 227.0]],
    [[213.0, 548.8, 332.0], [343.0, 548.8, 332.0], [343.0, 548.8, 559.2], [213.0, 548.8, 559.2]],
];
const SHORT_BLOCK: [Quad; 5] = [
    [[130.0, 165.0, 65.0], [82.0, 165.0, 225.0], [240.0, 165.0, 272.0], [290.0, 165.0, 114.0]],
    [[290.0, 0.0, 114.0], [290.0, 165.0, 114.0], [240.0, 165.0, 272.0], [240.0, 0.0, 272.0]],
    [[130.0, 0.0, 65.0], [130.0, 165.0, 65.0], [290.0, 165.0, 114.0], [290.0, 0.0, 114.0]],
    [[82.0, 0.0, 225.0], [82.0, 165.0, 225.0], [130.0, 165.0, 65.0], [130.0, 0.0, 65.0]],
    [[240.0, 0.0, 272.0], [240.0, 165.0, 272.0], [82.0, 165.0, 225.0], [82.0, 0.0, 225.0]],
];
const TALL_BLOCK: [Quad; 5] = [
    [[423.0, 330.0, 247.0], [265.0, 330.0, 296.0], [314.0, 330.0, 456.0], [472.0, 330.0, 406.0]],
    [[423.0, 0.0, 247.0], [423.0, 330.0, 247.0], [472.0, 330.0, 406.0], [472.0, 0.0, 406.0]],
    [[472.0, 0.0, 406.0], [472.0, 330.0, 406.0], [314.0, 330.0, 456.0], [314.0, 0.0, 456.0]],
    [[314.0, 0.0, 456.0], [314.0, 330.0, 456.0], [265.0, 330.0, 296.0], [265.0, 0.0, 296.0]],
    [[265.0, 0.0, 296.0], [265.0, 330.0, 296.0], [423.0, 330.0, 247.0], [423.0, 0.0, 247.0]],
];

/// The longest wall edge, in millimetres.
const LONGEST_EDGE: f64 = 559.2;
/// A point inside the box, which room surfaces face.
const INSIDE: Vec3 = Vec3::new(278.0, 274.4, 279.6);

fn vertices(q: &Quad) -> [Vec3; 4] {
    q.map(Vec3::from_array)
}

/// The quad turned so that its normal points towards `target` (or away, if `towards` is false).
fn oriented(q: &Quad, target: Vec3, towards: bool) -> [Vec3; 4] {
    let v = vertices(q);
    let normal = (v[2] - v[0]).cross(v[3] - v[1]);
    let centre = (v[0] + v[1] + v[2] + v[3]) * 0.25;
    if (normal.dot(target - centre) > 0.0) == towards { v } else { [v[0], v[3], v[2], v[1]] }
}

/// The centre of a block: the mean of its top face's corners, at half its height.
fn block_centre(faces: &[Quad; 5]) -> Vec3 {
    let top = vertices(&faces[0]);
    let c = (top[0] + top[1] + top[2] + top[3]) * 0.25;
    Vec3::new(c.x, c.y * 0.5, c.z)
}

/// Builds the scene.
pub fn build(name: &str, params: &KeyValueParams) -> Result<LoadedScene, GeomError> {
    let res = params.count("res", 8, 1, 1000)?;
    let front = params.flag("front", false)?;
    let target = LONGEST_EDGE / res as f64;

    let mut b = SceneBuilder::new(name);
    let white = b.material(Material::new("white", Spectrum::rgb(0.725, 0.71, 0.68), Spectrum::ZERO))?;
    let red = b.material(Material::new("red", Spectrum::rgb(0.63, 0.065, 0.05), Spectrum::ZERO))?;
    let green = b.material(Material::new("green", Spectrum::rgb(0.14, 0.45, 0.091), Spectrum::ZERO))?;
    let light = b.material(Material::new("light", Spectrum::grey(0.78), Spectrum::rgb(17.0, 12.0, 4.0)))?;

    let room =
        |b: &mut SceneBuilder, name: &str, quads: &[Quad], material: MaterialId| -> Result<ObjectId, GeomError> {
            let object = b.object(name);
            for q in quads {
                b.quad_sized(oriented(q, INSIDE, true), target, material, object)?;
            }
            Ok(object)
        };
    room(&mut b, "floor", &[FLOOR], white)?;
    room(&mut b, "ceiling", &CEILING, white)?;
    room(&mut b, "light", &[LIGHT], light)?;
    room(&mut b, "back wall", &[BACK], white)?;
    room(&mut b, "red wall", &[RED_WALL], red)?;
    room(&mut b, "green wall", &[GREEN_WALL], green)?;
    if front {
        room(&mut b, "front wall", &[FRONT], white)?;
    }
    for (name, faces) in [("short block", &SHORT_BLOCK), ("tall block", &TALL_BLOCK)] {
        let object = b.object(name);
        let centre = block_centre(faces);
        for q in faces {
            b.quad_sized(oriented(q, centre, false), target, white, object)?;
        }
    }
    Ok(LoadedScene { scene: b.build()?, warnings: Vec::new() })
}

/// The camera preset: the published camera (focal length 35 mm, 25 mm film: 39.3°), from in
/// front of the open side at z = 0, red wall (x ≈ 556) on the left. A closed box
/// (`front=true`) is seen from just inside its front wall, high, looking down past the blocks.
pub fn camera(scene: &Scene) -> CameraPreset {
    let v = Vec3::new;
    if scene.objects().iter().any(|o| o == "front wall") {
        CameraPreset { eye: v(278.0, 440.0, 8.0), target: v(278.0, 180.0, 559.2), fov: 72.0 }
    } else {
        CameraPreset { eye: v(278.0, 273.0, -800.0), target: v(278.0, 273.0, 0.0), fov: 39.3 }
    }
}
