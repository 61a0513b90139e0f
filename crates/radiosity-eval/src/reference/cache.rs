//! The on-disk cache of what is expensive to compute and deterministic: stored form-factor
//! matrices (the `matrix` backend) and reference solutions.
//!
//! An entry is named by the xxh3 hash of its **key**, a string holding everything the value
//! depends on: the format version, the crate version and the revision of the backends' entries
//! ([`radiosity_ff::ENTRIES_REVISION`]), the scene's name, its patch count and a
//! fingerprint of every patch's vertices (a file edited in place keeps its name, not its
//! geometry), and the canonical backend argument with the parameters of what was computed.
//! The key is stored inside the entry with a checksum of the body and both are checked on
//! load, so a hash collision, a truncated file or an entry of another build is never taken
//! for a hit: it is reported and replaced. Writes go to a temporary file that is then renamed,
//! so an interrupted or concurrent run never leaves half an entry under the final name.
//!
//! The directory is the caller's choice ([`Cache::at`]); [`Cache::from_env`] reads
//! `$RADIOSITY_CACHE_DIR` first.

use radiosity_core::Scene;
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::{Xxh3Default, xxh3_64};

/// The environment variable that overrides the cache directory.
pub const CACHE_DIR_VAR: &str = "RADIOSITY_CACHE_DIR";

/// A cache directory.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Cache {
    dir: PathBuf,
}

/// What looking an entry up gave.
#[derive(Debug)]
pub enum Lookup {
    /// The entry's bytes.
    Hit(Vec<u8>),
    /// No entry under this key.
    Miss,
    /// An entry that could not be read; it will be replaced.
    Unreadable(String),
}

impl Cache {
    /// A cache in `dir` (created on the first write).
    pub fn at(dir: impl Into<PathBuf>) -> Cache {
        Cache { dir: dir.into() }
    }

    /// A cache in `$RADIOSITY_CACHE_DIR` when it is set and not empty, otherwise in `default`.
    pub fn from_env(default: impl Into<PathBuf>) -> Cache {
        match std::env::var_os(CACHE_DIR_VAR) {
            Some(dir) if !dir.is_empty() => Cache::at(dir),
            _ => Cache::at(default),
        }
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The file of the entry `kind` (`ff`, `reference`) with `key`.
    pub fn path(&self, kind: &str, key: &str) -> PathBuf {
        self.dir.join(format!("{kind}-{:016x}.bin", xxh3_64(key.as_bytes())))
    }

    /// Reads the entry `kind` with `key`.
    pub fn read(&self, kind: &str, key: &str) -> Lookup {
        let path = self.path(kind, key);
        match std::fs::read(&path) {
            Ok(bytes) => Lookup::Hit(bytes),
            // No directory (or a file where it would be) holds no entry: a write says why.
            Err(e) if matches!(e.kind(), std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory) => {
                Lookup::Miss
            }
            Err(e) => Lookup::Unreadable(format!("cannot read cache file {}: {e}", path.display())),
        }
    }

    /// Creates the directory when it is missing, or says why it cannot: before a caller turns
    /// what it would keep into bytes, which may be as large as what it holds.
    pub fn prepare(&self) -> Result<(), String> {
        std::fs::create_dir_all(&self.dir).map_err(|e| format!("cannot create {}: {e}", self.dir.display()))
    }

    /// Writes the entry `kind` with `key` atomically; returns its path, or why it failed.
    pub fn write(&self, kind: &str, key: &str, bytes: &[u8]) -> Result<PathBuf, String> {
        let path = self.path(kind, key);
        self.prepare()?;
        let tmp = path.with_extension(format!("tmp{}", std::process::id()));
        std::fs::write(&tmp, bytes).map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
        std::fs::rename(&tmp, &path)
            .map_err(|e| format!("cannot rename {} to {}: {e}", tmp.display(), path.display()))?;
        Ok(path)
    }
}

/// The part of every key that names the build and the scene: the crate version and the
/// revision of the backends' entries, the scene's name, patch count and a fingerprint of every
/// patch's vertices.
pub fn scene_key(scene: &Scene) -> String {
    let mut geometry = Xxh3Default::new();
    for p in scene.patches() {
        geometry.update(&(p.vertices().len() as u64).to_le_bytes());
        for v in p.vertices() {
            for c in v.to_array() {
                geometry.update(&c.to_bits().to_le_bytes());
            }
        }
    }
    format!(
        "radiosity {} (entries revision {}); scene {}; {} patches; geometry {:016x}",
        env!("CARGO_PKG_VERSION"),
        radiosity_ff::ENTRIES_REVISION,
        scene.name(),
        scene.len(),
        geometry.digest()
    )
}

/// The xxh3 checksum of `bytes`, for entries that carry one.
pub(crate) fn checksum(bytes: &[u8]) -> u64 {
    xxh3_64(bytes)
}
