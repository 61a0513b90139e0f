//! `multi-cubes`: the paper's first scene, a cube full of small cubes (heavy occlusion).
//!
//! Rousselle & Renaud describe it as "a large external cube including 64 smaller cubes that
//! generate a lot of occlusions", 480 patches, mean reflectivity 0.44. Our reconstruction:
//!
//! - **Outer cube** `[0, 4]³`, faces facing inwards, each cut into `divisions × divisions`
//!   patches (4 × 4 = 16 per face, 96 in all by default). Grey walls, reflectivity 0.5.
//! - **Light**: the central 2 × 2 block of ceiling patches (y = 4) is the emitter material,
//!   white emission `light` (default 1), reflectivity 0 (sources reflect little, as the paper
//!   notes in §4). With an odd `divisions`, the central patch alone.
//! - **Small cubes**: a 4 × 4 × 4 lattice, one per unit cell, each of side `cube` (default 0.5)
//!   centred in its cell, faces facing outwards, one patch per face (384 patches).
//!   Colours cycle through red (0.7, 0.3, 0.2), green (0.25, 0.65, 0.3), blue (0.2, 0.35, 0.65)
//!   and yellow (0.6, 0.5, 0.1) with `(ix + iy + iz) mod 4`; each has mean 0.4.
//!
//! Default: 480 patches; area-weighted mean reflectivity (92·0.5 + 96·0.4) / 192 = 0.4396.

use crate::LoadedScene;
use crate::error::GeomError;
use crate::mesh::{BoxFace, Facing, SceneBuilder};
use crate::scenes::camera::CameraPreset;
use crate::spec::{KeyValueParams, ParamDoc};
use radiosity_core::{Material, Scene, Spectrum, Vec3};

/// One line for scene listings.
pub const SUMMARY: &str = "the paper's multi-cubes: 64 small cubes inside a large cube, heavy occlusion";

/// Parameters.
pub const PARAMS: &[ParamDoc] = &[
    ParamDoc { key: "divisions", default: "4", doc: "patches along each edge of an outer face" },
    ParamDoc { key: "cube", default: "0.5", doc: "side of a small cube relative to its lattice cell, in (0, 1)" },
    ParamDoc { key: "light", default: "1", doc: "emission of the ceiling light, grey or r/g/b" },
];

const SIDE: f64 = 4.0;
const PALETTE: [(&str, Spectrum); 4] = [
    ("red", Spectrum::rgb(0.7, 0.3, 0.2)),
    ("green", Spectrum::rgb(0.25, 0.65, 0.3)),
    ("blue", Spectrum::rgb(0.2, 0.35, 0.65)),
    ("yellow", Spectrum::rgb(0.6, 0.5, 0.1)),
];

/// Builds the scene.
pub fn build(name: &str, params: &KeyValueParams) -> Result<LoadedScene, GeomError> {
    let d = params.count("divisions", 4, 1, 200)?;
    let cube = params.real("cube", 0.5, |v| v > 0.0 && v < 1.0, "a relative size in (0, 1)")?;
    let light = params.spectrum("light", Spectrum::grey(1.0), |v| v >= 0.0, "an emission >= 0")?;

    let mut b = SceneBuilder::new(name);
    let walls = b.material(Material::new("walls", Spectrum::grey(0.5), Spectrum::ZERO))?;
    let lamp = b.material(Material::new("light", Spectrum::ZERO, light))?;
    let colours = PALETTE
        .iter()
        .map(|&(n, rho)| b.material(Material::new(n, rho, Spectrum::ZERO)))
        .collect::<Result<Vec<_>, _>>()?;

    let outer = b.object("outer cube");
    let (lo, hi) = (Vec3::ZERO, Vec3::splat(SIDE));
    // The central cells of the ceiling grid are the light: 2 × 2 for even d, 1 for odd d.
    let central = |k: usize| if d % 2 == 0 { k + 1 == d / 2 || k == d / 2 } else { k == d / 2 };
    for face in BoxFace::ALL {
        let c = face.corners(lo, hi);
        let inward = [c[0], c[3], c[2], c[1]];
        for (idx, cell) in crate::mesh::subdivide_quad(inward, d, d).into_iter().enumerate() {
            let (a, bb) = (idx % d, idx / d);
            let material = if face == BoxFace::MaxY && central(a) && central(bb) { lamp } else { walls };
            b.polygon(&cell, material, outer)?;
        }
    }
    let half = cube * 0.5;
    for ix in 0..4 {
        for iy in 0..4 {
            for iz in 0..4 {
                let centre = Vec3::new(ix as f64 + 0.5, iy as f64 + 0.5, iz as f64 + 0.5);
                let object = b.object(format!("cube {ix},{iy},{iz}"));
                let material = colours[(ix + iy + iz) % 4];
                let lo = centre - Vec3::splat(half);
                let hi = centre + Vec3::splat(half);
                b.axis_box([lo, hi], &BoxFace::ALL, Facing::Outward, f64::INFINITY, material, object)?;
            }
        }
    }
    Ok(LoadedScene { scene: b.build()?, warnings: Vec::new() })
}

/// The camera preset: inside the closed cube [0, 4]³, against the front wall (z = 0) where two
/// gaps of the lattice cross (x = y = 1), looking up across the cubes to the ceiling light.
pub fn camera(_scene: &Scene) -> CameraPreset {
    let v = Vec3::new;
    CameraPreset { eye: v(1.0, 1.0, 0.05), target: v(3.0, 3.0, 4.0), fov: 80.0 }
}
