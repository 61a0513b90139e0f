//! The problem a solver works on: the linear system and the form-factor columns, with the
//! accounting of every column fetched.
//!
//! Solvers never call a `ColumnSource` directly. They ask the [`Problem`] for a column or a
//! row; the problem counts the columns computed and the seconds spent in them, which is the
//! unit of cost of every method (docs/design.md §3.3). A row costs one column too: the source gives
//! it when it can ([`radiosity_core::ColumnSource::fill_row`]), and otherwise it follows from the
//! same column by reciprocity, `F_ji = F_ij A_i / A_j`.
//!
//! A product `F x` of a whole vector ([`Problem::multiply`]) is the source's own when it has
//! one ([`radiosity_core::ColumnSource::multiply`]: a stored matrix's pass over its entries, a
//! hierarchical operator's `O(links + n)`), counted as one product beside the columns;
//! otherwise it is the columns of the patches where the vector is not zero, each counted.
//!
//! **The run's clock.** Every column, row and product is timed. A source that charges a
//! modelled cost for what it serves ([`ColumnSource::charged_seconds`]: a lab's stored matrix
//! in place of the backend) sets the run's clock to [`Clock::Charged`]: the problem's
//! form-factor seconds ([`Problem::ff_seconds`]), which the executor adds to the state, a
//! `time=` rule reads and a timed group frequency divides by the columns, are then the charge
//! since the problem was made, and the time the source took is kept apart
//! ([`Problem::measured_ff_seconds`]) so that the solving time excludes it. Otherwise the
//! clock is [`Clock::Measured`] and both are the measured time.
//!
//! **Transport by rays.** A problem may carry a [`TransportSampler`]
//! ([`Problem::with_transport`]), for the solvers that estimate transport with rays and never
//! form `F` (stochastic relaxation, random walks). They cast through [`Problem::cast`], which
//! hands them a [`Rays`] that counts every ray (atomically: rays are cast in parallel) and
//! times the whole section as form-factor seconds, measured: the rays are those solvers'
//! form factors. On a charged clock the rays' measured seconds are added to the charge, as no
//! source charges for them. The same problem's columns still serve the others; a problem without a
//! sampler refuses the solvers that need one ([`SolverError::NotApplicable`]).
//!
//! **Links.** A source that shows its links ([`ColumnSource::link_source`], the hierarchical
//! operator) serves the solvers that shoot from the nodes of its tree
//! ([`Problem::through_links`], timed as form-factor seconds, measured). Over such a source the
//! problem also counts the links every column, row and product touches (a column or a row
//! those of its patch's leaf and ancestors, a product every link), so that every solver over
//! it has one cost axis beside columns and products ([`Problem::spent`]).
//!
//! A problem may also carry a spatially coherent order of the patches
//! ([`Problem::with_patch_order`]), for solvers that group patches by proximity
//! (`group-gs-gM:groups=spatial`, `h-xu:groups=spatial`); the others ignore it.

use crate::error::SolverError;
use crate::run::cost::Unit;
use radiosity_core::operator::{Product, multiply_by_columns};
use radiosity_core::{
    Clock, Collective, ColumnSource, LineTransfers, LinearSystem, LinkSource, NO_PARENT, Real, SampleCost,
    TransportSampler,
};
use std::cell::{Cell, OnceCell};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// A system and its form factors.
pub struct Problem<'a> {
    system: &'a LinearSystem,
    columns: Columns<'a>,
    /// What was spent in each unit ([`Unit`]), atomically: rays are cast in parallel.
    spent: [AtomicU64; Unit::ALL.len()],
    /// Seconds spent in the source, measured.
    ff_seconds: Cell<f64>,
    /// What the source had charged when the problem was made, when it charges (module doc).
    charged_from: Option<Real>,
    order: Option<&'a [usize]>,
    transport: Option<&'a dyn TransportSampler>,
    /// Seconds spent casting rays or shooting through links, measured (also in `ff_seconds`):
    /// on a charged clock they are added to the charge, since no source charges for them.
    uncharged_seconds: Cell<f64>,
    /// The links each patch's column touches, and all the links: counted once, when the
    /// source shows its links.
    link_costs: OnceCell<(Vec<u64>, u64)>,
    /// The ranks the problem is solved over when its source is not split itself
    /// ([`Problem::with_collective`]).
    collective: Option<&'a dyn Collective>,
}

/// Where a problem's columns come from.
enum Columns<'a> {
    /// A column source.
    Source(&'a dyn ColumnSource),
    /// None: the problem samples transport only ([`Problem::sampled`]).
    Unformed(Unformed),
}

/// The column source of a problem that has none ([`Problem::sampled`]): `F` is never formed.
/// Every entry it gives is NaN, which no solver gets to see: the executor refuses, before any
/// work, a solver that does not sample transport on such a problem.
struct Unformed {
    n: usize,
}

impl ColumnSource for Unformed {
    fn patch_count(&self) -> usize {
        self.n
    }

    fn fill_column(&self, _j: usize, column: &mut [Real]) {
        column.fill(Real::NAN);
    }
}

impl Columns<'_> {
    fn source(&self) -> &dyn ColumnSource {
        match self {
            Columns::Source(source) => *source,
            Columns::Unformed(unformed) => unformed,
        }
    }
}

/// A problem's [`TransportSampler`] while a solver casts ([`Problem::cast`]): every ray it
/// casts is counted. `Sync`, for casting in parallel.
pub struct Rays<'p> {
    sampler: &'p dyn TransportSampler,
    count: &'p AtomicU64,
}

impl Rays<'_> {
    /// One ray from the front of `from` driven by `u` ([`TransportSampler::cast`]).
    pub fn cast(&self, from: usize, u: [Real; 4]) -> Option<usize> {
        self.count.fetch_add(1, Ordering::Relaxed);
        self.sampler.cast(from, u)
    }

    /// A batch of rays from `from` ([`TransportSampler::cast_batch`]).
    pub fn cast_batch(&self, from: usize, u: &[[Real; 4]], landings: &mut [Option<usize>]) {
        self.count.fetch_add(u.len() as u64, Ordering::Relaxed);
        self.sampler.cast_batch(from, u, landings)
    }

    /// One global line ([`TransportSampler::global_line`]), its rays counted; `false` when
    /// the sampler has no lines.
    pub fn global_line(&self, u: [Real; 4], line: &mut LineTransfers) -> bool {
        let has = self.sampler.global_line(u, line);
        if has {
            self.count.fetch_add(line.rays, Ordering::Relaxed);
        }
        has
    }

    /// The power a ray from `from` carries ([`TransportSampler::ray_weight`]).
    pub fn ray_weight(&self, from: usize) -> Real {
        self.sampler.ray_weight(from)
    }

    /// `Σ_j F_ij` when the sampler knows it ([`TransportSampler::row_sum`]).
    pub fn row_sum(&self, i: usize) -> Option<Real> {
        self.sampler.row_sum(i)
    }
}

impl<'a> Problem<'a> {
    /// A problem over `system` with form factors from `columns`.
    pub fn new(system: &'a LinearSystem, columns: &'a dyn ColumnSource) -> Result<Problem<'a>, SolverError> {
        if columns.patch_count() != system.len() {
            return Err(SolverError::SizeMismatch { columns: columns.patch_count(), system: system.len() });
        }
        Ok(Problem::over(system, Columns::Source(columns)))
    }

    /// A problem over `system` whose columns, of the system's size, come from `columns`.
    fn over(system: &'a LinearSystem, columns: Columns<'a>) -> Problem<'a> {
        let charged_from = columns.source().charged_seconds();
        Problem {
            system,
            columns,
            spent: Default::default(),
            ff_seconds: Cell::new(0.0),
            charged_from,
            order: None,
            transport: None,
            uncharged_seconds: Cell::new(0.0),
            link_costs: OnceCell::new(),
            collective: None,
        }
    }

    /// A problem with transport sampled by `sampler` and no form factors at all: only the
    /// solvers that sample transport run on it (the executor refuses the others before any
    /// work, [`Problem::forms_columns`]).
    pub fn sampled(system: &'a LinearSystem, sampler: &'a dyn TransportSampler) -> Result<Problem<'a>, SolverError> {
        Problem::over(system, Columns::Unformed(Unformed { n: system.len() })).with_transport(sampler)
    }

    /// Whether the problem has form factors to give (every problem but [`Problem::sampled`]'s).
    pub fn forms_columns(&self) -> bool {
        matches!(self.columns, Columns::Source(_))
    }

    /// The problem with transport sampled by `sampler` (module doc), which must have the
    /// system's patches.
    pub fn with_transport(mut self, sampler: &'a dyn TransportSampler) -> Result<Problem<'a>, SolverError> {
        if sampler.patch_count() != self.n() {
            return Err(SolverError::SizeMismatch { columns: sampler.patch_count(), system: self.n() });
        }
        self.transport = Some(sampler);
        Ok(self)
    }

    /// Whether the problem samples transport by rays ([`Problem::with_transport`]).
    pub fn samples_transport(&self) -> bool {
        self.transport.is_some()
    }

    /// What one ray costs, when the problem samples transport.
    pub fn ray_cost(&self) -> Option<SampleCost> {
        self.transport.map(|t| t.cost())
    }

    /// Runs `cast` with the problem's sampler, counting its rays and timing it as form-factor
    /// seconds (module doc). Refuses, for `solver`, a problem without a sampler.
    pub fn cast<R>(&self, solver: &str, cast: impl FnOnce(&Rays<'_>) -> R) -> Result<R, SolverError> {
        let sampler = self.transport.ok_or_else(|| SolverError::NotApplicable {
            solver: solver.to_string(),
            reason: "it samples transport with rays, and this problem has no transport sampler \
                     (Problem::with_transport; the lab gives one: rays in the scene, or the stored matrix sampled)"
                .into(),
        })?;
        let start = Instant::now();
        let out = cast(&Rays { sampler, count: &self.spent[Unit::Rays.at()] });
        let seconds = start.elapsed().as_secs_f64();
        self.ff_seconds.set(self.ff_seconds.get() + seconds);
        self.uncharged_seconds.set(self.uncharged_seconds.get() + seconds);
        Ok(out)
    }

    /// The problem with a spatially coherent order of its patches (patches near each other
    /// consecutive in it), which must be a permutation of `0..n`.
    pub fn with_patch_order(mut self, order: &'a [usize]) -> Result<Problem<'a>, SolverError> {
        let n = self.n();
        if order.len() != n {
            return Err(SolverError::BadParams(format!(
                "the patch order has {} entries but the system has {n} patches",
                order.len()
            )));
        }
        let mut seen = vec![false; n];
        for (at, &i) in order.iter().enumerate() {
            let why = if i >= n {
                "out of range"
            } else if std::mem::replace(&mut seen[i], true) {
                "repeated"
            } else {
                continue;
            };
            return Err(SolverError::BadParams(format!(
                "the patch order is not a permutation of 0..{n}: entry {at}, patch {i}, is {why}"
            )));
        }
        self.order = Some(order);
        Ok(self)
    }

    /// The spatially coherent patch order the caller gave, if any.
    pub fn patch_order(&self) -> Option<&[usize]> {
        self.order
    }

    /// The ranks the problem is solved over: those its source is split over
    /// ([`ColumnSource::collective`]), or else those given ([`Problem::with_collective`]).
    pub fn collective(&self) -> Option<&dyn Collective> {
        self.columns.source().collective().or(self.collective)
    }

    /// The problem solved over the ranks of `collective`, its source not split: every rank
    /// holds the whole problem, and a solver that divides its own work between ranks (the
    /// solvers that sample transport deal their replicates, [`crate::StochasticJacobi`])
    /// meets the others in `collective`'s sums. Decisions that read a clock are rank 0's
    /// ([`crate::Executor`]). A source split over ranks keeps its own.
    pub fn with_collective(mut self, collective: &'a dyn Collective) -> Problem<'a> {
        self.collective = Some(collective);
        self
    }

    /// The system.
    pub fn system(&self) -> &LinearSystem {
        self.system
    }

    /// The number of patches.
    pub fn n(&self) -> usize {
        self.system.len()
    }

    /// The number of solved channels.
    pub fn channels(&self) -> usize {
        self.system.channels().count()
    }

    /// Column `j` of F (`F_ij` for every `i`) into `out`: one column computed.
    pub fn column(&self, j: usize, out: &mut [Real]) {
        let start = Instant::now();
        self.columns.source().fill_column(j, out);
        self.ff_seconds.set(self.ff_seconds.get() + start.elapsed().as_secs_f64());
        self.spend(Unit::Columns, 1);
        self.count_line_links(j);
    }

    /// Counts the links a column or row of patch `p` touches, when the source shows them: the
    /// links of `p`'s leaf and of its ancestors.
    fn count_line_links(&self, p: usize) {
        if let Some(costs) = self.link_costs() {
            self.spend(Unit::Links, costs.0[p]);
        }
    }

    /// The links each patch's column touches, and all the links, when the source shows them.
    fn link_costs(&self) -> Option<&(Vec<u64>, u64)> {
        let links = self.link_source()?;
        Some(self.link_costs.get_or_init(|| {
            let parents = links.parents();
            let mut path = vec![0u64; parents.len()];
            for k in 0..parents.len() {
                let above = if parents[k] == NO_PARENT { 0 } else { path[parents[k] as usize] };
                path[k] = above + links.link_count(k) as u64;
            }
            let all = (0..parents.len()).map(|k| links.link_count(k) as u64).sum();
            (links.leaves().iter().map(|&leaf| path[leaf as usize]).collect(), all)
        }))
    }

    /// The source's links, when it shows them ([`ColumnSource::link_source`]): what the
    /// solvers that shoot from the nodes of a hierarchy use.
    pub fn link_source(&self) -> Option<&dyn LinkSource> {
        self.columns.source().link_source()
    }

    /// Runs `work` on the source's links, timed as form-factor seconds (measured on either
    /// clock, as rays are), counting `touched` links; `None` when the source shows none.
    pub fn through_links<R>(&self, touched: u64, work: impl FnOnce(&dyn LinkSource) -> R) -> Option<R> {
        let links = self.link_source()?;
        let start = Instant::now();
        let out = work(links);
        let seconds = start.elapsed().as_secs_f64();
        self.ff_seconds.set(self.ff_seconds.get() + seconds);
        self.uncharged_seconds.set(self.uncharged_seconds.get() + seconds);
        self.spend(Unit::Links, touched);
        Some(out)
    }

    /// Row `i` of F (`F_ij` for every `j`) into `out`: one column computed. The row is exact
    /// when the source can give it ([`ColumnSource::fill_row`]); otherwise it follows from
    /// column `i` by reciprocity, which is exact only as far as the source is reciprocal.
    pub fn row(&self, i: usize, out: &mut [Real]) {
        let start = Instant::now();
        let exact = self.columns.source().fill_row(i, out);
        if exact {
            self.ff_seconds.set(self.ff_seconds.get() + start.elapsed().as_secs_f64());
            self.spend(Unit::Columns, 1);
            self.count_line_links(i);
            return;
        }
        self.column(i, out);
        Self::reciprocal_row(self.system.areas(), i, out);
    }

    /// `out = F x`, both patch-major with the problem's channels: one product when the source
    /// multiplies itself, else a column for each patch where `x` is not zero (module doc).
    /// `column` is scratch space of `n` values for the second case.
    pub fn multiply(&self, x: &[Real], out: &mut [Real], column: &mut Vec<Real>) -> Product {
        let start = Instant::now();
        if self.columns.source().multiply(x, self.channels(), out) {
            self.ff_seconds.set(self.ff_seconds.get() + start.elapsed().as_secs_f64());
            self.spend(Unit::Products, 1);
            if let Some(&(_, all)) = self.link_costs() {
                self.spend(Unit::Links, all);
            }
            return Product::native();
        }
        column.resize(self.n(), 0.0);
        multiply_by_columns(x, self.channels(), out, column, |j, column| self.column(j, column))
    }

    /// Turns column `i`, in place, into row `i` by reciprocity: `F_ij = F_ji A_j / A_i`.
    fn reciprocal_row(area: &[Real], i: usize, column: &mut [Real]) {
        for (j, f) in column.iter_mut().enumerate() {
            *f *= area[j] / area[i];
        }
    }

    /// The reciprocity bound the form factors state
    /// ([`ColumnSource::reciprocity_bound`]), if any: what conjugate gradients on the
    /// symmetrized system need ([`crate::ConjugateGradients`]).
    pub fn reciprocity_bound(&self) -> Option<Real> {
        self.columns.source().reciprocity_bound()
    }

    /// What was spent so far in `unit`: columns (and rows) computed, products the source
    /// computed itself ([`Problem::multiply`]), rays cast ([`Problem::cast`]), columns served
    /// again from memory ([`Problem::note_reuse`]), and links touched when the source shows
    /// its links (a column or a row those of its patch's leaf and ancestors, a product every
    /// link, a shot its nodes' links, [`Problem::through_links`]; zero over a source that shows
    /// none).
    pub fn spent(&self, unit: Unit) -> u64 {
        self.spent[unit.at()].load(Ordering::Relaxed)
    }

    /// Counts `k` more of `unit` spent.
    fn spend(&self, unit: Unit, k: u64) {
        self.spent[unit.at()].fetch_add(k, Ordering::Relaxed);
    }

    /// Counts `k` of `unit` that the other ranks spent ([`Problem::collective`]): a solver that
    /// divides its work between ranks adds what they spent, so that every rank's counts, and
    /// the stop rules that read them, are the whole world's.
    pub fn spent_elsewhere(&self, unit: Unit, k: u64) {
        self.spend(unit, k);
    }

    /// Records that a solver served a column from its own memory instead of computing it
    /// ([`crate::ColumnMemory`] calls this): it costs no column, and is counted apart.
    pub fn note_reuse(&self) {
        self.spend(Unit::Reused, 1);
    }

    /// The clock the run's seconds are counted on (module doc).
    pub fn clock(&self) -> Clock {
        if self.charged_from.is_some() { Clock::Charged } else { Clock::Measured }
    }

    /// Seconds the columns, rows and products fetched so far cost on the run's clock
    /// ([`Problem::clock`]): charged by the source, or measured; rays cast are measured on
    /// either clock (no source charges for them).
    pub fn ff_seconds(&self) -> f64 {
        match (self.charged_from, self.columns.source().charged_seconds()) {
            (Some(from), Some(now)) => (now - from).max(0.0) + self.uncharged_seconds.get(),
            _ => self.ff_seconds.get(),
        }
    }

    /// Seconds spent in the source so far, measured, whatever the clock: what a step's wall
    /// time less its form factors leaves as solving time.
    pub fn measured_ff_seconds(&self) -> f64 {
        self.ff_seconds.get()
    }
}
