//! `furnace`: a closed box with one uniform material, whose exact radiosity is known.
//!
//! Layout: the unit cube `[0, 1]³`, every face facing inwards and cut into `res × res`
//! patches; with `block=true`, a solid cube `[0.3, 0.7]³` facing outwards sits in the middle,
//! cut to the same patch size. Every patch has reflectivity `rho` and emission `emission`.
//! `scale` multiplies every coordinate of the scene meshed at scale 1, so the same patches
//! appear at every scale: results that depend on the coordinate scale are bugs.
//!
//! Because the box is closed, every row of `F` sums to 1, so the uniform vector
//! `B = E / (1 − ρ)` (per channel) solves `B = E + ρ F B` exactly, with or without the block
//! and whatever the form factors are: the furnace identity. It tests solvers and, through
//! closure, form-factor backends.

use crate::LoadedScene;
use crate::error::GeomError;
use crate::mesh::{BoxFace, Facing, SceneBuilder};
use crate::scenes::camera::CameraPreset;
use crate::spec::{KeyValueParams, ParamDoc};
use radiosity_core::{Material, Scene, Spectrum, Vec3};

/// One line for scene listings.
pub const SUMMARY: &str = "closed box of one material, optional inner block; exact answer E/(1-rho)";

/// Parameters.
pub const PARAMS: &[ParamDoc] = &[
    ParamDoc { key: "res", default: "4", doc: "patches along each edge of a box face" },
    ParamDoc { key: "rho", default: "0.5", doc: "reflectivity of every patch, grey or r/g/b, each in [0, 1)" },
    ParamDoc { key: "emission", default: "1", doc: "emission of every patch, grey or r/g/b, each >= 0" },
    ParamDoc { key: "block", default: "false", doc: "add a solid cube in the middle of the box" },
    ParamDoc { key: "scale", default: "1", doc: "factor multiplying every coordinate, in [1e-8, 1e8]" },
];

/// Builds the scene.
pub fn build(name: &str, params: &KeyValueParams) -> Result<LoadedScene, GeomError> {
    let res = params.count("res", 4, 1, 1000)?;
    let rho = params.spectrum("rho", Spectrum::grey(0.5), |v| (0.0..1.0).contains(&v), "a reflectivity in [0, 1)")?;
    let emission = params.spectrum("emission", Spectrum::grey(1.0), |v| v >= 0.0, "an emission >= 0")?;
    let block = params.flag("block", false)?;
    let scale = params.real("scale", 1.0, |v| (1e-8..=1e8).contains(&v), "a scale in [1e-8, 1e8]")?;

    let mut b = SceneBuilder::new(name);
    let material = b.material(Material::new("furnace", rho, emission))?;
    let target = 1.0 / res as f64;
    let walls = b.object("box");
    b.axis_box([Vec3::ZERO, Vec3::ONE], &BoxFace::ALL, Facing::Inward, target, material, walls)?;
    if block {
        let inner = b.object("block");
        b.axis_box([Vec3::splat(0.3), Vec3::splat(0.7)], &BoxFace::ALL, Facing::Outward, target, material, inner)?;
    }
    Ok(LoadedScene { scene: super::scaled(b.build()?, scale)?, warnings: Vec::new() })
}

/// The camera preset: inside the closed cube (the unit cube times `scale`, from the bounds of
/// `scene`), near a top corner, looking across to the opposite bottom corner (past the inner
/// block, if any).
pub fn camera(scene: &Scene) -> CameraPreset {
    let v = Vec3::new;
    let (lo, hi) = scene.bounds();
    let size = (hi - lo).max_element();
    CameraPreset { eye: lo + size * v(0.08, 0.85, 0.08), target: lo + size * v(0.75, 0.3, 0.75), fov: 75.0 }
}
