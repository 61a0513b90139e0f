//! `office`: placeholder until its generator lands.

use crate::LoadedScene;
use crate::error::GeomError;
use crate::spec::{ParamDoc, SceneParams};

/// One line for scene listings.
pub const SUMMARY: &str = "not built yet";

/// Parameters.
pub const PARAMS: &[ParamDoc] = &[];

/// Builds the scene.
pub fn build(name: &str, _params: &SceneParams) -> Result<LoadedScene, GeomError> {
    crate::scenes::furnace::build(name, &SceneParams::default())
}
