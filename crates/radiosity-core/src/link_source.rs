//! The [`LinkSource`] trait: an operator that shows its links, so that a solver can shoot
//! from a node of its tree at the cost of that node's links instead of an `O(n)` column.
//!
//! ## The decomposition
//!
//! A hierarchical operator stores `F` as links between the nodes of a tree over the patches,
//! every pair of patches covered by at most one link (Hanrahan, Salzman & Aupperle 1991). Give
//! each link's two directions to their senders: `F = Σ_k S_k`, where `S_k` holds the entries
//! `F_ij` whose column `j` lies under node `k` and whose row `i` lies under the other end of one
//! of `k`'s links. The `S_k` are disjoint parts of `F`, each non-negative where `F` is.
//!
//! A solver that shoots node `k` sends `S_k u` for the radiosity `u` that `k` has not sent
//! yet. What `S_k u` needs of `u` is its **charge** at `k`, a few numbers per channel (a
//! cluster's moments); what a receiver gets is a **field** at a node, a few numbers per channel
//! that give, pushed down to the patches below, the irradiance `(F u)_i` of every patch `i`
//! under it. Both are opaque to the solver: it holds them in flat buffers of
//! [`LinkSource::charge_len`] and [`LinkSource::field_len`] numbers per node and channel, laid
//! out as the source chooses, only adds them (both are linear in `u`), and has the source
//! clear the charges of the nodes it shot ([`LinkSource::clear`]).
//!
//! - [`LinkSource::charges`] gives every node's charge of a vector (one pass up the tree);
//! - [`LinkSource::shoot`] sends the charges of some nodes through their links into the fields
//!   of the other ends;
//! - [`LinkSource::evaluate`] pushes the fields down the tree and evaluates them at the
//!   patches, `(Σ_k S_k u_k)_i` for every `i`, and clears them.
//!
//! A stored matrix has the same decomposition with one level: every patch its own node, its
//! links its column (the solvers crate adapts any column source so).
//!
//! ## What a solver may rely on
//!
//! - Nodes are numbered so that a parent comes before its children ([`LinkSource::parents`]),
//!   and every patch has a leaf ([`LinkSource::leaves`]); a node's patches are those whose leaf
//!   lies under it.
//! - Everything is linear and deterministic: the same inputs give the same bits, whatever the
//!   thread count.
//! - [`LinkSource::send_shares`] bounds what a node sends, so that a solver can bound its
//!   residual without a column: `‖ρ S_k u‖_A ≤ σ_k ‖u‖_A` with `‖x‖_A = Σ_i A_i |x_i|`.
//!
//! ## References
//!
//! - P. Hanrahan, D. Salzman, L. Aupperle, "A rapid hierarchical radiosity algorithm",
//!   SIGGRAPH 1991.
//! - S. Gortler, M. Cohen, P. Slusallek, "Radiosity and relaxation methods", IEEE CG&A 14(6),
//!   1994: shooting on the hierarchy, the unshot radiosity kept on its nodes.

use crate::math::Real;

/// The parent of a root in [`LinkSource::parents`].
pub const NO_PARENT: u32 = u32::MAX;

/// An operator that exposes its links (module doc).
pub trait LinkSource: Sync {
    /// The parent of every node ([`NO_PARENT`] for a root), a parent numbered before its
    /// children.
    fn parents(&self) -> &[u32];

    /// The leaf node of every patch (as many as the patches).
    fn leaves(&self) -> &[u32];

    /// The links node `k` sends through: what shooting it touches.
    fn link_count(&self, node: usize) -> usize;

    /// The numbers a node's charge holds per channel.
    fn charge_len(&self) -> usize;

    /// The numbers a node's field holds per channel.
    fn field_len(&self) -> usize;

    /// Writes into `charges` (`nodes × channels × charge_len` numbers, node-major unless the
    /// source says otherwise) every node's charge of `x` (patch-major, `channels` channels):
    /// what the node would send of `x` restricted to its patches.
    fn charges(&self, x: &[Real], channels: usize, charges: &mut [Real]);

    /// Zeroes in `charges` the charges of the nodes marked in `sending`, every channel. The
    /// default takes the charges node-major, as [`LinkSource::charges`] does unless the
    /// source lays them out otherwise.
    fn clear(&self, sending: &[bool], channels: usize, charges: &mut [Real]) {
        let len = channels * self.charge_len();
        for (charge, _) in charges.chunks_exact_mut(len).zip(sending).filter(|(_, s)| **s) {
            charge.fill(0.0);
        }
    }

    /// Sends the charges of the nodes marked in `sending` (one flag per node) through their
    /// links, adding to `fields` (`nodes × channels × field_len` numbers, laid out as the
    /// source chooses). `charges` has every node's
    /// slot; only the senders' are read.
    fn shoot(&self, charges: &[Real], sending: &[bool], channels: usize, fields: &mut [Real]);

    /// Writes into `out` (patch-major) what `fields` give every patch, pushed down the tree,
    /// and zeroes `fields`.
    fn evaluate(&self, fields: &mut [Real], channels: usize, out: &mut [Real]);

    /// Writes into `shares` (`nodes × channels`) a bound `σ_kc` on what node `k` sends, per
    /// unit of area-weighted radiosity, weighed at the receivers by `weights` (patch-major,
    /// non-negative, usually the reflectivities):
    /// `σ_kc ≥ max_j Σ_i weights_ic A_i (S_k)_ij / A_j` over the patches `j` under `k`.
    /// Returns `false` when the source cannot; the caller then bounds every `S_k` by `F`.
    fn send_shares(&self, weights: &[Real], channels: usize, shares: &mut [Real]) -> bool;

    /// Writes into `block` (`m × m`, row-major) the entries `F_ij` between the `m` patches
    /// of `patches` (distinct), `block[a m + b] = F_{patches[a], patches[b]}`.
    fn block(&self, patches: &[usize], block: &mut [Real]);
}
