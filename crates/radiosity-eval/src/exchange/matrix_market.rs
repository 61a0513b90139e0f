//! Matrix Market files: `F` as a `coordinate real general` matrix (1-based `i j F_ij`, one
//! non-zero entry a line) and the patches' areas, emissions and reflectivities as an
//! `array real general` matrix, `n` rows and `1 + 2k` columns (`A`, then `E` and `ρ` for each
//! of the `k` channels), column-major as the format orders arrays. Values are written in the
//! shortest form that reads back to the same `f64`.

use crate::exchange::sparse_columns::SparseColumns;
use radiosity_core::LinearSystem;
use std::io::{self, Write};

/// Writes `f` as a Matrix Market coordinate file, with `comments` as `%` lines after the
/// banner.
pub fn write_matrix(out: &mut impl Write, f: &SparseColumns, comments: &[String]) -> io::Result<()> {
    writeln!(out, "%%MatrixMarket matrix coordinate real general")?;
    write_comments(out, comments)?;
    writeln!(out, "{} {} {}", f.n, f.n, f.nonzeros())?;
    for j in 0..f.n {
        let (start, end) = (f.indptr[j] as usize, f.indptr[j + 1] as usize);
        for (i, v) in f.indices[start..end].iter().zip(&f.values[start..end]) {
            writeln!(out, "{} {} {v:e}", i + 1, j + 1)?;
        }
    }
    Ok(())
}

/// Writes the patches' areas, emissions and reflectivities of `system` as a Matrix Market
/// array file (module documentation), with `comments` as `%` lines after the banner and a
/// line naming the columns.
pub fn write_patches(out: &mut impl Write, system: &LinearSystem, comments: &[String]) -> io::Result<()> {
    let (n, k) = (system.len(), system.channels().count());
    writeln!(out, "%%MatrixMarket matrix array real general")?;
    write_comments(out, comments)?;
    let channel = |name: &str| (0..k).map(|c| format!("{name}[{c}]")).collect::<Vec<_>>().join(" ");
    writeln!(out, "% columns: area {} {}", channel("emission"), channel("reflectivity"))?;
    writeln!(out, "{n} {}", 1 + 2 * k)?;
    for a in system.areas() {
        writeln!(out, "{a:e}")?;
    }
    for values in [system.emissions(), system.reflectivities()] {
        for c in 0..k {
            for i in 0..n {
                writeln!(out, "{:e}", values[i * k + c])?;
            }
        }
    }
    Ok(())
}

fn write_comments(out: &mut impl Write, comments: &[String]) -> io::Result<()> {
    for line in comments.iter().flat_map(|c| c.lines()) {
        writeln!(out, "% {line}")?;
    }
    Ok(())
}
