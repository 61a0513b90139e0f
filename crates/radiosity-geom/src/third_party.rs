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
//! - Nothing here reads a file; [`ScenesFolder::file`] only asks whether one exists.

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
