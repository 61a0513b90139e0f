//! Overshooting: the overshoot rule types ([`overshoot`]), the variants that each define one
//! (`feda`, `shao`, `xu`, `relax-ω`), and the step that shoots with it, with the
//! [`ShootingMethod`](step::ShootingMethod) a point shooting name designates ([`step`]).
//!
//! The variants import only [`overshoot`]; [`step`] imports the variants.

pub(crate) mod feda;
pub(crate) mod overshoot;
pub(crate) mod relax;
pub(crate) mod shao;
pub(crate) mod step;
pub(crate) mod xu;
