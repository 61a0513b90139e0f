//! Geometry for radiosity: meshing, built-in scenes, glTF and MGF input, BVH visibility and scene
//! analysis.
//!
//! The entry point is [`load_scene`], which takes a scene argument as users write it on the
//! command line (`multi-cubes`, `cornell:res=8`, `room.glb:size=0.05`) and returns the patches
//! ready for form factors, with any warnings met on the way. [`Visibility`] answers occlusion
//! queries over the patches; [`SceneAnalysis`] decides what later stages may leave out.
//!
//! ```
//! use radiosity_geom::{SceneAnalysis, Visibility, load_scene};
//!
//! let scene = load_scene("furnace:res=2:block=true").unwrap().scene;
//! assert_eq!(scene.len(), 6 * 4 + 6);
//! let visibility = Visibility::new(&scene);
//! let analysis = SceneAnalysis::new(&scene, &visibility);
//! assert!(analysis.occlusion.value, "the block hides parts of the box");
//! assert!(analysis.closure.value.is_closed());
//! println!("left out: {:?}", analysis.left_out());
//! ```

pub mod analysis;
pub mod coplanar;
pub mod error;
pub mod gltf_input;
pub mod hidden;
pub mod mesh;
pub mod mgf;
pub mod prepared;
pub mod scenes;
pub mod spatial_order;
pub mod spec;
pub mod visibility;

pub use analysis::{Closure, Decision, SceneAnalysis};
pub use coplanar::{CoveredPatch, CutPatch, ResolvedOverlaps};
pub use error::GeomError;
pub use hidden::{HiddenGeometry, HiddenParams, HiddenPatch, HiddenReason, PartialContact};
pub use mesh::SceneBuilder;
pub use prepared::{DecisionReport, GeometryReport, PreparedScene, SceneReport, SetupSeconds};
pub use scenes::camera::CameraPreset;
pub use scenes::{BuiltinScene, builtin_scenes};
pub use spatial_order::spatial_order;
pub use spec::{KeyValueParams, ParamDoc};
pub use visibility::{RayHit, Visibility};

use radiosity_core::Scene;
use spec::{FileFormat, split_file_argument};

/// A scene with the warnings met while building or loading it (dropped triangles, ignored
/// attributes). Warnings are facts a user should see, not errors.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The scene.
    pub scene: Scene,
    /// One sentence per warning.
    pub warnings: Vec<String>,
}

/// Loads a scene from a command-line argument: a built-in name or a file path, each with
/// optional `:key=value` parameters.
pub fn load_scene(arg: &str) -> Result<LoadedScene, GeomError> {
    if let Some((path, format, params)) = split_file_argument(arg) {
        let docs = match format {
            FileFormat::Gltf => gltf_input::PARAMS,
            FileFormat::Mgf => mgf::PARAMS,
        };
        let params = KeyValueParams::parse(&format!("scene '{}'", path.display()), params, docs)?;
        return match format {
            FileFormat::Gltf => gltf_input::load(&path, &params),
            FileFormat::Mgf => mgf::load(&path, &params),
        };
    }
    let mut parts = arg.split(':');
    let name = parts.next().unwrap_or_default();
    let Some(builtin) = builtin_scenes().iter().find(|s| s.name == name) else {
        let valid = builtin_scenes().iter().map(|s| s.name).collect::<Vec<_>>().join(", ");
        return Err(GeomError::UnknownScene { name: arg.to_string(), valid });
    };
    let params = KeyValueParams::parse(&format!("scene '{name}'"), parts.filter(|s| !s.is_empty()), builtin.params)?;
    builtin.build(arg, &params)
}
