//! The solvers that estimate transport with rays and never form `F` (stochastic relaxation and
//! random walks, docs/stochastic.md), over [`crate::Problem::cast`], and the random numbers
//! they share.

pub(crate) mod estimate;
pub(crate) mod exact_sum;
pub(crate) mod random_walk;
pub(crate) mod ranks;
pub(crate) mod sequence;
pub(crate) mod stochastic_jacobi;
