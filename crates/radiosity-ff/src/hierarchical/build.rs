//! Building the operator: the cluster tree, the links refined from the root's link with
//! itself (`links`), the optional later passes, the figures, and closure.
//!
//! With `passes` above 1 the refinement is driven again by the solution (multigridding,
//! Hanrahan, Salzman & Aupperle's BF refinement on the current `B`): the operator of a pass is
//! swept from the emission (`SWEEPS` Jacobi products), the brightness is taken from that
//! radiosity instead of the estimate, and every far link that may no longer be far under it is
//! refined again from its nodes; the others keep their rays' tally. A pass refines and never
//! coarsens.

use super::HierarchicalColumns;
use super::adjacency::{Adjacency, FarLists, Lists, Transfer};
use super::brightness::Brightness;
use super::distribution::{Distribution, RankFigures};
use super::figures::{BuildStages, HeldBytes, HierarchyFigures};
use super::links::{self, BuildProgress, Links, Refiner, Watch};
use super::params::HierarchicalParams;
use super::shaft::ShaftTree;
use super::tree::{self, ClusterTree, HeldTree};
use crate::analytic::{AnalyticColumns, AnalyticParams};
use radiosity_core::{Collective, ColumnSource, Real, Scene, Vec3};
use radiosity_geom::{SceneAnalysis, Visibility};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

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
        HierarchicalColumns::build(scene, visibility, analysis, params, observe, None)
    }

    /// The operator, or with `split` (the ranks, and the tasks a rank) its rank's part
    /// ([`Self::new_distributed`]).
    pub(super) fn build(
        scene: &Scene,
        visibility: &Visibility,
        analysis: &SceneAnalysis,
        params: HierarchicalParams,
        observe: &(dyn Fn(BuildProgress) + Sync),
        split: Option<(Arc<dyn Collective>, usize)>,
    ) -> HierarchicalColumns {
        let start = Instant::now();
        let mut stages = BuildStages::default();
        let mut lap = Instant::now();
        let mut stage = |into: &mut f64| {
            *into += lap.elapsed().as_secs_f64();
            lap = Instant::now();
        };
        let collective = split.as_ref().map(|(c, _)| c.clone());
        let tree = ClusterTree::new(scene);
        stage(&mut stages.tree);
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
            trust: params.trust,
            strata: links::strata_order(params.rays.max(1)),
            seed: params.seed,
            shafts: shafts.as_ref(),
            tolerance: 1e-9 * scene.diagonal(),
            cumulative,
            watch: Watch::new(scene.len(), observe),
        };
        stage(&mut stages.near_field);
        // Split over ranks, each rank refines its share of the tasks; one process refines all of
        // its tasks on its threads. The links and their rays do not depend on the tasks, nor
        // does the operator (its lists are sorted).
        let (ranks, tasks_per_rank) = match split.as_ref().filter(|(c, _)| c.ranks() > 1) {
            None => ((0, 1), TASKS_ONE_PROCESS),
            Some((c, tasks_per_rank)) => ((c.rank(), c.ranks()), *tasks_per_rank),
        };
        let share = refiner.refine_share(ranks, tasks_per_rank, observe);
        stages.frontier = share.frontier;
        let (mut links, tasks, estimated) = (share.links, share.tasks, share.estimated);
        stage(&mut stages.refinement);
        stages.refinement -= stages.frontier;
        let assemble = |tree: ClusterTree, links: Links| {
            let mut operator = HierarchicalColumns::assemble(scene, tree, links, start);
            operator.distribution = collective.clone().map(Distribution::new);
            operator
        };
        for _ in 1..params.passes {
            // Multigridding: the radiosity of this pass's operator weighs the next pass.
            let b = assemble(tree.clone(), links.clone()).radiosity(scene, SWEEPS);
            let again = Refiner {
                brightness: Brightness::from_radiosity(scene, &tree, &b, params.floor),
                watch: Watch::new(scene.len(), &|_| {}),
                cumulative: refiner.cumulative.clone(),
                strata: refiner.strata.clone(),
                ..refiner
            };
            let Links { far, near, pairs, rays, near_rays, occluded, clear, .. } = std::mem::take(&mut links);
            let mut next = again.refine_again(&far.iter().copied().collect::<Vec<_>>());
            next.near.prepend(near);
            next.pairs.prepend(pairs);
            (next.rays, next.near_rays) = (next.rays + rays, next.near_rays + near_rays);
            (next.occluded, next.clear) = (next.occluded + occluded, next.clear + clear);
            links = next;
        }
        // Later passes count as refinement.
        stage(&mut stages.refinement);
        // The tree moves into the operator: a copy would double its memory at the peak.
        let mut operator = assemble(tree, std::mem::take(&mut links));
        stage(&mut stages.lists);
        let near = operator.near_sums();
        operator.figures.near_above = near.iter().filter(|&&s| s > 1.0).count();
        if params.closure {
            operator.close(&near);
        }
        stage(&mut stages.closure);
        operator.figures.stages = stages;
        operator.figures.seconds = start.elapsed().as_secs_f64();
        let own = RankFigures::new(&operator, tasks, estimated);
        if let Some(distribution) = &mut operator.distribution {
            // Every rank's figures, and the whole operator's from them.
            distribution.gather(own);
            operator.figures = totals(distribution.ranks(), &operator.figures);
        }
        operator
    }

    /// The operator of `links` over `tree`, its figures timed from `start`. Each kind of link is
    /// freed part by part as its lists are filled, so that the build's peak holds one kind
    /// twice at most, and less where the allocator hands freed parts back.
    fn assemble(scene: &Scene, tree: ClusterTree, links: Links, start: Instant) -> HierarchicalColumns {
        let tree = tree.held();
        let Links {
            far: far_links, near: near_links, pairs: pair_links, rays, near_rays, occluded, clear, zeroth, ..
        } = links;
        let counts = (far_links.len(), near_links.len(), pair_links.len());
        let far = FarLists::new(tree.nodes.len(), far_links, |l| (l.a, l.b, [l.clear, l.count]));
        let near = Adjacency::new(scene.len(), near_links, |l| (l.i, l.j, l.transfer as Transfer));
        let pairs = Adjacency::new(scene.len(), pair_links, |l| (l.i, l.j, l.transfer as Transfer));
        let held = HierarchicalColumns::held_by(&tree, [far.bytes(), near.bytes(), pairs.bytes()], scene.len());
        let figures = HierarchyFigures {
            nodes: tree.nodes.len(),
            far_links: counts.0,
            zeroth_links: zeroth as usize,
            near_links: counts.1 + counts.2,
            far_pairs: counts.2 as u64,
            rays,
            near_rays,
            occluded,
            clear_shafts: clear,
            seconds: start.elapsed().as_secs_f64(),
            stages: BuildStages::default(),
            bytes: held.total(),
            held,
            capped: 0,
            near_above: 0,
            lowest_weight: 1.0,
            loaded: false,
        };
        let weights = vec![1.0; scene.len()];
        HierarchicalColumns::from_parts(scene, tree, Lists { far, near, pairs, weights }, figures)
    }

    /// The operator of `tree` and its links over `scene`.
    pub(super) fn from_parts(
        scene: &Scene,
        tree: HeldTree,
        lists: Lists,
        figures: HierarchyFigures,
    ) -> HierarchicalColumns {
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
            distribution: None,
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
        self.summed(&mut estimated);
        estimated.iter_mut().zip(&self.weights).for_each(|(e, w)| *e *= w);
        (near, estimated)
    }

    /// Each row's near part: the sum of its near links' entries (over every rank's links).
    pub(super) fn near_sums(&self) -> Vec<Real> {
        let mut sums: Vec<Real> = (0..self.areas.len())
            .into_par_iter()
            .map(|i| self.near.of(i).map(|(_, t)| Real::from(t)).sum::<Real>() / self.areas[i])
            .collect();
        self.summed(&mut sums);
        sums
    }

    /// The links this operator holds (a rank's part: its own), each once with its ends in
    /// increasing order, sorted.
    pub fn links(&self) -> Vec<HierarchyLink> {
        let mut links: Vec<HierarchyLink> = (self.far.ends().map(|(a, b)| HierarchyLink::Far(a, b)))
            .chain(self.near.ends().map(|(i, j)| HierarchyLink::Near(i, j)))
            .chain(self.pairs.ends().map(|(i, j)| HierarchyLink::FarPair(i, j)))
            .collect();
        links.sort_unstable();
        links
    }

    /// The bytes the links hold (far links at both ends, near links and far pairs once with a
    /// back reference at their higher end), without the tree, the
    /// patch data and the lists' offsets, which every rank of a split operator holds.
    pub fn link_bytes(&self) -> usize {
        self.far.entry_bytes() + self.near.entry_bytes() + self.pairs.entry_bytes()
    }

    /// What building found and cost.
    pub fn figures(&self) -> HierarchyFigures {
        self.figures
    }

    /// The bytes held by a tree (its nodes, order and parents), its link lists (`[far, near,
    /// pairs]`, their bytes) and the patches' areas, normals, centroids and weights.
    pub(super) fn held_by(tree: &HeldTree, [far, near, pairs]: [usize; 3], patches: usize) -> HeldBytes {
        HeldBytes {
            tree: tree.nodes.len() * (size_of::<tree::HeldNode>() + size_of::<u32>())
                + (tree.order.len() + tree.leaf.len()) * size_of::<u32>(),
            far,
            near,
            pairs,
            patches: patches * (2 * size_of::<Vec3>() + 2 * size_of::<Real>()),
        }
    }
}

/// A link of the operator by its ends, the lower first ([`HierarchicalColumns::links`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum HierarchyLink {
    /// A far link between two nodes of the cluster tree.
    Far(u32, u32),
    /// A near link between two patches (the analytic backend's entry).
    Near(u32, u32),
    /// A far link between two patches, stored as its entry.
    FarPair(u32, u32),
}

/// The parent of each node of `tree` (`u32::MAX` for the root).
fn parents(tree: &HeldTree) -> Vec<u32> {
    let mut parent = vec![u32::MAX; tree.nodes.len()];
    for k in 0..tree.nodes.len() {
        if let Some(children) = tree.children(k) {
            for c in children {
                parent[c as usize] = k as u32;
            }
        }
    }
    parent
}

/// The tasks one process cuts its refinement into, as many as two ranks': its threads take them
/// one after another, and a task's own links still split between threads where its nodes are
/// large. The recursion of the root's link alone, split two ways at each node, left one of two
/// threads idle for 27% of the build at 956,319 patches (docs/distributed.md); more tasks make
/// a deeper frontier, which is expanded on one thread (1,024 took 2.8 s at 95,832 patches).
const TASKS_ONE_PROCESS: usize = 64;

/// The Jacobi sweeps of the radiosity a later refinement pass is weighed by: light bounced
/// this many times, enough for an oracle that only needs each patch's brightness to a factor.
const SWEEPS: usize = 8;

/// The figures of the whole operator from every rank's (`ranks`) and what closure found
/// (`closed`, the same on every rank): counts added up, the build's seconds the slowest rank's.
fn totals(ranks: &[RankFigures], closed: &HierarchyFigures) -> HierarchyFigures {
    let sum = |f: fn(&RankFigures) -> u64| ranks.iter().map(f).sum::<u64>();
    HierarchyFigures {
        far_links: sum(|r| r.far_links) as usize,
        zeroth_links: sum(|r| r.zeroth_links) as usize,
        near_links: sum(|r| r.near_links) as usize,
        far_pairs: sum(|r| r.far_pairs),
        rays: sum(|r| r.rays),
        near_rays: sum(|r| r.near_rays),
        occluded: sum(|r| r.occluded),
        clear_shafts: sum(|r| r.clear_shafts),
        seconds: ranks.iter().map(|r| r.seconds).fold(0.0, f64::max),
        bytes: sum(|r| r.bytes) as usize,
        ..*closed
    }
}
