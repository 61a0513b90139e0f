//! glTF 2.0 input: placeholder until the loader lands.

use crate::LoadedScene;
use crate::error::GeomError;
use crate::spec::{ParamDoc, SceneParams};
use std::path::Path;

/// Parameters a glTF file takes after its path.
pub const PARAMS: &[ParamDoc] = &[];

/// Loads a glTF file.
pub fn load(path: &Path, _params: &SceneParams) -> Result<LoadedScene, GeomError> {
    Err(GeomError::UnsupportedFormat { path: path.to_path_buf(), format: "glTF" })
}
