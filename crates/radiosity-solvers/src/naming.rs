//! Reading solver names: the [`SolverParams`] trait every family of names implements, the
//! [`ParseSolverError`] its `FromStr` gives, and the helpers the families share to take a name
//! apart (`head:params`, `head-gM`, `head-mK`) and to name the solver in a refusal.
//!
//! Parsing says one of three things: the name is not of this family
//! ([`ParseSolverError::OtherFamily`]); it is, but its parameters are refused
//! ([`ParseSolverError::Refused`], a message beginning `solver '…':` with the name as
//! written, [`named`]); or here are the parameters. [`validated`] lets `FromStr` refuse
//! parameters out of range, not only bad syntax, by building the solver once.
//!
//! This module imports no solver family: every family's module uses it, and the registry
//! ([`crate::registry`]) builds on the families.

use crate::error::SolverError;
use crate::run::executor::Solver;
use std::str::FromStr;
use thiserror::Error;

/// Why a family's `FromStr` did not give parameters.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum ParseSolverError {
    /// The name is not one of this family's: another family may take it.
    #[error("the name is not one of this solver family's")]
    OtherFamily,
    /// The name is this family's, but its parameters are refused (the message names the solver
    /// as written).
    #[error(transparent)]
    Refused(#[from] SolverError),
}

/// A family of solver names and its parameters: the typed constructor of a solver.
///
/// `FromStr` reads a command-line name (module doc); [`SolverParams::build`] makes the solver.
/// The constants describe the family to users.
pub trait SolverParams: FromStr<Err = ParseSolverError> {
    /// The family's names, with placeholders (`gauss-seidel, sor-ω`).
    const SYNTAX: &'static str;
    /// What the family does, in one line.
    const HELP: &'static str;
    /// Names of the family as users write them, the first ones the most common.
    const EXAMPLES: &'static [&'static str];

    /// The solver these parameters designate. Parameters out of range are
    /// [`SolverError::BadParams`].
    fn build(&self) -> Result<Box<dyn Solver>, SolverError>;
}

/// Gives a [`SolverError::BadParams`] that does not name its solver the beginning
/// `solver 'name': `.
pub(crate) fn named(name: &str, e: SolverError) -> SolverError {
    match e {
        SolverError::BadParams(reason) if !reason.starts_with("solver '") => {
            SolverError::BadParams(format!("solver '{name}': {reason}"))
        }
        e => e,
    }
}

/// Splits `head:params` at the first colon (`params` empty without one).
pub(crate) fn split_params(name: &str) -> (&str, &str) {
    name.split_once(':').unwrap_or((name, ""))
}

/// Splits `head-gM` into `head` and `M` (with `marker` `-g`; `-m` for a memory).
pub(crate) fn split_size<'a>(name: &'a str, marker: &str) -> Option<(&'a str, usize)> {
    let (head, size) = name.rsplit_once(marker)?;
    if size.is_empty() || !size.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some((head, size.parse().ok()?))
}

/// Claims `name` for a family of one plain name, `plain`, that takes no parameters:
/// [`ParseSolverError::OtherFamily`] for another head, a refusal for parameters.
pub(crate) fn plain_name(name: &str, plain: &str) -> Result<(), ParseSolverError> {
    let (head, params) = split_params(name);
    if head != plain {
        return Err(ParseSolverError::OtherFamily);
    }
    no_params(head, params)
}

/// Refuses parameters for a family that takes none.
pub(crate) fn no_params(head: &str, params: &str) -> Result<(), ParseSolverError> {
    if params.is_empty() {
        Ok(())
    } else {
        Err(SolverError::BadParams(format!("solver '{head}' takes no parameters, not '{params}'")).into())
    }
}

/// `params` if they build a solver, or the refusal, naming the solver as written (`name`):
/// the check that lets `FromStr` refuse parameters out of range, not only bad syntax.
pub(crate) fn validated<P: SolverParams>(name: &str, params: P) -> Result<P, ParseSolverError> {
    params.build().map_err(|e| ParseSolverError::Refused(named(name, e)))?;
    Ok(params)
}
