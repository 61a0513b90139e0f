//! Where scene files written by others are found: the folder named by the setting
//! `RADIOSITY_SCENES`, or [`DEFAULT_SCENES`] when it is unset.
//!
//! ## Rules
//!
//! - The setting is the environment variable [`SCENES_VARIABLE`]; unset or empty, the folder is
//!   [`DEFAULT_SCENES`]. A relative folder is taken from a base directory: the current one for a
//!   scene argument ([`ScenesFolder::from_env`]), the repository root for the tests.
//! - A scene argument names a file by a path. A relative path that does not exist from the
//!   current directory is looked up in the folder ([`ScenesFolder::resolve`]), so
//!   `mgf/office3/office.mgf` names RenderPark's office wherever the folder is. A path found
//!   from the current directory wins: the folder is a fallback, never a shadow.
//! - Nothing here reads a file; [`ScenesFolder::file`] only asks whether one exists, and
//!   [`ScenesFolder::nearest`] lists the folder's scene files (at most [`LISTED`], four
//!   folders deep) to suggest one for a path that names none.

use std::path::{Path, PathBuf};

/// The environment variable naming the folder of third-party scenes.
pub const SCENES_VARIABLE: &str = "RADIOSITY_SCENES";

/// The folder used when [`SCENES_VARIABLE`] is unset: beside the repository's checkout.
pub const DEFAULT_SCENES: &str = "../shared/scenes";

/// The folder of third-party scenes, and whether the setting named it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScenesFolder {
    path: PathBuf,
    from_setting: bool,
}

impl ScenesFolder {
    /// The folder the setting names, a relative one taken from the current directory.
    pub fn from_env() -> ScenesFolder {
        ScenesFolder::locate(Path::new(""))
    }

    /// The folder the setting names, a relative one taken from `base`.
    pub fn locate(base: &Path) -> ScenesFolder {
        let setting = std::env::var_os(SCENES_VARIABLE).filter(|v| !v.is_empty());
        let from_setting = setting.is_some();
        let named = setting.map_or_else(|| PathBuf::from(DEFAULT_SCENES), PathBuf::from);
        ScenesFolder { path: base.join(named), from_setting }
    }

    /// The folder itself (it may not exist).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// `relative` in the folder, if that file exists.
    pub fn file(&self, relative: impl AsRef<Path>) -> Option<PathBuf> {
        let path = self.path.join(relative);
        path.is_file().then_some(path)
    }

    /// Where a scene argument's `path` is read from: the path itself when it exists or is
    /// absolute, else the same relative path in the folder when that exists; otherwise the
    /// path as given, so that reading it reports it as written.
    pub fn resolve(&self, path: &Path) -> PathBuf {
        if path.is_absolute() || path.exists() {
            return path.to_path_buf();
        }
        self.file(path).unwrap_or_else(|| path.to_path_buf())
    }

    /// The scene file of the folder nearest to `written`, a path that exists neither from the
    /// current directory nor in the folder, as a typo of it
    /// ([`radiosity_core::suggest::nearest`]): compared path to path, then by file name alone, so
    /// that `clasroom.mgf` finds `mgf/salon/classroom.mgf`.
    pub fn nearest(&self, written: &Path) -> Option<PathBuf> {
        let mut files = Vec::new();
        list_scene_files(&self.path, Path::new(""), 4, &mut files);
        let paths: Vec<String> = files.iter().map(|f| f.to_string_lossy().into_owned()).collect();
        let text = written.to_string_lossy();
        if let Some(found) = radiosity_core::suggest::nearest(&text, paths.iter().map(String::as_str)) {
            return Some(PathBuf::from(found));
        }
        let name = written.file_name()?.to_string_lossy();
        let names: Vec<String> =
            files.iter().map(|f| f.file_name().unwrap_or_default().to_string_lossy().into_owned()).collect();
        let found = radiosity_core::suggest::nearest(&name, names.iter().map(String::as_str))?;
        files.into_iter().find(|f| f.file_name().is_some_and(|n| n.to_string_lossy() == found))
    }

    /// Says where the folder is and why, for messages: the path, then `(from
    /// RADIOSITY_SCENES)` or `(the default; RADIOSITY_SCENES is unset)`.
    pub fn describe(&self) -> String {
        if self.from_setting {
            format!("{} (from {SCENES_VARIABLE})", self.path.display())
        } else {
            format!("{} (the default; {SCENES_VARIABLE} is unset)", self.path.display())
        }
    }
}

/// The most scene files [`ScenesFolder::nearest`] lists.
pub const LISTED: usize = 10_000;

/// Appends to `out` the `.mgf`, `.gltf` and `.glb` files under `dir`, as paths relative to the
/// folder (`relative` is `dir`'s), descending at most `depth` folders, up to [`LISTED`] files.
fn list_scene_files(dir: &Path, relative: &Path, depth: usize, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<_> = entries.filter_map(Result::ok).map(|e| e.path()).collect();
    entries.sort();
    for path in entries {
        if out.len() >= LISTED {
            return;
        }
        let Some(name) = path.file_name() else { continue };
        if path.is_dir() {
            if depth > 0 {
                list_scene_files(&path, &relative.join(name), depth - 1, out);
            }
        } else if path.extension().is_some_and(|e| ["mgf", "gltf", "glb"].iter().any(|x| e.eq_ignore_ascii_case(x))) {
            out.push(relative.join(name));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_path_found_from_the_current_directory_wins_over_the_folder() {
        let dir = std::env::temp_dir().join(format!("radiosity-third-party-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("mgf")).unwrap();
        std::fs::write(dir.join("mgf/room.mgf"), "").unwrap();
        let folder = ScenesFolder { path: dir.clone(), from_setting: true };
        assert_eq!(folder.resolve(Path::new("mgf/room.mgf")), dir.join("mgf/room.mgf"));
        assert_eq!(folder.resolve(Path::new("mgf/none.mgf")), Path::new("mgf/none.mgf"));
        // This crate's manifest exists from the test's directory (the crate's own).
        assert_eq!(folder.resolve(Path::new("Cargo.toml")), Path::new("Cargo.toml"));
        assert!(folder.file("mgf/room.mgf").is_some() && folder.file("mgf").is_none());
        std::fs::remove_dir_all(dir).unwrap();
    }
}
