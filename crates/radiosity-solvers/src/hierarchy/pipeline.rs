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
//! ## Memory
//!
//! The charges are held in groups of channels, and the source is called for a group at a
//! time (its arithmetic is each channel's own, so the bits are the same whatever the groups).
//! A group's scratch takes at most [`GROUP_BYTES`]: all channels in one group up to about a
//! million patches, one channel at a time at ten million. A shot is pushed at once, group by
//! group, so the fields are never held for every channel: one buffer of a group's fields
//! serves the shots' fields and the pulls' charges in turn, and the hierarchical operator
//! works in these buffers in place. Per node, with `c` channels in groups of `g`, the pipeline
//! holds `c · charge_len + g · max(charge_len, field_len) + 3 c` numbers, not
//! `c · (2 charge_len + field_len + 3)`.

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
use radiosity_core::{NO_PARENT, Real, channel_groups, pick_channels, put_channels};
use std::ops::Range;

/// The most bytes a group of channels' scratch takes (module doc).
const GROUP_BYTES: usize = 1 << 30;

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
    /// The groups of channels the source is called with ([`GROUP_BYTES`]; linked sources).
    groups: Vec<Range<usize>>,
    /// The charges of the `u_k`, group by group, each group as the source lays out the charges
    /// of that many channels (nodes × the group's channels × charge).
    pending: Vec<Real>,
    /// `power_kc ≥ ‖u_kc‖_A` (nodes × channels).
    power: Vec<Real>,
    /// The send shares `σ_kc` (nodes × channels), when the source has them.
    shares: Option<Vec<Real>>,
    /// The explicit residual `z` (patch-major).
    explicit: Vec<Real>,
    /// Whether every amount pulled so far was non-negative.
    nonnegative: bool,
    /// Scratch: a group's fields of a shot or charges of a pull (nodes × the group's channels
    /// × the larger), the powers of a pull, a group's channels of a vector over the patches,
    /// a column.
    scratch: Vec<Real>,
    scratch_power: Vec<Real>,
    channels: Vec<Real>,
    column: Vec<Real>,
}

impl Pipeline {
    /// The pipeline over `problem`'s links (or one level), started from `B = E`.
    pub(crate) fn start(problem: &Problem<'_>, state: &State) -> Pipeline {
        Pipeline::start_in(problem, state, GROUP_BYTES)
    }

    /// [`Pipeline::start`], a group of channels' scratch taking at most `budget` bytes (one
    /// channel at least).
    fn start_in(problem: &Problem<'_>, state: &State, budget: usize) -> Pipeline {
        let (n, k) = (problem.n(), state.channels);
        let mut p = Pipeline { k, nonnegative: true, ..Pipeline::default() };
        match problem.link_source() {
            Some(links) => {
                p.linked = true;
                p.parents = links.parents().to_vec();
                p.leaves = links.leaves().to_vec();
                p.link_counts = (0..p.parents.len()).map(|node| links.link_count(node) as u64).collect();
                (p.charge_len, p.field_len) = (links.charge_len(), links.field_len());
                let nodes = p.parents.len();
                let widest = p.charge_len.max(p.field_len);
                p.groups = channel_groups(k, nodes * widest * size_of::<Real>(), budget);
                let mut shares = vec![0.0; nodes * k];
                let rho = problem.system().reflectivities();
                // The shares read every link once, as a product does: counted so. A group at a
                // time, so that the source's own buffers are one group's.
                let every: u64 = p.link_counts.iter().sum();
                let known = problem.through_links(every, |l| {
                    for group in &p.groups {
                        let g = group.len();
                        let mut rho_g = vec![0.0; n * g];
                        pick_channels(rho, k, group.clone(), &mut rho_g);
                        let mut shares_g = vec![0.0; nodes * g];
                        if !l.send_shares(&rho_g, g, &mut shares_g) {
                            return false;
                        }
                        put_channels(&shares_g, k, group.clone(), &mut shares);
                    }
                    true
                });
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
        p.explicit = vec![0.0; n * k];
        if let Some(widest_group) = p.groups.first().map(Range::len) {
            p.scratch = vec![0.0; nodes * widest_group * p.charge_len.max(p.field_len)];
            p.channels = vec![0.0; n * widest_group];
        }
        p.scratch_power = vec![0.0; p.power.len()];
        // B = E: every node holds E under it, unsent.
        p.add_pending(problem, &state.radiosity);
        p.nonnegative = state.radiosity.iter().all(|v| *v >= 0.0);
        p
    }

    /// Where the charges of the channels `group` lie in `pending`.
    fn charges_of(&self, group: &Range<usize>) -> Range<usize> {
        let per_channel = self.parents.len() * self.charge_len;
        group.start * per_channel..group.end * per_channel
    }

    /// The bytes the pipeline holds (its vectors' capacities).
    pub(crate) fn bytes(&self) -> usize {
        let reals = [&self.pending, &self.power, &self.explicit, &self.scratch, &self.scratch_power, &self.channels]
            .iter()
            .map(|v| v.capacity())
            .sum::<usize>()
            + self.shares.as_ref().map_or(0, Vec::capacity)
            + self.column.capacity();
        reals * size_of::<Real>()
            + (self.parents.capacity() + self.leaves.capacity()) * size_of::<u32>()
            + self.link_counts.capacity() * size_of::<u64>()
            + self.sizes.capacity() * size_of::<usize>()
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
            for group in &self.groups {
                let (g, range) = (group.len(), self.charges_of(group));
                let (channels, scratch) = (&mut self.channels[..s.len() / k * g], &mut self.scratch[..range.len()]);
                pick_channels(s, k, group.clone(), channels);
                problem.through_links(0, |l| l.charges(channels, g, scratch));
                self.pending[range].iter_mut().zip(scratch.iter()).for_each(|(p, d)| *p += d);
            }
        } else {
            self.pending.iter_mut().zip(s).for_each(|(p, d)| *p += d);
        }
    }

    /// Shoots the nodes `sending` marks and pushes what they sent down to the patches: their
    /// charges go through their links into the fields and their `u_k` are cleared, and
    /// `t = ρ P + z` is written into `t` (patch-major), leaving `P = 0`; the caller pulls an
    /// amount next ([`Pipeline::pull`]). A group of channels at a time: its fields are pushed
    /// before the next group's are sent. Returns the links touched.
    pub(crate) fn shoot_and_push(&mut self, problem: &Problem<'_>, sending: &[bool], t: &mut Vec<Real>) -> u64 {
        let (n, k) = (problem.n(), self.k);
        t.resize(n * k, 0.0);
        let touched: u64 = (0..sending.len()).filter(|&node| sending[node]).map(|node| self.link_counts[node]).sum();
        if self.linked {
            let field_len = self.parents.len() * self.field_len;
            let ranges: Vec<_> = self.groups.iter().map(|group| self.charges_of(group)).collect();
            let (pending, scratch, channels) = (&mut self.pending, &mut self.scratch, &mut self.channels);
            problem.through_links(touched, |l| {
                for (group, range) in self.groups.iter().zip(ranges) {
                    let g = group.len();
                    let (fields, out) = (&mut scratch[..field_len * g], &mut channels[..n * g]);
                    fields.fill(0.0);
                    l.shoot(&pending[range.clone()], sending, g, fields);
                    l.evaluate(fields, g, out);
                    put_channels(out, k, group.clone(), t);
                    l.clear(sending, g, &mut pending[range]);
                }
            });
        } else {
            t.fill(0.0);
            self.column.resize(n, 0.0);
            for j in (0..n).filter(|&j| sending[j]) {
                problem.column(j, &mut self.column);
                let amount = &self.pending[j * k..(j + 1) * k];
                for (field, &f) in t.chunks_exact_mut(k).zip(&self.column) {
                    if f != 0.0 {
                        field.iter_mut().zip(amount).for_each(|(v, a)| *v += f * a);
                    }
                }
            }
            for j in (0..n).filter(|&j| sending[j]) {
                self.pending[j * k..(j + 1) * k].fill(0.0);
            }
        }
        for node in (0..sending.len()).filter(|&node| sending[node]) {
            self.power[node * k..(node + 1) * k].fill(0.0);
        }
        let rho = problem.system().reflectivities();
        for ((t, rho), z) in t.iter_mut().zip(rho).zip(&self.explicit) {
            *t = rho * *t + z;
        }
        touched
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

#[cfg(test)]
mod tests {
    use super::*;
    use radiosity_core::{Channels, ColumnSource, DenseColumns, LinearSystem, LinkSource};

    /// Two levels over a dense matrix: a root over every patch, which sends nothing, and a leaf
    /// a patch, whose links are its column. A charge is a leaf's value, a field its irradiance.
    struct TwoLevels {
        f: DenseColumns,
        area: Vec<Real>,
        parents: Vec<u32>,
        leaves: Vec<u32>,
    }

    impl TwoLevels {
        fn new(f: DenseColumns, area: Vec<Real>) -> TwoLevels {
            let n = area.len();
            let parents = std::iter::once(NO_PARENT).chain(std::iter::repeat_n(0, n)).collect();
            TwoLevels { f, area, parents, leaves: (1..=n as u32).collect() }
        }
    }

    impl ColumnSource for TwoLevels {
        fn patch_count(&self) -> usize {
            self.area.len()
        }

        fn fill_column(&self, j: usize, column: &mut [Real]) {
            self.f.fill_column(j, column);
        }

        fn link_source(&self) -> Option<&dyn LinkSource> {
            Some(self)
        }
    }

    impl LinkSource for TwoLevels {
        fn parents(&self) -> &[u32] {
            &self.parents
        }

        fn leaves(&self) -> &[u32] {
            &self.leaves
        }

        fn link_count(&self, node: usize) -> usize {
            if node == 0 { 0 } else { self.area.len() }
        }

        fn charge_len(&self) -> usize {
            1
        }

        fn field_len(&self) -> usize {
            1
        }

        fn charges(&self, x: &[Real], k: usize, charges: &mut [Real]) {
            charges[..k].fill(0.0);
            charges[k..].copy_from_slice(x);
        }

        fn shoot(&self, charges: &[Real], sending: &[bool], k: usize, fields: &mut [Real]) {
            let n = self.area.len();
            for j in (0..n).filter(|&j| sending[1 + j]) {
                for i in 0..n {
                    for c in 0..k {
                        fields[(1 + i) * k + c] += self.f.get(i, j) * charges[(1 + j) * k + c];
                    }
                }
            }
        }

        fn evaluate(&self, fields: &mut [Real], k: usize, out: &mut [Real]) {
            out.copy_from_slice(&fields[k..]);
            fields.fill(0.0);
        }

        fn send_shares(&self, weights: &[Real], k: usize, shares: &mut [Real]) -> bool {
            let n = self.area.len();
            shares[..k].fill(0.0);
            for j in 0..n {
                for c in 0..k {
                    let sent: Real = (0..n).map(|i| weights[i * k + c] * self.area[i] * self.f.get(i, j)).sum();
                    shares[(1 + j) * k + c] = sent / self.area[j];
                }
            }
            true
        }

        fn block(&self, patches: &[usize], block: &mut [Real]) {
            let m = patches.len();
            for (a, &i) in patches.iter().enumerate() {
                for (b, &j) in patches.iter().enumerate() {
                    block[a * m + b] = self.f.get(i, j);
                }
            }
        }
    }

    #[test]
    fn groups_of_one_channel_give_the_bits_of_one_group_a_first_round_gives_rho_f_e_and_the_bytes_are_counted() {
        let n = 9;
        let area: Vec<Real> = (0..n).map(|i| 1.0 + (i % 4) as Real * 0.25).collect();
        let f = DenseColumns::from_fn(n, |i, j| if i == j { 0.0 } else { (1 + (i * 5 + j * 3) % 7) as Real / 60.0 });
        let rho: Vec<Real> = (0..3 * n).map(|idx| 0.2 + 0.7 * ((idx * 5) % 7) as Real / 7.0).collect();
        let e: Vec<Real> =
            (0..3 * n).map(|idx| if (idx / 3) % 3 == 1 { 1.0 + (idx % 3) as Real } else { 0.0 }).collect();
        let system = LinearSystem::new(Channels::Rgb, area.clone(), rho.clone(), e.clone()).unwrap();
        let source = TwoLevels::new(f.clone(), area);
        let problem = Problem::new(&system, &source).unwrap();
        let run = |budget: usize| {
            let mut state = State::from_emission(&e, 3);
            let mut pipeline = Pipeline::start_in(&problem, &state, budget);
            let group = pipeline.groups[0].len();
            let mut brought = Vec::new();
            for round in 0..5 {
                // Every leaf in the first round, then every other leaf in turn, and the root.
                let sending: Vec<bool> =
                    (0..=n).map(|node| node == 0 || round == 0 || (node + round) % 2 == 0).collect();
                let mut t = Vec::new();
                pipeline.shoot_and_push(&problem, &sending, &mut t);
                pipeline.pull(&problem, &mut state, &t, &t).unwrap();
                brought.push(t);
            }
            (group, brought, state.radiosity, pipeline.bound(&problem))
        };
        let (whole, one) = (run(usize::MAX), run(1));
        // What it counts of itself is what the allocator holds for it, within 10%.
        let state = State::from_emission(&e, 3);
        let mut started = None;
        let info = allocation_counter::measure(|| started = Some(Pipeline::start_in(&problem, &state, usize::MAX)));
        let (held, counted) = (info.bytes_current as f64, started.unwrap().bytes() as f64);
        assert!((counted - held).abs() <= 0.1 * held, "counted {counted} bytes, the allocator holds {held}");
        assert_eq!((whole.0, one.0), (3, 1));
        // The same bits, round for round.
        assert_eq!(whole.1, one.1);
        assert_eq!(whole.2, one.2);
        assert_eq!(format!("{:?}", whole.3), format!("{:?}", one.3));
        // The first round sends E from every patch: ρ F E.
        for i in 0..n {
            for c in 0..3 {
                let want = rho[i * 3 + c] * (0..n).map(|j| f.get(i, j) * e[j * 3 + c]).sum::<Real>();
                let got = whole.1[0][i * 3 + c];
                assert!((got - want).abs() <= 1e-15 * want.abs().max(1.0), "{i}, {c}: {got} against {want}");
            }
        }
    }
}
