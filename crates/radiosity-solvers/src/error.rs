//! Typed errors of the solvers.

use thiserror::Error;

/// What can stop a solver short of its stop rules.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum SolverError {
    /// A radiosity became NaN or infinite.
    #[error("step {step}: the radiosity of patch {patch} became {value}; the run was stopped")]
    NonFinite {
        /// The step that produced it.
        step: u64,
        /// The patch.
        patch: usize,
        /// The value.
        value: f64,
    },
    /// The form-factor source and the system disagree on the number of patches.
    #[error("the form factors have {columns} patches but the system has {system}")]
    SizeMismatch {
        /// Patches of the column source.
        columns: usize,
        /// Patches of the system.
        system: usize,
    },
    /// A stop rule that does not parse.
    #[error(
        "invalid stop rule '{rule}': {reason}; rules are columns=N, columns=2n, steps=N, rms=1e-3, residual=1e-4, time=30s"
    )]
    BadRule {
        /// The rule as written.
        rule: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A group gathering system `Φ_rr δ = R` that LU cannot solve ([`crate::group_gathering`];
    /// group shooting falls back to point shots instead, [`crate::group_step`]).
    #[error(
        "step {step}: the group system of {size} patches is singular in channel {channel} (pivot {pivot} is {value}); \
         are the form factors' rows summing far above 1?"
    )]
    SingularGroup {
        /// The step.
        step: u64,
        /// Patches in the group.
        size: usize,
        /// The channel.
        channel: usize,
        /// The pivot's index.
        pivot: usize,
        /// Its value.
        value: f64,
    },
    /// Invalid solver parameters.
    #[error("{0}")]
    BadParams(String),
    /// A solver name that names no solver.
    #[error("unknown solver '{name}'; solvers are {valid}")]
    UnknownSolver {
        /// The name given.
        name: String,
        /// The solvers there are, as listed to users.
        valid: &'static str,
    },
}
