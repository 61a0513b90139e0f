//! A scene argument parsed once, at the edge: [`SceneSpec`], where the scene comes from (a
//! built-in scene or a file) and its parameters, every key checked against what that scene
//! takes.
//!
//! Code that needs to know which built-in scene an argument names, or to vary one of its
//! parameters, asks the spec instead of splitting the string again. Parsing reads no file. A
//! relative file path is read from the current directory, or else from the folder of
//! third-party scenes ([`crate::third_party`]).

use crate::error::GeomError;
use crate::scenes::{BuiltinScene, builtin_scenes};
use crate::spec::{FileFormat, KeyValueParams, split_file_argument};
use crate::third_party::ScenesFolder;
use crate::{LoadedScene, gltf_input, mgf};
use std::fmt;
use std::path::Path;
use std::str::FromStr;

/// Where a scene comes from.
#[derive(Clone, Copy, Debug)]
pub enum SceneSource {
    /// A built-in scene.
    Builtin(&'static BuiltinScene),
    /// A file, by its path as written and its format.
    File(FileFormat),
}

/// A parsed scene argument: where the scene comes from and its parameters, every key checked
/// against what that scene takes. Parsing reads no file; [`SceneSpec::load`] does.
#[derive(Clone, Debug)]
pub struct SceneSpec {
    written: String,
    head: String,
    source: SceneSource,
    params: KeyValueParams,
}

impl SceneSpec {
    /// Parses `NAME[:key=value…]` (a built-in scene) or `PATH[:key=value…]` (a `.gltf`, `.glb`
    /// or `.mgf` file).
    pub fn parse(arg: &str) -> Result<SceneSpec, GeomError> {
        if let Some((path, format, items)) = split_file_argument(arg) {
            let docs = match format {
                FileFormat::Gltf => gltf_input::PARAMS,
                FileFormat::Mgf => mgf::PARAMS,
            };
            let params = KeyValueParams::parse(&format!("scene '{}'", path.display()), items, docs)?;
            let head = path.display().to_string();
            return Ok(SceneSpec { written: arg.to_string(), head, source: SceneSource::File(format), params });
        }
        let mut parts = arg.split(':');
        let name = parts.next().unwrap_or_default();
        let Some(builtin) = builtin_scenes().iter().find(|s| s.name == name) else {
            let valid = builtin_scenes().iter().map(|s| s.name).collect::<Vec<_>>().join(", ");
            let suggestion = radiosity_core::suggest::did_you_mean(name, builtin_scenes().iter().map(|s| s.name));
            return Err(GeomError::UnknownScene { name: arg.to_string(), valid, suggestion });
        };
        let params =
            KeyValueParams::parse(&format!("scene '{name}'"), parts.filter(|s| !s.is_empty()), builtin.params)?;
        Ok(SceneSpec {
            written: arg.to_string(),
            head: name.to_string(),
            source: SceneSource::Builtin(builtin),
            params,
        })
    }

    /// Where the scene comes from.
    pub fn source(&self) -> SceneSource {
        self.source
    }

    /// The built-in scene it names, if it names one.
    pub fn builtin(&self) -> Option<&'static BuiltinScene> {
        match self.source {
            SceneSource::Builtin(b) => Some(b),
            SceneSource::File(_) => None,
        }
    }

    /// The file it names, as written (relative paths not yet resolved), if it names one.
    pub fn file(&self) -> Option<&Path> {
        matches!(self.source, SceneSource::File(_)).then(|| Path::new(&self.head))
    }

    /// The built-in scene's name, or the file's path as written.
    pub fn head(&self) -> &str {
        &self.head
    }

    /// Its parameters.
    pub fn params(&self) -> &KeyValueParams {
        &self.params
    }

    /// The same scene with `key` set to `value`: the parameter replaced where it was given,
    /// appended otherwise. The key is checked as in [`SceneSpec::parse`].
    pub fn with_param(&self, key: &str, value: &str) -> Result<SceneSpec, GeomError> {
        let mut items: Vec<String> = Vec::with_capacity(self.params.given().count() + 1);
        let mut replaced = false;
        for (k, v) in self.params.given() {
            items.push(if k == key {
                replaced = true;
                format!("{key}={value}")
            } else {
                format!("{k}={v}")
            });
        }
        if !replaced {
            items.push(format!("{key}={value}"));
        }
        SceneSpec::parse(&std::iter::once(self.head.clone()).chain(items).collect::<Vec<_>>().join(":"))
    }

    /// Builds or loads the scene.
    pub fn load(&self) -> Result<LoadedScene, GeomError> {
        match self.source {
            SceneSource::Builtin(builtin) => builtin.build(&self.written, &self.params),
            SceneSource::File(format) => {
                let written = Path::new(&self.head);
                let folder = ScenesFolder::from_env();
                let path = folder.resolve(written);
                if written.is_relative() && !path.exists() {
                    let suggestion = folder.nearest(written).map(|p| format!("; did you mean {}?", p.display()));
                    return Err(GeomError::SceneFileNotFound {
                        path: path.clone(),
                        folder: folder.describe(),
                        suggestion: suggestion.unwrap_or_default(),
                    });
                }
                match format {
                    FileFormat::Gltf => gltf_input::load(&path, &self.params),
                    FileFormat::Mgf => mgf::load(&path, &self.params),
                }
            }
        }
    }
}

impl fmt::Display for SceneSpec {
    /// The argument as written.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.written)
    }
}

impl FromStr for SceneSpec {
    type Err = GeomError;

    fn from_str(arg: &str) -> Result<SceneSpec, GeomError> {
        SceneSpec::parse(arg)
    }
}

impl PartialEq for SceneSpec {
    /// Two specs are equal when they are written alike.
    fn eq(&self, other: &SceneSpec) -> bool {
        self.written == other.written
    }
}
