//! `relax-ω`: over-relaxed shooting (Gortler, Cohen & Slusallek 1993).
//!
//! Rule: `ΔB⁺_j = (ω − 1) ΔB_j`, so the shooter shoots `ω ΔB_j` and keeps `−(ω − 1) ΔB_j`
//! unshot: successive over-relaxation of Southwell iteration, with PR's area-weighted choice
//! (selection by `A_j |ΔB_j + ΔB⁺_j| = ω A_j |ΔB_j|`). `0 < ω < 2`; `ω = 1` is PR. The step is
//! the shared overshooting step ([`crate::overshooting`]).
//!
//! ## References
//!
//! - Gortler, Cohen & Slusallek 1993, "Radiosity and relaxation methods: progressive
//!   refinement is Southwell relaxation", Princeton CS-TR-408-93.

use crate::error::SolverError;
use crate::overshooting::{AmbientTerm, Overshoot, Overshooting};
use radiosity_core::Real;

/// The `relax-ω` solver; `omega` must lie in `(0, 2)`.
pub fn relax(omega: Real) -> Result<Overshooting, SolverError> {
    Overshooting::new(format!("relax-{omega}"), Overshoot { row: None, ambient: AmbientTerm::Off, omega })
}
