//! `group-jacobi-gM` and `group-gs-gM`: group (block) Jacobi and group Gauss–Seidel gathering
//! over a fixed partition of the patches into groups of `m`.
//!
//! ## Rule (docs/design.md §4.5, paper eqs. 3–4)
//!
//! The patches are cut once into groups of `m` consecutive patches of an order (the last group
//! may be smaller). For group `r`, and per channel, the step solves
//! `Φ_rr B_r = E_r + diag(ρ_r) Σ_{s≠r} F_rs B_s` with `Φ_rr = I − diag(ρ_r) F_rr` (`m × m`, LU
//! with partial pivoting, [`radiosity_core::dense_lu`]): the group gathers from the rest of the
//! scene and resolves its own exchanges exactly. It is solved in correction form,
//! `Φ_rr δ_r = R_r` with `R_i = E_i + ρ_i Σ_j F_ij B_j − B_i` the residual of `B` on the group,
//! and `B_r += δ_r`; the rows that give `R_r` give `F_rr` too.
//!
//! - `group-jacobi-gM`: every group of a sweep gathers from the radiosity at the start of the
//!   sweep (eq. 3), as [`crate::gathering::jacobi`] does for patches.
//! - `group-gs-gM`: groups in order, each gathering from the latest radiosity (eq. 4), as
//!   [`crate::gathering::gauss_seidel`] does for patches.
//!
//! `state.unshot` keeps the last change of each patch. The solver records its group steps
//! ([`crate::group::group_step::GroupStats`]): `group_steps`, `group_size_mean`, `group_size_max`,
//! `group_condition` (`κ_∞(Φ_rr)`, the largest met, from `1` as a second right-hand side
//! of each group solve; infinite for a group whose `Φ_rr` is not a nonsingular M-matrix) and `group_fallbacks` (always 0: a singular group system is an error here,
//! [`SolverError::SingularGroup`]). The residual reported is the sum over
//! the last sweep of each patch's residual in the vector its group gathered from (exact for
//! group Jacobi; for group Gauss–Seidel, of a vector that changes during the sweep, so an
//! estimate), relative to the emitted power; none before the first sweep ends.
//!
//! ## Partitions (`:groups=index`, the default, or `:groups=spatial`)
//!
//! A group's solve captures the energy exchanged inside the group, so a group helps most when
//! its patches exchange much energy: near patches, facing each other.
//!
//! - `index`: consecutive patch indices. Meshers emit patches object by object and grid by
//!   grid, so this is already fairly coherent for the built-in scenes.
//! - `spatial`: consecutive patches of a spatially coherent order that the caller gives through
//!   [`Problem::with_patch_order`] (`radiosity_geom::spatial_order`, a Morton order of the
//!   centroids). Without one, `init` fails.
//!
//! ## Cost
//!
//! A step gathers one group: `m` rows, so `m` columns ([`Problem::row`]), and one `m × m` LU
//! per channel (`O(m³)`, the paper's "`m³` operations"; with the all-ones right-hand side of
//! the recorded condition number), its time `state.cost.group_seconds`. A
//! sweep is `⌈n/m⌉` steps and `n` columns, as for point Jacobi and Gauss–Seidel. With `m ≥ n`
//! the one group is the whole system: one step solves it exactly.
//!
//! ## References
//!
//! - Rousselle & Renaud, "Group accelerated shooting methods for radiosity", §2.1–2.2 (group
//!   Jacobi and group Gauss–Seidel, eqs. 3–4; group gathering).
//! - Saad 2003, *Iterative Methods for Sparse Linear Systems*, §4.1 (block Jacobi and block
//!   Gauss–Seidel).

use crate::error::SolverError;
use crate::gathering::rule::{SweepResidual, gather, relax};
use crate::group::group_step::{GroupShot, GroupStats};
use crate::naming::{ParseSolverError, SolverParams, split_params, split_size, validated};
use crate::run::executor::{Solver, StepKind};
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::{ResidualBound, SweepChanges};
use crate::run::state::State;
use radiosity_core::Real;
use radiosity_core::dense_lu::{SingularPivot, lu_solve_columns, m_matrix_condition};
use std::str::FromStr;
use std::time::Instant;

/// The names `group-jacobi-gM` and `group-gs-gM`, with `:groups=index` (the default) or
/// `:groups=spatial`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GroupGatheringParams {
    /// Group Jacobi or group Gauss–Seidel.
    pub sweep: Sweep,
    /// Patches a group, `m ≥ 1`.
    pub group: usize,
    /// How the patches are cut into groups.
    pub partition: Partition,
}

impl FromStr for GroupGatheringParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<GroupGatheringParams, ParseSolverError> {
        let (head, params) = split_params(name);
        let (base, group) =
            head.strip_prefix("group-").and_then(|rest| split_size(rest, "-g")).ok_or(ParseSolverError::OtherFamily)?;
        let sweep = match base {
            "jacobi" => Sweep::Jacobi,
            "gs" => Sweep::GaussSeidel,
            _ => return Err(ParseSolverError::OtherFamily),
        };
        let partition = Partition::parse(head, params)?;
        validated(name, GroupGatheringParams { sweep, group, partition })
    }
}

impl SolverParams for GroupGatheringParams {
    const SYNTAX: &'static str = "group-jacobi-gM, group-gs-gM[:groups=index|spatial]";
    const HELP: &'static str = "group Jacobi and Gauss–Seidel gathering over fixed groups of M, by index or in space";
    const EXAMPLES: &'static [&'static str] = &["group-gs-g30", "group-jacobi-g30:groups=spatial"];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        Ok(Box::new(GroupGathering::new(self.sweep, self.group, self.partition)?))
    }
}

/// Which radiosity the groups of a sweep gather from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sweep {
    /// The radiosity at the start of the sweep (group Jacobi).
    Jacobi,
    /// The latest radiosity (group Gauss–Seidel).
    GaussSeidel,
}

/// How the patches are cut into groups.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Partition {
    /// Consecutive patch indices.
    #[default]
    Index,
    /// Consecutive patches of the problem's spatial order ([`Problem::patch_order`]).
    Spatial,
}

impl Partition {
    /// The partition named by a solver's parameters (`groups=index`, `groups=spatial`, or
    /// nothing for the default); `name` is the solver's name, for messages.
    pub fn parse(name: &str, params: &str) -> Result<Partition, SolverError> {
        let mut partition = Partition::default();
        for pair in params.split(':').filter(|p| !p.is_empty()) {
            partition = match pair {
                "groups=index" => Partition::Index,
                "groups=spatial" => Partition::Spatial,
                _ => {
                    return Err(SolverError::BadParams(format!(
                        "solver '{name}': '{pair}' is not a parameter; group gathering takes groups=index or \
                         groups=spatial"
                    )));
                }
            };
        }
        Ok(partition)
    }
}

/// Group Jacobi or group Gauss–Seidel with groups of `m` patches.
#[derive(Debug)]
pub struct GroupGathering {
    sweep: Sweep,
    m: usize,
    partition: Partition,
    /// The patches in group order: group `r` is `order[r m .. (r + 1) m]`.
    order: Vec<usize>,
    /// The next group of the sweep.
    next: usize,
    sweep_start: Vec<Real>,
    row: Vec<Real>,
    /// `F_rr`, row-major.
    block: Vec<Real>,
    /// The group's residual, then its correction, `[a * channels + c]`.
    residual: Vec<Real>,
    delta: Vec<Real>,
    residuals: SweepResidual,
    changes: SweepChanges,
    stats: GroupStats,
}

impl GroupGathering {
    /// Group gathering sweeping as `sweep`, with groups of `m ≥ 1` patches cut by `partition`.
    pub fn new(sweep: Sweep, m: usize, partition: Partition) -> Result<GroupGathering, SolverError> {
        if m == 0 {
            return Err(SolverError::BadParams("a group needs at least one patch (g ≥ 1)".into()));
        }
        Ok(GroupGathering {
            sweep,
            m,
            partition,
            order: Vec::new(),
            next: 0,
            sweep_start: Vec::new(),
            row: Vec::new(),
            block: Vec::new(),
            residual: Vec::new(),
            delta: Vec::new(),
            residuals: SweepResidual::default(),
            changes: SweepChanges::default(),
            stats: GroupStats::default(),
        })
    }

    /// The name without parameters (`group-gs-g30`).
    fn head(&self) -> String {
        let base = match self.sweep {
            Sweep::Jacobi => "jacobi",
            Sweep::GaussSeidel => "gs",
        };
        format!("group-{base}-g{}", self.m)
    }
}

impl Solver for GroupGathering {
    fn name(&self) -> String {
        match self.partition {
            Partition::Index => self.head(),
            Partition::Spatial => format!("{}:groups=spatial", self.head()),
        }
    }

    fn init(&mut self, problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        self.order = match self.partition {
            Partition::Index => (0..problem.n()).collect(),
            Partition::Spatial => problem
                .patch_order()
                .ok_or_else(|| {
                    SolverError::BadParams(format!(
                        "{} needs a spatial patch order, which the caller did not give",
                        self.name()
                    ))
                })?
                .to_vec(),
        };
        self.next = 0;
        self.residuals = SweepResidual::default();
        self.changes = SweepChanges::default();
        self.stats = GroupStats::default();
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let (n, k) = (problem.n(), state.channels);
        if self.sweep == Sweep::Jacobi && self.next == 0 {
            self.sweep_start.clone_from(&state.radiosity);
        }
        let start = self.next * self.m;
        let group = &self.order[start..(start + self.m).min(n)];
        let size = group.len();
        self.residual.resize(size * k, 0.0);
        self.block.resize(size * size, 0.0);
        // The group's rows: its residual in the vector gathered from, and F_rr.
        for (a, &i) in group.iter().enumerate() {
            let from = match self.sweep {
                Sweep::Jacobi => &self.sweep_start,
                Sweep::GaussSeidel => &state.radiosity,
            };
            gather(problem, from, i, &mut self.row, &mut self.residual[a * k..(a + 1) * k]);
            for (b, &j) in group.iter().enumerate() {
                self.block[a * size + b] = self.row[j];
            }
        }
        // Φ_rr δ = R per channel.
        let timer = Instant::now();
        let system = problem.system();
        self.delta.resize(size * k, 0.0);
        let mut condition: Real = 0.0;
        for c in 0..k {
            // Φ_rr = I − N_rr; `1` as a second right-hand side on the same factorisation gives
            // the condition number the solver records.
            let n_rr: Vec<Real> = (0..size * size).map(|ab| system.rho(group[ab / size], c) * self.block[ab]).collect();
            let phi = |a: usize, b: usize| Real::from(a == b) - n_rr[a * size + b];
            let rhs = [(0..size).map(|a| self.residual[a * k + c]).collect(), vec![1.0; size]];
            let mut solved = lu_solve_columns(size, false, phi, &rhs).map_err(|SingularPivot { pivot, value }| {
                SolverError::SingularGroup { step: state.step + 1, size, channel: c, pivot, value }
            })?;
            let ones = solved.pop().expect("two right-hand sides");
            condition = condition.max(m_matrix_condition(size, &n_rr, &ones).unwrap_or(Real::INFINITY));
            for (a, &v) in solved[0].iter().enumerate() {
                self.delta[a * k + c] = v;
            }
        }
        state.cost.group_seconds += timer.elapsed().as_secs_f64();
        let shot = GroupShot { size, condition, fell_back: false, operations: 0 };
        self.stats.add(&shot);
        // For group Jacobi the group's B is still its value at the start of the sweep: no
        // other group of the sweep changes it.
        for (a, &i) in group.iter().enumerate() {
            self.changes.replacing(problem, state, i);
            relax(state, i, 1.0, &self.delta[a * k..(a + 1) * k])?;
            self.residuals.add(problem, i, &self.residual[a * k..(a + 1) * k]);
        }
        self.next = if start + size == n { 0 } else { self.next + 1 };
        if self.next == 0 {
            self.changes.end_sweep();
        }
        Ok(shot.figures())
    }

    fn residual_power(&self, _problem: &Problem<'_>, _state: &State) -> Option<Real> {
        self.residuals.last()
    }

    fn residual_bound(&self, problem: &Problem<'_>, state: &State) -> Option<ResidualBound> {
        Some(self.changes.bound(problem, state, self.sweep == Sweep::Jacobi, 1.0))
    }

    fn step_kind(&self) -> StepKind {
        StepKind::Gather
    }

    fn record(&self) -> Record {
        let mut record = Record::new();
        self.stats.record(&mut record);
        record
    }
}
