//! The built-in scenes, each in its own module with its layout, emitters and colours
//! documented there, and the registry that finds them by name.
//!
//! All built-in scenes are procedural and deterministic: the same name and parameters give
//! the same patches in the same order (scenes with random layout take a `seed`). The y axis is
//! up in every built-in scene.

pub mod cornell;
pub mod furnace;
pub mod labyrinth;
pub mod multi_cubes;
pub mod office;

use crate::LoadedScene;
use crate::error::GeomError;
use crate::spec::{KeyValueParams, ParamDoc};

/// A built-in scene: its name, a one-line summary, its parameters and its generator.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinScene {
    /// The name used on the command line.
    pub name: &'static str,
    /// One line saying what the scene is.
    pub summary: &'static str,
    /// The `key=value` parameters it takes.
    pub params: &'static [ParamDoc],
    generator: fn(&str, &KeyValueParams) -> Result<LoadedScene, GeomError>,
}

impl BuiltinScene {
    /// Builds the scene; `full_name` (with parameters) becomes the scene's name.
    pub fn build(&self, full_name: &str, params: &KeyValueParams) -> Result<LoadedScene, GeomError> {
        (self.generator)(full_name, params)
    }
}

const BUILTIN: &[BuiltinScene] = &[
    BuiltinScene {
        name: "multi-cubes",
        summary: multi_cubes::SUMMARY,
        params: multi_cubes::PARAMS,
        generator: multi_cubes::build,
    },
    BuiltinScene {
        name: "labyrinth",
        summary: labyrinth::SUMMARY,
        params: labyrinth::PARAMS,
        generator: labyrinth::build,
    },
    BuiltinScene { name: "office", summary: office::SUMMARY, params: office::PARAMS, generator: office::build },
    BuiltinScene { name: "cornell", summary: cornell::SUMMARY, params: cornell::PARAMS, generator: cornell::build },
    BuiltinScene { name: "furnace", summary: furnace::SUMMARY, params: furnace::PARAMS, generator: furnace::build },
];

/// Every built-in scene, in a fixed order.
pub fn builtin_scenes() -> &'static [BuiltinScene] {
    BUILTIN
}
