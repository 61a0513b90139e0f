//! Which reference a lab measures against (`auto`, `matrix`, `shooting` or `none`,
//! docs/design.md §6.2), and the memory budget `auto` decides by.
//!
//! - `matrix`: the backend's full matrix stored in `f32` (dense or sparse, whichever is
//!   smaller; the analytic backend computes each pair once and takes the other entry by
//!   reciprocity), solved by dense LU up to 4000 patches and by Gauss–Seidel over its columns
//!   to a certified relative bound of 1e-10 above ([`crate::reference::solution`]);
//! - `shooting`: no matrix; a long shooting run to a certified relative bound of 1e-8
//!   ([`crate::reference::shooting`]), `O(n)` memory;
//! - `none`: no reference, so no e_rms: runs report their certified bound alone;
//! - `auto` (the default): `matrix` when the backend is a stored matrix already or when the
//!   matrix fits the memory budget, `shooting` otherwise.
//!
//! The budget is `RADIOSITY_MEMORY` (bytes, or with a unit: `6G`, `6GiB`, `512M`), by default
//! a quarter of the machine's memory (`/proc/meminfo`; 4 GiB where it cannot be read). A
//! matrix's size is not known before it is assembled, so [`matrix_bytes`] estimates the peak
//! of its assembly from the non-zeros of a few sampled columns: the stored entries (dense
//! `4 n²` bytes, or sparse `8` bytes per non-zero) plus the `6` bytes per non-zero that
//! assembly by reciprocity keeps until every pair is computed, with a margin of 10%.

use crate::error::EvalError;
use radiosity_core::{ColumnSource, Real};
use std::fmt;
use std::str::FromStr;

/// Which reference to measure against.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ReferenceKind {
    /// `matrix` when it fits the memory budget, `shooting` otherwise.
    #[default]
    Auto,
    /// The stored matrix, solved to a certified relative bound of 1e-10.
    Matrix,
    /// A long shooting run without a matrix, to a certified relative bound of 1e-8.
    Shooting,
    /// No reference: the certified bound alone.
    None,
}

impl ReferenceKind {
    /// The names, as on the command line.
    pub const NAMES: [&'static str; 4] = ["auto", "matrix", "shooting", "none"];

    /// The name, as on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            ReferenceKind::Auto => "auto",
            ReferenceKind::Matrix => "matrix",
            ReferenceKind::Shooting => "shooting",
            ReferenceKind::None => "none",
        }
    }
}

impl fmt::Display for ReferenceKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for ReferenceKind {
    type Err = EvalError;

    fn from_str(s: &str) -> Result<ReferenceKind, EvalError> {
        match s.trim() {
            "auto" => Ok(ReferenceKind::Auto),
            "matrix" => Ok(ReferenceKind::Matrix),
            "shooting" => Ok(ReferenceKind::Shooting),
            "none" => Ok(ReferenceKind::None),
            other => Err(EvalError::InvalidParameter {
                name: "reference",
                value: other.to_string(),
                reason: "it must be one of auto, matrix, shooting or none",
            }),
        }
    }
}

/// The memory a lab may give a stored matrix, in bytes, and where the figure came from.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryBudget {
    /// Bytes.
    pub bytes: u64,
    /// Where the figure came from, for reports: `RADIOSITY_MEMORY=6G`, `a quarter of 24.0 GiB`.
    pub source: String,
}

/// The environment variable that sets the memory budget.
pub const MEMORY_VARIABLE: &str = "RADIOSITY_MEMORY";

impl MemoryBudget {
    /// The budget `RADIOSITY_MEMORY` sets, or a quarter of the machine's memory.
    pub fn from_env() -> Result<MemoryBudget, EvalError> {
        match std::env::var(MEMORY_VARIABLE) {
            Ok(value) => {
                Ok(MemoryBudget { bytes: parse_bytes(&value)?, source: format!("{MEMORY_VARIABLE}={}", value.trim()) })
            }
            Err(_) => Ok(match machine_memory() {
                Some(total) => MemoryBudget { bytes: total / 4, source: format!("a quarter of {}", gib(total)) },
                None => MemoryBudget { bytes: 4 << 30, source: "4 GiB (the machine's memory is unknown)".into() },
            }),
        }
    }

    /// A fixed budget.
    pub fn fixed(bytes: u64) -> MemoryBudget {
        MemoryBudget { bytes, source: "fixed by the caller".into() }
    }
}

impl fmt::Display for MemoryBudget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", gib(self.bytes), self.source)
    }
}

/// `bytes` in GiB with two decimals, or in MiB below 1 GiB.
pub(crate) fn gib(bytes: u64) -> String {
    if bytes < 1 << 30 {
        format!("{:.1} MiB", bytes as Real / (1u64 << 20) as Real)
    } else {
        format!("{:.2} GiB", bytes as Real / (1u64 << 30) as Real)
    }
}

/// Parses a byte count: a whole number, optionally followed by `K`, `M`, `G` or `T` (powers of
/// 1024, with or without `iB` or `B`).
pub fn parse_bytes(value: &str) -> Result<u64, EvalError> {
    let refuse = || EvalError::InvalidParameter {
        name: MEMORY_VARIABLE,
        value: value.to_string(),
        reason: "it must be a number of bytes, optionally with a unit K, M, G or T (powers of 1024), e.g. 6G",
    };
    let v = value.trim();
    let digits = v.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(v.len());
    let (number, unit) = v.split_at(digits);
    let number: Real = number.parse().map_err(|_| refuse())?;
    let unit = unit.trim().to_ascii_uppercase();
    let unit = unit.trim_end_matches("IB").trim_end_matches('B');
    let scale: u64 = match unit {
        "" => 1,
        "K" => 1 << 10,
        "M" => 1 << 20,
        "G" => 1 << 30,
        "T" => 1 << 40,
        _ => return Err(refuse()),
    };
    let bytes = number * scale as Real;
    if !(bytes.is_finite() && bytes >= 1.0) {
        return Err(refuse());
    }
    Ok(bytes as u64)
}

/// The machine's memory in bytes, from `/proc/meminfo`.
fn machine_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Columns sampled to estimate a matrix's non-zeros.
const SAMPLED_COLUMNS: usize = 8;

/// The estimated peak bytes of assembling and storing the full matrix of `source` (module
/// doc), from `SAMPLED_COLUMNS` evenly spaced columns, and the fraction of non-zeros they
/// show. Costs those columns only when the dense bound alone exceeds `budget`.
pub fn matrix_bytes(source: &dyn ColumnSource, budget: u64) -> (u64, Option<Real>) {
    let n = source.patch_count() as u64;
    let dense = 4 * n * n;
    // Dense storage plus the pairs kept while assembling, if every entry were non-zero.
    let worst = (dense + 6 * n * n) as Real * 1.1;
    if worst <= budget as Real {
        return (worst as u64, None);
    }
    let mut column = vec![0.0; n as usize];
    let mut nonzeros = 0usize;
    let sampled = SAMPLED_COLUMNS.min(n as usize).max(1);
    for s in 0..sampled {
        let j = (s * n as usize) / sampled + (n as usize / sampled) / 2;
        source.fill_column(j.min(n as usize - 1), &mut column);
        nonzeros += column.iter().filter(|v| **v as f32 != 0.0).count();
    }
    let fraction = nonzeros as Real / (sampled as Real * n as Real);
    let nnz = fraction * (n * n) as Real;
    let stored = (dense as Real).min(8.0 * nnz + 4.0 * (n + 1) as Real);
    (((stored + 6.0 * nnz) * 1.1) as u64, Some(fraction))
}
