//! Typed errors of the geometry crate: scene names and parameters, meshing, and file input.

use radiosity_core::CoreError;
use std::path::PathBuf;
use thiserror::Error;

/// What can go wrong when building or loading a scene. Messages are single sentences.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum GeomError {
    /// Invalid core data (a material, a patch), with where it came from.
    ///
    /// The core error is part of the message rather than a `source`, so error chains
    /// (`anyhow`'s `{:#}`) do not print it twice.
    #[error("{context}: {cause}")]
    Core {
        /// Which object, material or file the data belongs to.
        context: String,
        /// The underlying problem.
        cause: CoreError,
    },
    /// A scene name that is neither built in nor a supported file.
    #[error(
        "unknown scene '{name}'{suggestion}; built-in scenes are {valid}, or give a path to a .gltf, .glb or .mgf file"
    )]
    UnknownScene {
        /// The name given.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
        /// ` (did you mean 'NAME'?)` for a typo of a built-in name, or nothing.
        suggestion: String,
    },
    /// A `key=value` parameter the scene or backend does not take.
    #[error("{owner} has no parameter '{key}'{suggestion}; its parameters are {valid}")]
    UnknownParameter {
        /// What the parameters belong to: `scene 'furnace'`.
        owner: String,
        /// The key given.
        key: String,
        /// The valid keys, comma-separated.
        valid: String,
        /// ` (did you mean 'KEY'?)` for a typo of a valid key, or nothing.
        suggestion: String,
    },
    /// A parameter value that does not parse or is out of range.
    #[error("{owner}: parameter {key}={value} is invalid; expected {expected}")]
    BadParameter {
        /// What the parameters belong to: `scene 'furnace'`.
        owner: String,
        /// The key.
        key: String,
        /// The value given.
        value: String,
        /// What was expected.
        expected: String,
    },
    /// A parameter written without `=`.
    #[error("{owner}: parameter '{item}' is not of the form key=value")]
    MalformedParameter {
        /// What the parameter belongs to: `scene 'cornell'`, `backend 'analytic'`.
        owner: String,
        /// The item as written.
        item: String,
    },
    /// A relative scene path found neither from the current directory nor in the folder of
    /// third-party scenes.
    #[error(
        "scene file {path} not found, neither from the current directory nor in the scenes folder {folder}{suggestion}"
    )]
    SceneFileNotFound {
        /// The path as written.
        path: PathBuf,
        /// `; did you mean PATH?` for the folder's scene file nearest to it, or nothing.
        suggestion: String,
        /// The folder looked in, and why that one ([`crate::third_party::ScenesFolder::describe`]).
        folder: String,
    },
    /// A file that cannot be read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's message.
        message: String,
    },
    /// A glTF file that is not valid glTF or uses something we cannot load.
    #[error("{path} is not a usable glTF file: {message}")]
    Gltf {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A file with no usable surface.
    #[error("{path} contains no usable triangles{detail}")]
    EmptyFile {
        /// The file.
        path: PathBuf,
        /// Why nothing was usable, starting with "; " or empty.
        detail: String,
    },
    /// A file read as text that holds binary data.
    #[error("{path} is not a text file: byte {offset} is binary data")]
    NotText {
        /// The file.
        path: PathBuf,
        /// The offset of the first byte that is not text (a NUL, or not UTF-8).
        offset: usize,
    },
    /// An MGF entity with wrong or missing arguments.
    #[error("{path}:{line}: {message}")]
    MgfBadEntity {
        /// The file.
        path: PathBuf,
        /// The line (1-based) where the entity starts.
        line: usize,
        /// What is wrong, naming the entity.
        message: String,
    },
    /// A reference to a vertex, material or colour that was never defined.
    #[error("{path}:{line}: undefined {kind} '{name}'")]
    MgfUndefined {
        /// The file.
        path: PathBuf,
        /// The line (1-based) of the reference.
        line: usize,
        /// `vertex`, `material` or `colour`.
        kind: &'static str,
        /// The name referred to.
        name: String,
    },
    /// An MGF include that is already being read further up the chain of includes.
    #[error("{path}:{line}: including {include} makes an include cycle")]
    MgfIncludeCycle {
        /// The including file.
        path: PathBuf,
        /// The line of the `i` entity.
        line: usize,
        /// The included file.
        include: PathBuf,
    },
    /// An MGF include that cannot be read.
    #[error("{path}:{line}: cannot read included file {include}: {message}")]
    MgfMissingInclude {
        /// The including file.
        path: PathBuf,
        /// The line of the `i` entity.
        line: usize,
        /// The included file.
        include: PathBuf,
        /// The operating system's message.
        message: String,
    },
    /// An MGF file that would make more instances or patches, or take more work, than a file
    /// may (see [`crate::mgf::Limits`]), found before the work is done.
    #[error("{}: {message}", location(.path, .line))]
    MgfLimit {
        /// The file.
        path: PathBuf,
        /// The line (1-based) of the entity that would cross the limit; `None` when it is the
        /// meshing of the whole file.
        line: Option<usize>,
        /// What would be made, how much, and the limit.
        message: String,
    },
    /// A file format this build does not read yet.
    #[error("{path}: {format} input is not supported yet")]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
        /// The format's name.
        format: &'static str,
    },
    /// Rays asked of a prepared scene whose BVH was released
    /// ([`crate::PreparedScene::release_visibility`]).
    #[error(
        "the scene's BVH was released once nothing in the run traced rays, so {wanted} cannot be done in this run; \
         ask for it in a run of its own"
    )]
    VisibilityReleased {
        /// What needed the rays: `a render`.
        wanted: String,
    },
}

/// `path:line`, or the path alone.
fn location(path: &std::path::Path, line: &Option<usize>) -> String {
    match line {
        Some(line) => format!("{}:{line}", path.display()),
        None => path.display().to_string(),
    }
}

impl GeomError {
    /// Wraps a core error with context.
    pub fn core(context: impl Into<String>, source: CoreError) -> GeomError {
        GeomError::Core { context: context.into(), cause: source }
    }
}
