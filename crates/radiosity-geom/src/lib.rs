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
pub mod scene_spec;
pub mod scenes;
pub mod spatial_order;
pub mod spec;
pub mod third_party;
pub mod visibility;

pub use analysis::{Closure, Decision, SceneAnalysis};
pub use coplanar::{CoveredPatch, CutPatch, ResolvedOverlaps};
pub use error::GeomError;
pub use hidden::{HiddenGeometry, HiddenParams, HiddenPatch, HiddenReason, PartialContact};
pub use mesh::SceneBuilder;
pub use prepared::{DecisionReport, GeometryReport, PreparedScene, SceneMemory, SceneReport, SetupSeconds};
pub use scene_spec::{SceneSource, SceneSpec};
pub use scenes::camera::CameraPreset;
pub use scenes::{BuiltinScene, builtin_scenes};
pub use spatial_order::spatial_order;
pub use spec::{KeyValueParams, ParamDoc};
pub use third_party::ScenesFolder;
pub use visibility::{BvhBuild, RayHit, Visibility};

use radiosity_core::Scene;

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
/// optional `:key=value` parameters ([`SceneSpec::parse`], then [`SceneSpec::load`]).
pub fn load_scene(arg: &str) -> Result<LoadedScene, GeomError> {
    SceneSpec::parse(arg)?.load()
}
