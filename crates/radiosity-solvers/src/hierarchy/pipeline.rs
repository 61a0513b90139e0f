//! The unshot radiosity on the nodes of a hierarchy: what every node shooter keeps, and the
//! shots, pushes and pulls that move it.
//!
//! ## The invariant
//!
//! With `F = Σ_k S_k`, each node `k` sending through its own links
//! ([`radiosity_core::LinkSource`]), the pipeline keeps for every node the charge of `u_k`, the
//! radiosity added under `k` that `k` has not sent yet, and a per-patch explicit residual `z`,
//! such that the displayed radiosity `B` has the residual
//!
//! `r(B) = E + ρ F B − B = ρ Σ_k S_k u_k + ρ P + z`,
//!
//! `P` what shots have sent into the fields and no push has brought down yet.
//!
//! - **Start**: `B = E`, every `u_k = E` under `k`, `z = 0`: `r(E) = ρ F E`.
//! - **Shoot** node `k`: its charge goes through its links into the fields (`S_k u_k` moves
//!   into `P`), `u_k = 0`: `r` unchanged.
//! - **Push**: the fields are evaluated at the patches, `Δ = ρ P`, and with `t = Δ + z` the
//!   residual is `ρ Σ_k S_k u_k + t`.
//! - **Pull** an amount `s` (the solver's choice: `t`, or `t` overshot, or a group's solve):
//!   `B += s`, every `u_k += s` under `k`, and `z = t − s`. Since
//!   `r(B + s) = r(B) − s + ρ F s`, the invariant holds again.
//!
//! Every step ends on a pull, so `P = 0` between steps.
//!
//! ## The bound
//!
//! Each node keeps `power_kc ≥ ‖u_kc‖_A` (the area-weighted sums of `|s|` pulled under it since
//! it last shot: equal while everything pulled is non-negative). With the send shares `σ_kc`
//! of the source ([`radiosity_core::LinkSource::send_shares`], weighed by `ρ`),
//! `‖r_c‖_A ≤ Σ_k σ_kc power_kc + ‖z_c‖_A`: a bound on the displayed radiosity's residual
//! that needs no column ([`ResidualBound`], all of it direct). A source without shares (a
//! stored matrix taken as one level) gives `‖ρ S_k u‖_A ≤ κ ‖u‖_A`, since `S_k ≤ F`: the bound
//! is then `κ Σ_k power_kc + ‖z_c‖_A`. The residual is non-negative while every `u_k` and `z`
//! are: from non-negative emissions, as long as nothing is overshot.
//!
//! ## One level
//!
//! A source that shows no links is taken as one level: every patch its own node and root, its
//! column its links, a charge the patch's value and a field a patch's irradiance. Shooting a
//! node then costs a column, counted as one, and the pipeline is point shooting with its
//! pushes batched.

use crate::error::SolverError;
use crate::run::problem::Problem;
use crate::run::residual_bound::{ResidualBound, area_norms};
use crate::run::state::State;
use radiosity_core::{NO_PARENT, Real};

/// The unshot radiosity on the nodes (module doc).
#[derive(Debug, Default)]
pub(crate) struct Pipeline {
    /// Channels.
    k: usize,
    /// Whether the source shows its links (else one level over columns).
    linked: bool,
    parents: Vec<u32>,
    leaves: Vec<u32>,
    /// The links each node sends through.
    link_counts: Vec<u64>,
    /// The patches under each node.
    sizes: Vec<usize>,
    charge_len: usize,
    field_len: usize,
    /// The charges of the `u_k` (nodes × channels × charge).
    pending: Vec<Real>,
    /// `power_kc ≥ ‖u_kc‖_A` (nodes × channels).
    power: Vec<Real>,
    /// The send shares `σ_kc` (nodes × channels), when the source has them.
    shares: Option<Vec<Real>>,
    /// What shots sent and no push brought down (nodes × channels × field).
    fields: Vec<Real>,
    /// The explicit residual `z` (patch-major).
    explicit: Vec<Real>,
    /// Whether every amount pulled so far was non-negative.
    nonnegative: bool,
    /// Scratch: the charges of a pull, the powers of a pull, a column.
    scratch: Vec<Real>,
    scratch_power: Vec<Real>,
    column: Vec<Real>,
}

impl Pipeline {
    /// The pipeline over `problem`'s links (or one level), started from `B = E`.
    pub(crate) fn start(problem: &Problem<'_>, state: &State) -> Pipeline {
        let (n, k) = (problem.n(), state.channels);
        let mut p = Pipeline { k, nonnegative: true, ..Pipeline::default() };
        match problem.link_source() {
            Some(links) => {
                p.linked = true;
                p.parents = links.parents().to_vec();
                p.leaves = links.leaves().to_vec();
                p.link_counts = (0..p.parents.len()).map(|node| links.link_count(node) as u64).collect();
                (p.charge_len, p.field_len) = (links.charge_len(), links.field_len());
                let mut shares = vec![0.0; p.parents.len() * k];
                let rho = problem.system().reflectivities();
                // The shares read every link once, as a product does: counted so.
                let every: u64 = p.link_counts.iter().sum();
                let known = problem.through_links(every, |l| l.send_shares(rho, k, &mut shares));
                p.shares = known.unwrap_or(false).then_some(shares);
            }
            None => {
                p.parents = vec![NO_PARENT; n];
                p.leaves = (0..n as u32).collect();
                p.link_counts = vec![n as u64; n];
                (p.charge_len, p.field_len) = (1, 1);
            }
        }
        let nodes = p.parents.len();
        p.sizes = vec![0; nodes];
        for &leaf in &p.leaves {
            p.sizes[leaf as usize] += 1;
        }
        for node in (0..nodes).rev() {
            if p.parents[node] != NO_PARENT {
                p.sizes[p.parents[node] as usize] += p.sizes[node];
            }
        }
        p.pending = vec![0.0; nodes * k * p.charge_len];
        p.power = vec![0.0; nodes * k];
        p.fields = vec![0.0; nodes * k * p.field_len];
        p.explicit = vec![0.0; n * k];
        p.scratch = vec![0.0; p.pending.len()];
        p.scratch_power = vec![0.0; p.power.len()];
        // B = E: every node holds E under it, unsent.
        p.add_pending(problem, &state.radiosity);
        p.nonnegative = state.radiosity.iter().all(|v| *v >= 0.0);
        p
    }

    /// The number of nodes.
    pub(crate) fn nodes(&self) -> usize {
        self.parents.len()
    }

    /// The parent of every node.
    pub(crate) fn parents(&self) -> &[u32] {
        &self.parents
    }

    /// The patches under every node.
    pub(crate) fn sizes(&self) -> &[usize] {
        &self.sizes
    }

    /// `power_kc` of node `node` (channels).
    pub(crate) fn power(&self, node: usize) -> &[Real] {
        &self.power[node * self.k..(node + 1) * self.k]
    }

    /// `Σ_c σ_kc power_kc`: what shooting node `node` takes off the bound (with shares; else
    /// its power, the bound's `κ` left out).
    pub(crate) fn gain(&self, node: usize) -> Real {
        let power = self.power(node);
        match &self.shares {
            Some(s) => power.iter().zip(&s[node * self.k..]).map(|(p, s)| p * s).sum(),
            None => power.iter().sum(),
        }
    }

    /// Adds `s` (patch-major) to every `u_k` under `k`, and `Σ A |s|` to the powers.
    fn add_pending(&mut self, problem: &Problem<'_>, s: &[Real]) {
        let k = self.k;
        let area = problem.system().areas();
        self.scratch_power.fill(0.0);
        for (p, &leaf) in self.leaves.iter().enumerate() {
            for c in 0..k {
                self.scratch_power[leaf as usize * k + c] += area[p] * s[p * k + c].abs();
            }
        }
        for node in (0..self.parents.len()).rev() {
            let parent = self.parents[node];
            if parent != NO_PARENT {
                for c in 0..k {
                    self.scratch_power[parent as usize * k + c] += self.scratch_power[node * k + c];
                }
            }
        }
        self.power.iter_mut().zip(&self.scratch_power).for_each(|(p, d)| *p += d);
        if self.linked {
            let scratch = &mut self.scratch;
            problem.through_links(0, |l| l.charges(s, k, scratch));
            self.pending.iter_mut().zip(&self.scratch).for_each(|(p, d)| *p += d);
        } else {
            self.pending.iter_mut().zip(s).for_each(|(p, d)| *p += d);
        }
    }

    /// Shoots the nodes `sending` marks: their charges into the fields, their `u_k` cleared.
    /// Returns the links touched.
    pub(crate) fn shoot(&mut self, problem: &Problem<'_>, sending: &[bool]) -> u64 {
        let k = self.k;
        let touched: u64 = (0..sending.len()).filter(|&node| sending[node]).map(|node| self.link_counts[node]).sum();
        if self.linked {
            let (pending, fields) = (&self.pending, &mut self.fields);
            problem.through_links(touched, |l| l.shoot(pending, sending, k, fields));
        } else {
            let n = problem.n();
            self.column.resize(n, 0.0);
            for j in (0..n).filter(|&j| sending[j]) {
                problem.column(j, &mut self.column);
                let amount = &self.pending[j * k..(j + 1) * k];
                for (field, &f) in self.fields.chunks_exact_mut(k).zip(&self.column) {
                    if f != 0.0 {
                        field.iter_mut().zip(amount).for_each(|(v, a)| *v += f * a);
                    }
                }
            }
        }
        let (charge, pending, power) = (k * self.charge_len, &mut self.pending, &mut self.power);
        for node in (0..sending.len()).filter(|&node| sending[node]) {
            pending[node * charge..(node + 1) * charge].fill(0.0);
            power[node * k..(node + 1) * k].fill(0.0);
        }
        touched
    }

    /// Pushes what the shots sent down to the patches: writes `t = ρ P + z` into `t`
    /// (patch-major) and leaves `P = 0`; the caller pulls an amount next ([`Pipeline::pull`]).
    pub(crate) fn push(&mut self, problem: &Problem<'_>, t: &mut Vec<Real>) {
        let k = self.k;
        t.resize(problem.n() * k, 0.0);
        if self.linked {
            let fields = &mut self.fields;
            problem.through_links(0, |l| l.evaluate(fields, k, t));
        } else {
            t.copy_from_slice(&self.fields);
            self.fields.fill(0.0);
        }
        let rho = problem.system().reflectivities();
        for ((t, rho), z) in t.iter_mut().zip(rho).zip(&self.explicit) {
            *t = rho * *t + z;
        }
    }

    /// Pulls `s` after a push that gave `t`: `B += s`, every `u_k += s` under `k`,
    /// `z = t − s` (module doc). Stops the run on a value that is not finite.
    pub(crate) fn pull(
        &mut self,
        problem: &Problem<'_>,
        state: &mut State,
        t: &[Real],
        s: &[Real],
    ) -> Result<(), SolverError> {
        let k = self.k;
        for idx in 0..s.len() {
            state.radiosity[idx] += s[idx];
            self.explicit[idx] = t[idx] - s[idx];
            state.unshot[idx] = s[idx];
            // The radiosity, or else the residual left, whichever is not finite.
            let value = [state.radiosity[idx], self.explicit[idx]].into_iter().find(|v| !v.is_finite());
            if let Some(value) = value {
                return Err(SolverError::NonFinite { step: state.step + 1, patch: idx / k, value });
            }
        }
        self.nonnegative &= s.iter().all(|v| *v >= 0.0) && self.explicit.iter().all(|v| *v >= 0.0);
        self.add_pending(problem, s);
        Ok(())
    }

    /// Per channel, what the nodes still hold unsent, bounded as the residual is (`Σ_k σ_kc
    /// power_kc`, or `Σ_k power_kc` without shares): the light a later round will bring.
    pub(crate) fn unshot_norms(&self) -> Vec<Real> {
        let bound = self.bound_of(&vec![0.0; self.k]);
        (0..self.k).map(|c| bound.residual_norm(c, 1.0)).collect()
    }

    /// The bound on the displayed radiosity's residual (module doc).
    pub(crate) fn bound(&self, problem: &Problem<'_>) -> ResidualBound {
        self.bound_of(&area_norms(problem.system().areas(), &self.explicit, self.k))
    }

    /// The bound with `explicit` (per channel) for `‖z_c‖_A`.
    fn bound_of(&self, explicit: &[Real]) -> ResidualBound {
        let k = self.k;
        let mut direct = explicit.to_vec();
        let mut through_f = vec![0.0; k];
        for node in 0..self.nodes() {
            for c in 0..k {
                let power = self.power[node * k + c];
                match &self.shares {
                    Some(s) => direct[c] += s[node * k + c] * power,
                    None => through_f[c] += power,
                }
            }
        }
        ResidualBound::new(through_f, direct).with_nonnegative_residual(self.nonnegative)
    }

    /// The bound's residual power relative to the emitted power, `κ` taken as 1 where the
    /// source has no shares.
    pub(crate) fn residual_power(&self, problem: &Problem<'_>) -> Real {
        let bound = self.bound(problem);
        let system = problem.system();
        let emitted: Real = area_norms(system.areas(), system.emissions(), self.k).iter().sum();
        let r: Real = (0..self.k).map(|c| bound.residual_norm(c, 1.0)).sum();
        if emitted > 0.0 { r / emitted } else { 0.0 }
    }
}
