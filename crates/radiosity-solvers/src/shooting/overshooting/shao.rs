//! `shao`: overshooting by a positive gather along the shooter's own row (Shao & Badler 1993).
//!
//! Rule: `ΔB⁺_j = ρ_j Σ_k F_jk max(ΔB_k, 0)`: the light the shooter will receive in the next
//! shots of the patches it sees, counting only light still to come (negative unshot, left by
//! earlier overshoots, is ignored). Row `j` comes from the shooter's column by reciprocity, so
//! it costs nothing more. The step is the shared overshooting step
//! ([`super::step`]), which also says how the row term is estimated for selection.
//!
//! ## References
//!
//! - Shao & Badler 1993, "Analysis and acceleration of progressive refinement radiosity
//!   method", Fourth Eurographics Workshop on Rendering, 247–258.

use crate::shooting::overshooting::overshoot::{AmbientTerm, Overshoot, RowTerm};

/// Shao's overshoot.
pub const RULE: Overshoot = Overshoot { row: Some(RowTerm::Positive), ambient: AmbientTerm::Off, omega: 1.0 };
