//! The operator's links shown to solvers ([`LinkSource`]): shooting from a node of the cluster
//! tree through its own links, at their cost.
//!
//! A node's **charge** (per channel, [`CHARGE`] numbers) is what its far links read of a
//! vector `x` over its patches, the moments `M0 = Σ A_j w_j x_j m_j` and
//! `M1 = Σ A_j w_j x_j m_j b_jᵀ` of the product (`product`), and at a leaf also `x_p` itself,
//! which its near links and far pairs read. A node's **field** ([`FIELD`] numbers) is the
//! linear form `n · V + nᵀ W a` its far links give the patches below it, and at a leaf also
//! the irradiance its near links and far pairs brought, weights applied. Pushed down the tree
//! (shifting `V` by `W δ`) and evaluated at the patches, weighed by their closure weights,
//! the fields give `Σ_k S_k x_k`: exactly what a product gives when every node sends the
//! charge of the same `x` (tested).
//!
//! A buffer of charges over `N` nodes and `k` channels holds every node's moments first
//! (`N k` of them, node-major), then every node's value (`N k` numbers, only the leaves'
//! used); fields likewise, their forms first. So the moments and forms are read and written in
//! place, with no copy of their own: at ten million patches a copy is 2 GB a channel.
//!
//! An operator split over ranks does not show its links: each rank holds a share of them, and a
//! shot's fields would need a sum over ranks at every push (not built).

use super::HierarchicalColumns;
use super::links::{Span, kernel_factor};
use super::product::{Form, Moments};
use radiosity_core::{LinkSource, Real};
use rayon::prelude::*;

/// The numbers of a charge per channel: `M0` (3), `M1` (9), and a leaf's `x_p`.
const CHARGE: usize = 13;
/// The numbers of a field per channel: `V` (3), `W` (9), and a leaf's irradiance from its near
/// links and far pairs.
const FIELD: usize = 13;

/// What [`LinkSource::send_shares`] adds to every share, relative: the shares are computed by
/// the product's moments, a few roundings from the entries the columns give.
const SHARE_MARGIN: Real = 1e-9;

/// The moments and the values of a buffer of charges (or the forms and the irradiances of a
/// buffer of fields) over `nodes` nodes and `k` channels (module doc).
fn parts<T: bytemuck::Pod>(buffer: &[Real], nodes: usize, k: usize) -> (&[T], &[Real]) {
    let (head, values) = buffer.split_at(nodes * k * size_of::<T>() / size_of::<Real>());
    (bytemuck::cast_slice(head), values)
}

/// [`parts`], to write.
fn parts_mut<T: bytemuck::Pod>(buffer: &mut [Real], nodes: usize, k: usize) -> (&mut [T], &mut [Real]) {
    let (head, values) = buffer.split_at_mut(nodes * k * size_of::<T>() / size_of::<Real>());
    (bytemuck::cast_slice_mut(head), values)
}

impl HierarchicalColumns {
    /// The patch of leaf `node`.
    fn patch_of_leaf(&self, node: usize) -> usize {
        self.tree.order[self.tree.nodes[node].first as usize] as usize
    }

    /// What patch `p`'s near links and far pairs bring it from the values `value(q)` of the
    /// patches at their other ends (`None`: not sent), weights applied.
    fn receive_near(&self, p: usize, value: impl Fn(usize) -> Option<Real>) -> Real {
        let mut s = 0.0;
        for (q, t) in self.near.of(p) {
            let t = Real::from(t);
            if let Some(x) = value(q as usize) {
                s += t / self.areas[p] * x;
            }
        }
        for (q, t) in self.pairs.of(p) {
            let t = Real::from(t);
            if let Some(x) = value(q as usize) {
                s += self.weights[p] * self.weights[q as usize] * (t / self.areas[p]) * x;
            }
        }
        s
    }

    /// Whether node `o` holds the leaf `leaf`: in pre-order, `o`'s subtree is the `2 count − 1`
    /// nodes from `o`.
    fn holds(&self, o: usize, leaf: u32) -> bool {
        let span = 2 * self.tree.nodes[o].count as usize - 1;
        (o..o + span).contains(&(leaf as usize))
    }
}

impl LinkSource for HierarchicalColumns {
    fn parents(&self) -> &[u32] {
        &self.parent
    }

    fn leaves(&self) -> &[u32] {
        &self.tree.leaf
    }

    fn link_count(&self, node: usize) -> usize {
        let near = if self.tree.nodes[node].is_leaf() {
            let p = self.patch_of_leaf(node);
            self.near.degree(p) + self.pairs.degree(p)
        } else {
            0
        };
        self.far.degree(node) + near
    }

    fn charge_len(&self) -> usize {
        CHARGE
    }

    fn field_len(&self) -> usize {
        FIELD
    }

    /// The product's moments, gathered up the tree (`product`) into the buffer itself.
    fn charges(&self, x: &[Real], k: usize, charges: &mut [Real]) {
        let (moments, values) = parts_mut::<Moments>(charges, self.tree.nodes.len(), k);
        self.gather_into(x, k, &self.weights, moments);
        values.fill(0.0);
        for (p, &leaf) in self.tree.leaf.iter().enumerate() {
            values[leaf as usize * k..(leaf as usize + 1) * k].copy_from_slice(&x[p * k..(p + 1) * k]);
        }
    }

    /// In parallel over the receivers, each summing its links in their fixed order.
    fn shoot(&self, charges: &[Real], sending: &[bool], k: usize, fields: &mut [Real]) {
        let (leaves, nodes) = (&self.tree.leaf, self.tree.nodes.len());
        let (moments, values) = parts::<Moments>(charges, nodes, k);
        let (forms, near) = parts_mut::<Form>(fields, nodes, k);
        forms.par_chunks_mut(k).zip(near.par_chunks_mut(k)).enumerate().for_each(|(node, (forms, near))| {
            if self.far.degree(node) > 0 {
                self.receive_far(node, moments, Some(sending), forms);
            }
            if self.tree.nodes[node].is_leaf() {
                let p = self.patch_of_leaf(node);
                for (ch, near) in near.iter_mut().enumerate() {
                    let value = |q: usize| {
                        let leaf = leaves[q] as usize;
                        sending[leaf].then(|| values[leaf * k + ch])
                    };
                    *near += self.receive_near(p, value);
                }
            }
        });
    }

    /// Zeroes the moments and values of the nodes `sending` marks.
    fn clear(&self, sending: &[bool], k: usize, charges: &mut [Real]) {
        let (moments, values) = parts_mut::<Moments>(charges, self.tree.nodes.len(), k);
        (moments.par_chunks_mut(k).zip(values.par_chunks_mut(k)).zip(sending)).for_each(|((m, v), &s)| {
            if s {
                m.fill(Moments::default());
                v.fill(0.0);
            }
        });
    }

    /// Pushed down in pre-order (`product`), in place, then evaluated at the leaves.
    fn evaluate(&self, fields: &mut [Real], k: usize, out: &mut [Real]) {
        let (forms, near) = parts_mut::<Form>(fields, self.tree.nodes.len(), k);
        self.pushed_down(forms, k, out);
        for (p, &leaf) in self.tree.leaf.iter().enumerate() {
            for ch in 0..k {
                out[p * k + ch] = self.weights[p] * out[p * k + ch] + near[leaf as usize * k + ch];
            }
        }
        fields.fill(0.0);
    }

    /// Each node's far links receive the charges of `weights` (`A_i w_i weights_i` moments:
    /// `A_i F_ij / A_j = F_ji` by the kernel's symmetry), evaluated at each of its patches
    /// without what its ancestors receive, plus a leaf's near links and far pairs; the largest,
    /// raised by [`SHARE_MARGIN`].
    fn send_shares(&self, weights: &[Real], k: usize, shares: &mut [Real]) -> bool {
        if self.distribution.is_some() {
            return false;
        }
        let nodes = &self.tree.nodes;
        let mut charges = vec![0.0; nodes.len() * k * CHARGE];
        self.charges(weights, k, &mut charges);
        let (moments, _) = parts::<Moments>(&charges, nodes.len(), k);
        shares.par_chunks_mut(k).enumerate().for_each(|(node, share)| {
            let mut forms = vec![Form::default(); k];
            self.receive_far(node, moments, None, &mut forms);
            share.fill(0.0);
            let centre = nodes[node].centre;
            for &j in self.tree.patches_of(node as u32) {
                let j = j as usize;
                for ch in 0..k {
                    let mut s = self.weights[j] * forms[ch].at(self.normals[j], self.centroids[j] - centre);
                    if nodes[node].is_leaf() {
                        s += self.receive_near(j, |q| Some(weights[q * k + ch]));
                    }
                    share[ch] = share[ch].max(s * (1.0 + SHARE_MARGIN));
                }
            }
        });
        true
    }

    /// For each column `j`, the far links of `j`'s ancestors whose other end holds a patch of
    /// the block, and `j`'s near links and far pairs, as `fill_line` computes them.
    fn block(&self, patches: &[usize], block: &mut [Real]) {
        let m = patches.len();
        block.fill(0.0);
        let leaves: Vec<u32> = patches.iter().map(|&p| self.tree.leaf[p]).collect();
        let mut marked: Vec<u32> = Vec::new();
        for &p in patches {
            self.ancestors(p, |a| marked.push(a));
        }
        marked.sort_unstable();
        marked.dedup();
        let w = &self.weights;
        for (b, &j) in patches.iter().enumerate() {
            self.ancestors(j, |a| {
                let ca = self.tree.nodes[a as usize].centre;
                for (o, [clear, count]) in self.far.of(a as usize) {
                    if marked.binary_search(&o).is_err() {
                        continue;
                    }
                    let co = self.tree.nodes[o as usize].centre;
                    let span = Span::new(ca, co, clear, count);
                    for (r, &i) in patches.iter().enumerate() {
                        if self.holds(o as usize, leaves[r]) {
                            let kappa = kernel_factor(
                                &span,
                                (self.normals[j], self.centroids[j] - ca),
                                (self.normals[i], self.centroids[i] - co),
                            );
                            block[r * m + b] = w[j] * w[i] * (self.areas[j] * (span.g * kappa));
                        }
                    }
                }
            });
            for (r, &i) in patches.iter().enumerate() {
                let near = self.near.of(j).find(|&(q, _)| q as usize == i).map(|(_, t)| Real::from(t) / self.areas[i]);
                let pair = self
                    .pairs
                    .of(j)
                    .find(|&(q, _)| q as usize == i)
                    .map(|(_, t)| w[i] * w[j] * (Real::from(t) / self.areas[i]));
                if let Some(v) = near.or(pair) {
                    block[r * m + b] = v;
                }
            }
        }
    }
}
