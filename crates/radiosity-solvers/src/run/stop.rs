//! Stop rules (docs/cli.md, "Stop rules") and why a run ended.
//!
//! Rules are a comma list, and the first that holds stops the run: a count of any paid unit
//! of cost ([`Unit`]: `columns=N`, `columns=2n` (a multiple of the patch count), `products=40`,
//! `rays=1e7` (rays cast by a solver that samples transport), `links=1e9` (links of a
//! hierarchy touched), each also as a multiple of `n`), `steps=N` (also `steps=3n`),
//! `rms=1e-3`, `residual=1e-4`, `std_error=1e-2` (the solver's own standard error, for a
//! solver whose answer is an estimate, [`crate::Solver::standard_error`]; never met by one
//! without),
//! `time=30s` (`ms`, `s` or `min`, on the run's clock: measured, or charged by the source,
//! [`crate::Problem::clock`]). Every run ends even if no rule can hold any more: at
//! round-off convergence (nothing left to shoot or gather), at a step cap of `20n` steps,
//! raised to the largest `steps=` or `columns=` rule given and lifted by a `time=` rule, or
//! when the residual power shows that the iteration diverges ([`crate::run::executor`]).

use crate::error::SolverError;
use crate::run::cost::Unit;
use radiosity_core::Real;
use std::time::Duration;

/// A count that may be given in multiples of the number of patches `n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Count {
    /// An absolute number.
    Absolute(u64),
    /// A multiple of `n`.
    PerPatch(f64),
}

impl Count {
    /// A count as written: a positive whole number (`480`, `1e7`) or a positive multiple of
    /// `n` (`2n`, `n`, `0.5n`); otherwise why not, as a clause (`expected …`).
    pub fn parse(value: &str) -> Result<Count, &'static str> {
        if let Some(m) = value.strip_suffix('n') {
            let m = if m.is_empty() { 1.0 } else { m.parse::<f64>().map_err(|_| "expected a number before n")? };
            if !(m.is_finite() && m > 0.0) {
                return Err("the multiple of n must be positive");
            }
            return Ok(Count::PerPatch(m));
        }
        // A whole number, also in exponent form (`1e7`).
        match value.parse::<u64>().ok().or_else(|| {
            let v = value.parse::<f64>().ok()?;
            (v.is_finite() && v >= 1.0 && v.fract() == 0.0 && v < 1.8e19).then_some(v as u64)
        }) {
            Some(k) if k > 0 => Ok(Count::Absolute(k)),
            _ => Err("expected a positive integer (such as 480 or 1e7) or a multiple of n such as 2n"),
        }
    }

    /// The count for a system of `n` patches.
    pub fn resolve(self, n: usize) -> u64 {
        match self {
            Count::Absolute(k) => k,
            Count::PerPatch(m) => (m * n as f64).round() as u64,
        }
    }
}

/// One stop rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StopRule {
    /// Stop once this much was spent in a paid unit ([`Unit::paid`]): columns computed,
    /// products, rays cast, links touched ([`crate::Problem::spent`]).
    Spent(Unit, Count),
    /// Stop after this many steps.
    Steps(Count),
    /// Stop once the observed `e_rms` is at most this.
    Rms(Real),
    /// Stop once the solver's residual power is at most this.
    Residual(Real),
    /// Stop once the solver's standard error, relative as e_rms is
    /// ([`crate::StandardError::relative_rms`]), is at most this: for the solvers whose answer
    /// is an estimate; a solver without one never meets it.
    StdError(Real),
    /// Stop once the run's time (form factors and solving) reaches this, on the run's clock
    /// ([`crate::Problem::clock`]): the seconds every report of the run prints.
    Time(Duration),
}

/// The shorter of a number's plain and exponent forms (`0.05`, `1e-3`), plain on a tie.
fn short(v: f64) -> String {
    let (plain, exponent) = (format!("{v}"), format!("{v:e}"));
    if exponent.len() < plain.len() { exponent } else { plain }
}

/// As written in a rule: `480`, `2n`, `n`.
impl std::fmt::Display for Count {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Count::Absolute(k) => write!(f, "{k}"),
            Count::PerPatch(1.0) => write!(f, "n"),
            Count::PerPatch(m) => write!(f, "{}n", short(m)),
        }
    }
}

/// As written in a rule list, in a form [`StopRules::parse`] reads back: `columns=2n`,
/// `rms=1e-3`, `time=30s`.
impl std::fmt::Display for StopRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            StopRule::Spent(unit, c) => write!(f, "{}={c}", unit.key()),
            StopRule::Steps(c) => write!(f, "steps={c}"),
            StopRule::Rms(e) => write!(f, "rms={}", short(e)),
            StopRule::Residual(r) => write!(f, "residual={}", short(r)),
            StopRule::StdError(s) => write!(f, "std_error={}", short(s)),
            StopRule::Time(t) => write!(f, "time={}s", short(t.as_secs_f64())),
        }
    }
}

/// A list of stop rules; the first that holds stops the run.
#[derive(Clone, Debug, PartialEq)]
pub struct StopRules {
    /// The rules, in the order given.
    pub rules: Vec<StopRule>,
    /// The step cap, in multiples of `n` (default 20).
    pub step_cap: f64,
}

impl Default for StopRules {
    fn default() -> Self {
        StopRules { rules: Vec::new(), step_cap: 20.0 }
    }
}

/// The rules' keys that are not a unit of cost, for a typo's suggestion.
const OTHER_KEYS: [&str; 5] = ["steps", "rms", "residual", "std_error", "time"];

fn bad(rule: &str, reason: &str) -> SolverError {
    SolverError::BadRule { rule: rule.to_string(), reason: reason.to_string() }
}

fn parse_count(rule: &str, value: &str) -> Result<Count, SolverError> {
    Count::parse(value).map_err(|reason| bad(rule, reason))
}

fn parse_positive(rule: &str, value: &str) -> Result<Real, SolverError> {
    match value.parse::<Real>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(bad(rule, "expected a positive number")),
    }
}

fn parse_duration(rule: &str, value: &str) -> Result<Duration, SolverError> {
    let (number, scale) = if let Some(v) = value.strip_suffix("ms") {
        (v, 1e-3)
    } else if let Some(v) = value.strip_suffix("min") {
        (v, 60.0)
    } else if let Some(v) = value.strip_suffix('s') {
        (v, 1.0)
    } else {
        return Err(bad(rule, "expected a duration with a unit: ms, s or min"));
    };
    let seconds = parse_positive(rule, number)? * scale;
    Ok(Duration::from_secs_f64(seconds))
}

impl StopRules {
    /// Parses a comma list of rules (an empty string gives no rule: only round-off and the
    /// step cap stop the run).
    pub fn parse(list: &str) -> Result<StopRules, SolverError> {
        let mut rules = Vec::new();
        for rule in list.split(',').map(str::trim).filter(|r| !r.is_empty()) {
            let (key, value) = rule.split_once('=').ok_or_else(|| bad(rule, "expected key=value"))?;
            let key = key.trim();
            if let Some(unit) = Unit::from_key(key) {
                rules.push(StopRule::Spent(unit, parse_count(rule, value.trim())?));
                continue;
            }
            rules.push(match key {
                "steps" => StopRule::Steps(parse_count(rule, value.trim())?),
                "rms" => StopRule::Rms(parse_positive(rule, value.trim())?),
                "residual" => StopRule::Residual(parse_positive(rule, value.trim())?),
                "std_error" => StopRule::StdError(parse_positive(rule, value.trim())?),
                "time" => StopRule::Time(parse_duration(rule, value.trim())?),
                other => {
                    let units = Unit::ALL.into_iter().filter(|u| u.paid()).map(Unit::key);
                    let guess = radiosity_core::suggest::did_you_mean(other, units.chain(OTHER_KEYS));
                    return Err(bad(rule, &format!("unknown rule{guess}")));
                }
            });
        }
        Ok(StopRules { rules, ..StopRules::default() })
    }

    /// Whether any rule needs the error against a reference (`rms=`).
    pub fn needs_error(&self) -> bool {
        self.rules.iter().any(|r| matches!(r, StopRule::Rms(_)))
    }

    /// Whether any rule needs the solver's standard error (`std_error=`).
    pub fn needs_standard_error(&self) -> bool {
        self.rules.iter().any(|r| matches!(r, StopRule::StdError(_)))
    }
}

/// Why a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum TerminationReason {
    /// A rule on a unit of cost reached (`columns=`, `rays=`), with what was spent.
    Spent(Unit, u64),
    /// `steps=` reached.
    Steps(u64),
    /// `rms=` reached.
    Rms(Real),
    /// `residual=` reached.
    Residual(Real),
    /// `std_error=` reached, with the standard error then.
    StdError(Real),
    /// `time=` reached.
    Time(Duration),
    /// Nothing left to do: the residual is zero or at round-off.
    RoundOff,
    /// The step cap was reached before any rule held.
    StepCap(u64),
    /// The residual power rose far above its minimum ([`crate::Executor`]): the iteration
    /// diverges, usually because the form factors are not physical (`ρ F` row sums above 1).
    /// The run's state is returned as it stands.
    Diverged {
        /// The steps taken when the rise was seen.
        step: u64,
        /// The residual power then.
        residual: Real,
        /// The smallest residual power before it.
        minimum: Real,
    },
    /// An observer asked the run to end ([`crate::Observer::wants_stop`]): a caller watching
    /// it (a Python callback, an interactive session) had seen enough.
    Stopped {
        /// The steps taken.
        step: u64,
    },
    /// The method could not go on ([`crate::SolverError::Breakdown`]): the state is the one
    /// before the step that broke down.
    Breakdown {
        /// The step that broke down.
        step: u64,
        /// Why, in one sentence.
        reason: String,
    },
}

impl std::fmt::Display for TerminationReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TerminationReason::Spent(unit, k) => write!(f, "{k} {}", unit.spent()),
            TerminationReason::Steps(k) => write!(f, "{k} steps taken"),
            TerminationReason::Rms(e) => write!(f, "e_rms reached {e:e}"),
            TerminationReason::Residual(r) => write!(f, "residual power reached {r:e}"),
            TerminationReason::StdError(s) => write!(f, "standard error reached {s:e}"),
            TerminationReason::Time(t) => write!(f, "time limit of {:.3} s reached", t.as_secs_f64()),
            TerminationReason::RoundOff => write!(f, "converged to round-off"),
            TerminationReason::StepCap(k) => write!(f, "step cap of {k} steps reached before any rule held"),
            TerminationReason::Diverged { step, residual, minimum } => {
                write!(f, "diverged: the residual power rose from {minimum:.1e} to {residual:.1e} by step {step}")
            }
            TerminationReason::Stopped { step } => write!(f, "stopped by its observer after {step} steps"),
            TerminationReason::Breakdown { step, reason } => write!(f, "broke down at step {step}: {reason}"),
        }
    }
}
