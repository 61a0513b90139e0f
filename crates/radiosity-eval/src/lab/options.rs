//! How a lab is set up ([`LabOptions`]) and how its solvers pay for the columns they fetch
//! ([`ColumnCost`], [`ColumnCharge`]).

use crate::lab::timing::{median, sample};
use crate::reference::cache::Cache;
use crate::reference::kind::{MemoryBudget, ReferenceKind};
use crate::reference::shooting::ShootingParams;
use crate::reference::solution::ReferenceParams;
use radiosity_core::{ColumnSource, Real};
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
    /// How solvers pay for their columns (default [`ColumnCost::Charged`]).
    pub columns: ColumnCost,
}

/// How a lab's solvers pay for the columns (and rows) of F they fetch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum ColumnCost {
    /// Every column is computed through the backend when a solver asks for it, and its time is
    /// the run's form-factor time.
    Computed,
    /// Where the lab keeps the stored matrix of a geometric backend (a `matrix` reference),
    /// solvers read their columns from it, the same `f32` entries the backend's columns give,
    /// and each column fetched is charged the backend's median time for a fresh column,
    /// measured once on a seeded sample ([`ColumnCharge`]). Elsewhere as `Computed`.
    #[default]
    Charged,
}

/// What each column a solver fetches is charged, when a lab serves columns from its stored
/// matrix ([`ColumnCost::Charged`]): the median time of a fresh column of the backend, one
/// column at a time (as solvers fetch them), over a seeded sample, measured with the
/// backend's memory of earlier columns forgotten first.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ColumnCharge {
    /// Seconds charged for each column or row fetched.
    pub seconds_per_column: Real,
    /// Columns timed.
    pub sampled: usize,
}

impl ColumnCharge {
    /// Columns timed to measure the charge.
    pub const SAMPLE: usize = 8;

    /// Times [`ColumnCharge::SAMPLE`] seeded fresh columns of `source` (fewer when it has
    /// fewer patches), one at a time, and takes the median.
    pub fn measure(source: &dyn ColumnSource) -> ColumnCharge {
        let n = source.patch_count();
        let sample = sample(n, Self::SAMPLE.min(n), 0);
        source.reset_memory();
        let mut column = vec![0.0; n];
        let times: Vec<f64> = sample
            .iter()
            .map(|&j| {
                let start = Instant::now();
                source.fill_column(j, &mut column);
                start.elapsed().as_secs_f64()
            })
            .collect();
        source.reset_memory();
        ColumnCharge { seconds_per_column: median(&times), sampled: sample.len() }
    }

    /// The form-factor seconds of `columns` fetched.
    pub fn seconds(&self, columns: u64) -> Real {
        columns as Real * self.seconds_per_column
    }

    /// One sentence saying how a run's columns were paid for, for reports.
    pub fn describe(&self) -> String {
        format!(
            "columns read from the stored matrix, each charged {:.3} ms (median of {} fresh columns of the backend, one at a time)",
            self.seconds_per_column * 1e3,
            self.sampled
        )
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

    /// Sets [`LabOptions::shooting`].
    pub fn with_shooting(mut self, shooting: ShootingParams) -> Self {
        self.shooting = shooting;
        self
    }
}
