//! `group-southwell-gM`, `group-pr-gM`, `group-xu-gM` and the other group overshooting
//! variants: shooting from a whole group at a time, the group rebuilt at every step.
//!
//! ## Rule
//!
//! Each step builds the group from the `m` patches with the largest selection values
//! (`A_j Σ_c |ΔB_jc + ΔB⁺_jc|`, without `A_j` for Southwell; the overshoot estimated as in
//! [`crate::shooting::overshooting::step`]), fetches their `m` columns, computes each member's
//! exact overshoot from its own column, and runs the group step of [`crate::group::group_step`]. A
//! step costs `m` columns, fewer when a member's column is still held from the previous step (the
//! last `m` columns are kept, and a column served again is counted as reused).
//!
//! The solver records its group steps ([`crate::group::group_step::GroupStats`]: `group_steps`,
//! `group_size_mean`, `group_size_max`, `group_condition`, `group_fallbacks`).
//!
//! ## References
//!
//! - Rousselle & Renaud, "Group accelerated shooting methods for radiosity", §3.2–3.3 (group
//!   PR and group overshooting, groups built dynamically).

use crate::error::SolverError;
use crate::group::group_step::{GroupShot, GroupStats, InnerSolve, group_shot};
use crate::group::memory::ColumnMemory;
use crate::naming::{ParseSolverError, SolverParams, named, no_params, split_params, split_size, validated};
use crate::run::executor::Solver;
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::{self, ResidualBound};
use crate::run::state::State;
use crate::shooting::overshooting::overshoot::Overshoot;
use crate::shooting::overshooting::step::{Ambient, OvershootTracker, ShootingMethod, top};
use crate::shooting::rule::unshot_power;
use radiosity_core::Real;
use std::str::FromStr;
use std::time::Instant;

/// The names `group-S-gM`: group shooting with method `S` (any point shooting method) and
/// groups of `M`; no parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroupShootingParams {
    /// The shooting method.
    pub method: ShootingMethod,
    /// Patches a group, `m ≥ 1`.
    pub group: usize,
}

impl FromStr for GroupShootingParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<GroupShootingParams, ParseSolverError> {
        let (head, params) = split_params(name);
        let (base, group) =
            head.strip_prefix("group-").and_then(|rest| split_size(rest, "-g")).ok_or(ParseSolverError::OtherFamily)?;
        let method = ShootingMethod::parse(base).ok_or(ParseSolverError::OtherFamily)?.map_err(|e| named(name, e))?;
        no_params(head, params)?;
        validated(name, GroupShootingParams { method, group })
    }
}

impl SolverParams for GroupShootingParams {
    const SYNTAX: &'static str = "group-S-gM";
    const HELP: &'static str = "group shooting: the M patches with the most unshot power shoot together (S a point \
                                shooting method)";
    const EXAMPLES: &'static [&'static str] = &["group-pr-g30", "group-xu-g30"];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        let name = format!("group-{}-g{}", self.method.name(), self.group);
        Ok(Box::new(GroupShooting::new(name, self.group, self.method.overshoot(), self.method.by_area())?))
    }
}

/// Group shooting with groups of `m` patches.
#[derive(Debug)]
pub struct GroupShooting {
    name: String,
    m: usize,
    tracker: OvershootTracker,
    memory: ColumnMemory,
    stats: GroupStats,
}

impl GroupShooting {
    /// Group shooting named `name`, with groups of `m ≥ 1` patches, shooting with `rule`,
    /// choosing by area-weighted values (`by_area`) or plain ones (Southwell).
    pub fn new(
        name: impl Into<String>,
        m: usize,
        rule: Overshoot,
        by_area: bool,
    ) -> Result<GroupShooting, SolverError> {
        if m == 0 {
            return Err(SolverError::BadParams("a group needs at least one patch (g ≥ 1)".into()));
        }
        let tracker = OvershootTracker::new(rule, by_area)?;
        Ok(GroupShooting {
            name: name.into(),
            m,
            tracker,
            memory: ColumnMemory::new(0, 0),
            stats: GroupStats::default(),
        })
    }
}

/// Runs a group step on `group`, whose columns `memory` holds: exact overshoots from the
/// stored columns, the group shot, and the tracker told. Returns what the group shot did, its
/// operations including the members' exact overshoots, and the seconds it took.
///
/// The overshoot of a group member anticipates only the light from outside the group (our
/// correction of the paper's rule, which applies the point overshoot unchanged): its row term
/// leaves out the group, the ambient term counts the unshot radiosity outside it, and the
/// ambient's bounces are those of the outside only (`1/(1 − ρ̄ φ)`, φ the outside fraction of
/// the area; [`OvershootTracker`]). The group's solve already resolves every exchange inside
/// it, so counting them again adds to the residual what the solve removed. Measured with the
/// paper's rule: with the whole scene in one group (the furnace with 30 patches,
/// `group-feda-g30`) the ambient unshot radiosity is multiplied by `−ρ̄ R̄` at every step,
/// which stalls at ρ̄ = 0.5 (residual power stuck at 0.49) and diverges above (the 53-patch
/// Cornell box reached e_rms 4e65); with half the scene in a group (the unit cube, ρ = 0.9,
/// `group-feda-g3`, `group-xu-g3`) Feda diverged and Xu stalled. With the correction, all
/// converge.
pub(crate) fn shoot_group(
    problem: &Problem<'_>,
    state: &mut State,
    tracker: &mut OvershootTracker,
    memory: &ColumnMemory,
    group: &[usize],
    inner: InnerSolve,
) -> Result<(GroupShot, f64), SolverError> {
    let start = Instant::now();
    let k = state.channels;
    let mut sorted = group.to_vec();
    sorted.sort_unstable();
    let ambient = Ambient::measure_outside(problem, state, &sorted);
    let columns: Vec<&[Real]> = group.iter().map(|&g| memory.peek(g).expect("group columns are stored")).collect();
    let (mut rows, mut plus) = (vec![0.0; group.len() * k], vec![0.0; group.len() * k]);
    for (a, &g) in group.iter().enumerate() {
        let (row, p) = (&mut rows[a * k..(a + 1) * k], &mut plus[a * k..(a + 1) * k]);
        tracker.exact(problem, state, &ambient, g, columns[a], &sorted, row, p);
    }
    let mut shot = group_shot(problem, state, group, &columns, &plus, inner)?;
    shot.operations += group.len() as u64 * tracker.exact_operations(problem.n(), k);
    let power = Ambient::measure(problem, state).power();
    for (a, &g) in group.iter().enumerate() {
        tracker.record(g, &rows[a * k..(a + 1) * k], power);
    }
    Ok((shot, start.elapsed().as_secs_f64()))
}

impl Solver for GroupShooting {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn init(&mut self, problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        self.tracker.init(problem);
        self.memory = ColumnMemory::new(problem.n(), self.m);
        self.stats = GroupStats::default();
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let ambient = Ambient::measure(problem, state);
        let values = self.tracker.values(problem, state, &ambient);
        let group = top(&values, 0..problem.n(), self.m);
        if group.is_empty() {
            return Ok(Record::new());
        }
        let mut scratch = Vec::new();
        for &g in &group {
            self.memory.column(problem, g, &mut scratch);
        }
        let (shot, seconds) = shoot_group(problem, state, &mut self.tracker, &self.memory, &group, InnerSolve::Lu)?;
        state.cost.group_seconds += seconds;
        self.stats.add(&shot);
        Ok(shot.figures())
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
        record
    }
}
