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
//! - **Emitters first.** Group steps start once every emitter has shot, and emitters' columns
//!   are not stored: an emitter usually reflects little, and a group of emitters exchanges
//!   almost nothing (paper §4.1).
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
//! ## References
//!
//! - Rousselle & Renaud, "Group accelerated shooting methods for radiosity", §4.

use crate::error::SolverError;
use crate::executor::Solver;
use crate::group_shooting::shoot_group;
use crate::memory::ColumnMemory;
use crate::overshooting::{Ambient, Overshoot, OvershootTracker, argmax, shoot_with_overshoot, top};
use crate::problem::Problem;
use crate::shooting::unshot_power;
use crate::state::State;
use radiosity_core::Real;

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

/// Parameters of a group-accelerated method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroupAcceleratedParams {
    /// Group size `m`.
    pub group: usize,
    /// Columns kept in memory, `K ≥ m`.
    pub memory: usize,
    /// How often group steps run.
    pub frequency: Frequency,
}

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
    /// Group steps run.
    groups: u64,
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
            groups: 0,
        })
    }

    /// Group steps run so far.
    pub fn group_steps(&self) -> u64 {
        self.groups
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
        let ambient = Ambient::measure(problem, state);
        let mut values = vec![0.0; problem.n()];
        self.exact_values(problem, state, &ambient, &mut values);
        let group = top(&values, self.memory.patches().iter().copied(), self.params.group);
        let seconds =
            if group.is_empty() { 0.0 } else { shoot_group(problem, state, &mut self.tracker, &self.memory, &group)? };
        state.group_seconds += seconds;
        self.groups += 1;
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

    fn point_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        let ambient = Ambient::measure(problem, state);
        let j = argmax(&self.tracker.values(problem, state, &ambient));
        let column = if self.emitters_left[j] || self.is_emitter(problem, j) {
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
        self.groups = 0;
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
