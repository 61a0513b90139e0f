//! `gmres-K`: the generalised minimal residual method, restarted every `K` products.
//!
//! ## Rule
//!
//! Per channel, on `A B = E` with `A = I − diag(ρ) F` ([`crate::krylov::operator`]), in the
//! area inner product `⟨u, v⟩ = Σ_i A_i u_i v_i` (the norm closest to the metrics, which weigh patches
//! by area). A cycle starts from `x_0` with the residual `r_0 = E − A x_0` computed from `F`
//! (one product: the first step, and the first step of every cycle after it), `β = ‖r_0‖`,
//! `v_1 = r_0 / β`. Step `m` of the cycle is one Arnoldi step:
//!
//! `w = A v_m`, `h_im = ⟨w, v_i⟩` and `w −= h_im v_i` for `i ≤ m` (modified Gram–Schmidt,
//! done twice, which keeps the basis orthogonal to round-off), `h_{m+1,m} = ‖w‖`,
//! `v_{m+1} = w / h_{m+1,m}`;
//!
//! then `y_m` minimises `‖β e_1 − H̄_m y‖` (Givens rotations, updated one column a step), the
//! displayed radiosity is `x_m = x_0 + V_m y_m` and its residual
//! `r_m = r_0 − V_{m+1} H̄_m y_m`, both formed every step (`O(n m)`, against `O(n²)` for the
//! product). After `K` Arnoldi steps the cycle restarts from `x_K`. A zero `h_{m+1,m}` (the
//! "lucky breakdown") means the solution lies in the basis: the channel is solved and waits
//! for the others. So a cycle costs `K + 1` products, and `‖r_m‖` never rises within one.
//!
//! GMRES needs no symmetry, so it runs on every backend; it keeps `K + 1` basis vectors of
//! `n` patches and every channel.
//!
//! ## References
//!
//! - Saad & Schultz 1986, "GMRES: a generalized minimal residual algorithm for solving
//!   nonsymmetric linear systems", SIAM J. Sci. Stat. Comput. 7(3).
//! - Saad 2003, *Iterative Methods for Sparse Linear Systems*, 2nd ed., §6.5.
//! - Giraud, Langou & Rozložník 2005, "The loss of orthogonality in the Gram–Schmidt
//!   orthogonalization process", Comput. Math. Appl. 50 ("twice is enough").

use crate::error::SolverError;
use crate::krylov::operator::{self, Operator, area_weights, axpy, dots};
use crate::naming::{ParseSolverError, SolverParams, no_params, split_params, validated};
use crate::run::executor::{Solver, StepKind};
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::ResidualBound;
use crate::run::state::State;
use radiosity_core::Real;
use std::str::FromStr;

/// The names `gmres-K`: GMRES restarted every `K ≥ 1` Arnoldi steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GmresParams {
    /// Arnoldi steps per cycle.
    pub restart: usize,
}

impl FromStr for GmresParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<GmresParams, ParseSolverError> {
        let (head, params) = split_params(name);
        let Some(restart) = head.strip_prefix("gmres-") else { return Err(ParseSolverError::OtherFamily) };
        let Ok(restart) = restart.parse::<usize>() else { return Err(ParseSolverError::OtherFamily) };
        no_params(head, params)?;
        validated(name, GmresParams { restart })
    }
}

impl SolverParams for GmresParams {
    const SYNTAX: &'static str = "gmres-K";
    const HELP: &'static str = "GMRES restarted every K products by F (one product a step); needs no symmetry";
    const EXAMPLES: &'static [&'static str] = &["gmres-30"];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        Ok(Box::new(Gmres::new(self.restart)?))
    }
}

/// One channel's Arnoldi process within a cycle.
#[derive(Clone, Debug, Default)]
struct Channel {
    /// `β = ‖r_0‖` of the cycle.
    beta: Real,
    /// Raw Hessenberg columns: `h[m][i] = h_im`, `i ≤ m + 1`.
    h: Vec<Vec<Real>>,
    /// The same columns after the Givens rotations: upper triangular.
    r: Vec<Vec<Real>>,
    /// Rotations `(cos, sin)`.
    rotations: Vec<(Real, Real)>,
    /// `Q^T β e_1`, one entry longer than the steps taken.
    g: Vec<Real>,
    /// Whether the channel takes part in the cycle: a non-zero residual and no breakdown.
    active: bool,
}

/// GMRES(K) (module doc).
#[derive(Debug)]
pub struct Gmres {
    restart: usize,
    operator: Operator,
    weights: Vec<Real>,
    /// The basis `v_1, v_2, …` of the cycle, each patch-major over every channel.
    basis: Vec<Vec<Real>>,
    channels: Vec<Channel>,
    /// The cycle's start `x_0` and residual `r_0`.
    start: Vec<Real>,
    start_residual: Vec<Real>,
    /// The residual of the displayed radiosity.
    residual: Vec<Real>,
    product: Vec<Real>,
    /// Whether the next step starts a cycle (computes `r_0` from F).
    restart_next: bool,
    started: bool,
    cycles: u64,
    breakdowns: u64,
}

impl Gmres {
    /// GMRES restarted every `restart ≥ 1` Arnoldi steps.
    pub fn new(restart: usize) -> Result<Gmres, SolverError> {
        if restart == 0 {
            return Err(SolverError::BadParams("GMRES needs a restart length K ≥ 1, not 0".into()));
        }
        Ok(Gmres {
            restart,
            operator: Operator::default(),
            weights: Vec::new(),
            basis: Vec::new(),
            channels: Vec::new(),
            start: Vec::new(),
            start_residual: Vec::new(),
            residual: Vec::new(),
            product: Vec::new(),
            restart_next: true,
            started: false,
            cycles: 0,
            breakdowns: 0,
        })
    }

    /// Starts a cycle from the displayed radiosity: `r_0` from F, `v_1 = r_0 / β`.
    fn begin_cycle(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        let (k, len) = (state.channels, state.radiosity.len());
        self.residual.resize(len, 0.0);
        self.operator.residual(problem, &state.radiosity, &mut self.residual, state.step + 1)?;
        self.start.clone_from(&state.radiosity);
        self.start_residual.clone_from(&self.residual);
        let norms = dots(&self.weights, &self.residual, &self.residual, k);
        self.channels = norms
            .iter()
            .map(|&nn| {
                let beta = nn.sqrt();
                Channel { beta, g: vec![beta], active: beta > 0.0, ..Channel::default() }
            })
            .collect();
        let scale: Vec<Real> = self.channels.iter().map(|ch| if ch.active { 1.0 / ch.beta } else { 0.0 }).collect();
        let mut v1 = vec![0.0; len];
        axpy(&scale, &self.residual, &mut v1);
        self.basis.clear();
        self.basis.push(v1);
        self.restart_next = false;
        self.started = true;
        self.cycles += 1;
        state.unshot.clone_from(&self.residual);
        Ok(())
    }

    /// One Arnoldi step on the last basis vector, then the displayed radiosity and its
    /// residual from the cycle's least-squares solution.
    fn arnoldi_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        let (k, len) = (state.channels, state.radiosity.len());
        let m = self.basis.len() - 1;
        self.product.resize(len, 0.0);
        self.operator.apply(problem, &self.basis[m], &mut self.product, state.step + 1)?;
        let mut w = std::mem::take(&mut self.product);
        let mut column = vec![vec![0.0; m + 2]; k];
        for _pass in 0..2 {
            for (i, v) in self.basis.iter().enumerate() {
                let h = dots(&self.weights, &w, v, k);
                let minus: Vec<Real> = (0..k).map(|c| if self.channels[c].active { -h[c] } else { 0.0 }).collect();
                axpy(&minus, v, &mut w);
                for c in 0..k {
                    column[c][i] -= minus[c];
                }
            }
        }
        let norms = dots(&self.weights, &w, &w, k);
        let mut scale = vec![0.0; k];
        for c in 0..k {
            let ch = &mut self.channels[c];
            if !ch.active {
                continue;
            }
            let hn = norms[c].sqrt();
            column[c][m + 1] = hn;
            // Breakdown: the next direction is zero to round-off against the column's size.
            let size: Real = column[c].iter().map(|v| v * v).sum::<Real>().sqrt();
            if hn > Real::EPSILON * size {
                scale[c] = 1.0 / hn;
            } else {
                column[c][m + 1] = 0.0;
            }
            ch.h.push(column[c].clone());
            let mut rotated = column[c].clone();
            for (i, &(cs, sn)) in ch.rotations.iter().enumerate() {
                let (a, b) = (rotated[i], rotated[i + 1]);
                rotated[i] = cs * a + sn * b;
                rotated[i + 1] = -sn * a + cs * b;
            }
            let (a, b) = (rotated[m], rotated[m + 1]);
            let radius = a.hypot(b);
            let (cs, sn) = if radius > 0.0 { (a / radius, b / radius) } else { (1.0, 0.0) };
            rotated[m] = radius;
            rotated[m + 1] = 0.0;
            ch.rotations.push((cs, sn));
            let gm = ch.g[m];
            ch.g[m] = cs * gm;
            ch.g.push(-sn * gm);
            ch.r.push(rotated);
        }
        let mut next = vec![0.0; len];
        axpy(&scale, &w, &mut next);
        self.product = w;
        self.basis.push(next);
        self.display(state);
        for (c, ch) in self.channels.iter_mut().enumerate() {
            if ch.active && scale[c] == 0.0 {
                ch.active = false;
                self.breakdowns += 1;
            }
        }
        if self.basis.len() > self.restart || self.channels.iter().all(|ch| !ch.active) {
            self.restart_next = true;
        }
        operator::check_finite(state)
    }

    /// `x = x_0 + V y` and `r = r_0 − V H̄ y` for every channel that took a step this cycle,
    /// with `y` the least-squares solution of its rotated system.
    fn display(&mut self, state: &mut State) {
        let k = state.channels;
        // Per basis vector l, the coefficient of each channel in x (`y_l`) and in r (`(H̄ y)_l`).
        let mut in_x = vec![vec![0.0; k]; self.basis.len()];
        let mut in_r = vec![vec![0.0; k]; self.basis.len()];
        for (c, ch) in self.channels.iter().enumerate() {
            let steps = ch.r.len();
            // Back substitution on the upper-triangular R y = g.
            let mut y = vec![0.0; steps];
            for i in (0..steps).rev() {
                let mut s = ch.g[i];
                for (l, yl) in y.iter().enumerate().skip(i + 1) {
                    s -= ch.r[l][i] * yl;
                }
                y[i] = if ch.r[i][i] != 0.0 { s / ch.r[i][i] } else { 0.0 };
            }
            for (l, yl) in y.iter().enumerate() {
                in_x[l][c] = *yl;
                for (i, h) in ch.h[l].iter().enumerate() {
                    in_r[i][c] -= h * yl;
                }
            }
        }
        state.radiosity.clone_from(&self.start);
        self.residual.clone_from(&self.start_residual);
        for ((v, a), b) in self.basis.iter().zip(&in_x).zip(&in_r) {
            axpy(a, v, &mut state.radiosity);
            axpy(b, v, &mut self.residual);
        }
        state.unshot.clone_from(&self.residual);
    }
}

impl Solver for Gmres {
    fn name(&self) -> String {
        format!("gmres-{}", self.restart)
    }

    fn init(&mut self, problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        self.weights = area_weights(problem);
        self.operator = Operator::default();
        self.restart_next = true;
        self.started = false;
        self.cycles = 0;
        self.breakdowns = 0;
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        if self.restart_next {
            self.begin_cycle(problem, state)?;
        } else {
            self.arnoldi_step(problem, state)?;
        }
        Ok(Record::new())
    }

    fn residual_power(&self, problem: &Problem<'_>, _state: &State) -> Option<Real> {
        operator::power_once_known(problem, &self.residual, self.started)
    }

    fn residual_bound(&self, problem: &Problem<'_>, _state: &State) -> Option<ResidualBound> {
        Some(operator::bound_once_known(problem, &self.residual, self.started))
    }

    fn step_kind(&self) -> StepKind {
        StepKind::Product
    }

    fn record(&self) -> Record {
        let mut record = self.operator.record();
        record.set("cycles", self.cycles).set("breakdowns", self.breakdowns);
        record
    }
}
