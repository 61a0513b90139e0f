//! `pr-gM`, `xu-gM`, `pr-gM-mK`, `xu-gM-mK` (and the other overshooting variants):
//! group-accelerated shooting, the paper's method.
//!
//! ## Rule
//!
//! A point shooting method (PR or an overshooting variant, [`crate::shooting::overshooting::step`])
//! keeps the columns it computes in a memory of `K` columns ([`ColumnMemory`], least recently used
//! evicted; `K = m` by default). A shooter whose column is stored costs no new column. Every `f`
//! point steps, a *group step* ([`crate::group::group_step`]) runs on the `m` stored patches with
//! the largest `A_k Σ_c |ΔB_kc + ΔB⁺_kc|`, their overshoots computed exactly from their stored
//! columns: it computes no column at all. With `K = m` the group is the last `m` shooters (the
//! paper's "first approach", §4.1); with `K > m` it is the best `m` of everything stored (its
//! optimised variant, §4.2, `pr-g30-m480`).
//!
//! - **Emitters first.** The first shots are the emitters', each once, in order of selection
//!   value; group steps start after them, and emitters' columns are not stored: an emitter
//!   usually reflects little, and a group of emitters exchanges almost nothing (paper §4.1).
//! - **Frequency.** Fixed (`:f=N`), modelled (`:f=auto`, the default) or measured
//!   (`:f=timed`, the paper's rule). After each group step the next one is due `f` point steps
//!   later, `f = max(1, ⌈c_group / (target · c_column)⌉)`, with `target` the allowed overhead
//!   (`:target=0.05`): a group step then costs at most about `target` of the columns of the
//!   `f` point steps after it. The first group step runs as soon as `m` columns are stored.
//!   - `auto`: `c_group = ops_group`, the operations the group step counted, and
//!     `c_column =` [`column_operations`]`(n)`, the modelled cost of one form-factor column.
//!   - `timed`: `c_group` the measured seconds of that group step and `c_column` the mean
//!     seconds of a column so far, on the run's clock ([`Problem::ff_seconds`]): measured, or
//!     what the source charged, as the run's report prints them.
//! - **Steps are shooting steps.** A step is one point shot, followed by a group step when one
//!   is due, so the group holds the newest shooter; `steps=` counts shots, the paper's axis.
//!   A group step costs no column. Its seconds are reported apart ([`State::group_seconds`]).
//! - **Point selection uses estimates.** Selection among all patches uses the estimated
//!   overshoot of [`crate::shooting::overshooting::step`]; making it exact for the stored
//!   patches (their rows are known) costs `O(n K)` a step and, measured on multi-cubes with `xu-g30-m480`,
//!   changed no choice in `n` steps. Group selection is over stored patches only, and exact.
//!
//! ## The cost model of `:f=auto`
//!
//! Measured times make the steps depend on the machine: the same problem run twice, or beside
//! another job, takes its group steps at other points and ends at another radiosity. The
//! model counts instead, so that two runs take the same steps. `ops_group` is, with `n`
//! patches, `k` channels, `K` stored columns and a group of `m`:
//!
//! - choosing the group: the exact overshoot of every stored patch, `K n k` when the rule has
//!   a row term (`K k` without one, [`OvershootTracker::exact_operations`]), `m K` more for
//!   the interaction scores (`:groups=interaction`), and the members' overshoots without the
//!   group, `m n k` (`m k`);
//! - building `Φ_rr`: `m² k`;
//! - solving it: `(⌊2m³/3⌋ + 4m²) k` for the LU with its two right-hand sides, as
//!   [`radiosity_core::dense_lu::solve_m_matrix`] does it, or the inner Gauss–Seidel's counted
//!   sweeps, `m²` each ([`crate::group::group_step`]);
//! - shooting `y` to every patch: `n m k`.
//!
//! Work linear in `n k` (the ambient sums, the selection values) is left out. An operation is
//! about one floating-point operation of these loops.
//!
//! A column's modelled cost is [`column_operations`]`(n) =`
//! [`COLUMN_OPERATIONS_PER_ROOT_PATCH`]` · √n` operations: a column does not cost `n` times a
//! pair, since most pairs of a large scene face away or are far enough for the cheapest
//! quadrature, so a pair's cost falls about as `1/√n`. The constant is a model, fixed so that
//! `:f=auto` is reproducible; it was fitted to the analytic backend's columns of an earlier
//! visibility estimator, and today's analytic columns cost several times more, so the group
//! steps' share of the time stays below `target` (the fit and today's column times are in
//! `docs/solvers.md`). It is charged for every point step, whether or not the step computed a
//! column (as in the timed rule, which also takes the mean column time). Other backends cost
//! otherwise (a stored matrix serves a column for `n` reads, a hemicube traces its rays
//! whatever `n`): with them, as with today's analytic columns, `:f=timed` (the paper's rule)
//! or a fixed `:f=N` follows the time better.
//!
//! ## Beyond the paper
//!
//! The paper names three directions as future work (§4.2, §5); each is a parameter here, to be
//! compared against its rule:
//!
//! - `:groups=interaction` ([`GroupBuilding::Interaction`]): groups grown for the energy their
//!   members exchange, from the stored form factors, instead of the top `m` by unshot energy;
//! - `:inner=gs` ([`InnerSolve::GaussSeidel`]): large groups solved by Gauss–Seidel instead
//!   of LU;
//! - `:adaptive=τ`: the group takes every stored patch whose selection value is at least `τ`
//!   times the largest, between 4 and `m` patches.
//!
//! ## References
//!
//! - Rousselle & Renaud, "Group accelerated shooting methods for radiosity", §4 (the timed
//!   frequency rule, §4.1).
//!
//! ## Record
//!
//! The solver records its group steps ([`crate::group::group_step::GroupStats`]: `group_steps`,
//! `group_size_mean`, `group_size_max`, `group_condition`, `group_fallbacks`), the counted
//! operations of them all (`group_operations`, the model's `ops_group` summed) and the point
//! steps between the last group step and the next (`group_period`, 0 before the first).

use crate::error::SolverError;
use crate::group::group_shooting::shoot_group;
use crate::group::group_step::{GroupShot, GroupStats, InnerSolve};
use crate::group::memory::ColumnMemory;
use crate::naming::{ParseSolverError, SolverParams, named, split_params, split_size, validated};
use crate::run::cost::Unit;
use crate::run::executor::Solver;
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::{self, ResidualBound};
use crate::run::state::State;
use crate::shooting::overshooting::step::{
    Ambient, OvershootTracker, ShootingMethod, argmax, shoot_with_overshoot, top,
};
use crate::shooting::rule::unshot_power;
use radiosity_core::Real;
use std::str::FromStr;
use std::time::Instant;

/// The modelled cost of one form-factor column of `n` patches, over `√n`, in counted
/// operations of a group step: fitted to analytic columns on the paper's three scenes at about
/// 1 ns an operation (the cost model of the module doc).
pub const COLUMN_OPERATIONS_PER_ROOT_PATCH: u64 = 20_000;

/// The modelled cost of one form-factor column of `n` patches, in counted operations:
/// [`COLUMN_OPERATIONS_PER_ROOT_PATCH`]` · √n`.
pub fn column_operations(n: usize) -> Real {
    COLUMN_OPERATIONS_PER_ROOT_PATCH as Real * (n as Real).sqrt()
}

/// The allowed overhead of the automatic frequencies when none is given (the paper's 5%).
pub const DEFAULT_TARGET: Real = 0.05;

/// How often group steps run (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Frequency {
    /// After every `f` point steps.
    Fixed(u64),
    /// From counted operations, keeping the modelled group cost near `target` of the modelled
    /// column cost: reproducible.
    Auto {
        /// The allowed overhead, a fraction of the column cost (the paper's 5%: 0.05).
        target: Real,
    },
    /// From measured times, keeping group solving near `target` of the form-factor time (the
    /// paper's rule): runs differ with the machine's load.
    Timed {
        /// The allowed overhead, a fraction of the column time (the paper's 5%: 0.05).
        target: Real,
    },
}

impl Default for Frequency {
    /// `Auto` at the paper's 5%.
    fn default() -> Frequency {
        Frequency::Auto { target: DEFAULT_TARGET }
    }
}

/// How the group is chosen among the stored patches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum GroupBuilding {
    /// The paper's rule: the `m` stored patches with the largest `A |ΔB + ΔB⁺|`.
    #[default]
    Unshot,
    /// Beyond the paper: seeded with the stored patch of largest `A |ΔB + ΔB⁺|`, then grown by
    /// the stored patch that exchanges the most unshot energy with the group so far (from the
    /// stored form factors; see [`GroupAccelerated`]).
    Interaction,
}

/// Parameters of a group-accelerated method, and its names `S-gM` and `S-gM-mK` with
/// `:f=N|auto|timed`, `:target=X`, `:groups=unshot|interaction`, `:inner=lu|gs` and
/// `:adaptive=X`.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupAcceleratedParams {
    /// The point shooting method (PR or an overshooting variant; not Southwell).
    pub method: ShootingMethod,
    /// Group size `m` (the largest size when `adaptive` is set).
    pub group: usize,
    /// Columns kept in memory, `K ≥ m`.
    pub memory: usize,
    /// How often group steps run.
    pub frequency: Frequency,
    /// How the group is chosen.
    pub building: GroupBuilding,
    /// Beyond the paper: adaptive `m`, taking every stored patch whose selection value is at
    /// least this fraction of the largest (at most `group`, at least [`MIN_ADAPTIVE_GROUP`]).
    pub adaptive: Option<Real>,
    /// How group systems are solved.
    pub inner: InnerSolve,
    /// The name the solver reports: as written on the command line when parsed (parameters
    /// may come in any order, defaults spelled out), [`GroupAcceleratedParams::canonical_name`]
    /// when `None`.
    pub name: Option<String>,
}

impl Default for GroupAcceleratedParams {
    /// `pr-g30`: the paper's method with PR, groups of 30 from the last 30 shooters, automatic
    /// frequency.
    fn default() -> GroupAcceleratedParams {
        GroupAcceleratedParams::paper(ShootingMethod::Pr, 30, 30, Frequency::default())
    }
}

impl GroupAcceleratedParams {
    /// The paper's method: `method` with groups of `group` from a memory of `memory` columns,
    /// by unshot energy, solved by LU.
    pub fn paper(method: ShootingMethod, group: usize, memory: usize, frequency: Frequency) -> GroupAcceleratedParams {
        GroupAcceleratedParams {
            method,
            group,
            memory,
            frequency,
            building: GroupBuilding::Unshot,
            adaptive: None,
            inner: InnerSolve::Lu,
            name: None,
        }
    }

    /// The name with the parameters that differ from the defaults, in a fixed order:
    /// `xu-g30-m480:f=10:groups=interaction`.
    pub fn canonical_name(&self) -> String {
        let mut name = format!("{}-g{}", self.method.name(), self.group);
        if self.memory != self.group {
            name.push_str(&format!("-m{}", self.memory));
        }
        let target = |t: Real| if t == DEFAULT_TARGET { String::new() } else { format!(":target={t}") };
        match self.frequency {
            Frequency::Fixed(f) => name.push_str(&format!(":f={f}")),
            Frequency::Auto { target: t } => name.push_str(&target(t)),
            Frequency::Timed { target: t } => name.push_str(&format!(":f=timed{}", target(t))),
        }
        if self.building == GroupBuilding::Interaction {
            name.push_str(":groups=interaction");
        }
        if self.inner == InnerSolve::GaussSeidel {
            name.push_str(":inner=gs");
        }
        if let Some(fraction) = self.adaptive {
            name.push_str(&format!(":adaptive={fraction}"));
        }
        name
    }

    /// The name the solver reports: `name`, or the canonical one.
    pub fn solver_name(&self) -> String {
        self.name.clone().unwrap_or_else(|| self.canonical_name())
    }

    /// Reads the `:key=value` parameters of `name` (`params`, without the head) into `self`.
    fn parse_params(&mut self, name: &str, params: &str) -> Result<(), SolverError> {
        #[derive(Clone, Copy)]
        enum Kind {
            Fixed(u64),
            Auto,
            Timed,
        }
        let (mut kind, mut target) = (Kind::Auto, DEFAULT_TARGET);
        for pair in params.split(':').filter(|p| !p.is_empty()) {
            let bad = |why: &str| SolverError::BadParams(format!("solver '{name}': '{pair}' {why}"));
            let fraction = |v: &str| v.parse::<Real>().ok().filter(|t| *t > 0.0 && t.is_finite());
            match pair.split_once('=') {
                Some(("f", "auto")) => kind = Kind::Auto,
                Some(("f", "timed")) => kind = Kind::Timed,
                Some(("f", v)) => {
                    let f = v.parse::<u64>().ok().filter(|&f| f > 0);
                    kind = Kind::Fixed(f.ok_or_else(|| bad("needs f=auto, f=timed or f ≥ 1"))?);
                }
                Some(("target", v)) => target = fraction(v).ok_or_else(|| bad("needs a positive number"))?,
                Some(("groups", "unshot")) => self.building = GroupBuilding::Unshot,
                Some(("groups", "interaction")) => self.building = GroupBuilding::Interaction,
                Some(("groups", _)) => return Err(bad("needs groups=unshot or groups=interaction")),
                Some(("inner", "lu")) => self.inner = InnerSolve::Lu,
                Some(("inner", "gs")) => self.inner = InnerSolve::GaussSeidel,
                Some(("inner", _)) => return Err(bad("needs inner=lu or inner=gs")),
                Some(("adaptive", v)) => {
                    let adaptive = fraction(v).filter(|t| *t <= 1.0);
                    self.adaptive = Some(adaptive.ok_or_else(|| bad("needs a fraction in (0, 1]"))?);
                }
                _ => {
                    return Err(bad(
                        "is not a parameter; group-accelerated solvers take f=N, f=auto, f=timed, target=X, \
                         groups=unshot|interaction, inner=lu|gs and adaptive=X",
                    ));
                }
            }
        }
        self.frequency = match kind {
            Kind::Fixed(f) => Frequency::Fixed(f),
            Kind::Auto => Frequency::Auto { target },
            Kind::Timed => Frequency::Timed { target },
        };
        Ok(())
    }
}

impl FromStr for GroupAcceleratedParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<GroupAcceleratedParams, ParseSolverError> {
        let (head, params) = split_params(name);
        if head.starts_with("group-") {
            return Err(ParseSolverError::OtherFamily);
        }
        let (grouped, memory) = match split_size(head, "-m") {
            Some((grouped, k)) if grouped.contains("-g") => (grouped, Some(k)),
            _ => (head, None),
        };
        let (base, group) = split_size(grouped, "-g").ok_or(ParseSolverError::OtherFamily)?;
        let method = ShootingMethod::parse(base).ok_or(ParseSolverError::OtherFamily)?.map_err(|e| named(name, e))?;
        let mut out = GroupAcceleratedParams::paper(method, group, memory.unwrap_or(group), Frequency::default());
        out.parse_params(name, params)?;
        out.name = Some(name.to_string());
        validated(name, out)
    }
}

impl SolverParams for GroupAcceleratedParams {
    const SYNTAX: &'static str =
        "S-gM[-mK][:f=N|auto|timed][:target=X][:groups=unshot|interaction][:inner=lu|gs][:adaptive=X]";
    const HELP: &'static str = "group-accelerated shooting, the paper's method: S shoots keeping K columns (default M), \
                                a group step over M stored patches every f shots (f=auto: from modelled costs)";
    const EXAMPLES: &'static [&'static str] = &["pr-g30", "xu-g30", "xu-g30-m480:f=10"];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        Ok(Box::new(GroupAccelerated::new(self.clone())?))
    }
}

/// `⌈ratio⌉`, at least 1 (and at most 10¹²): the point steps until the next group step.
fn period(ratio: Real) -> u64 {
    ratio.ceil().clamp(1.0, 1e12) as u64
}

/// The smallest group an adaptive size gives.
pub const MIN_ADAPTIVE_GROUP: usize = 4;

/// Group-accelerated shooting.
#[derive(Debug)]
pub struct GroupAccelerated {
    name: String,
    params: GroupAcceleratedParams,
    tracker: OvershootTracker,
    memory: ColumnMemory,
    scratch: Vec<Real>,
    /// Emitters that have not shot yet.
    emitters_left: Vec<bool>,
    emitters_count: usize,
    /// Point steps since the last group step.
    since_group: u64,
    /// Point steps between group steps (0 before the first).
    period: u64,
    /// What the group steps did.
    stats: GroupStats,
    /// Their counted operations, summed.
    operations: u64,
}

impl GroupAccelerated {
    /// A group-accelerated method with `params`, named [`GroupAcceleratedParams::solver_name`].
    pub fn new(params: GroupAcceleratedParams) -> Result<GroupAccelerated, SolverError> {
        if !params.method.by_area() {
            return Err(SolverError::BadParams(format!(
                "group acceleration applies to PR and the overshooting methods, not to {}",
                params.method.name()
            )));
        }
        if params.group == 0 {
            return Err(SolverError::BadParams("a group needs at least one patch (g ≥ 1)".into()));
        }
        if params.memory < params.group {
            return Err(SolverError::BadParams(format!(
                "the memory (m{}) must hold at least a group (g{})",
                params.memory, params.group
            )));
        }
        match params.frequency {
            Frequency::Fixed(0) => {
                return Err(SolverError::BadParams("the group frequency f must be at least 1".into()));
            }
            Frequency::Auto { target } | Frequency::Timed { target } if !(target > 0.0 && target.is_finite()) => {
                return Err(SolverError::BadParams(format!("the target overhead must be positive, not {target}")));
            }
            _ => {}
        }
        let tracker = OvershootTracker::new(params.method.overshoot(), true)?;
        Ok(GroupAccelerated {
            name: params.solver_name(),
            params,
            tracker,
            memory: ColumnMemory::new(0, 0),
            scratch: Vec::new(),
            emitters_left: Vec::new(),
            emitters_count: 0,
            since_group: 0,
            period: 0,
            stats: GroupStats::default(),
            operations: 0,
        })
    }

    fn group_due(&self) -> bool {
        self.emitters_count == 0 && self.memory.len() >= self.params.group && self.since_group >= self.period
    }

    /// Selection values with stored patches' overshoots exact (their rows are known), written
    /// over `values`.
    fn exact_values(&self, problem: &Problem<'_>, state: &State, ambient: &Ambient, values: &mut [Real]) {
        let k = state.channels;
        let (mut row, mut plus) = (vec![0.0; k], vec![0.0; k]);
        for &j in self.memory.patches() {
            let column = self.memory.peek(j).expect("stored");
            self.tracker.exact(problem, state, ambient, j, column, &[], &mut row, &mut plus);
            values[j] = self.tracker.value(problem, state, j, &plus);
        }
    }

    /// A group step over the stored patches; the group's shot, unless there was no group.
    fn group_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Option<GroupShot>, SolverError> {
        // Everything here is the group step's cost, in seconds and in counted operations (the
        // cost model of the module doc): choosing the group (exact overshoots of every stored
        // patch, `O(n K)`) as well as solving it.
        let start = Instant::now();
        let (n, k, stored) = (problem.n(), problem.channels(), self.memory.len());
        let ambient = Ambient::measure(problem, state);
        let mut values = vec![0.0; n];
        self.exact_values(problem, state, &ambient, &mut values);
        let group = self.choose_group(problem, &values);
        let mut operations = stored as u64 * self.tracker.exact_operations(n, k);
        if self.params.building == GroupBuilding::Interaction {
            operations += (group.len() * stored) as u64;
        }
        let mut done = None;
        if !group.is_empty() {
            let (shot, _) = shoot_group(problem, state, &mut self.tracker, &self.memory, &group, self.params.inner)?;
            operations += shot.operations;
            self.stats.add(&shot);
            done = Some(shot);
        }
        let seconds = start.elapsed().as_secs_f64();
        state.cost.group_seconds += seconds;
        self.operations += operations;
        self.since_group = 0;
        self.period = match self.params.frequency {
            Frequency::Fixed(f) => f,
            Frequency::Auto { target } => {
                let column = column_operations(n);
                period(operations as Real / (target * column))
            }
            Frequency::Timed { target } => {
                let columns = problem.spent(Unit::Columns).max(1) as Real;
                let column_seconds = problem.ff_seconds() / columns;
                if column_seconds > 0.0 { period(seconds / (target * column_seconds)) } else { u64::MAX }
            }
        };
        Ok(done)
    }

    /// The group among the stored patches, given every stored patch's selection value.
    fn choose_group(&self, problem: &Problem<'_>, values: &[Real]) -> Vec<usize> {
        let stored = self.memory.patches();
        let size = match self.params.adaptive {
            None => self.params.group,
            Some(fraction) => {
                let best = stored.iter().map(|&j| values[j]).fold(0.0, Real::max);
                let above = stored.iter().filter(|&&j| values[j] >= fraction * best && values[j] > 0.0).count();
                above.clamp(MIN_ADAPTIVE_GROUP.min(self.params.group), self.params.group)
            }
        };
        match self.params.building {
            GroupBuilding::Unshot => top(values, stored.iter().copied(), size),
            GroupBuilding::Interaction => self.interaction_group(problem, values, size),
        }
    }

    /// Greedy interaction group: start from the stored patch of largest value `v`, then add the
    /// stored patch `k` maximising `Σ_{g ∈ G} (v_g ρ̄_k F_gk + v_k ρ̄_g F_kg)`, the unshot power
    /// the group and `k` would send each other and reflect (`ρ̄` the mean over channels; the
    /// form factors from the stored columns). `O(m K)` for the scores.
    fn interaction_group(&self, problem: &Problem<'_>, values: &[Real], size: usize) -> Vec<usize> {
        let stored = self.memory.patches();
        let system = problem.system();
        let k = problem.channels();
        let rho = |j: usize| (0..k).map(|c| system.rho(j, c)).sum::<Real>() / k as Real;
        let Some(&seed) = top(values, stored.iter().copied(), 1).first() else { return Vec::new() };
        let mut group = vec![seed];
        let mut score = vec![0.0; stored.len()];
        let mut taken: Vec<bool> = stored.iter().map(|&j| j == seed).collect();
        let mut last = seed;
        while group.len() < size {
            // Add the exchanges with the last member to every candidate's score.
            let last_column = self.memory.peek(last).expect("stored");
            for (slot, &j) in stored.iter().enumerate() {
                if !taken[slot] {
                    let column = self.memory.peek(j).expect("stored");
                    // F_{last, j} = column_j[last]; F_{j, last} = column_last[j].
                    score[slot] += values[last] * rho(j) * column[last] + values[j] * rho(last) * last_column[j];
                }
            }
            let best =
                (0..stored.len()).filter(|&s| !taken[s]).max_by(|&a, &b| score[a].total_cmp(&score[b]).then(b.cmp(&a)));
            let Some(best) = best.filter(|&s| score[s] > 0.0) else { break };
            taken[best] = true;
            last = stored[best];
            group.push(last);
        }
        group
    }

    fn point_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        let ambient = Ambient::measure(problem, state);
        let mut values = self.tracker.values(problem, state, &ambient);
        if self.emitters_count > 0 {
            // Emitters first: until each has shot, only they are candidates, so a weak
            // emitter cannot hold group steps back for long.
            for (v, &left) in values.iter_mut().zip(&self.emitters_left) {
                if !left {
                    *v = Real::NEG_INFINITY;
                }
            }
        }
        let j = argmax(&values);
        let column = if self.is_emitter(problem, j) {
            // Emitters' columns are not kept (see the module documentation).
            self.scratch.resize(problem.n(), 0.0);
            problem.column(j, &mut self.scratch);
            &self.scratch[..]
        } else {
            self.memory.column(problem, j, &mut self.scratch)
        };
        shoot_with_overshoot(problem, state, &mut self.tracker, &ambient, j, column)?;
        if self.emitters_left[j] {
            self.emitters_left[j] = false;
            self.emitters_count -= 1;
        }
        self.since_group += 1;
        Ok(())
    }

    fn is_emitter(&self, problem: &Problem<'_>, j: usize) -> bool {
        (0..problem.channels()).any(|c| problem.system().e(j, c) > 0.0)
    }
}

impl Solver for GroupAccelerated {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn init(&mut self, problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        self.tracker.init(problem);
        self.memory = ColumnMemory::new(problem.n(), self.params.memory);
        self.emitters_left = (0..problem.n()).map(|j| self.is_emitter(problem, j)).collect();
        self.emitters_count = self.emitters_left.iter().filter(|&&e| e).count();
        self.since_group = 0;
        self.period = 0;
        self.stats = GroupStats::default();
        self.operations = 0;
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        self.point_step(problem, state)?;
        if !self.group_due() {
            return Ok(Record::new());
        }
        let shot = self.group_step(problem, state)?;
        Ok(shot.map_or_else(Record::new, |shot| shot.figures()))
    }

    fn residual_power(&self, problem: &Problem<'_>, state: &State) -> Option<Real> {
        Some(unshot_power(problem, state))
    }

    fn residual_bound(&self, problem: &Problem<'_>, state: &State) -> Option<ResidualBound> {
        Some(residual_bound::shooting(problem, state))
    }

    fn record(&self) -> Record {
        let mut record = Record::new();
        self.stats.record(&mut record);
        record.set("group_operations", self.operations).set("group_period", self.period);
        record
    }
}
