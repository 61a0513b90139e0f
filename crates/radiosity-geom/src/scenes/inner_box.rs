//! `inner-box`: a closed box with a smaller box inside, the geometry of the stiff and extreme
//! cases of the stability suite.
//!
//! Layout: the unit cube `[0, 1]³`, every face facing inwards and cut into `res × res`
//! patches, as in `furnace`. Inside it, an axis-aligned box facing outwards spans `size` in x
//! and z, centred on `x = z = 0.5`, and `height` in y (the y axis is up), its bottom `gap`
//! above the floor: `[0.5 − size/2, 0.5 + size/2] × [gap, gap + height] × [0.5 − size/2,
//! 0.5 + size/2]`. It is meshed at the walls' target patch size `1/res`, so a tiny box has one
//! patch per face and a thin slab has thin strips for sides. All six faces of the inner box
//! are always kept: at `gap=0` its bottom face lies on the floor, facing it (the two touch
//! over the bottom's whole area and exchange nothing, since each is behind the other's
//! plane), and its side faces meet the floor along their bottom edges. `scale` multiplies
//! every coordinate of the scene meshed at scale 1, so the patches are the same at every
//! scale, each coordinate rounded once.
//!
//! Every patch has reflectivity `rho`; the walls emit `emission` and the inner box's faces
//! `inner-emission`. With `inner-emission` equal to `emission` (the default) the scene is a
//! closed box of one uniform material, so `B = E / (1 − ρ)` (per channel) solves
//! `B = E + ρ F B` exactly whatever the form factors, as long as every row of `F` sums to 1:
//! the furnace identity, here with an occluder that makes shadow rays necessary.
//!
//! Why a separate scene: the extreme cases of the suite are all one parameter away from this
//! layout, and each stresses a different part of the pipeline (area ratios, near-singular
//! kernels, grazing shadow rays, relative tolerances). The suite builds, exactly:
//!
//! - area ratio 1e6: `inner-box:res=2:size=5e-4:height=5e-4` (wall patch 0.25, inner face
//!   2.5e-7; 24 + 6 patches);
//! - a tiny, very bright emitter:
//!   `inner-box:res=2:size=5e-4:height=5e-4:emission=0:inner-emission=1e6` (30 patches, the
//!   6 inner faces the only emitters);
//! - touching along edges: `inner-box:gap=0` (the side faces meet the floor along their bottom
//!   edges; 54 + 24 patches);
//! - nearly touching: `inner-box:gap=1e-6` (54 + 24 patches);
//! - a thin slab: `inner-box:size=0.8:height=1e-4:gap=0.45` (top and bottom 3 × 3, each side
//!   a row of 3 strips 0.27 by 1e-4; 54 + 30 patches);
//! - coordinate scales: `inner-box:scale=1e-4` and `inner-box:scale=1e4` (78 patches each, the
//!   default layout scaled), whose results must equal those at scale 1.

use crate::LoadedScene;
use crate::error::GeomError;
use crate::mesh::{BoxFace, Facing, SceneBuilder};
use crate::spec::{KeyValueParams, ParamDoc};
use radiosity_core::{Material, Spectrum, Vec3};

/// One line for scene listings.
pub const SUMMARY: &str = "closed box with a smaller box inside, for extreme cases; uniform: exact answer E/(1-rho)";

/// Parameters.
pub const PARAMS: &[ParamDoc] = &[
    ParamDoc {
        key: "res",
        default: "3",
        doc: "patches along each edge of a wall; the inner box is cut to the same size",
    },
    ParamDoc { key: "size", default: "0.4", doc: "width and depth of the inner box (x and z), in (0, 1)" },
    ParamDoc { key: "height", default: "0.4", doc: "height of the inner box (y), in (0, 1)" },
    ParamDoc {
        key: "gap",
        default: "0.3",
        doc: "height of the inner box's bottom above the floor, >= 0, gap + height < 1",
    },
    ParamDoc { key: "rho", default: "0.5", doc: "reflectivity of every patch, grey or r/g/b, each in [0, 1)" },
    ParamDoc { key: "emission", default: "1", doc: "emission of the walls, grey or r/g/b, each >= 0" },
    ParamDoc {
        key: "inner-emission",
        default: "1",
        doc: "emission of the inner box's faces, grey or r/g/b, each >= 0; default: same as emission",
    },
    ParamDoc { key: "scale", default: "1", doc: "factor multiplying every coordinate, in [1e-8, 1e8]" },
];

/// Builds the scene.
pub fn build(name: &str, params: &KeyValueParams) -> Result<LoadedScene, GeomError> {
    let res = params.count("res", 3, 1, 1000)?;
    let open_unit = |v: f64| v > 0.0 && v < 1.0;
    let size = params.real("size", 0.4, open_unit, "a width in (0, 1)")?;
    let height = params.real("height", 0.4, open_unit, "a height in (0, 1)")?;
    let gap = params.real("gap", 0.3, |v| v >= 0.0, "a gap >= 0")?;
    if gap + height >= 1.0 {
        // Name the key the user gave; with both given, the gap is what moves the box.
        let gap_given = params.given().any(|(k, _)| k == "gap");
        return Err(if gap_given {
            params.reject("gap", &format!("gap + height < 1 so that the inner box fits (height is {height})"))
        } else {
            params.reject("height", &format!("gap + height < 1 so that the inner box fits (gap is {gap})"))
        });
    }
    let rho = params.spectrum("rho", Spectrum::grey(0.5), |v| (0.0..1.0).contains(&v), "a reflectivity in [0, 1)")?;
    let emission = params.spectrum("emission", Spectrum::grey(1.0), |v| v >= 0.0, "an emission >= 0")?;
    let inner_emission = params.spectrum("inner-emission", emission, |v| v >= 0.0, "an emission >= 0")?;
    let scale = params.real("scale", 1.0, |v| (1e-8..=1e8).contains(&v), "a scale in [1e-8, 1e8]")?;

    let mut b = SceneBuilder::new(name);
    let wall_material = b.material(Material::new("walls", rho, emission))?;
    let inner_material = b.material(Material::new("inner box", rho, inner_emission))?;
    let target = 1.0 / res as f64;
    let walls = b.object("box");
    b.axis_box([Vec3::ZERO, Vec3::ONE], &BoxFace::ALL, Facing::Inward, target, wall_material, walls)?;
    let half = 0.5 * size;
    let lo = Vec3::new(0.5 - half, gap, 0.5 - half);
    let hi = Vec3::new(0.5 + half, gap + height, 0.5 + half);
    let inner = b.object("inner box");
    b.axis_box([lo, hi], &BoxFace::ALL, Facing::Outward, target, inner_material, inner)?;
    // Meshed at scale 1 and scaled afterwards, so that every scale has the same patches
    // (see `scenes::scaled` for what meshing at scale did).
    Ok(LoadedScene { scene: super::scaled(b.build()?, scale)?, warnings: Vec::new() })
}
