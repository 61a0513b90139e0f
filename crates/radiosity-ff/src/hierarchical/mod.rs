//! The hierarchical form-factor operator: `F` on the scene's own patches as links between
//! clusters of a tree, so that a product `F x` costs `O(links + n)` and a column `O(n)`
//! instead of `n` pairs each.
//!
//! ## What it stores
//!
//! A cluster tree (`tree`) over the patches (leaves are patches: this is an operator on the
//! scene's mesh, not a remeshing) and links (`links`) refined from the root's link with itself,
//! every pair of patches covered by exactly one link or by none:
//!
//! - a **far** link between nodes `A` and `B` gives `F_ij = A_j · g · κ_ij` for every `i` in
//!   one and `j` in the other, with `g = V / (π r²)` between the centres and `κ` the kernel
//!   `cos θ_i cos θ_j r² / |y − x|²` to first order in the patches' offsets from the centres
//!   (`kernel_factor`), or to zeroth order (the cosines with the link's direction) on grazing
//!   links, where the first-order terms could turn it negative;
//! - a **near** link between two patches stores `A_i F_ij`: the analytic backend's, or, for
//!   two patches far apart, the far kernel's.
//!
//! So `A_i F_ij = A_j F_ji` holds by construction (up to rounding: `κ` is symmetric in the two
//! ends), and every entry is non-negative: far links are made to first order only where the
//! first-order terms cannot outweigh the product of the cosines, and to zeroth order only
//! where every patch faces the other side. A row sums to 1 only approximately: `eps`
//! bounds the second-order error of each far link, weighed by how much light it carries
//! (`brightness`: links from the lights are refined further, links between dim or dark
//! patches less), and `V` is sampled.
//!
//! ## Closure
//!
//! A far link's visible fraction is one number for all its pairs. A cluster that holds
//! patches inside an enclosure (a bookcase's shelves) and patches outside it gives the inside
//! ones light that only the outside ones see, on top of the near links that already close
//! their rows: on `office`, 3,484 of 10,990 rows summed above 1.01 and the largest 1.32. The
//! visible fraction of the three probe rays of a far pair of patches is noisy in the same
//! way (multi-cubes, without far links between clusters, reached 1.07). A row above 1 sends
//! more light than a patch receives, whatever its reflectivity, so closure (`closure`, on
//! by default) holds every row to at most 1, the summation rule, keeping reciprocity, as
//! view factors estimated by sampling are corrected in thermal radiation (Larsen & Howell
//! 1986, "Least-squares smoothing of direct-exchange areas in zonal analysis", J. Heat
//! Transfer 108). Each patch gets a weight in `[0, 1]`, and each entry of a far link or a far
//! pair is multiplied by the weights of both its patches, so `A_i F_ij = A_j F_ji` and
//! `F ≥ 0` still hold and no entry grows. The near links, the analytic backend's entries, are
//! left as they are: their rows' noise is that estimator's (its shadow rays, `budget`), as in
//! the analytic backend, and capping it too biases every row below 1, which at ρ = 0.999 moved
//! `inner-box`'s exact solution 34% from the furnace identity instead of 3.4%. A row whose near
//! part alone sums above 1 keeps it, its estimated part weighed to 0.
//!
//! The weights are found by `CLOSURE_STEPS` fixed-point steps from 1, each giving every row
//! the weight that brings it to 1 (at most 1) against the others' weights of the step
//! before, then one step that only lowers the weights of the rows still above 1. Lowering a
//! weight lowers every other row, so after it no row is above 1 but by its near part
//! (rounding aside). A step is a product over the estimated links with one channel. Closure
//! removes leaked light where it shows, in rows above 1; a leak into a row that stays below 1,
//! and light missing from the outside patches of such a cluster, are not corrected. Rows are
//! never raised towards 1, even in a closed scene: spreading a row's missing light over its
//! estimated links (weights up to 1.5 or 3) put it in the wrong places and moved `office`'s
//! exact solution from 1.84e-3 to 2.6e-3 and 3.0e-3 from the analytic one. Its cost and effect
//! are measured in `docs/hierarchical.md`.
//!
//! With `passes` above 1 the refinement is driven again by the solution (multigridding,
//! Hanrahan, Salzman & Aupperle's BF refinement on the current `B`): the operator of a pass is
//! swept from the emission (`SWEEPS` Jacobi products), the brightness is taken from that
//! radiosity instead of the estimate, and every far link that may no longer be far under it is
//! refined again from its nodes; the others keep their rays' tally. A pass refines and never
//! coarsens.
//!
//! A far link is stored as its two nodes and its rays' tally, 12 bytes; its direction, length
//! and `g` are worked out again from the nodes' centres wherever it is used, to the same bits.
//!
//! ## Products and columns
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

//! ## References
//!
//! - P. Hanrahan, D. Salzman, L. Aupperle, "A rapid hierarchical radiosity algorithm",
//!   SIGGRAPH 1991.
//! - B. Smits, J. Arvo, D. Greenberg, "A clustering algorithm for radiosity in complex
//!   environments", SIGGRAPH 1994.
//! - F. Sillion, "A unified hierarchical algorithm for global illumination with scattering
//!   volumes and object clusters", IEEE TVCG 1(3), 1995.
//! - E. Haines, J. Wallace, "Shaft culling for efficient ray-cast radiosity", Photorealistic
//!   Rendering in Computer Graphics (Eurographics Workshop on Rendering), 1994 (`shaft`).

mod brightness;
mod links;
mod shaft;
mod stored;
mod tree;

use crate::analytic::{AnalyticColumns, AnalyticParams};
use brightness::Brightness;
pub use brightness::Oracle;
use links::{Links, Refiner, Span, Watch};
use radiosity_core::{ColumnSource, Real, Scene, Vec3};
use radiosity_geom::{ParamDoc, SceneAnalysis, Visibility};
use rayon::prelude::*;
use shaft::ShaftTree;
use std::time::Instant;
use tree::ClusterTree;

/// Parameters of the hierarchical operator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HierarchicalParams {
    /// The largest error estimate a far link may have: what it may change a receiver's
    /// radiosity by, relative to the RMS radiosity (`oracle=flux`), or a row of `F`
    /// (`oracle=area`).
    pub eps: Real,
    /// A far link larger than `shadows · eps` (in the same units) is split when its rays
    /// disagree: its visible fraction would be one number for all its pairs.
    pub shadows: Real,
    /// Shadow rays per far link larger than `shadows · eps`; smaller ones trace a quarter.
    pub rays: usize,
    /// The near pairs' shadow-ray budget: the analytic backend's `budget` (rays per unit of a
    /// pair's unoccluded form factor), lower than that backend's own default: it trades the
    /// near pairs' visibility noise for build time (measured in `docs/hierarchical.md`).
    pub budget: usize,
    /// The near pairs' largest Gauss–Legendre order: the analytic backend's `order`.
    pub order: usize,
    /// The relative quadrature error the near pairs' rule aims at: the analytic backend's
    /// `tol`.
    pub tolerance: Real,
    /// The seed of the rays (and of the near links' analytic entries).
    pub seed: u64,
    /// What a link's error is weighed by: the flux it carries (the default) or its area.
    pub oracle: Oracle,
    /// The smallest weight of a patch's estimated brightness and of its reflectivity under the
    /// flux oracle: every link stays within `eps / floor²` of a row of `F` (`eps / floor`
    /// towards a receiver that reflects).
    pub floor: Real,
    /// Refinement passes: the first driven by the estimated brightness, each later one by the
    /// radiosity of the operator the pass before built (multigridding, module doc).
    pub passes: usize,
    /// Whether each row is held to at most 1 by weighing its estimated part at both ends
    /// (closure, module doc); without it the rows are left as the links give them.
    pub closure: bool,
    /// Whether a link between patches or flat clusters searches its shaft for patches before
    /// tracing rays: a clear shaft gives the tally its rays would have, without them, so the
    /// operator is the same either way (`links`). Off by default: at the default `rays` the
    /// search costs more than it saves on the scenes measured (`docs/hierarchical.md`).
    pub shafts: bool,
}

impl Default for HierarchicalParams {
    fn default() -> Self {
        HierarchicalParams {
            eps: 3e-3,
            shadows: 0.05,
            rays: 14,
            budget: 512,
            order: 8,
            tolerance: 1e-3,
            seed: 0,
            oracle: Oracle::Flux,
            floor: 0.1,
            passes: 1,
            closure: true,
            shafts: false,
        }
    }
}

/// Parameters of `hierarchical`.
pub const HIERARCHICAL_PARAMS: &[ParamDoc] = &[
    ParamDoc {
        key: "eps",
        default: "3e-3",
        doc: "largest error estimate of a far link: a receiver's radiosity relative to the RMS radiosity (a row of F with oracle=area)",
    },
    ParamDoc {
        key: "shadows",
        default: "0.05",
        doc: "a far link larger than shadows·eps is split when its rays disagree, in (0, 1]",
    },
    ParamDoc {
        key: "rays",
        default: "14",
        doc: "shadow rays per far link larger than shadows·eps (a quarter for smaller ones), 1 to 4096",
    },
    ParamDoc {
        key: "budget",
        default: "512",
        doc: "the near pairs' shadow rays per unit of unoccluded form factor (the analytic backend's budget)",
    },
    ParamDoc {
        key: "order",
        default: "8",
        doc: "the near pairs' largest Gauss-Legendre order, 1 to 32 (the analytic backend's order)",
    },
    ParamDoc {
        key: "tol",
        default: "1e-3",
        doc: "the relative quadrature error the near pairs' rule aims at, in (0, 1] (the analytic backend's tol)",
    },
    ParamDoc { key: "seed", default: "0", doc: "seed of the rays" },
    ParamDoc {
        key: "oracle",
        default: "flux",
        doc: "what a link's error is weighed by: flux (estimated sender radiosity times receiver reflectivity) or area",
    },
    ParamDoc {
        key: "floor",
        default: "0.1",
        doc: "the flux oracle's smallest weight of a brightness or a reflectivity, in (0, 1]: every link stays within eps/floor² of a row of F",
    },
    ParamDoc {
        key: "passes",
        default: "1",
        doc: "refinement passes, 1 to 4: the first by the estimated brightness, each later one by the radiosity the pass before gives",
    },
    ParamDoc {
        key: "closure",
        default: "true",
        doc: "hold every row to at most 1 by weighing its far links and far pairs at both ends, reciprocity kept; its near links (analytic entries) are left as they are (false: rows as the links give them)",
    },
    ParamDoc {
        key: "shafts",
        default: "false",
        doc: "links between patches or flat clusters search their shafts for patches first, and a clear one traces no ray: the same operator, fewer rays, a faster build only where links trace many rays (rays=64)",
    },
];

/// What building the operator found and cost (written with the links when they are cached).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HierarchyFigures {
    /// Nodes of the cluster tree.
    pub nodes: usize,
    /// Far links with a cluster at one end at least (a far link between two patches is
    /// stored as a near link, counted in `far_pairs`).
    pub far_links: usize,
    /// Of the far links, those whose kernel is taken to zeroth order (grazing links, where the
    /// first-order kernel could turn negative).
    pub zeroth_links: usize,
    /// Near links, patch to patch, each one number: the analytic entry, or the far kernel's
    /// for patches far apart (`far_pairs`).
    pub near_links: usize,
    /// Of the near links, those between patches far apart.
    pub far_pairs: u64,
    /// Shadow rays traced for far links.
    pub rays: u64,
    /// Links dropped because every ray was blocked.
    pub occluded: u64,
    /// Far links and near pairs whose shafts held no patch: seen whole without their rays
    /// (`shafts=true`).
    pub clear_shafts: u64,
    /// Seconds to build the tree and the links.
    pub seconds: f64,
    /// Bytes held by the tree and the links.
    pub bytes: usize,
    /// Patches whose far links and far pairs closure weighs below 1: the rows that would
    /// otherwise sum above 1.
    pub capped: usize,
    /// Rows whose near links alone sum above 1 (their analytic entries' noise), counted with
    /// closure or without; closure leaves them above 1.
    pub near_above: usize,
    /// The smallest closure weight (1 when no row was capped).
    pub lowest_weight: Real,
    /// Whether the links were read from disk ([`HierarchicalColumns::from_bytes`]) rather than
    /// built: the figures above are then the build's.
    pub loaded: bool,
}

/// How far a build has come ([`HierarchicalColumns::new_observed`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildProgress {
    /// The share of the pairs of patches settled: covered by a link, or dropped as unseen. It
    /// ends at 1; it is not a share of the time, since links high in the tree settle many
    /// pairs at once.
    pub settled: Real,
    /// Links made so far.
    pub links: u64,
}

/// The hierarchical operator over a scene.
#[derive(Debug)]
pub struct HierarchicalColumns {
    tree: ClusterTree,
    parent: Vec<u32>,
    /// Far links by node, each in the lists of both its nodes: the other nodes and the rays
    /// found clear of the link's rays.
    far: Adjacency<[u16; 2]>,
    /// Near links by patch, each in the lists of both its patches: the other patches and the
    /// links' `A_p F_pq`, the analytic backend's.
    near: Adjacency<Real>,
    /// Far links between two patches, like `near`, with the far kernel's `A_p F_pq`.
    pairs: Adjacency<Real>,
    /// Each patch's closure weight: its far links' and far pairs' entries are weighed by the
    /// weights of both their patches (module doc).
    weights: Vec<Real>,
    areas: Vec<Real>,
    normals: Vec<Vec3>,
    centroids: Vec<Vec3>,
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
        HierarchicalColumns::new_observed(scene, visibility, analysis, params, &|_| {})
    }

    /// [`HierarchicalColumns::new`], calling `observe` from the building threads every
    /// thousandth of the pairs of patches settled.
    pub fn new_observed(
        scene: &Scene,
        visibility: &Visibility,
        analysis: &SceneAnalysis,
        params: HierarchicalParams,
        observe: &(dyn Fn(BuildProgress) + Sync),
    ) -> HierarchicalColumns {
        let start = Instant::now();
        let tree = ClusterTree::new(scene);
        let near_params = AnalyticParams {
            order: params.order,
            tolerance: params.tolerance,
            seed: params.seed,
            budget: params.budget,
            ..AnalyticParams::default()
        };
        let analytic = AnalyticColumns::new(scene, visibility, analysis, near_params);
        let mut cumulative = Vec::with_capacity(scene.len() + 1);
        cumulative.push(0.0);
        for &p in &tree.order {
            cumulative.push(cumulative.last().unwrap() + scene.patches()[p as usize].area());
        }
        let shafts = (params.shafts && analysis.occlusion.value).then(|| ShaftTree::new(scene));
        let refiner = Refiner {
            scene,
            tree: &tree,
            visibility: analysis.occlusion.value.then_some(visibility),
            analytic: &analytic,
            brightness: Brightness::estimate(scene, &tree, params.oracle, params.floor),
            eps: params.eps,
            shadows: params.shadows * params.eps,
            strata: links::strata_order(params.rays.max(1)),
            seed: params.seed,
            shafts: shafts.as_ref(),
            tolerance: 1e-9 * scene.diagonal(),
            cumulative,
            watch: Watch::new(scene.len(), observe),
        };
        let mut links = refiner.refine_all();
        for _ in 1..params.passes {
            // Multigridding: the radiosity of this pass's operator weighs the next pass.
            let b = HierarchicalColumns::assemble(scene, tree.clone(), &links, start).radiosity(scene, SWEEPS);
            let again = Refiner {
                brightness: Brightness::from_radiosity(scene, &tree, &b, params.floor),
                watch: Watch::new(scene.len(), &|_| {}),
                cumulative: refiner.cumulative.clone(),
                strata: refiner.strata.clone(),
                ..refiner
            };
            let Links { far, near, pairs, rays, occluded, clear, .. } = std::mem::take(&mut links);
            let mut next = again.refine_again(&far);
            next.near.splice(0..0, near);
            next.pairs.splice(0..0, pairs);
            (next.rays, next.occluded, next.clear) = (next.rays + rays, next.occluded + occluded, next.clear + clear);
            links = next;
        }
        let mut operator = HierarchicalColumns::assemble(scene, tree, &links, start);
        let near = operator.near_sums();
        operator.figures.near_above = near.iter().filter(|&&s| s > 1.0).count();
        if params.closure {
            operator.close(&near);
        }
        operator.figures.seconds = start.elapsed().as_secs_f64();
        operator
    }

    /// The operator of `links` over `tree`, its figures timed from `start`.
    fn assemble(scene: &Scene, tree: ClusterTree, links: &Links, start: Instant) -> HierarchicalColumns {
        let Links { far: far_links, near: near_links, pairs: pair_links, rays, occluded, clear, zeroth, .. } = links;
        let far = Adjacency::new(tree.nodes.len(), far_links, |l| (l.a, l.b, [l.clear, l.count]));
        let near = Adjacency::new(scene.len(), near_links, |l| (l.i, l.j, l.transfer));
        let pairs = Adjacency::new(scene.len(), pair_links, |l| (l.i, l.j, l.transfer));
        let figures = HierarchyFigures {
            nodes: tree.nodes.len(),
            far_links: far_links.len(),
            zeroth_links: *zeroth as usize,
            near_links: near_links.len() + pair_links.len(),
            far_pairs: pair_links.len() as u64,
            rays: *rays,
            occluded: *occluded,
            clear_shafts: *clear,
            seconds: start.elapsed().as_secs_f64(),
            bytes: HierarchicalColumns::bytes_of(&tree, &[far.bytes(), near.bytes(), pairs.bytes()], scene.len()),
            capped: 0,
            near_above: 0,
            lowest_weight: 1.0,
            loaded: false,
        };
        let weights = vec![1.0; scene.len()];
        HierarchicalColumns::from_parts(scene, tree, Lists { far, near, pairs, weights }, figures)
    }

    /// The operator of `tree` and its links over `scene`.
    fn from_parts(scene: &Scene, tree: ClusterTree, lists: Lists, figures: HierarchyFigures) -> HierarchicalColumns {
        let Lists { far, near, pairs, weights } = lists;
        HierarchicalColumns {
            parent: parents(&tree),
            far,
            near,
            pairs,
            weights,
            areas: scene.patches().iter().map(|p| p.area()).collect(),
            normals: scene.patches().iter().map(|p| p.normal()).collect(),
            centroids: scene.patches().iter().map(|p| p.centroid()).collect(),
            tree,
            figures,
        }
    }

    /// An approximation of the operator's radiosity over `scene` in RGB: `sweeps` Jacobi
    /// sweeps from the emission, each one product.
    fn radiosity(&self, scene: &Scene, sweeps: usize) -> Vec<Real> {
        let n = scene.len();
        let e: Vec<Real> = (0..3 * n).map(|idx| scene.emission(idx / 3).0[idx % 3]).collect();
        let (mut b, mut fb) = (e.clone(), vec![0.0; 3 * n]);
        for _ in 0..sweeps {
            self.multiply(&b, 3, &mut fb);
            for (idx, v) in b.iter_mut().enumerate() {
                *v = e[idx] + scene.reflectivity(idx / 3).0[idx % 3] * fb[idx];
            }
        }
        b
    }

    /// Each row's two parts, summed: its near links' (the analytic backend's entries) and its
    /// far links' and far pairs' (with their closure weights). A row is their sum.
    pub fn row_parts(&self) -> (Vec<Real>, Vec<Real>) {
        let n = self.areas.len();
        let near = self.near_sums();
        let mut estimated = vec![0.0; n];
        self.estimated_product(&vec![1.0; n], 1, &self.weights, &mut estimated);
        estimated.iter_mut().zip(&self.weights).for_each(|(e, w)| *e *= w);
        (near, estimated)
    }

    /// Each row's near part: the sum of its near links' entries.
    fn near_sums(&self) -> Vec<Real> {
        (0..self.areas.len())
            .into_par_iter()
            .map(|i| self.near.of(i).map(|(_, &t)| t).sum::<Real>() / self.areas[i])
            .collect()
    }

    /// What building found and cost.
    pub fn figures(&self) -> HierarchyFigures {
        self.figures
    }

    /// The bytes held by a tree, its link lists (`lists`, their bytes) and the patches' areas,
    /// normals, centroids and weights.
    fn bytes_of(tree: &ClusterTree, lists: &[usize], patches: usize) -> usize {
        tree.nodes.len() * (size_of::<tree::Node>() + 4) + lists.iter().sum::<usize>() + patches * 48
    }

    /// Calls `f(k)` for the leaf of `patch` and each of its ancestors.
    fn ancestors(&self, patch: usize, mut f: impl FnMut(u32)) {
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
    fn fill_line(&self, p: usize, line: &mut [Real], row: bool) {
        line.fill(0.0);
        let w = &self.weights;
        self.ancestors(p, |k| {
            let ck = self.tree.nodes[k as usize].centre;
            for (&other, &[clear, count]) in self.far.of(k as usize) {
                let span = Span::new(&self.tree, k, other, clear, count);
                let co = self.tree.nodes[other as usize].centre;
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
        for (&q, &transfer) in self.near.of(p) {
            let q = q as usize;
            line[q] = transfer / if row { self.areas[p] } else { self.areas[q] };
        }
        for (&q, &transfer) in self.pairs.of(p) {
            let q = q as usize;
            line[q] = w[p] * w[q] * (transfer / if row { self.areas[p] } else { self.areas[q] });
        }
    }

    /// Holds every row to at most 1 (closure, module doc) as far as its estimated part can:
    /// the weights that bring each row whose near part and weighed estimated part sum above 1
    /// down to 1.
    /// `near` holds each row's near part ([`Self::near_sums`]).
    fn close(&mut self, near: &[Real]) {
        let ones = vec![1.0; self.areas.len()];
        let weights = capped_weights(near, |w, out| self.estimated_product(&ones, 1, w, out));
        self.figures.capped = weights.iter().filter(|&&w| w < 1.0).count();
        self.figures.lowest_weight = weights.iter().copied().fold(1.0, Real::min);
        self.weights = weights;
    }
}

/// The parent of each node of `tree` (`u32::MAX` for the root).
fn parents(tree: &ClusterTree) -> Vec<u32> {
    let mut parent = vec![u32::MAX; tree.nodes.len()];
    for (k, node) in tree.nodes.iter().enumerate() {
        if let Some(children) = node.children {
            for c in children {
                parent[c as usize] = k as u32;
            }
        }
    }
    parent
}

/// The kernel of a far link to first order about the centres, without its `1 / (π r²)`:
/// for `x` on `a`'s side (normal `n`, offset `a` from `a`'s centre) and `y` on `b`'s (normal
/// `m`, offset `b`), with `e` the link's direction, `P = I − e eᵀ`, `Δ = b − a`, `α = n · e`,
/// `β = −m · e`:
/// `κ = αβ (1 − 2 e · Δ / r) + (β n · PΔ − α m · PΔ) / r`. It is symmetric in the two ends (swap
/// them and `e`), and non-negative wherever the link was made.
fn kernel_factor(span: &Span, (n, a): (Vec3, Vec3), (m, b): (Vec3, Vec3)) -> Real {
    let e = span.d;
    if !span.first {
        return n.dot(e) * -m.dot(e);
    }
    let delta = b - a;
    let p_delta = delta - e * e.dot(delta);
    let (alpha, beta) = (n.dot(e), -m.dot(e));
    alpha * beta * (1.0 - 2.0 * e.dot(delta) / span.r) + (beta * n.dot(p_delta) - alpha * m.dot(p_delta)) / span.r
}

/// Closure's fixed-point steps at most, and the largest change of a weight at which they
/// stop. On `office` four steps leave its exact solution 1.842e-3 from the analytic one, six
/// (where the weights settle) 1.838e-3, none (the lowering step alone, which caps more than
/// it needs) 2.55e-3.
const CLOSURE_STEPS: usize = 4;
const CLOSURE_SETTLED: Real = 1e-3;

/// The link lists of an operator and its closure weights.
struct Lists {
    far: Adjacency<[u16; 2]>,
    near: Adjacency<Real>,
    pairs: Adjacency<Real>,
    weights: Vec<Real>,
}

/// The weights `w ≤ 1` that hold every row `fixed_i + w_i Σ_j M_ij w_j` to at most 1, with
/// `product(w, out)` writing `Σ_j M_ij w_j` (`M ≥ 0`): fixed-point steps from 1, each giving
/// every row the weight that brings it to 1 (at most 1) against the others' weights of the
/// step before, then one step that only lowers the weights of the rows still above 1.
/// Lowering a weight lowers every other row, so that step leaves no row above 1 (rounding
/// aside), whatever the steps before converged to.
fn capped_weights(fixed: &[Real], product: impl Fn(&[Real], &mut [Real])) -> Vec<Real> {
    let n = fixed.len();
    let bringing = |fixed: Real, sum: Real| if sum > 0.0 { ((1.0 - fixed) / sum).clamp(0.0, 1.0) } else { 1.0 };
    let (mut weights, mut sums) = (vec![1.0; n], vec![0.0; n]);
    for _ in 0..CLOSURE_STEPS {
        product(&weights, &mut sums);
        let mut moved: Real = 0.0;
        for i in 0..n {
            let next = bringing(fixed[i], sums[i]);
            moved = moved.max((next - weights[i]).abs());
            weights[i] = next;
        }
        if moved < CLOSURE_SETTLED {
            break;
        }
    }
    product(&weights, &mut sums);
    for i in 0..n {
        if fixed[i] + weights[i] * sums[i] > 1.0 {
            weights[i] = weights[i].min(bringing(fixed[i], sums[i]));
        }
    }
    weights
}

/// The Jacobi sweeps of the radiosity a later refinement pass is weighed by: light bounced
/// this many times, enough for an oracle that only needs each patch's brightness to a factor.
const SWEEPS: usize = 8;

/// Links by the node or patch at either end: for each of `len` keys, the other end and the
/// link's value, ordered by the other end (so that a product reads its vector in order).
#[derive(Debug)]
struct Adjacency<T> {
    start: Vec<usize>,
    other: Vec<u32>,
    value: Vec<T>,
}

impl<T: Copy + Default + Send> Adjacency<T> {
    /// The lists of `links` `(a, b, value)`, each in `a`'s list and in `b`'s. A pair is linked
    /// once, so the order within a list is total.
    fn new<L>(len: usize, links: &[L], ends: impl Fn(&L) -> (u32, u32, T)) -> Adjacency<T> {
        let mut start = vec![0usize; len + 1];
        for (a, b, _) in links.iter().map(&ends) {
            start[a as usize + 1] += 1;
            start[b as usize + 1] += 1;
        }
        for k in 0..len {
            start[k + 1] += start[k];
        }
        let mut next = start.clone();
        let (mut other, mut value) = (vec![0u32; start[len]], vec![T::default(); start[len]]);
        for (a, b, v) in links.iter().map(&ends) {
            for (p, q) in [(a, b), (b, a)] {
                (other[next[p as usize]], value[next[p as usize]]) = (q, v);
                next[p as usize] += 1;
            }
        }
        let (mut rest_other, mut rest_value) = (other.as_mut_slice(), value.as_mut_slice());
        let mut lists = Vec::with_capacity(len);
        for k in 0..len {
            let count = start[k + 1] - start[k];
            let (o, tail_o) = rest_other.split_at_mut(count);
            let (v, tail_v) = rest_value.split_at_mut(count);
            lists.push((o, v));
            (rest_other, rest_value) = (tail_o, tail_v);
        }
        lists.into_par_iter().for_each_init(Vec::new, |entries, (o, v)| {
            entries.clear();
            entries.extend(o.iter().copied().zip(v.iter().copied()));
            entries.sort_unstable_by_key(|e: &(u32, T)| e.0);
            for (k, &(q, x)) in entries.iter().enumerate() {
                (o[k], v[k]) = (q, x);
            }
        });
        Adjacency { start, other, value }
    }

    /// The list of `k`: the other ends and the values.
    fn of(&self, k: usize) -> impl Iterator<Item = (&u32, &T)> {
        let at = self.start[k]..self.start[k + 1];
        self.other[at.clone()].iter().zip(&self.value[at])
    }

    /// The bytes the lists hold.
    fn bytes(&self) -> usize {
        self.start.len() * size_of::<usize>() + self.other.len() * (size_of::<u32>() + size_of::<T>())
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
            for (&j, &transfer) in self.near.of(i) {
                let f = transfer / self.areas[i];
                for ch in 0..channels {
                    out[ch] += f * x[j as usize * channels + ch];
                }
            }
        });
        true
    }
}

impl HierarchicalColumns {
    /// `Σ_j E_ij w_j x_j` for every `i`, over the estimated entries `E` alone (far links and
    /// far pairs, before any closure weight), each sender weighed by `weights`.
    fn estimated_product(&self, x: &[Real], channels: usize, weights: &[Real], out: &mut [Real]) {
        let k = channels;
        let nodes = &self.tree.nodes;
        let mut moments = vec![Moments::default(); nodes.len() * k];
        // Gathered up: children come after their parent, so a backward pass sees them first.
        for node in (0..nodes.len()).rev() {
            match nodes[node].children {
                None => {
                    let p = self.tree.order[nodes[node].first as usize] as usize;
                    let offset = self.centroids[p] - nodes[node].centre;
                    for ch in 0..k {
                        let w = self.areas[p] * weights[p] * x[p * k + ch];
                        moments[node * k + ch] = Moments::of(self.normals[p] * w, offset);
                    }
                }
                Some([a, b]) => {
                    let (da, db) =
                        (nodes[a as usize].centre - nodes[node].centre, nodes[b as usize].centre - nodes[node].centre);
                    for ch in 0..k {
                        moments[node * k + ch] =
                            moments[a as usize * k + ch].shifted(da).plus(&moments[b as usize * k + ch].shifted(db));
                    }
                }
            }
        }
        let mut forms = vec![Form::default(); nodes.len() * k];
        forms.par_chunks_mut(k).enumerate().for_each(|(node, forms)| {
            for (&other, &[clear, count]) in self.far.of(node) {
                // From this node to the other end.
                let span = Span::new(&self.tree, node as u32, other, clear, count);
                let from = &moments[other as usize * k..(other as usize + 1) * k];
                Form::receive(forms, from, &span);
            }
        });
        for node in 0..nodes.len() {
            match nodes[node].children {
                None => {
                    let p = self.tree.order[nodes[node].first as usize] as usize;
                    let offset = self.centroids[p] - nodes[node].centre;
                    for ch in 0..k {
                        out[p * k + ch] = forms[node * k + ch].at(self.normals[p], offset);
                    }
                }
                Some(children) => {
                    for c in children {
                        let delta = nodes[c as usize].centre - nodes[node].centre;
                        for ch in 0..k {
                            let shifted = forms[node * k + ch].shifted(delta);
                            forms[c as usize * k + ch].add(&shifted);
                        }
                    }
                }
            }
        }
        out.par_chunks_mut(k).enumerate().for_each(|(i, out)| {
            for (&j, &transfer) in self.pairs.of(i) {
                let f = transfer / self.areas[i] * weights[j as usize];
                for ch in 0..k {
                    out[ch] += f * x[j as usize * k + ch];
                }
            }
        });
    }
}

/// What a node sends through its far links: `M0 = Σ w m` and `M1 = Σ w m bᵀ` (rows `k` of
/// `M1` are `Σ w m_k b`) over its patches, `w = A x`, `m` the normal and `b` the offset of the
/// centroid from the node's centre.
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    m0: Vec3,
    m1: [Vec3; 3],
}

impl Moments {
    fn of(wm: Vec3, b: Vec3) -> Moments {
        Moments { m0: wm, m1: [b * wm.x, b * wm.y, b * wm.z] }
    }

    /// About a centre `δ` away: `b` becomes `b + δ`.
    fn shifted(&self, delta: Vec3) -> Moments {
        let m = self.m0;
        Moments { m0: m, m1: [self.m1[0] + delta * m.x, self.m1[1] + delta * m.y, self.m1[2] + delta * m.z] }
    }

    fn plus(&self, o: &Moments) -> Moments {
        Moments { m0: self.m0 + o.m0, m1: [self.m1[0] + o.m1[0], self.m1[1] + o.m1[1], self.m1[2] + o.m1[2]] }
    }
}

/// What a node receives through its far links, as a function of a patch's normal `n` and
/// offset `a` from the node's centre: `n · V + Σ_k n_k (W_k · a)`.
#[derive(Clone, Copy, Debug, Default)]
struct Form {
    v: Vec3,
    w: [Vec3; 3],
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
    fn receive(forms: &mut [Form], from: &[Moments], span: &Span) {
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
    fn shifted(&self, delta: Vec3) -> Form {
        Form { v: self.v + Vec3::new(self.w[0].dot(delta), self.w[1].dot(delta), self.w[2].dot(delta)), w: self.w }
    }

    fn add(&mut self, o: &Form) {
        self.v += o.v;
        for k in 0..3 {
            self.w[k] += o.w[k];
        }
    }

    fn at(&self, n: Vec3, a: Vec3) -> Real {
        n.dot(self.v) + n.x * self.w[0].dot(a) + n.y * self.w[1].dot(a) + n.z * self.w[2].dot(a)
    }
}
