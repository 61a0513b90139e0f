//! What a solver knows, without computing any column, that bounds the residual of the radiosity
//! it displays: [`ResidualBound`], returned by [`crate::Solver::residual_bound`].
//!
//! ## Rule
//!
//! The bound is always about the **displayed** radiosity `B = state.radiosity`
//! (docs/design.md §6.1), per channel `c`, with residual `r = E + ρ F B − B` and the
//! area-weighted L1 norm `‖x‖_A = Σ_i A_i |x_i|`. A solver that knows one gives two
//! non-negative vectors `d` and `e` (by their norms) with, elementwise,
//!
//! `|r_ic| ≤ ρ_ic Σ_j F_ij |d_jc| + |e_ic|`,
//!
//! hence `‖r_c‖_A ≤ Σ_j |d_jc| Σ_i A_i ρ_ic F_ij + ‖e_c‖_A ≤ κ_c ‖d_c‖_A + ‖e_c‖_A` with
//!
//! `κ_c = max_j Σ_i A_i ρ_ic F_ij / A_j`.
//!
//! [`ResidualBound::through_f`] is `‖d_c‖_A`, [`ResidualBound::direct`] is `‖e_c‖_A`, and
//! [`ResidualBound::residual_norm`] is the bound. The solver never needs `κ_c`; the caller
//! knows it or bounds it: with exact reciprocity `A_i F_ij = A_j F_ji`,
//! `κ_c = max_j Σ_i ρ_ic F_ji ≤ (max_i ρ_ic) · (max_j Σ_i F_ji)`, at most `max_i ρ_ic` when
//! the rows sum to at most 1. With the certificate of docs/design.md §6.3,
//! `Σ A |B − B*| ≤ ‖r‖_A / (1 − ρ_max)`.
//!
//! ## Derivations, by family
//!
//! - **Shooting** (`southwell`, `pr`, `feda`, `shao`, `xu`, `xu-direct`, `xu-ambient`,
//!   `relax-ω`, group shooting `group-S-gM`, group-accelerated `S-gM[-mK]…`): every step keeps
//!   `ΔB = state.unshot` exactly the residual of the shot radiosity `x = B − ΔB`
//!   ([`crate::shooting::overshooting::step`], [`crate::group::group_step`]: a point shot, an
//!   overshooting shot, a group solve by LU or by the inner Gauss–Seidel, which keeps its own
//!   residual as unshot, and the fallback's point shots). So `B = x + ΔB` and
//!   `r(B) = r(x) + ρ F ΔB − ΔB = ρ F ΔB` exactly: `d = ΔB`, `e = 0`.
//!   The shooter's own share of its shot (`ρ_j F_jj s`, non-zero only for a patch that sees
//!   itself) stays unshot ([`crate::shooting::rule::own_share`]); before this was so, a point shot
//!   cleared it, and with `F_jj > 0` `ΔB` was not the residual of `x`.
//! - **Node shooting** (`h-southwell`, `h-pr`, `h-xu`, `h-jacobi`, `h-gauss-seidel`): between
//!   steps `r(B) = ρ Σ_k S_k u_k + z` exactly, `F = Σ_k S_k` the parts each node sends through
//!   its links, `u_k` the radiosity under node `k` it has not sent and `z` the explicit residual
//!   ([`crate::hierarchy::pipeline`]). With `power_k ≥ ‖u_k‖_A` and the source's send shares
//!   `σ_k ≥ max_j Σ_i A_i ρ_i (S_k)_ij / A_j`, `‖r‖_A ≤ Σ_k σ_k power_k + ‖z‖_A`: all of it
//!   `direct` (`‖d‖_A = 0`). Over a source without shares (one level), `S_k ≤ F` gives
//!   `‖d‖_A = Σ_k power_k` and `‖e‖_A = ‖z‖_A`.
//! - **Gauss–Seidel** (`gauss-seidel`, ω = 1) with `u = state.unshot`, each patch's last
//!   change. Gathering patch `i` moves `B_i` by its residual `c_i`, which leaves
//!   `r_i = ρ_i F_ii c_i` and adds `ρ_l F_li c_i` to every other `r_l`. Between two updates of
//!   `l` every other patch is updated once, so
//!   `r_l = ρ_l Σ_{j ∈ S_l} F_lj u_j`, `S_l` = `l` and the patches updated since `l` was: `d = u`.
//!   The first sweep differs: the initial state `B = ΔB = E` is the result of one simultaneous
//!   change `E` of every patch from zero (`r(E) = ρ F E`, so the bound holds at init with
//!   `d = u = E`), and a patch `l` not yet gathered in the first sweep still has
//!   `r_l = ρ_l Σ_j F_lj (E_j + [j gathered] u_j)`. So during the first sweep
//!   `d = |u| + [j gathered] |E_j|`: `‖d‖_A = ‖u‖_A + Σ_{j gathered} A_j |E_j|`, a running sum.
//! - **SOR** (`sor-ω`, ω ≠ 1): gathering `i` moves `B_i` by `u_i = ω c_i` and leaves
//!   `r_i = c_i + (ρ_i F_ii − 1) ω c_i = (1/ω − 1 + ρ_i F_ii) u_i`, so, as for Gauss–Seidel,
//!   `r_l = (1/ω − 1) u_l + ρ_l Σ_{j ∈ S_l} F_lj u_j`: `d` as for Gauss–Seidel (with its first
//!   sweep), `e = |1/ω − 1| u`.
//! - **Jacobi** (`jacobi`): a sweep gathers every patch from `B^k`, its start, moving it by
//!   `c^k_j = r_j(B^k)`. A full sweep gives `r(B^{k+1}) = r(B^k) + ρ F c^k − c^k = ρ F c^k`,
//!   and `r(B^0) = r(E) = ρ F E` (take `c^{-1} = E`). Mid-sweep, with the patches `j < p`
//!   gathered, `r_l = ρ_l (Σ_j F_lj c^{k-1}_j + Σ_{j<p} F_lj c^k_j)` for `l ≥ p`, and
//!   `r_l = ρ_l Σ_{j<p} F_lj c^k_j` for `l < p`. `u = state.unshot` holds `c^k` for `j < p`
//!   and `c^{k-1}` for the others, so `d = |u| + [j < p] |c^{k-1}_j|`, `e = 0`, and
//!   `‖d‖_A = ‖u‖_A` plus the running sum of `A_j |c^{k-1}_j|` over the patches gathered this
//!   sweep, taken just before each is overwritten (O(channels) memory).
//! - **Group Gauss–Seidel** (`group-gs-gM`): a group step solves `Φ_rr δ_r = R_r` by LU and
//!   sets `B_r += δ_r`, which zeroes the group's residual (its own exchanges included) and adds
//!   `ρ_l Σ_{j∈r} F_lj δ_j` to every other `r_l`: as for Gauss–Seidel, with `S_l` the groups
//!   updated since `l`'s group was (not `l`'s own), `d = u` after the first sweep and
//!   `d = |u| + [j gathered] |E_j|` during it; `e = 0`.
//! - **Group Jacobi** (`group-jacobi-gM`): every group of a sweep gathers from `B^k`; for `l`
//!   in a solved group `r`, `r_l = ρ_l Σ_{j solved, j∉r} F_lj δ^k_j`, and for the others
//!   `r_l = r_l(B^k) + ρ_l Σ_{j solved} F_lj δ^k_j` with `r(B^k) = ρ F δ^{k-1}` (own group
//!   left out; `δ^{-1} = E`): `d` and `e` as for point Jacobi.
//!
//! ## The sign of the residual
//!
//! A solver may also state that its residual is elementwise non-negative
//! ([`ResidualBound::nonnegative`]). Then `B* − B = (I − ρ F)⁻¹ r = Σ_k (ρ F)^k r ≥ 0`, so
//! `Σ A B* ≥ Σ A B`, a lower bound on the answer's norm that a caller can divide by (the
//! relative bound of `radiosity-eval`). Shooting states it whenever every `ΔB ≥ 0`, since then
//! `r = ρ F ΔB ≥ 0`: always for `southwell` and `pr` from non-negative emissions, and for
//! overshooting methods until some patch is overshot. Gathering solvers do not state it.
//!
//! Group gathering has no fallback (a singular group system is an error), and its LU solves
//! are exact but for round-off, so nothing enters `e`. Every built-in solver returns a bound;
//! a solver of one's own returns `None` unless it implements [`crate::Solver::residual_bound`].
//!
//! ## What the bound leaves out
//!
//! The derivations hold in exact arithmetic. In floating point the invariants drift by
//! round-off: about `ε ‖B‖_A` a step for the vectors updated, and, for a group step solved by
//! LU, the group system's own residual, up to about `κ_∞(Φ_rr) ε ‖s_r‖` (at most
//! [`crate::group::group_step::CONDITION_LIMIT`]` · ε`, 2e-6 relative, for a group that is trusted;
//! physical groups are far better conditioned). Gathering solvers' bounds are about the system
//! whose rows they gather ([`crate::gathering::rule`]): the column system exactly only when the
//! source gives exact rows.

use crate::run::problem::Problem;
use crate::run::state::State;
use radiosity_core::Real;

/// What a solver knows, without extra columns, that bounds the residual of its displayed
/// radiosity (module doc).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct ResidualBound {
    /// Per channel, `‖d_c‖_A`, where `|r| ≤ ρ F |d| + |e|` elementwise.
    pub through_f: Vec<Real>,
    /// Per channel, `‖e_c‖_A`.
    pub direct: Vec<Real>,
    /// Whether the residual is known to be elementwise non-negative, so that `B* ≥ B`
    /// (module doc); `false` when the solver does not know.
    pub nonnegative: bool,
}

impl ResidualBound {
    /// The bound with `through_f = ‖d_c‖_A` and `direct = ‖e_c‖_A` per channel (the same
    /// number of channels in both).
    pub fn new(through_f: Vec<Real>, direct: Vec<Real>) -> ResidualBound {
        assert_eq!(through_f.len(), direct.len(), "a residual bound has as many direct terms as channels");
        ResidualBound { through_f, direct, nonnegative: false }
    }

    /// The same bound, stating that the residual is elementwise non-negative (module doc).
    pub fn with_nonnegative_residual(mut self, nonnegative: bool) -> ResidualBound {
        self.nonnegative = nonnegative;
        self
    }

    /// `‖r_c‖_A ≤ kappa[c] · through_f[c] + direct[c]` for channel c.
    pub fn residual_norm(&self, c: usize, kappa: Real) -> Real {
        kappa * self.through_f[c] + self.direct[c]
    }

    /// The number of channels.
    pub fn channels(&self) -> usize {
        self.through_f.len()
    }
}

/// Per channel `c`, `‖v_c‖_A = Σ_i A_i |v_ic|` of the patch-major vector `values`
/// (`[i * channels + c]`) with patch areas `areas`.
pub fn area_norms(areas: &[Real], values: &[Real], channels: usize) -> Vec<Real> {
    let mut norms = vec![0.0; channels];
    for (a, patch) in areas.iter().zip(values.chunks_exact(channels)) {
        for (norm, v) in norms.iter_mut().zip(patch) {
            *norm += a * v.abs();
        }
    }
    norms
}

/// The bound of a shooting method: `d = ΔB`, `e = 0`, and `r = ρ F ΔB ≥ 0` when every
/// `ΔB ≥ 0` (module doc).
pub(crate) fn shooting(problem: &Problem<'_>, state: &State) -> ResidualBound {
    let through_f = area_norms(problem.system().areas(), &state.unshot, state.channels);
    let direct = vec![0.0; state.channels];
    let nonnegative = state.unshot.iter().all(|v| *v >= 0.0);
    ResidualBound { through_f, direct, nonnegative }
}

/// What a sweeping (gathering) solver keeps for its bound: per channel, `Σ A_j |u_j|` of the
/// values of `u = state.unshot` that patches gathered in the current sweep overwrote, and
/// whether the first sweep is running (module doc).
#[derive(Clone, Debug, Default)]
pub(crate) struct SweepChanges {
    replaced: Vec<Real>,
    later_sweep: bool,
}

impl SweepChanges {
    /// Notes that patch `i` is about to be gathered: its previous change is overwritten.
    pub(crate) fn replacing(&mut self, problem: &Problem<'_>, state: &State, i: usize) {
        let k = state.channels;
        self.replaced.resize(k, 0.0);
        let area = problem.system().areas()[i];
        for (sum, u) in self.replaced.iter_mut().zip(State::of(&state.unshot, k, i)) {
            *sum += area * u.abs();
        }
    }

    /// Closes a sweep.
    pub(crate) fn end_sweep(&mut self) {
        self.replaced.fill(0.0);
        self.later_sweep = true;
    }

    /// The bound with `d = |u| + replaced` (`always`: Jacobi's rule, every sweep; otherwise
    /// Gauss–Seidel's, the first sweep only) and `e = |1/ω − 1| · |u|`.
    pub(crate) fn bound(&self, problem: &Problem<'_>, state: &State, always: bool, omega: Real) -> ResidualBound {
        let norms = area_norms(problem.system().areas(), &state.unshot, state.channels);
        let extra = always || !self.later_sweep;
        let through_f = norms
            .iter()
            .enumerate()
            .map(|(c, u)| u + if extra { self.replaced.get(c).copied().unwrap_or(0.0) } else { 0.0 })
            .collect();
        let factor = (1.0 / omega - 1.0).abs();
        let direct = norms.iter().map(|u| factor * u).collect();
        ResidualBound { through_f, direct, nonnegative: false }
    }
}
