//! `feda`: overshooting by the ambient term (Feda & Purgathofer 1992).
//!
//! Rule: `ΔB⁺_j = ρ_j R̄ ΔB̄`, with `ΔB̄ = Σ_k A_k ΔB_k / Σ_k A_k` the ambient unshot radiosity
//! and `R̄ = 1/(1 − ρ̄)`, `ρ̄` the area-weighted mean reflectivity, per channel: the light the
//! shooter would get back from all future bounces if the unshot light were spread evenly over
//! the scene. The step is the shared overshooting step ([`super::step`]); the
//! overshoot needs no row, so selection uses it exactly for every patch.
//!
//! ## References
//!
//! - Feda & Purgathofer 1992, "Accelerating radiosity by overshooting", Third Eurographics
//!   Workshop on Rendering, 21–32.

use crate::shooting::overshooting::overshoot::{AmbientTerm, Overshoot};

/// Feda's overshoot.
pub const RULE: Overshoot = Overshoot { row: None, ambient: AmbientTerm::AllBounces, omega: 1.0 };
