//! The formats by a path's extension, and the files a system written to a path fills.

use crate::error::EvalError;
use crate::exchange::sparse_columns::SparseColumns;
use crate::exchange::{matrix_market, npz};
use radiosity_core::LinearSystem;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// A file format of the system, named by a path's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.mtx`: `F` in the file, the patches in `.patches.mtx` beside it ([`matrix_market`]).
    MatrixMarket,
    /// `.npz`: everything in one archive ([`npz`]).
    Npz,
}

impl Format {
    /// The format `path`'s extension names.
    pub fn of(path: &Path) -> Result<Format, EvalError> {
        match path.extension().and_then(|e| e.to_str()) {
            Some("mtx") => Ok(Format::MatrixMarket),
            Some("npz") => Ok(Format::Npz),
            _ => Err(EvalError::Write {
                path: path.to_path_buf(),
                message: "a system is written as .mtx (Matrix Market) or .npz (NumPy)".into(),
            }),
        }
    }

    /// The files a system written to `path` fills, in the order [`write_system`] takes them.
    pub fn files(self, path: &Path) -> Vec<PathBuf> {
        match self {
            Format::MatrixMarket => vec![path.to_path_buf(), path.with_extension("patches.mtx")],
            Format::Npz => vec![path.to_path_buf()],
        }
    }
}

/// Writes `f` and the patches of `system` to the files `path` names, in the format its
/// extension names ([`Format::of`], [`Format::files`]); the paths written.
pub fn write_files(
    path: &Path,
    f: &SparseColumns,
    system: &LinearSystem,
    comments: &[String],
) -> Result<Vec<PathBuf>, EvalError> {
    let format = Format::of(path)?;
    let paths = format.files(path);
    let cannot = |path: &Path, e: io::Error| EvalError::Write { path: path.to_path_buf(), message: e.to_string() };
    let mut files = paths
        .iter()
        .map(|p| std::fs::File::create(p).map(io::BufWriter::new).map_err(|e| cannot(p, e)))
        .collect::<Result<Vec<_>, _>>()?;
    write_system(format, &mut files, f, system, comments)
        .and_then(|()| files.iter_mut().try_for_each(Write::flush))
        .map_err(|e| cannot(path, e))?;
    Ok(paths)
}

/// Writes `f` and the patches of `system` in `format` to `files` (opened by the caller, as
/// [`Format::files`] names them), with `comments` where the format keeps them.
///
/// # Panics
///
/// When `files` does not hold one writer for each of the format's files.
pub fn write_system(
    format: Format,
    files: &mut [impl Write],
    f: &SparseColumns,
    system: &LinearSystem,
    comments: &[String],
) -> io::Result<()> {
    match (format, files) {
        (Format::MatrixMarket, [matrix, patches]) => {
            matrix_market::write_matrix(matrix, f, comments)?;
            matrix_market::write_patches(patches, system, comments)
        }
        (Format::Npz, [archive]) => npz::write_system(archive, f, system),
        (format, files) => {
            panic!("{format:?} writes {} files, not {}", format.files(Path::new("F")).len(), files.len())
        }
    }
}
