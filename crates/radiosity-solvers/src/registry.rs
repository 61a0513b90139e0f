//! Solvers by name: the families of command-line names (docs/cli.md), each a typed parameter
//! struct, and the [`SolverRegistry`] that builds a solver from a name.
//!
//! ## Rule
//!
//! A *family* is a set of names with one syntax (`sor-ω`, `S-gM[-mK][:f=N|auto|timed]…`) and
//! one parameter struct that implements [`SolverParams`]: `FromStr` reads a name into the
//! struct, and [`SolverParams::build`] makes the solver. Parsing says one of three things: the
//! name is not of this family ([`ParseSolverError::OtherFamily`]); it is, but its parameters
//! are refused ([`ParseSolverError::Refused`], a message beginning `solver '…':` with the name
//! as written); or here are the parameters.
//!
//! A registry holds families in order. [`SolverRegistry::build`] asks each in turn and the
//! first that claims the name decides: it builds the solver or refuses the parameters. When
//! none claims it, the error is [`SolverError::UnknownSolver`], with the list of names
//! ([`SolverRegistry::names`]) and, when a known name is within a small edit distance, that
//! name as a suggestion ([`SolverRegistry::suggest`]).
//!
//! The built-in families ([`SolverRegistry::builtin`]), in this order: [`JacobiParams`],
//! [`GaussSeidelParams`], [`PointShootingParams`], [`GroupGatheringParams`],
//! [`GroupShootingParams`], [`GroupAcceleratedParams`], [`NodeShootingParams`], [`CgParams`], [`GmresParams`],
//! [`BicgstabParams`], [`StochasticJacobiParams`] and [`RandomWalkParams`]. Library users add their own,
//! typed ([`SolverRegistry::register`]) or as a closure ([`SolverRegistry::register_fn`]);
//! built-in families come first, so a new family cannot change what a built-in name means
//! unless the user starts from [`SolverRegistry::empty`].
//!
//! Suggestions use the Damerau–Levenshtein distance (adjacent transpositions count as one
//! edit) from the `strsim` crate, against every family's example names, their heads without
//! `:key=value` parameters, and the plain names in its syntax; a name is suggested when at
//! most [`radiosity_core::suggest::suggestion_distance`] edits away (the nearest, the first family's on a tie).
//!
//! ## References
//!
//! - Damerau 1964, "A technique for computer detection and correction of spelling errors",
//!   Communications of the ACM 7(3).

use crate::error::SolverError;
use crate::gathering::gauss_seidel::GaussSeidelParams;
use crate::gathering::jacobi::JacobiParams;
use crate::group::group_accelerated::GroupAcceleratedParams;
use crate::group::group_gathering::GroupGatheringParams;
use crate::group::group_shooting::GroupShootingParams;
use crate::hierarchy::node_shooting::NodeShootingParams;
use crate::krylov::bicgstab::BicgstabParams;
use crate::krylov::cg::CgParams;
use crate::krylov::gmres::GmresParams;
use crate::naming::{ParseSolverError, SolverParams, named, split_params};
use crate::run::executor::Solver;
use crate::shooting::overshooting::step::PointShootingParams;
use crate::stochastic::random_walk::RandomWalkParams;
use crate::stochastic::stochastic_jacobi::StochasticJacobiParams;
use std::fmt;
use std::sync::{Arc, OnceLock};

/// What a registry entry does with a name: `Ok(None)` when the name is not its own.
type BuildFn = dyn Fn(&str) -> Result<Option<Box<dyn Solver>>, SolverError> + Send + Sync;

/// One family of a [`SolverRegistry`].
#[derive(Clone)]
pub struct SolverEntry {
    syntax: String,
    help: String,
    examples: Vec<String>,
    build: Arc<BuildFn>,
}

impl SolverEntry {
    /// The family's names, with placeholders.
    pub fn syntax(&self) -> &str {
        &self.syntax
    }

    /// What the family does, in one line.
    pub fn help(&self) -> &str {
        &self.help
    }

    /// Example names.
    pub fn examples(&self) -> &[String] {
        &self.examples
    }

    /// The solver `name` designates if it is this family's (`Ok(None)` otherwise).
    pub fn build(&self, name: &str) -> Result<Option<Box<dyn Solver>>, SolverError> {
        (self.build)(name)
    }

    /// The plain names of the syntax (alternatives without placeholders or options, such as
    /// `jacobi` or `xu-direct`).
    fn plain_names(&self) -> impl Iterator<Item = &str> {
        self.syntax.split(", ").map(|alt| alt.split('[').next().unwrap_or(alt)).filter(|alt| {
            !alt.is_empty() && alt.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-')
        })
    }
}

impl fmt::Debug for SolverEntry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SolverEntry")
            .field("syntax", &self.syntax)
            .field("help", &self.help)
            .field("examples", &self.examples)
            .finish_non_exhaustive()
    }
}

/// Families of solver names, tried in order (module doc).
#[derive(Clone, Debug, Default)]
pub struct SolverRegistry {
    entries: Vec<SolverEntry>,
}

impl SolverRegistry {
    /// A registry with no family: every name is unknown until families are registered.
    pub fn empty() -> SolverRegistry {
        SolverRegistry::default()
    }

    /// The built-in families (module doc). Cheap: twelve entries.
    pub fn builtin() -> SolverRegistry {
        let mut registry = SolverRegistry::empty();
        registry
            .register::<JacobiParams>()
            .register::<GaussSeidelParams>()
            .register::<PointShootingParams>()
            .register::<GroupGatheringParams>()
            .register::<GroupShootingParams>()
            .register::<GroupAcceleratedParams>()
            .register::<NodeShootingParams>()
            .register::<CgParams>()
            .register::<GmresParams>()
            .register::<BicgstabParams>()
            .register::<StochasticJacobiParams>()
            .register::<RandomWalkParams>();
        registry
    }

    /// Adds the family of parameter struct `P`, after those already there.
    pub fn register<P: SolverParams + 'static>(&mut self) -> &mut SolverRegistry {
        self.register_fn(P::SYNTAX, P::HELP, P::EXAMPLES.iter().copied(), |name| match name.parse::<P>() {
            Ok(params) => params.build().map(Some),
            Err(ParseSolverError::OtherFamily) => Ok(None),
            Err(ParseSolverError::Refused(e)) => Err(e),
        })
    }

    /// Adds a family, after those already there, from its syntax, help line, example names and
    /// a closure that builds the solver a name designates, `Ok(None)` for a name that is not
    /// its own, or refuses its parameters ([`SolverError::BadParams`]; a message that does not
    /// begin `solver '…':` is given that beginning).
    pub fn register_fn<F>(
        &mut self,
        syntax: impl Into<String>,
        help: impl Into<String>,
        examples: impl IntoIterator<Item = impl Into<String>>,
        build: F,
    ) -> &mut SolverRegistry
    where
        F: Fn(&str) -> Result<Option<Box<dyn Solver>>, SolverError> + Send + Sync + 'static,
    {
        self.entries.push(SolverEntry {
            syntax: syntax.into(),
            help: help.into(),
            examples: examples.into_iter().map(Into::into).collect(),
            build: Arc::new(build),
        });
        self
    }

    /// The families, in the order they are tried.
    pub fn entries(&self) -> &[SolverEntry] {
        &self.entries
    }

    /// The solver `name` designates. Every refusal names the solver as written:
    /// [`SolverError::UnknownSolver`] when no family takes the name, [`SolverError::BadParams`]
    /// beginning `solver '…':` for parameters out of range.
    pub fn build(&self, name: &str) -> Result<Box<dyn Solver>, SolverError> {
        for entry in &self.entries {
            match entry.build(name) {
                Ok(Some(solver)) => return Ok(solver),
                Ok(None) => continue,
                Err(e) => return Err(named(name, e)),
            }
        }
        Err(SolverError::UnknownSolver { name: name.to_string(), valid: self.names(), suggestion: self.suggest(name) })
    }

    /// The names there are, as listed to users: each family's syntax, followed by the examples
    /// that are not plain names of it (`sor-ω (e.g. sor-1.2)`), families separated by `; `.
    pub fn names(&self) -> String {
        let families: Vec<String> = self
            .entries
            .iter()
            .map(|entry| {
                let plain: Vec<&str> = entry.plain_names().collect();
                let extra: Vec<&str> =
                    entry.examples.iter().map(String::as_str).filter(|e| !plain.contains(e)).collect();
                if extra.is_empty() {
                    entry.syntax.clone()
                } else {
                    format!("{} (e.g. {})", entry.syntax, extra.join(", "))
                }
            })
            .collect();
        families.join("; ")
    }

    /// A help text for a command line: one line per family, its syntax, then its examples,
    /// then what it does; each line ends with a newline.
    pub fn help(&self) -> String {
        let width = |text: &dyn Fn(&SolverEntry) -> String| {
            self.entries.iter().map(|e| text(e).chars().count()).filter(|&w| w <= COLUMN).max().unwrap_or(0)
        };
        let examples = |e: &SolverEntry| format!("e.g. {}", e.examples.join(", "));
        let (syntax_width, examples_width) = (width(&|e| e.syntax.clone()), width(&examples));
        let mut out = String::new();
        for entry in &self.entries {
            // A syntax too long for the column is not padded to, nor are its examples.
            let fits = entry.syntax.chars().count() <= syntax_width;
            let (syntax, examples) = if fits {
                (pad(&entry.syntax, syntax_width), pad(&examples(entry), examples_width))
            } else {
                (entry.syntax.clone(), examples(entry))
            };
            let line = format!("{syntax}  {examples}  {}", entry.help);
            out.push_str(line.trim_end());
            out.push('\n');
        }
        out
    }

    /// The known name nearest to `name` (module doc), if one is near enough to be a typo. The
    /// heads are compared; the parameters given (`:f=10`) are kept.
    pub fn suggest(&self, name: &str) -> Option<String> {
        let (head, params) = split_params(name);
        let candidates = self.entries.iter().flat_map(|entry| {
            let examples = entry.examples.iter().flat_map(|e| [e.as_str(), split_params(e).0]);
            examples.chain(entry.plain_names()).collect::<Vec<_>>()
        });
        let candidate = radiosity_core::suggest::nearest(head, candidates)?;
        Some(if params.is_empty() { candidate.to_string() } else { format!("{candidate}:{params}") })
    }
}

/// Columns of [`SolverRegistry::help`] wider than this are not padded to.
const COLUMN: usize = 40;

/// `text` padded with spaces to `width` characters.
fn pad(text: &str, width: usize) -> String {
    let length = text.chars().count();
    format!("{text}{}", " ".repeat(width.saturating_sub(length)))
}

/// The built-in registry, built once ([`crate::solver_by_name`]).
pub(crate) fn builtin() -> &'static SolverRegistry {
    static BUILTIN: OnceLock<SolverRegistry> = OnceLock::new();
    BUILTIN.get_or_init(SolverRegistry::builtin)
}
