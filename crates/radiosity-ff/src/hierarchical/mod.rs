//! The hierarchical form-factor operator: `F` on the scene's own patches as links between
//! clusters of a tree, so that a product `F x` costs `O(links + n)` and a column `O(n)`
//! instead of `n` pairs each.
//!
//! ## What it stores
//!
//! A [cluster tree](tree) over the patches (leaves are patches: this is an operator on the
//! scene's mesh, not a remeshing) and [links](links) refined from the root's link with itself,
//! every pair of patches covered by exactly one link or by none:
//!
//! - a **far** link between nodes `A` and `B` gives `F_ij = g · A_j · cos_j · cos_i` for every
//!   `i` in one and `j` in the other, with one direction `d` between their centres for both
//!   cosines (`cos_i = n_i · d`, `cos_j = n_j · (−d)` for `i ∈ A`) and `g = V / (π r²)`;
//! - a **near** link between two patches stores the analytic backend's `A_i F_ij`.
//!
//! So `A_i F_ij = A_j F_ji` holds by construction (up to rounding), and every entry is
//! non-negative: far links are made only where every cosine is. A row sums to 1 only
//! approximately: the far links' kernel is the one between the centres, and `eps` bounds its
//! error per link.
//!
//! ## Products and columns
//!
//! With the clamp of the cosines inactive on every far link, a far link's transfer is bilinear
//! in the normals: `Σ_{j∈B} A_j x_j cos_j = −d · M_B` with the moment `M_B = Σ_{j∈B} A_j x_j n_j`.
//! A product gathers the moments up the tree, adds `d g (−d · M_B)` to a vector `R_A` per link
//! end, pushes the `R` down and ends with `y_i = n_i · R_leaf(i)`, plus the near links:
//! `O(links + n)`. A column `j` pushes the links of `j`'s ancestors into the patches of their
//! other ends; each entry comes from exactly one link, so a row (`F_ij` for every `j`, through
//! `i`'s ancestors) holds bit for bit the entries the columns hold.
//!
//! ## References
//!
//! - P. Hanrahan, D. Salzman, L. Aupperle, "A rapid hierarchical radiosity algorithm",
//!   SIGGRAPH 1991.
//! - B. Smits, J. Arvo, D. Greenberg, "A clustering algorithm for radiosity in complex
//!   environments", SIGGRAPH 1994.
//! - F. Sillion, "A unified hierarchical algorithm for global illumination with scattering
//!   volumes and object clusters", IEEE TVCG 1(3), 1995.

mod links;
mod tree;

use crate::analytic::{AnalyticColumns, AnalyticParams};
use links::{FarLink, Links, NearLink, Refiner};
use radiosity_core::{ColumnSource, Real, Scene, Vec3};
use radiosity_geom::{ParamDoc, SceneAnalysis, Visibility};
use std::time::Instant;
use tree::ClusterTree;

/// Parameters of the hierarchical operator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HierarchicalParams {
    /// The largest error estimate a far link may have, in units of a row of `F`.
    pub eps: Real,
    /// Shadow rays per far link.
    pub rays: usize,
    /// The seed of the rays (and of the near links' analytic entries).
    pub seed: u64,
}

impl Default for HierarchicalParams {
    fn default() -> Self {
        HierarchicalParams { eps: 1e-3, rays: 16, seed: 0 }
    }
}

/// Parameters of `hierarchical`.
pub const HIERARCHICAL_PARAMS: &[ParamDoc] = &[
    ParamDoc { key: "eps", default: "1e-3", doc: "largest error estimate of a far link, in units of a row of F" },
    ParamDoc { key: "rays", default: "16", doc: "shadow rays per far link, 1 to 4096" },
    ParamDoc { key: "seed", default: "0", doc: "seed of the rays" },
];

/// What building the operator found and cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HierarchyFigures {
    /// Nodes of the cluster tree.
    pub nodes: usize,
    /// Far links, between clusters or patches.
    pub far_links: usize,
    /// Near links, patch to patch with the analytic entry.
    pub near_links: usize,
    /// Shadow rays traced for far links.
    pub rays: u64,
    /// Links dropped because every ray was blocked.
    pub occluded: u64,
    /// Seconds to build the tree and the links.
    pub seconds: f64,
    /// Bytes held by the tree and the links.
    pub bytes: usize,
}

/// The hierarchical operator over a scene.
#[derive(Debug)]
pub struct HierarchicalColumns {
    tree: ClusterTree,
    parent: Vec<u32>,
    far: Vec<FarLink>,
    near: Vec<NearLink>,
    /// Far links by node (CSR): `far_at[far_start[k]..far_start[k + 1]]`.
    far_start: Vec<u32>,
    far_at: Vec<u32>,
    /// Near links by patch (CSR).
    near_start: Vec<u32>,
    near_at: Vec<u32>,
    areas: Vec<Real>,
    normals: Vec<Vec3>,
    figures: HierarchyFigures,
}

impl HierarchicalColumns {
    /// Builds the operator: the tree, then the links (on rayon's threads, the same whatever
    /// their number).
    pub fn new(
        scene: &Scene,
        visibility: &Visibility,
        analysis: &SceneAnalysis,
        params: HierarchicalParams,
    ) -> HierarchicalColumns {
        let start = Instant::now();
        let tree = ClusterTree::new(scene);
        let near_params = AnalyticParams { seed: params.seed, ..AnalyticParams::default() };
        let analytic = AnalyticColumns::new(scene, visibility, analysis, near_params);
        let mut cumulative = Vec::with_capacity(scene.len() + 1);
        cumulative.push(0.0);
        for &p in &tree.order {
            cumulative.push(cumulative.last().unwrap() + scene.patches()[p as usize].area());
        }
        let refiner = Refiner {
            scene,
            tree: &tree,
            visibility: analysis.occlusion.value.then_some(visibility),
            analytic: &analytic,
            eps: params.eps,
            rays: params.rays,
            seed: params.seed,
            tolerance: 1e-9 * scene.diagonal(),
            cumulative,
        };
        let Links { far, near, rays, occluded } = refiner.refine_all();
        let mut parent = vec![u32::MAX; tree.nodes.len()];
        for (k, node) in tree.nodes.iter().enumerate() {
            if let Some(children) = node.children {
                for c in children {
                    parent[c as usize] = k as u32;
                }
            }
        }
        let (far_start, far_at) = csr(tree.nodes.len(), far.iter().flat_map(|l| [l.a, l.b]));
        let (near_start, near_at) = csr(scene.len(), near.iter().flat_map(|l| [l.i, l.j]));
        let bytes = tree.nodes.len() * (size_of::<tree::Node>() + 4)
            + far.len() * (size_of::<FarLink>() + 8)
            + near.len() * (size_of::<NearLink>() + 8)
            + scene.len() * 40;
        let figures = HierarchyFigures {
            nodes: tree.nodes.len(),
            far_links: far.len(),
            near_links: near.len(),
            rays,
            occluded,
            seconds: start.elapsed().as_secs_f64(),
            bytes,
        };
        HierarchicalColumns {
            parent,
            far,
            near,
            far_start,
            far_at,
            near_start,
            near_at,
            areas: scene.patches().iter().map(|p| p.area()).collect(),
            normals: scene.patches().iter().map(|p| p.normal()).collect(),
            tree,
            figures,
        }
    }

    /// What building found and cost.
    pub fn figures(&self) -> HierarchyFigures {
        self.figures
    }

    /// Calls `f(k)` for the leaf of `patch` and each of its ancestors.
    fn ancestors(&self, patch: usize, mut f: impl FnMut(u32)) {
        let mut k = self.tree.leaf[patch];
        while k != u32::MAX {
            f(k);
            k = self.parent[k as usize];
        }
    }

    /// `F_ij` for every `i` (`towards_i = false`: a column) or every `j` (`true`: a row), for
    /// the patch `p` that is `j` or `i` respectively. Each entry is
    /// `(g · (A_j · cos_j)) · cos_i`, computed the same way either way.
    fn fill_line(&self, p: usize, line: &mut [Real], row: bool) {
        line.fill(0.0);
        let (np, ap) = (self.normals[p], self.areas[p]);
        self.ancestors(p, |k| {
            for &l in &self.far_at[self.far_start[k as usize] as usize..self.far_start[k as usize + 1] as usize] {
                let link = &self.far[l as usize];
                // The direction from p's side to the other side.
                let (other, d) = if link.a == k { (link.b, link.d) } else { (link.a, -link.d) };
                let cos_p = np.dot(d);
                for &q in self.tree.patches_of(other) {
                    let q = q as usize;
                    let cos_q = self.normals[q].dot(-d);
                    line[q] = match row {
                        // F_pq: j = q.
                        true => (link.g * (self.areas[q] * cos_q)) * cos_p,
                        // F_qp: j = p.
                        false => (link.g * (ap * cos_p)) * cos_q,
                    };
                }
            }
        });
        for &l in &self.near_at[self.near_start[p] as usize..self.near_start[p + 1] as usize] {
            let link = &self.near[l as usize];
            let q = if link.i as usize == p { link.j } else { link.i } as usize;
            line[q] = link.transfer / if row { ap } else { self.areas[q] };
        }
    }
}

/// Compressed lists: for each of `len` keys, the indices of the items naming it.
fn csr(len: usize, keys: impl Iterator<Item = u32> + Clone) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; len + 1];
    for k in keys.clone() {
        start[k as usize + 1] += 1;
    }
    for k in 0..len {
        start[k + 1] += start[k];
    }
    let mut next = start.clone();
    let mut at = vec![0u32; start[len] as usize];
    // Two keys per item: the item's index is its position halved.
    for (n, k) in keys.enumerate() {
        at[next[k as usize] as usize] = (n / 2) as u32;
        next[k as usize] += 1;
    }
    (start, at)
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

    /// Moments up the tree, one multiply-add per far link end, the sums down the tree, and
    /// the near links: `O(links + n)` per channel.
    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        let nodes = self.tree.nodes.len();
        let c = channels;
        // Moments, gathered up: children come after their parent, so a backward pass sees
        // them first.
        let mut moment = vec![Vec3::ZERO; nodes * c];
        for k in (0..nodes).rev() {
            match self.tree.nodes[k].children {
                None => {
                    let p = self.tree.order[self.tree.nodes[k].first as usize] as usize;
                    for ch in 0..c {
                        moment[k * c + ch] = self.normals[p] * (self.areas[p] * x[p * c + ch]);
                    }
                }
                Some([a, b]) => {
                    for ch in 0..c {
                        moment[k * c + ch] = moment[a as usize * c + ch] + moment[b as usize * c + ch];
                    }
                }
            }
        }
        let mut pushed = vec![Vec3::ZERO; nodes * c];
        for link in &self.far {
            let (a, b, d) = (link.a as usize, link.b as usize, link.d);
            for ch in 0..c {
                let into_a = link.g * (-d).dot(moment[b * c + ch]);
                let into_b = link.g * d.dot(moment[a * c + ch]);
                pushed[a * c + ch] += d * into_a;
                pushed[b * c + ch] -= d * into_b;
            }
        }
        for k in 0..nodes {
            match self.tree.nodes[k].children {
                None => {
                    let p = self.tree.order[self.tree.nodes[k].first as usize] as usize;
                    for ch in 0..c {
                        out[p * c + ch] = self.normals[p].dot(pushed[k * c + ch]);
                    }
                }
                Some([a, b]) => {
                    for ch in 0..c {
                        let r = pushed[k * c + ch];
                        pushed[a as usize * c + ch] += r;
                        pushed[b as usize * c + ch] += r;
                    }
                }
            }
        }
        for link in &self.near {
            let (i, j) = (link.i as usize, link.j as usize);
            for ch in 0..c {
                out[i * c + ch] += link.transfer / self.areas[i] * x[j * c + ch];
                out[j * c + ch] += link.transfer / self.areas[j] * x[i * c + ch];
            }
        }
        true
    }
}
