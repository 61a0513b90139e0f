//! Products and columns of the operator, and what it can do as a [`FormFactorBackend`].
//!
//! `κ` is bilinear in a sender's normal `m` and offset `b`, so a far link's transfer needs only
//! the sender's moments `M0 = Σ A_j x_j m_j` and `M1 = Σ A_j x_j m_j b_jᵀ`, and gives the
//! receiver a linear form `n · V + nᵀ W a` of a patch's normal and offset. A product gathers
//! the moments up the tree (shifting `M1` by `M0 δᵀ` to a parent's centre), adds each link's
//! form at both ends, pushes the forms down (shifting `V` by `W δ`) and evaluates them at the
//! leaves, plus the near links: `O(links + n)`. A column `j` evaluates the links of `j`'s
//! ancestors at the patches of their other ends; each entry comes from exactly one link, so a
//! row (`F_ij` for every `j`, through `i`'s ancestors) holds bit for bit the entries the
//! columns hold.

use super::HierarchicalColumns;
use super::distribution::Distribution;
use super::links::{Span, kernel_factor};
use crate::backend::{BackendFigures, FormFactorBackend};
use radiosity_core::{Collective, ColumnSource, LinkSource, Real, Vec3, channel_groups, pick_channels, put_channels};
use rayon::prelude::*;

impl HierarchicalColumns {
    /// Calls `f(k)` for the leaf of `patch` and each of its ancestors.
    pub(super) fn ancestors(&self, patch: usize, mut f: impl FnMut(u32)) {
        let mut k = self.tree.leaf[patch];
        while k != u32::MAX {
            f(k);
            k = self.parent[k as usize];
        }
    }

    /// `F_ij` for every `i` (`row = false`: a column) or every `j` (`row = true`: a row), for
    /// the patch `p` that is `j` or `i` respectively. A far entry is `A_j · g · κ` with `κ` the
    /// link's kernel factor ([`kernel_factor`]) seen from `p`'s end: swapping the ends negates
    /// `e`, `Δ` and `PΔ` exactly and swaps `α` and `β`, so a row and a column compute each
    /// entry to the same bits.
    pub(super) fn fill_line(&self, p: usize, line: &mut [Real], row: bool) {
        line.fill(0.0);
        let w = &self.weights;
        self.ancestors(p, |k| {
            let ck = self.tree.nodes[k as usize].centre;
            for (other, [clear, count]) in self.far.of(k as usize) {
                let co = self.tree.nodes[other as usize].centre;
                let span = Span::new(ck, co, clear, count);
                let at_p = (self.normals[p], self.centroids[p] - ck);
                for &q in self.tree.patches_of(other) {
                    let q = q as usize;
                    let kappa = kernel_factor(&span, at_p, (self.normals[q], self.centroids[q] - co));
                    // F_pq or F_qp: the area is the sender's.
                    let sender = if row { q } else { p };
                    line[q] = w[p] * w[q] * (self.areas[sender] * (span.g * kappa));
                }
            }
        });
        for (q, transfer) in self.near.of(p) {
            let transfer = Real::from(transfer);
            let q = q as usize;
            line[q] = transfer / if row { self.areas[p] } else { self.areas[q] };
        }
        for (q, transfer) in self.pairs.of(p) {
            let transfer = Real::from(transfer);
            let q = q as usize;
            line[q] = w[p] * w[q] * (transfer / if row { self.areas[p] } else { self.areas[q] });
        }
        // Split over ranks, every entry is on one rank and zero on the others.
        self.summed(line);
    }
}

impl ColumnSource for HierarchicalColumns {
    fn patch_count(&self) -> usize {
        self.areas.len()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        self.fill_line(j, column, false);
    }

    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        self.fill_line(i, row, true);
        true
    }

    /// Each pair's two entries are `(g (A_j c_j)) c_i` and `(g (A_i c_i)) c_j`, or
    /// `t / A_i` and `t / A_j`: a few roundings apart.
    fn reciprocity_bound(&self) -> Option<Real> {
        Some(16.0 * Real::EPSILON)
    }

    /// Moments up the tree, the far links' transfers gathered at each node (in parallel over
    /// the nodes, each summing its own links in a fixed order, so the result is the same
    /// whatever the thread count), the linear forms down the tree, and the pairs and near
    /// links: `O(links + n)` for all channels in one pass over the links (module doc).
    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        self.estimated_product(x, channels, &self.weights, out);
        out.par_chunks_mut(channels).enumerate().for_each(|(i, out)| {
            let w = self.weights[i];
            out.iter_mut().for_each(|o| *o *= w);
            for (j, transfer) in self.near.of(i) {
                let transfer = Real::from(transfer);
                let f = transfer / self.areas[i];
                for ch in 0..channels {
                    out[ch] += f * x[j as usize * channels + ch];
                }
            }
        });
        // Split over ranks, each rank's part summed.
        self.summed(out);
        true
    }

    fn collective(&self) -> Option<&dyn Collective> {
        self.distribution.as_ref().map(Distribution::collective)
    }

    /// Its links, for shooting from its nodes (`nodal`); not when split over ranks.
    fn link_source(&self) -> Option<&dyn LinkSource> {
        self.distribution.is_none().then_some(self as &dyn LinkSource)
    }
}

impl FormFactorBackend for HierarchicalColumns {
    fn serves_rows(&self) -> bool {
        true
    }

    fn figures(&self) -> Option<BackendFigures> {
        let mut figures: BackendFigures = HierarchicalColumns::figures(self).into();
        let link_bytes = match &self.distribution {
            Some(d) => d.ranks().iter().map(|r| r.link_bytes as usize).sum(),
            None => self.link_bytes(),
        };
        figures.counts.push(("link bytes".into(), link_bytes as f64));
        if let Some(d) = &self.distribution {
            figures.summary = format!("{} over {} ranks", figures.summary, d.ranks().len());
            figures.ranks = d.ranks().iter().map(|r| r.into()).collect();
        }
        Some(figures)
    }

    /// One process's operator; a rank's part is not kept (its links are a share only).
    fn persist(&self, key: &str) -> Option<Vec<u8>> {
        self.distribution.is_none().then(|| HierarchicalColumns::to_bytes(self, key))
    }
}

impl HierarchicalColumns {
    /// `Σ_j E_ij w_j x_j` for every `i`, over the estimated entries `E` alone (far links and
    /// far pairs, before any closure weight), each sender weighed by `weights`.
    /// The channels go through the tree in groups whose moments take at most
    /// [`MOMENT_BYTES`] (one channel at a time past it): each channel's arithmetic is its own,
    /// so the groups give the same bits as one pass.
    pub(super) fn estimated_product(&self, x: &[Real], channels: usize, weights: &[Real], out: &mut [Real]) {
        self.estimated_product_in(x, channels, weights, out, MOMENT_BYTES);
    }

    /// [`Self::estimated_product`] with the moments held to `budget` bytes.
    fn estimated_product_in(&self, x: &[Real], channels: usize, weights: &[Real], out: &mut [Real], budget: usize) {
        let k = channels;
        let groups = channel_groups(k, self.tree.nodes.len() * size_of::<Moments>(), budget);
        if groups.len() <= 1 {
            let moments = self.gathered_moments(x, k, weights);
            self.received_down(&moments, k, out);
        } else {
            let n = self.areas.len();
            for group in groups {
                let g = group.len();
                let mut part = vec![0.0; n * g];
                pick_channels(x, k, group.clone(), &mut part);
                let moments = self.gathered_moments(&part, g, weights);
                self.received_down(&moments, g, &mut part);
                drop(moments);
                put_channels(&part, k, group, out);
            }
        }
        out.par_chunks_mut(k).enumerate().for_each(|(i, out)| {
            for (j, transfer) in self.pairs.of(i) {
                let transfer = Real::from(transfer);
                let f = transfer / self.areas[i] * weights[j as usize];
                for ch in 0..k {
                    out[ch] += f * x[j as usize * k + ch];
                }
            }
        });
    }

    /// Every node's moments of `x` (`k` channels), each sender weighed by `weights`: gathered
    /// up the tree, subtrees on rayon's threads (each node's from its children's alone, so
    /// the same whatever their number).
    pub(super) fn gathered_moments(&self, x: &[Real], k: usize, weights: &[Real]) -> Vec<Moments> {
        let mut moments = vec![Moments::default(); self.tree.nodes.len() * k];
        self.gather_into(x, k, weights, &mut moments);
        moments
    }

    /// [`Self::gathered_moments`] into `moments` (nodes × `k`), every one written.
    pub(super) fn gather_into(&self, x: &[Real], k: usize, weights: &[Real], moments: &mut [Moments]) {
        if !moments.is_empty() {
            self.gather_up(0, moments, x, k, weights);
        }
    }

    /// The moments of `node`'s subtree into `moments` (its nodes × `k`, in pre-order from
    /// `node`: a subtree over `m` patches is `2m − 1` nodes in a row, its first child's
    /// subtree after it, then its second's).
    fn gather_up(&self, node: usize, moments: &mut [Moments], x: &[Real], k: usize, weights: &[Real]) {
        let nodes = &self.tree.nodes;
        match self.tree.children(node) {
            None => {
                let p = self.tree.order[nodes[node].first as usize] as usize;
                let offset = self.centroids[p] - nodes[node].centre;
                for ch in 0..k {
                    let w = self.areas[p] * weights[p] * x[p * k + ch];
                    moments[ch] = Moments::of(self.normals[p] * w, offset);
                }
            }
            Some([a, b]) => {
                let (a, b) = (a as usize, b as usize);
                debug_assert_eq!((a, b), (node + 1, node + 2 * nodes[a].count as usize));
                let (here, below) = moments.split_at_mut(k);
                let (under_a, under_b) = below.split_at_mut((b - a) * k);
                both(
                    nodes[node].count,
                    || self.gather_up(a, under_a, x, k, weights),
                    || self.gather_up(b, under_b, x, k, weights),
                );
                let (da, db) = (nodes[a].centre - nodes[node].centre, nodes[b].centre - nodes[node].centre);
                for ch in 0..k {
                    here[ch] = under_a[ch].shifted(da).plus(&under_b[ch].shifted(db));
                }
            }
        }
    }

    /// Adds to `forms` (one per channel) what node `node` receives through its far links from
    /// the moments of the other ends (`moments`, nodes × channels) that `sending` marks (all of
    /// them when `None`), in the links' fixed order.
    pub(super) fn receive_far(&self, node: usize, moments: &[Moments], sending: Option<&[bool]>, forms: &mut [Form]) {
        let k = forms.len();
        for (other, [clear, count]) in self.far.of(node) {
            if sending.is_some_and(|s| !s[other as usize]) {
                continue;
            }
            // From this node to the other end.
            let span = Span::new(self.tree.nodes[node].centre, self.tree.nodes[other as usize].centre, clear, count);
            Form::receive(forms, &moments[other as usize * k..(other as usize + 1) * k], &span);
        }
    }

    /// What every patch receives through the far links from the senders' `moments` (nodes ×
    /// `k` channels), into `out`: each node's forms received and pushed down the tree in one
    /// pass, subtrees on rayon's threads, so that only the forms of the nodes above the one
    /// at work are held, not every node's (96 bytes a node and a channel). Each node's form
    /// is its links' in their fixed order plus its parent's shifted to its centre, as
    /// [`Self::pushed_down`] adds them: the same bits.
    fn received_down(&self, moments: &[Moments], k: usize, out: &mut [Real]) {
        let mut values = vec![0.0; out.len()];
        if !self.tree.nodes.is_empty() {
            self.receive_down(0, None, moments, k, &mut values);
        }
        self.put_in_patch_order(&values, k, out);
    }

    /// [`Self::received_down`] over `node`'s subtree, given its parent's forms and centre,
    /// writing its leaves' values into `values` (its patches × `k`, in tree order).
    fn receive_down(
        &self,
        node: usize,
        parent: Option<(&[Form], Vec3)>,
        moments: &[Moments],
        k: usize,
        values: &mut [Real],
    ) {
        let (mut few, mut many) = ([Form::default(); 3], Vec::new());
        let here: &mut [Form] = if k <= few.len() {
            &mut few[..k]
        } else {
            many.resize(k, Form::default());
            &mut many
        };
        self.receive_far(node, moments, None, here);
        let centre = self.tree.nodes[node].centre;
        if let Some((above, at)) = parent {
            for (form, above) in here.iter_mut().zip(above) {
                form.add(&above.shifted(centre - at));
            }
        }
        match self.tree.children(node) {
            None => {
                let p = self.tree.order[self.tree.nodes[node].first as usize] as usize;
                let offset = self.centroids[p] - centre;
                for ch in 0..k {
                    values[ch] = here[ch].at(self.normals[p], offset);
                }
            }
            Some([a, b]) => {
                let (a, b) = (a as usize, b as usize);
                let here = Some((&*here, centre));
                let (values_a, values_b) = values.split_at_mut(self.tree.nodes[a].count as usize * k);
                both(
                    self.tree.nodes[node].count,
                    || self.receive_down(a, here, moments, k, values_a),
                    || self.receive_down(b, here, moments, k, values_b),
                );
            }
        }
    }

    /// `values` (patches × `k` in tree order) into `out` (in patch order).
    fn put_in_patch_order(&self, values: &[Real], k: usize, out: &mut [Real]) {
        let nodes = &self.tree.nodes;
        out.par_chunks_mut(k).enumerate().for_each(|(p, out)| {
            let at = nodes[self.tree.leaf[p] as usize].first as usize * k;
            out.copy_from_slice(&values[at..at + k]);
        });
    }

    /// Pushes `forms` (nodes × `k` channels) down the tree, a parent's shifted into its
    /// children's, subtrees on rayon's threads, and writes each leaf's form evaluated at its
    /// patch into `out`.
    pub(super) fn pushed_down(&self, forms: &mut [Form], k: usize, out: &mut [Real]) {
        // The leaves' values in tree order first, where a subtree's patches are a range.
        let mut values = vec![0.0; out.len()];
        if !forms.is_empty() {
            self.push_down(0, forms, k, &mut values);
        }
        self.put_in_patch_order(&values, k, out);
    }

    /// Pushes the forms of `node`'s subtree (`forms`, its nodes × `k` in pre-order from
    /// `node`) down, writing its leaves' values into `values` (its patches × `k`, in tree
    /// order).
    fn push_down(&self, node: usize, forms: &mut [Form], k: usize, values: &mut [Real]) {
        let nodes = &self.tree.nodes;
        match self.tree.children(node) {
            None => {
                let p = self.tree.order[nodes[node].first as usize] as usize;
                let offset = self.centroids[p] - nodes[node].centre;
                for ch in 0..k {
                    values[ch] = forms[ch].at(self.normals[p], offset);
                }
            }
            Some([a, b]) => {
                let (a, b) = (a as usize, b as usize);
                let (here, below) = forms.split_at_mut(k);
                let (under_a, under_b) = below.split_at_mut((b - a) * k);
                for (c, under) in [(a, &mut *under_a), (b, &mut *under_b)] {
                    let delta = nodes[c].centre - nodes[node].centre;
                    for ch in 0..k {
                        under[ch].add(&here[ch].shifted(delta));
                    }
                }
                let (values_a, values_b) = values.split_at_mut(nodes[a].count as usize * k);
                both(
                    nodes[node].count,
                    || self.push_down(a, under_a, k, values_a),
                    || self.push_down(b, under_b, k, values_b),
                );
            }
        }
    }
}

/// Subtrees over more patches than this have their passes run beside each other.
const PARALLEL_PATCHES: usize = 4096;

/// A pass over a node's two subtrees, beside each other on rayon's threads when the node holds
/// more than [`PARALLEL_PATCHES`] patches, one after the other otherwise.
fn both(patches: u32, a: impl FnOnce() + Send, b: impl FnOnce() + Send) {
    if patches as usize > PARALLEL_PATCHES {
        rayon::join(a, b);
    } else {
        a();
        b();
    }
}

/// The most bytes a product's moments take at once, for all the channels that go through the
/// tree together. They are 96 bytes a node and a channel, held only during the product: three
/// channels at ten million patches would take 6 GB on top of the operator, more than its far
/// links. Below it (a million patches and three channels: 0.55 GB) every channel goes in one
/// pass, which reads each link once.
const MOMENT_BYTES: usize = 1 << 30;

/// What a node sends through its far links: `M0 = Σ w m` and `M1 = Σ w m bᵀ` (rows `k` of
/// `M1` are `Σ w m_k b`) over its patches, `w = A x`, `m` the normal and `b` the offset of the
/// centroid from the node's centre.
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct Moments {
    pub(super) m0: Vec3,
    pub(super) m1: [Vec3; 3],
}

impl Moments {
    pub(super) fn of(wm: Vec3, b: Vec3) -> Moments {
        Moments { m0: wm, m1: [b * wm.x, b * wm.y, b * wm.z] }
    }

    /// About a centre `δ` away: `b` becomes `b + δ`.
    pub(super) fn shifted(&self, delta: Vec3) -> Moments {
        let m = self.m0;
        Moments { m0: m, m1: [self.m1[0] + delta * m.x, self.m1[1] + delta * m.y, self.m1[2] + delta * m.z] }
    }

    pub(super) fn plus(&self, o: &Moments) -> Moments {
        Moments { m0: self.m0 + o.m0, m1: [self.m1[0] + o.m1[0], self.m1[1] + o.m1[1], self.m1[2] + o.m1[2]] }
    }
}

/// What a node receives through its far links, as a function of a patch's normal `n` and
/// offset `a` from the node's centre: `n · V + Σ_k n_k (W_k · a)`.
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct Form {
    pub(super) v: Vec3,
    pub(super) w: [Vec3; 3],
}

impl Form {
    /// Adds to `forms` (one per channel) the transfer from a node with moments `from` (one per
    /// channel) along the direction `e` (from this
    /// node to that one), at distance `r`, with `g = V / (π r²)`: the first-order kernel of
    /// [`kernel_factor`] summed over the sender's patches. With `S = Σ w β = −e · M0`,
    /// `Q = Σ w β (e · b) = −eᵀ M1 e`, `U = Σ w β b = −M1ᵀ e`, `T = Σ w m · P b = tr M1 − eᵀ M1 e`:
    /// `V += g (S e − 2Q e / r + P U / r − T e / r)` and
    /// `W += g (2S e eᵀ / r − S P / r + e (P M0)ᵀ / r)`.
    /// To zeroth order (`span.first` false), `V += g S e` alone.
    pub(super) fn receive(forms: &mut [Form], from: &[Moments], span: &Span) {
        let (e, r, g) = (span.d, span.r, span.g);
        if !span.first {
            for (form, from) in forms.iter_mut().zip(from) {
                form.v += e * (g * -e.dot(from.m0));
            }
            return;
        }
        // `W`'s rows are `(g / r) (e_k (3S e + P M0) − S u_k)`, `u_k` the unit vectors.
        let g_r = g / r;
        for (form, from) in forms.iter_mut().zip(from) {
            let m1e = Vec3::new(from.m1[0].dot(e), from.m1[1].dot(e), from.m1[2].dot(e));
            let e_m1_e = e.dot(m1e);
            let m1t_e = from.m1[0] * e.x + from.m1[1] * e.y + from.m1[2] * e.z;
            let e_m0 = e.dot(from.m0);
            let s = -e_m0;
            let q = -e_m1_e;
            let u = -m1t_e;
            let t = from.m1[0].x + from.m1[1].y + from.m1[2].z - e_m1_e;
            let pu = u - e * e.dot(u);
            let pm0 = from.m0 - e * e_m0;
            form.v += g * (e * (s - (2.0 * q + t) / r) + pu / r);
            let c = e * (3.0 * s) + pm0;
            for k in 0..3 {
                form.w[k] += (g_r * e[k]) * c;
                form.w[k][k] -= g_r * s;
            }
        }
    }

    /// About a centre `δ` away (a child's): `a` becomes `a + δ`.
    pub(super) fn shifted(&self, delta: Vec3) -> Form {
        Form { v: self.v + Vec3::new(self.w[0].dot(delta), self.w[1].dot(delta), self.w[2].dot(delta)), w: self.w }
    }

    pub(super) fn add(&mut self, o: &Form) {
        self.v += o.v;
        for k in 0..3 {
            self.w[k] += o.w[k];
        }
    }

    pub(super) fn at(&self, n: Vec3, a: Vec3) -> Real {
        n.dot(self.v) + n.x * self.w[0].dot(a) + n.y * self.w[1].dot(a) + n.z * self.w[2].dot(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hierarchical::params::HierarchicalParams;
    use radiosity_geom::PreparedScene;

    /// An operator with links of every kind on the Cornell box, and its number of patches.
    fn operator() -> (HierarchicalColumns, usize) {
        let p = PreparedScene::load("cornell:res=8").unwrap();
        let params = HierarchicalParams { eps: 0.02, ..HierarchicalParams::default() };
        (HierarchicalColumns::new(p.scene(), &p.visibility().unwrap(), &p.analysis, params), p.scene().len())
    }

    /// A positive vector of `len` values, none alike its neighbours.
    fn uneven(len: usize) -> Vec<Real> {
        (0..len).map(|i| 0.1 + ((i * 7919) % 101) as Real / 101.0).collect()
    }

    fn bits(v: &[Real]) -> Vec<u64> {
        v.iter().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn forms_received_on_the_way_down_are_those_of_every_node_pushed_down_to_the_bit() {
        let (h, n) = operator();
        for k in [1, 3, 4] {
            let x = uneven(n * k);
            let moments = h.gathered_moments(&x, k, &h.weights);
            let mut forms = vec![Form::default(); h.tree.nodes.len() * k];
            forms.par_chunks_mut(k).enumerate().for_each(|(node, forms)| h.receive_far(node, &moments, None, forms));
            let (mut every, mut fused) = (vec![0.0; n * k], vec![0.0; n * k]);
            h.pushed_down(&mut forms, k, &mut every);
            h.received_down(&moments, k, &mut fused);
            assert!(every.iter().any(|&v| v > 0.0));
            assert_eq!(bits(&every), bits(&fused), "{k} channels");
        }
    }

    #[test]
    fn channels_in_groups_give_the_bits_of_one_pass() {
        let (h, n) = operator();
        let one_channel = h.tree.nodes.len() * size_of::<Moments>();
        let k = 5;
        let x = uneven(n * k);
        let weights: Vec<Real> = (0..n).map(|i| 0.5 + (i % 7) as Real / 14.0).collect();
        let mut whole = vec![0.0; n * k];
        h.estimated_product_in(&x, k, &weights, &mut whole, usize::MAX);
        assert!(whole.iter().all(|&v| v > 0.0));
        // One channel at a time (a budget below one channel's moments), then two at a time.
        for budget in [1, 2 * one_channel] {
            let mut grouped = vec![0.0; n * k];
            h.estimated_product_in(&x, k, &weights, &mut grouped, budget);
            assert_eq!(bits(&grouped), bits(&whole), "moments held to {budget} bytes");
        }
    }
}
