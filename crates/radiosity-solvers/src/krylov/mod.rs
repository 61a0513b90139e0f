//! Krylov solvers, the numerical analyst's comparators: what they share ([`operator`]: the
//! operator `A = I − diag(ρ) F` through columns, inner products per channel), and `cg`
//! ([`cg`]), `gmres-K` ([`gmres`]) and `bicgstab` ([`bicgstab`]).

pub(crate) mod bicgstab;
pub(crate) mod cg;
pub(crate) mod gmres;
pub(crate) mod operator;
