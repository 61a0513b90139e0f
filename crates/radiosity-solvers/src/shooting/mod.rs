//! Point shooting: the shooting update ([`rule`]), the solvers `southwell` ([`southwell`]) and
//! `pr` ([`progressive`]), and overshooting with its variants ([`overshooting`]).

pub(crate) mod overshooting;
pub(crate) mod progressive;
pub(crate) mod rule;
pub(crate) mod southwell;
