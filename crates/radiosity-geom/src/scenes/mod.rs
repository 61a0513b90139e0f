//! The built-in scenes, each in its own module with its layout, emitters and colours
//! documented there and the camera preset it is best seen from ([`camera`]), and the registry
//! that finds them by name.
//!
//! All built-in scenes are procedural and deterministic: the same name and parameters give
//! the same patches in the same order (scenes with random layout take a `seed`). The y axis is
//! up in every built-in scene.

pub mod camera;
pub mod cornell;
pub mod furnace;
pub mod inner_box;
pub mod labyrinth;
pub mod multi_cubes;
pub mod office;

use crate::LoadedScene;
use crate::error::GeomError;
use crate::mesh::SceneBuilder;
use crate::scenes::camera::CameraPreset;
use crate::spec::{KeyValueParams, ParamDoc};
use radiosity_core::{Real, Scene, Vec3};

/// A built-in scene: its name, a one-line summary, its parameters, its generator and its
/// camera preset.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinScene {
    /// The name used on the command line.
    pub name: &'static str,
    /// One line saying what the scene is.
    pub summary: &'static str,
    /// The `key=value` parameters it takes.
    pub params: &'static [ParamDoc],
    generator: fn(&str, &KeyValueParams) -> Result<LoadedScene, GeomError>,
    camera: Option<fn(&Scene) -> CameraPreset>,
}

impl BuiltinScene {
    /// Builds the scene; `full_name` (with parameters) becomes the scene's name.
    pub fn build(&self, full_name: &str, params: &KeyValueParams) -> Result<LoadedScene, GeomError> {
        (self.generator)(full_name, params)
    }

    /// Where to see `scene` (this scene, as built) from, when the scene has a preset.
    pub fn camera(&self, scene: &Scene) -> Option<CameraPreset> {
        self.camera.map(|preset| preset(scene))
    }
}

const BUILTIN: &[BuiltinScene] = &[
    BuiltinScene {
        name: "multi-cubes",
        summary: multi_cubes::SUMMARY,
        params: multi_cubes::PARAMS,
        generator: multi_cubes::build,
        camera: Some(multi_cubes::camera),
    },
    BuiltinScene {
        name: "labyrinth",
        summary: labyrinth::SUMMARY,
        params: labyrinth::PARAMS,
        generator: labyrinth::build,
        camera: Some(labyrinth::camera),
    },
    BuiltinScene {
        name: "office",
        summary: office::SUMMARY,
        params: office::PARAMS,
        generator: office::build,
        camera: Some(office::camera),
    },
    BuiltinScene {
        name: "cornell",
        summary: cornell::SUMMARY,
        params: cornell::PARAMS,
        generator: cornell::build,
        camera: Some(cornell::camera),
    },
    BuiltinScene {
        name: "furnace",
        summary: furnace::SUMMARY,
        params: furnace::PARAMS,
        generator: furnace::build,
        camera: Some(furnace::camera),
    },
    BuiltinScene {
        name: "inner-box",
        summary: inner_box::SUMMARY,
        params: inner_box::PARAMS,
        generator: inner_box::build,
        // None: seen as any scene without a preset is.
        camera: None,
    },
];

/// Every built-in scene, in a fixed order.
pub fn builtin_scenes() -> &'static [BuiltinScene] {
    BUILTIN
}

/// `scene` with every vertex multiplied by `scale`, patches, materials and objects unchanged
/// and in order; `scale = 1` returns it as it is.
///
/// Scenes with a `scale` parameter mesh at scale 1 and scale afterwards, so that each
/// coordinate is the unit scene's, rounded once. Meshing at the target scale instead rounds
/// differently at each scale: bilinear subdivision computes a coordinate that all corners of a
/// face share as `x (1 − s) + x s`, which is exactly `x` for some `x` and an ulp off for others.
/// That tilted the wall at `x = 1e-4` of `inner-box:scale=1e-4` by 2e-16 where the wall at
/// `x = 1` stays flat, and a tilt whose sign flips the z component of a normal turns the
/// tangent frame about it by 180°, so every Monte Carlo ray of that wall went elsewhere.
pub(crate) fn scaled(scene: Scene, scale: Real) -> Result<Scene, GeomError> {
    if scale == 1.0 {
        return Ok(scene);
    }
    let mut b = SceneBuilder::new(scene.name());
    for material in scene.materials() {
        b.material(material.clone())?;
    }
    for object in scene.objects() {
        b.object(object.clone());
    }
    for p in scene.patches() {
        let v: Vec<Vec3> = p.vertices().iter().map(|v| *v * scale).collect();
        b.polygon(&v, p.material, p.object)?;
    }
    b.build()
}
