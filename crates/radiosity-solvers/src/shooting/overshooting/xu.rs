//! `xu`: overshooting by direct illumination plus an estimate of the multiple reflections
//! (after Xu & Fussell 1994).
//!
//! Rule: `ΔB⁺_j = ρ_j (Σ_k F_jk ΔB_k + ρ̄ R̄ ΔB̄)`, per channel, with `ΔB̄` the area-weighted
//! ambient unshot radiosity, `ρ̄` the area-weighted mean reflectivity and `R̄ = 1/(1 − ρ̄)`.
//! The first part is the light the shooter receives directly when the patches it sees shoot
//! (signed: earlier overshoots are taken back); the second is the ambient estimate of every
//! bounce after that.
//!
//! **This form is a reconstruction.** Xu & Fussell's paper was not available to us; Rousselle
//! & Renaud describe the method only as "direct illumination plus an estimation of the energy
//! due to multiple reflections in the scene before shooting". The two parts are therefore
//! separately switchable: `xu-direct` keeps only the row term, `xu-ambient` only the ambient
//! term, so what each contributes can be measured.
//!
//! The step is the shared overshooting step ([`super::step`]), which also says how the
//! row term is estimated for selection.
//!
//! ## References
//!
//! - Xu & Fussell 1994, "A fast solver of radiosity equation systems", Pacific Graphics.
//! - Rousselle & Renaud, "Group accelerated shooting methods for radiosity", §2.

use crate::shooting::overshooting::overshoot::{AmbientTerm, Overshoot, RowTerm};

/// Which parts of Xu's overshoot to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct XuParts {
    /// The direct part `Σ_k F_jk ΔB_k`.
    pub direct: bool,
    /// The multiple-reflection part `ρ̄ R̄ ΔB̄`.
    pub ambient: bool,
}

impl XuParts {
    /// Both parts: `xu`.
    pub const BOTH: XuParts = XuParts { direct: true, ambient: true };

    /// The command-line name of this combination.
    pub fn name(self) -> &'static str {
        match (self.direct, self.ambient) {
            (true, true) => "xu",
            (true, false) => "xu-direct",
            (false, true) => "xu-ambient",
            (false, false) => "pr",
        }
    }
}

/// Xu's overshoot with the parts chosen (`XuParts::BOTH` for `xu`).
pub fn rule(parts: XuParts) -> Overshoot {
    Overshoot {
        row: parts.direct.then_some(RowTerm::Signed),
        ambient: if parts.ambient { AmbientTerm::LaterBounces } else { AmbientTerm::Off },
        omega: 1.0,
    }
}
