//! How a lab is set up ([`LabOptions`]), how its solvers pay for the columns they fetch
//! ([`ColumnCost`], [`ColumnCharge`]), and where the solvers that sample transport cast their
//! rays ([`Transport`]).

use crate::error::EvalError;
use crate::lab::timing::sample;
use crate::reference::cache::Cache;
use crate::reference::kind::{MemoryBudget, ReferenceKind};
use crate::reference::shooting::ShootingParams;
use crate::reference::solution::ReferenceParams;
use radiosity_core::{ColumnSource, Real};
use std::fmt;
use std::str::FromStr;
use std::time::Instant;

/// How a lab is set up.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct LabOptions {
    /// Keep the stored matrix whenever the reference is `matrix`, so that recorded steps carry
    /// the residual of the displayed radiosity (default). Without it, the matrix is assembled
    /// only when the reference is not in the cache (and then kept, since it is there).
    pub residuals: bool,
    /// Where reference solutions (and stored matrices) are cached; none by default.
    pub cache: Option<Cache>,
    /// How a `matrix` reference is solved.
    pub reference: ReferenceParams,
    /// Which reference to measure against (default `auto`, [`ReferenceKind`]).
    pub kind: ReferenceKind,
    /// How a `shooting` reference is run.
    pub shooting: ShootingParams,
    /// The memory a stored matrix may take; `None`: [`MemoryBudget::from_env`].
    pub memory: Option<MemoryBudget>,
    /// How solvers pay for their columns, and so the clock of their seconds (default
    /// [`ColumnCost::Computed`]).
    pub columns: ColumnCost,
    /// Where the solvers that sample transport cast their rays (default
    /// [`Transport::Scene`]).
    pub transport: Transport,
}

/// Where a lab's solvers that sample transport (`StepKind::Sampled`) cast their rays: the
/// [`radiosity_core::TransportSampler`] of their problem, built once per lab, when the first
/// such run starts.
///
/// - `Scene` (the default): rays through the scene's BVH (`radiosity_ff::SceneTransport`),
///   the exact geometry, which the lab's backend approximates; the sampler states that rows
///   of F sum to 1 (for a control variate) only where the scene analysis finds the scene
///   closed. Its system is the scene's, so e_rms against a reference over another backend
///   includes that backend's form-factor error.
/// - `Matrix`: the lab's stored matrix sampled exactly (`radiosity_core::ColumnTransport`, an
///   alias table per column, built by reading every column): the very system the reference
///   solves, so e_rms is the solver's error alone. It needs the stored matrix: a `matrix`
///   reference (which then keeps the matrix) or a stored backend.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Transport {
    /// Rays in the scene (the default).
    #[default]
    Scene,
    /// The stored matrix, sampled exactly.
    Matrix,
}

impl Transport {
    /// Both, in a fixed order.
    pub const ALL: [Transport; 2] = [Transport::Scene, Transport::Matrix];

    /// The name the command line (`--transport`) and Python (`transport=`) take: `scene` or
    /// `matrix`.
    pub fn name(self) -> &'static str {
        match self {
            Transport::Scene => "scene",
            Transport::Matrix => "matrix",
        }
    }
}

/// Reads [`Transport::name`].
impl FromStr for Transport {
    type Err = EvalError;

    fn from_str(s: &str) -> Result<Transport, EvalError> {
        Transport::ALL.into_iter().find(|t| t.name() == s.trim()).ok_or_else(|| EvalError::InvalidParameter {
            name: "transport",
            value: s.to_string(),
            reason: "it must be scene or matrix",
        })
    }
}

/// [`Transport::name`].
impl fmt::Display for Transport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How a lab's solvers pay for the columns (and rows) of F they fetch, which decides the
/// clock of their seconds ([`crate::Clock`]): computed columns are timed (`measured`), stored
/// ones charged (`charged`).
///
/// The default is `Computed`: the charged seconds of the default comparison's solvers do not
/// rank them as their computed seconds do (`docs/solvers.md`, "The default comparison"), so
/// the seconds a report prints by default are measured ones.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum ColumnCost {
    /// Every column is computed through the backend when a solver asks for it, and its time is
    /// the run's form-factor time (the default).
    #[default]
    Computed,
    /// Where the lab keeps the stored matrix of a geometric backend (a `matrix` reference),
    /// solvers read their columns from it, the same `f32` entries the backend's columns give,
    /// and each column fetched is charged the backend's median time for a fresh column,
    /// measured once on a seeded sample ([`ColumnCharge`]). Elsewhere as `Computed`.
    Charged,
}

impl ColumnCost {
    /// Both ways, in a fixed order.
    pub const ALL: [ColumnCost; 2] = [ColumnCost::Computed, ColumnCost::Charged];

    /// The name the command line (`--columns`) and Python (`columns=`) take: `computed` or
    /// `charged`.
    pub fn name(self) -> &'static str {
        match self {
            ColumnCost::Computed => "computed",
            ColumnCost::Charged => "charged",
        }
    }
}

/// Reads [`ColumnCost::name`].
impl FromStr for ColumnCost {
    type Err = EvalError;

    fn from_str(s: &str) -> Result<ColumnCost, EvalError> {
        ColumnCost::ALL.into_iter().find(|c| c.name() == s.trim()).ok_or_else(|| EvalError::InvalidParameter {
            name: "columns",
            value: s.to_string(),
            reason: "it must be computed or charged",
        })
    }
}

/// [`ColumnCost::name`].
impl fmt::Display for ColumnCost {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The prices a lab charges for the columns its solvers fetch from its stored matrix
/// ([`ColumnCost::Charged`]), measured once on the backend. A fresh column costs the mean of
/// the matrix's assembly when the lab assembled it (every pair once, the cost of all its
/// columns with every pair traced once; or every column once), else the mean over a seeded
/// sample of columns computed one at a time (as solvers fetch them) with the backend's memory
/// of earlier columns forgotten. A recorded column costs the mean over the sample computed
/// again, once the backend has recorded their pairs' visible fractions.
///
/// A run is charged as the backend would have cost it ([`ColumnCharge::column_seconds`]): a
/// column fetched before is charged as recorded; a new one fetched after `known` other
/// columns has `known` of its `n` pairs recorded already (the analytic backend traces each
/// pair once, for the first of its two columns), so it is charged the fresh price less that
/// share of the difference. Rows are charged as the columns of the same patch. A backend that
/// records nothing costs the same either way, and is charged its fresh price.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ColumnCharge {
    /// Mean seconds of a fresh column.
    pub fresh: Real,
    /// Mean seconds of a column whose pairs the backend has recorded (at most `fresh`).
    pub recorded: Real,
    /// Columns timed (twice).
    pub sampled: usize,
    /// Whether `fresh` comes from the matrix's assembly rather than the sample.
    pub from_assembly: bool,
}

impl ColumnCharge {
    /// Columns timed to measure the charge.
    pub const SAMPLE: usize = 8;

    /// Prices given rather than measured: `fresh` seconds a fresh column, `recorded` (at most
    /// `fresh`) one whose pairs the backend has recorded; for runs whose charge must be known
    /// in advance ([`crate::Lab::with_charge`]).
    pub fn new(fresh: Real, recorded: Real) -> ColumnCharge {
        ColumnCharge { fresh, recorded: recorded.min(fresh), sampled: 0, from_assembly: false }
    }

    /// Times [`ColumnCharge::SAMPLE`] seeded columns of `source` (fewer when it has fewer
    /// patches), one at a time, fresh and then again; `assembled`, a fresh column's mean cost
    /// from a matrix assembly, takes the place of the fresh sample's (type doc).
    pub fn measure(source: &dyn ColumnSource, assembled: Option<Real>) -> ColumnCharge {
        let n = source.patch_count();
        let sample = sample(n, Self::SAMPLE.min(n), 0);
        let mut column = vec![0.0; n];
        let mut mean_time = || {
            let total: f64 = sample
                .iter()
                .map(|&j| {
                    let start = Instant::now();
                    source.fill_column(j, &mut column);
                    start.elapsed().as_secs_f64()
                })
                .sum();
            total / sample.len().max(1) as f64
        };
        source.reset_memory();
        let sampled_fresh = mean_time();
        let recorded = mean_time();
        source.reset_memory();
        let fresh = assembled.unwrap_or(sampled_fresh);
        ColumnCharge { fresh, recorded: recorded.min(fresh), sampled: sample.len(), from_assembly: assembled.is_some() }
    }

    /// The seconds charged for a column of an `n`-patch scene fetched after `known` other
    /// columns of the run, `repeated` if it was itself fetched before (type doc).
    pub fn column_seconds(&self, n: usize, known: usize, repeated: bool) -> Real {
        if repeated {
            self.recorded
        } else {
            self.fresh - (self.fresh - self.recorded) * known.min(n) as Real / n.max(1) as Real
        }
    }

    /// One sentence saying how a run's columns were paid for, for reports.
    pub fn describe(&self) -> String {
        let prices = if self.sampled == 0 {
            format!(
                "{:.3} ms a fresh column, {:.3} ms one whose pairs it has recorded (prices given)",
                self.fresh * 1e3,
                self.recorded * 1e3
            )
        } else {
            let fresh = if self.from_assembly { "the matrix's assembly" } else { "the sample" };
            format!(
                "{:.3} ms a fresh column (mean of {fresh}), {:.3} ms one whose pairs it has recorded (mean of {} \
                 columns computed twice)",
                self.fresh * 1e3,
                self.recorded * 1e3,
                self.sampled
            )
        };
        format!("columns read from the stored matrix and charged as the backend computes them: {prices}")
    }
}

impl Default for LabOptions {
    fn default() -> Self {
        LabOptions {
            residuals: true,
            cache: None,
            reference: ReferenceParams::default(),
            kind: ReferenceKind::Auto,
            shooting: ShootingParams::default(),
            memory: None,
            columns: ColumnCost::default(),
            transport: Transport::default(),
        }
    }
}

impl LabOptions {
    /// Sets [`LabOptions::residuals`].
    pub fn with_residuals(mut self, residuals: bool) -> Self {
        self.residuals = residuals;
        self
    }

    /// Sets [`LabOptions::cache`].
    pub fn with_cache(mut self, cache: Option<Cache>) -> Self {
        self.cache = cache;
        self
    }

    /// Sets [`LabOptions::kind`].
    pub fn with_reference(mut self, kind: ReferenceKind) -> Self {
        self.kind = kind;
        self
    }

    /// Sets [`LabOptions::memory`].
    pub fn with_memory(mut self, memory: MemoryBudget) -> Self {
        self.memory = Some(memory);
        self
    }

    /// Sets [`LabOptions::columns`].
    pub fn with_columns(mut self, columns: ColumnCost) -> Self {
        self.columns = columns;
        self
    }

    /// Sets [`LabOptions::transport`].
    pub fn with_transport(mut self, transport: Transport) -> Self {
        self.transport = transport;
        self
    }

    /// Sets [`LabOptions::shooting`].
    pub fn with_shooting(mut self, shooting: ShootingParams) -> Self {
        self.shooting = shooting;
        self
    }
}
