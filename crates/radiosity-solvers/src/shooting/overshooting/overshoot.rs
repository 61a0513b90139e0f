//! The overshoot rule types: which terms a variant's overshoot `ΔB⁺` uses ([`Overshoot`]),
//! shared by the variants (`feda`, `shao`, `xu`, `relax-ω`) that define one and by the
//! overshooting step that applies it ([`crate::shooting::overshooting::step`]).
//!
//! Per channel `c`: `ΔB⁺_jc = ρ_jc · (row term + a_c ΔB̄_c) + (ω − 1) ΔB_jc`, with the row
//! term a sum along the patch's own row ([`RowTerm`]) and `a_c` the ambient weight
//! ([`AmbientTerm`]). This module imports nothing of the crate.

use radiosity_core::Real;

/// A sum along the shooter's own row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowTerm {
    /// `Σ_k F_jk ΔB_k`.
    Signed,
    /// `Σ_k F_jk max(ΔB_k, 0)`.
    Positive,
}

/// The ambient term's weight `a_c` on `ΔB̄_c`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AmbientTerm {
    /// No ambient term.
    Off,
    /// `a = R̄ = 1/(1 − ρ̄)`: all future bounces of the ambient light (Feda).
    AllBounces,
    /// `a = ρ̄ R̄`: the bounces after the first (Xu's second part).
    LaterBounces,
}

/// Which terms an overshooting variant uses; all off is PR.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overshoot {
    /// The row term, if any.
    pub row: Option<RowTerm>,
    /// The ambient term.
    pub ambient: AmbientTerm,
    /// `ω`: the relaxation term is `(ω − 1) ΔB_j` (1 for none).
    pub omega: Real,
}

impl Overshoot {
    /// No overshoot: progressive refinement.
    pub const NONE: Overshoot = Overshoot { row: None, ambient: AmbientTerm::Off, omega: 1.0 };
}
