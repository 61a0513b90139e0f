//! `pr-gM`, `xu-gM`, `pr-gM-mK`, `xu-gM-mK` (and the other overshooting variants):
//! group-accelerated shooting, the paper's method.
//!
//! ## Rule
//!
//! A point shooting method (PR or an overshooting variant, [`crate::overshooting`]) keeps the
//! columns it computes in a memory of `K` columns ([`ColumnMemory`], least recently used
//! evicted; `K = m` by default). A shooter whose column is stored costs no new column. Every
//! `f` point steps, a *group step* ([`crate::group_step`]) runs on the `m` stored patches with
//! the largest `A_k Σ_c |ΔB_kc + ΔB⁺_kc|`, their overshoots computed exactly from their stored
//! columns: it computes no column at all. With `K = m` the group is the last `m` shooters (the
//! paper's "first approach", §4.1); with `K > m` it is the best `m` of everything stored (its
//! optimised variant, §4.2, `pr-g30-m480`).
//!
//! - **Emitters first.** The first shots are the emitters', each once, in order of selection
//!   value; group steps start after them, and emitters' columns are not stored: an emitter
//!   usually reflects little, and a group of emitters exchanges almost nothing (paper §4.1).
//! - **Frequency.** Fixed (`:f=N`, deterministic), or automatic (`:f=auto`, the default; the
//!   paper's rule): after each group step, `f = ⌈t_group / (target · t_column)⌉` with `t_group`
//!   the measured seconds of that group step, `t_column` the mean seconds of a column so far
//!   and `target` the allowed overhead (`:target=0.05`). The first group step runs as soon as
//!   `m` columns are stored.
//! - **Steps are shooting steps.** A step is one point shot, followed by a group step when one
//!   is due, so the group holds the newest shooter; `steps=` counts shots, the paper's axis.
//!   A group step costs no column. Its seconds are reported apart ([`State::group_seconds`]).
//! - **Point selection uses estimates.** Selection among all patches uses the estimated
//!   overshoot of [`crate::overshooting`]; making it exact for the stored patches (their rows
//!   are known) costs `O(n K)` a step and, measured on multi-cubes with `xu-g30-m480`,
//!   changed no choice in `n` steps. Group selection is over stored patches only, and exact.
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
//! - Rousselle & Renaud, "Group accelerated shooting methods for radiosity", §4.

use crate::error::SolverError;
use crate::executor::Solver;
use crate::group_shooting::shoot_group;
use crate::group_step::InnerSolve;
use crate::memory::ColumnMemory;
use crate::overshooting::{Ambient, Overshoot, OvershootTracker, argmax, shoot_with_overshoot, top};
use crate::problem::Problem;
use crate::shooting::unshot_power;
use crate::state::State;
use radiosity_core::Real;
use std::time::Instant;

/// How often group steps run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Frequency {
    /// After every `f` point steps.
    Fixed(u64),
    /// From measured times, keeping group solving near `target` of the form-factor time.
    Auto {
        /// The allowed overhead, a fraction of the column time (the paper's 5%: 0.05).
        target: Real,
    },
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

/// Parameters of a group-accelerated method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroupAcceleratedParams {
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
}

impl GroupAcceleratedParams {
    /// The paper's method: groups of `group` from a memory of `memory` columns, by unshot
    /// energy, solved by LU.
    pub fn paper(group: usize, memory: usize, frequency: Frequency) -> GroupAcceleratedParams {
        GroupAcceleratedParams {
            group,
            memory,
            frequency,
            building: GroupBuilding::Unshot,
            adaptive: None,
            inner: InnerSolve::Lu,
        }
    }
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
}

impl GroupAccelerated {
    /// A group-accelerated method named `name`, shooting with `rule`.
    pub fn new(
        name: impl Into<String>,
        rule: Overshoot,
        params: GroupAcceleratedParams,
    ) -> Result<GroupAccelerated, SolverError> {
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
            Frequency::Auto { target } if !(target > 0.0 && target.is_finite()) => {
                return Err(SolverError::BadParams(format!("the target overhead must be positive, not {target}")));
            }
            _ => {}
        }
        Ok(GroupAccelerated {
            name: name.into(),
            params,
            tracker: OvershootTracker::new(rule, true)?,
            memory: ColumnMemory::new(0, 0),
            scratch: Vec::new(),
            emitters_left: Vec::new(),
            emitters_count: 0,
            since_group: 0,
            period: 0,
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

    fn group_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        // Everything here is the group step's cost: choosing the group (exact overshoots of
        // every stored patch, `O(n K)`) as well as solving it.
        let start = Instant::now();
        let ambient = Ambient::measure(problem, state);
        let mut values = vec![0.0; problem.n()];
        self.exact_values(problem, state, &ambient, &mut values);
        let group = self.choose_group(problem, &values);
        if !group.is_empty() {
            shoot_group(problem, state, &mut self.tracker, &self.memory, &group, self.params.inner)?;
        }
        let seconds = start.elapsed().as_secs_f64();
        state.group_seconds += seconds;
        self.since_group = 0;
        if let Frequency::Fixed(f) = self.params.frequency {
            self.period = f;
        } else if let Frequency::Auto { target } = self.params.frequency {
            let columns = problem.columns_fetched().max(1) as Real;
            let column_seconds = problem.ff_seconds() / columns;
            self.period = if column_seconds > 0.0 {
                (seconds / (target * column_seconds)).ceil().clamp(1.0, 1e12) as u64
            } else {
                u64::MAX
            };
        }
        Ok(())
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
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        self.point_step(problem, state)?;
        if self.group_due() {
            self.group_step(problem, state)?;
        }
        Ok(())
    }

    fn residual_power(&self, problem: &Problem<'_>, state: &State) -> Option<Real> {
        Some(unshot_power(problem, state))
    }
}
