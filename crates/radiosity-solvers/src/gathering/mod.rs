//! Point gathering: the gathering update ([`rule`]) and the solvers built on it, `jacobi`
//! ([`jacobi`]) and `gauss-seidel`, `sor-ω` ([`gauss_seidel`]).

pub(crate) mod gauss_seidel;
pub(crate) mod jacobi;
pub(crate) mod rule;
