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
        "invalid stop rule '{rule}': {reason}; rules are columns=N, columns=2n, steps=N, rays=1e7, links=1e9, rms=1e-3, residual=1e-4, time=30s"
    )]
    BadRule {
        /// The rule as written.
        rule: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A group gathering system `Φ_rr δ = R` that LU cannot solve ([`crate::GroupGathering`];
    /// group shooting falls back to point shots instead, [`crate::group_shot`]).
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
    /// A solver name that names no solver ([`crate::SolverRegistry::build`]). Its message is
    /// one sentence: the name, the nearest known name when one is close, and where every
    /// family is listed; the list itself is `valid`.
    #[error("{}", unknown_solver(name, suggestion.as_deref()))]
    UnknownSolver {
        /// The name given.
        name: String,
        /// The solvers there are, as listed to users ([`crate::SolverRegistry::names`]).
        valid: String,
        /// The known name nearest to the one given, when one is near enough to be a typo.
        suggestion: Option<String>,
    },
    /// A solver whose hypothesis this system or these form factors do not satisfy, refused
    /// before its first step or stopped when the hypothesis is seen to fail (conjugate
    /// gradients on form factors that are not reciprocal, [`crate::ConjugateGradients`]).
    #[error("{solver} cannot solve this system: {reason}")]
    NotApplicable {
        /// The solver.
        solver: String,
        /// Why, in one sentence.
        reason: String,
    },
    /// The method cannot go on from this state (a recurrence that breaks down, a system seen
    /// not to be positive definite). Returned by [`crate::Solver::next_step`] with the state
    /// as it was before the step, it ends the run with
    /// [`crate::TerminationReason::Breakdown`] and the state kept.
    #[error("{solver} broke down: {reason}")]
    Breakdown {
        /// The solver.
        solver: String,
        /// Why, in one sentence.
        reason: String,
    },
    /// A stop rule that needs the error against a reference (`rms=`) in a run without an
    /// error monitor ([`crate::ErrorMonitor`]): the rule could never hold.
    #[error("the stop rule {rule} needs e_rms against a reference solution, which this run does not measure")]
    ErrorNotMeasured {
        /// The rule, as the stop rules show it (`rms=0.001`).
        rule: String,
    },
}

/// The message of [`SolverError::UnknownSolver`].
fn unknown_solver(name: &str, suggestion: Option<&str>) -> String {
    let guess = suggestion.map(|s| format!(" (did you mean '{s}'?)")).unwrap_or_default();
    format!(
        "unknown solver '{name}'{guess}; `cargo xtask solve --help` lists every solver family (SolverRegistry::help)"
    )
}
