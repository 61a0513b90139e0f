//! Scene arguments: `NAME[:key=value…]` for built-in scenes, `PATH[:key=value…]` for files,
//! and the `key=value` parameters they (and form-factor backends) take.
//!
//! A path is recognised by its extension (`.gltf`, `.glb`, `.mgf`, any case); parameters after
//! it follow the same `:key=value` form. Every key is checked against the scene's declared
//! parameters, so a typo is an error that lists the valid keys rather than a silent default.
//! Parameters that take a colour accept one value (grey) or three values separated by `/`
//! (`rho=0.99/0.5/0`).
//!
//! A whole scene argument is parsed once, at the edge, into a
//! [`SceneSpec`](crate::scene_spec::SceneSpec) built on these pieces.

use crate::error::GeomError;
use radiosity_core::{Real, Spectrum};
use std::path::PathBuf;

/// The documentation of one scene parameter.
#[derive(Clone, Copy, Debug)]
pub struct ParamDoc {
    /// The key, as written on the command line.
    pub key: &'static str,
    /// The default value, as written on the command line.
    pub default: &'static str,
    /// What it controls.
    pub doc: &'static str,
}

/// Parsed `key=value` parameters of one scene or backend, with typed, range-checked getters.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KeyValueParams {
    /// What the parameters belong to, as errors name it: `scene 'furnace'`.
    owner: String,
    values: Vec<(String, String)>,
}

impl KeyValueParams {
    /// Parses `key=value` items and checks every key against `docs`. `owner` names what the
    /// parameters belong to in error messages, e.g. `scene 'furnace'`.
    pub fn parse<'a>(
        owner: &str,
        items: impl IntoIterator<Item = &'a str>,
        docs: &[ParamDoc],
    ) -> Result<KeyValueParams, GeomError> {
        let mut values: Vec<(String, String)> = Vec::new();
        for item in items {
            let (key, value) = item
                .split_once('=')
                .ok_or_else(|| GeomError::MalformedParameter { owner: owner.to_string(), item: item.to_string() })?;
            let (key, value) = (key.trim(), value.trim());
            if !docs.iter().any(|d| d.key == key) {
                let valid = if docs.is_empty() {
                    "none".to_string()
                } else {
                    docs.iter().map(|d| d.key).collect::<Vec<_>>().join(", ")
                };
                let suggestion = radiosity_core::suggest::did_you_mean(key, docs.iter().map(|d| d.key));
                return Err(GeomError::UnknownParameter {
                    owner: owner.to_string(),
                    key: key.to_string(),
                    valid,
                    suggestion,
                });
            }
            values.retain(|(k, _)| k != key);
            values.push((key.to_string(), value.to_string()));
        }
        Ok(KeyValueParams { owner: owner.to_string(), values })
    }

    /// The parameters given, in order, as `key=value`.
    pub fn given(&self) -> impl Iterator<Item = (&str, &str)> {
        self.values.iter().map(|(k, v)| (k.as_str(), v.as_str()))
    }

    /// The value given for `key`, as written; `None` when it was not given.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.raw(key)
    }

    fn raw(&self, key: &str) -> Option<&str> {
        self.values.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    /// The error for a given parameter whose value is unacceptable for a reason the typed
    /// getters do not check; `expected` says what would be acceptable.
    pub fn reject(&self, key: &str, expected: &str) -> GeomError {
        self.bad(key, self.raw(key).unwrap_or_default(), expected)
    }

    fn bad(&self, key: &str, value: &str, expected: &str) -> GeomError {
        GeomError::BadParameter {
            owner: self.owner.clone(),
            key: key.to_string(),
            value: value.to_string(),
            expected: expected.to_string(),
        }
    }

    /// A real number satisfying `ok`, described by `expected` in the error.
    pub fn real(&self, key: &str, default: Real, ok: impl Fn(Real) -> bool, expected: &str) -> Result<Real, GeomError> {
        match self.raw(key) {
            None => Ok(default),
            Some(s) => match s.parse::<Real>() {
                Ok(v) if v.is_finite() && ok(v) => Ok(v),
                _ => Err(self.bad(key, s, expected)),
            },
        }
    }

    /// An integer in `min..=max`.
    pub fn count(&self, key: &str, default: usize, min: usize, max: usize) -> Result<usize, GeomError> {
        match self.raw(key) {
            None => Ok(default),
            Some(s) => match s.parse::<usize>() {
                Ok(v) if (min..=max).contains(&v) => Ok(v),
                _ => Err(self.bad(key, s, &format!("an integer from {min} to {max}"))),
            },
        }
    }

    /// An unsigned 64-bit seed.
    pub fn seed(&self, key: &str, default: u64) -> Result<u64, GeomError> {
        match self.raw(key) {
            None => Ok(default),
            Some(s) => s.parse::<u64>().map_err(|_| self.bad(key, s, "a non-negative integer seed")),
        }
    }

    /// `true`/`false` (also `1`/`0`, `yes`/`no`).
    pub fn flag(&self, key: &str, default: bool) -> Result<bool, GeomError> {
        match self.raw(key) {
            None => Ok(default),
            Some("true" | "1" | "yes") => Ok(true),
            Some("false" | "0" | "no") => Ok(false),
            Some(s) => Err(self.bad(key, s, "true or false")),
        }
    }

    /// A colour: one value for grey or three separated by `/`, each satisfying `ok`.
    pub fn spectrum(
        &self,
        key: &str,
        default: Spectrum,
        ok: impl Fn(Real) -> bool,
        expected: &str,
    ) -> Result<Spectrum, GeomError> {
        let Some(s) = self.raw(key) else { return Ok(default) };
        let parts: Vec<Option<Real>> = s.split('/').map(|p| p.trim().parse::<Real>().ok()).collect();
        let valid = |v: &Option<Real>| v.is_some_and(|v| v.is_finite() && ok(v));
        match parts.as_slice() {
            [a] if valid(a) => Ok(Spectrum::grey(a.unwrap())),
            [a, b, c] if valid(a) && valid(b) && valid(c) => Ok(Spectrum::rgb(a.unwrap(), b.unwrap(), c.unwrap())),
            _ => Err(self.bad(key, s, &format!("{expected}, one value or three separated by '/'"))),
        }
    }
}

/// A scene file format, from the path's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileFormat {
    /// glTF 2.0, text (`.gltf`) or binary (`.glb`).
    Gltf,
    /// Materials and Geometry Format (`.mgf`).
    Mgf,
}

/// Splits a scene argument into a file path and its parameters, when it names a file.
pub fn split_file_argument(arg: &str) -> Option<(PathBuf, FileFormat, Vec<&str>)> {
    let lower = arg.to_ascii_lowercase();
    for (ext, format) in [(".gltf", FileFormat::Gltf), (".glb", FileFormat::Gltf), (".mgf", FileFormat::Mgf)] {
        let mut search = 0;
        while let Some(pos) = lower[search..].find(ext) {
            let end = search + pos + ext.len();
            if end == arg.len() || arg[end..].starts_with(':') {
                let params = arg[end..].split(':').filter(|s| !s.is_empty()).collect();
                return Some((PathBuf::from(&arg[..end]), format, params));
            }
            search = end;
        }
    }
    None
}
