//! What every solver runs on, whatever its family: the problem it reads form factors from,
//! the state it updates and what it costs, the stop rules, the executor that loops, the solver's own record and
//! its residual bound, and the standard error of a solver whose answer is an estimate.
//!
//! Nothing here imports a solver family: the families import this room, never the reverse.

pub(crate) mod cost;
pub(crate) mod executor;
pub(crate) mod problem;
pub(crate) mod record;
pub(crate) mod residual_bound;
pub(crate) mod standard_error;
pub(crate) mod state;
pub(crate) mod stop;
