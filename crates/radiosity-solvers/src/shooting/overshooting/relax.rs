//! `relax-ω`: over-relaxed shooting (Gortler, Cohen & Slusallek 1993).
//!
//! Rule: `ΔB⁺_j = (ω − 1) ΔB_j`, so the shooter shoots `ω ΔB_j` and keeps `−(ω − 1) ΔB_j`
//! unshot: successive over-relaxation of Southwell iteration, with PR's area-weighted choice
//! (selection by `A_j |ΔB_j + ΔB⁺_j| = ω A_j |ΔB_j|`). `0 < ω < 2`; `ω = 1` is PR. The step is
//! the shared overshooting step ([`super::step`]).
//!
//! ## References
//!
//! - Gortler, Cohen & Slusallek 1993, "Radiosity and relaxation methods: progressive
//!   refinement is Southwell relaxation", Princeton CS-TR-408-93.

use crate::shooting::overshooting::overshoot::{AmbientTerm, Overshoot};
use radiosity_core::Real;

/// The over-relaxation overshoot; `omega` must lie in `(0, 2)`, which the solvers check.
pub fn rule(omega: Real) -> Overshoot {
    Overshoot { row: None, ambient: AmbientTerm::Off, omega }
}
