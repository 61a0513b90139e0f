//! The operator split over ranks ([`Collective`]): each rank holds the links it built (`share`),
//! and every product, column and row is its rank's part followed by one collective sum.
//!
//! **What is replicated and what is split.** Every rank holds the scene, the cluster tree, the
//! closure weights and the vectors of a solve (`O(n)` each); the links, almost all of the
//! operator's memory, are split, each on one rank. A product is each rank's partial product over
//! its own links (moments up the whole tree, its links' transfers, forms down), then one sum of
//! `n · channels` values: the single process's product up to the order of summation. A column or
//! a row is each rank's entries, zero elsewhere, then one sum: every entry comes from one rank,
//! so it is the single process's entry (adding zeros is exact). Closure sums the rows' parts the
//! same way, so every rank gets the same weights.
//!
//! Vectors stay replicated: a product's result is needed whole by every rank's moments in the
//! next product, and the solvers' `O(n)` work is small beside the links' (docs/distributed.md).

use super::HierarchicalColumns;
use super::figures::BuildStages;
use super::links::BuildProgress;
use super::params::HierarchicalParams;
use crate::backend::BackendFigures;
use radiosity_core::{Collective, Real, Scene};
use radiosity_geom::{SceneAnalysis, Visibility};
use std::fmt;
use std::sync::Arc;

/// What one rank built.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct RankFigures {
    /// Far links with a cluster at one end at least ([`crate::HierarchyFigures::far_links`]).
    pub far_links: u64,
    /// Of them, those to zeroth order.
    pub zeroth_links: u64,
    /// Near links, far pairs of patches included.
    pub near_links: u64,
    /// Of them, the far pairs.
    pub far_pairs: u64,
    /// Shadow rays traced for the rank's own far links.
    pub rays: u64,
    /// Shadow rays traced for the rank's own near pairs.
    pub near_rays: u64,
    /// Links dropped as occluded.
    pub occluded: u64,
    /// Links seen whole through clear shafts.
    pub clear_shafts: u64,
    /// Bytes held by the rank's operator: its links, and the tree and patch data every rank
    /// holds.
    pub bytes: u64,
    /// Of them, the bytes of its links ([`HierarchicalColumns::link_bytes`]).
    pub link_bytes: u64,
    /// Seconds the rank took to build its part, closure included.
    pub seconds: f64,
    /// Tasks of the refinement dealt to the rank.
    pub tasks: u64,
    /// The rank's share of the estimated cost of the refinement.
    pub estimated_share: f64,
    /// The rank's build, stage by stage.
    pub stages: BuildStages,
}

impl RankFigures {
    /// A rank's figures from its part of the operator, its `tasks` and its estimated share.
    pub(super) fn new(part: &HierarchicalColumns, tasks: usize, estimated_share: f64) -> RankFigures {
        let figures = &part.figures;
        RankFigures {
            far_links: figures.far_links as u64,
            zeroth_links: figures.zeroth_links as u64,
            near_links: figures.near_links as u64,
            far_pairs: figures.far_pairs,
            rays: figures.rays,
            near_rays: figures.near_rays,
            occluded: figures.occluded,
            clear_shafts: figures.clear_shafts,
            bytes: figures.bytes as u64,
            link_bytes: part.link_bytes() as u64,
            seconds: figures.seconds,
            tasks: tasks as u64,
            estimated_share,
            stages: figures.stages,
        }
    }

    fn to_values(self) -> [Real; 19] {
        let s = self.stages;
        [
            self.far_links as Real,
            self.zeroth_links as Real,
            self.near_links as Real,
            self.far_pairs as Real,
            self.rays as Real,
            self.occluded as Real,
            self.clear_shafts as Real,
            self.bytes as Real,
            self.link_bytes as Real,
            self.seconds,
            self.tasks as Real,
            self.estimated_share,
            self.near_rays as Real,
            s.tree,
            s.near_field,
            s.frontier,
            s.refinement,
            s.lists,
            s.closure,
        ]
    }

    fn from_values(v: &[Real]) -> RankFigures {
        RankFigures {
            far_links: v[0] as u64,
            zeroth_links: v[1] as u64,
            near_links: v[2] as u64,
            far_pairs: v[3] as u64,
            rays: v[4] as u64,
            occluded: v[5] as u64,
            clear_shafts: v[6] as u64,
            bytes: v[7] as u64,
            link_bytes: v[8] as u64,
            seconds: v[9],
            tasks: v[10] as u64,
            estimated_share: v[11],
            near_rays: v[12] as u64,
            stages: BuildStages {
                tree: v[13],
                near_field: v[14],
                frontier: v[15],
                refinement: v[16],
                lists: v[17],
                closure: v[18],
            },
        }
    }
}

impl From<&RankFigures> for BackendFigures {
    fn from(r: &RankFigures) -> BackendFigures {
        let counts = [
            ("far links", r.far_links as f64),
            ("near links", r.near_links as f64),
            ("shadow rays", r.rays as f64),
            ("near shadow rays", r.near_rays as f64),
            ("link bytes", r.link_bytes as f64),
            ("tasks", r.tasks as f64),
            ("estimated share", r.estimated_share),
        ];
        BackendFigures {
            stages: r.stages.named().iter().map(|&(l, v)| (l.to_string(), v)).collect(),
            parts: Vec::new(),
            seconds: r.seconds,
            bytes: r.bytes as usize,
            loaded: false,
            counts: counts.into_iter().map(|(l, v)| (l.to_string(), v)).collect(),
            summary: format!(
                "{} far links, {} near links, {} shadow rays; {} tasks, {:.1}% of the estimated cost",
                r.far_links,
                r.near_links,
                r.rays,
                r.tasks,
                100.0 * r.estimated_share
            ),
            ranks: Vec::new(),
        }
    }
}

/// The ranks an operator is split over and what each built.
pub struct Distribution {
    collective: Arc<dyn Collective>,
    ranks: Vec<RankFigures>,
}

impl fmt::Debug for Distribution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Distribution")
            .field("rank", &self.collective.rank())
            .field("ranks", &self.ranks)
            .finish_non_exhaustive()
    }
}

impl Distribution {
    /// The distribution over `collective`, its ranks' figures not yet gathered (a part still
    /// being built: its products and closure already sum over the ranks).
    pub(super) fn new(collective: Arc<dyn Collective>) -> Distribution {
        Distribution { collective, ranks: Vec::new() }
    }

    /// Gathers every rank's figures, this rank's being `own`: a collective call, once the part
    /// is built.
    pub(super) fn gather(&mut self, own: RankFigures) {
        self.ranks = self.collective.gather(&own.to_values()).iter().map(|v| RankFigures::from_values(v)).collect();
    }

    /// The ranks the operator is split over.
    pub fn collective(&self) -> &dyn Collective {
        &*self.collective
    }

    /// What each rank built, in rank order (the same on every rank).
    pub fn ranks(&self) -> &[RankFigures] {
        &self.ranks
    }
}

impl HierarchicalColumns {
    /// Builds rank `collective.rank()`'s part of the operator split over `collective`'s ranks
    /// (module doc), the refinement cut into about `tasks_per_rank` tasks a rank
    /// ([`TASKS_PER_RANK`](super::TASKS_PER_RANK) by default), calling `observe` as its own
    /// pairs of patches are settled. Every rank calls it with the same arguments. On one rank
    /// it is the single process's operator.
    pub fn new_distributed(
        scene: &Scene,
        visibility: &Visibility,
        analysis: &SceneAnalysis,
        params: HierarchicalParams,
        observe: &(dyn Fn(BuildProgress) + Sync),
        collective: Arc<dyn Collective>,
        tasks_per_rank: usize,
    ) -> HierarchicalColumns {
        HierarchicalColumns::build(scene, visibility, analysis, params, observe, Some((collective, tasks_per_rank)))
    }

    /// The ranks the operator is split over and what each built; `None` for one process.
    pub fn distribution(&self) -> Option<&Distribution> {
        self.distribution.as_ref()
    }

    /// Sums `values` over the ranks, when the operator is split.
    pub(super) fn summed(&self, values: &mut [Real]) {
        if let Some(d) = &self.distribution {
            d.collective.sum(values);
        }
    }
}
