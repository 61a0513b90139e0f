//! What building the hierarchical operator found and cost: its counts, its stages' seconds and
//! the bytes of its parts ([`HierarchyFigures`]), and how the lab reads them
//! ([`BackendFigures`]).

use crate::backend::BackendFigures;
use radiosity_core::Real;

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
    /// Shadow rays traced for near pairs' analytic entries.
    pub near_rays: u64,
    /// Links dropped because every ray was blocked.
    pub occluded: u64,
    /// Far links and near pairs whose shafts held no patch: seen whole without their rays
    /// (`shafts=true`).
    pub clear_shafts: u64,
    /// Seconds to build the tree and the links.
    pub seconds: f64,
    /// The build's seconds, stage by stage.
    pub stages: BuildStages,
    /// Bytes held by the tree, the links and the patches' data.
    pub bytes: usize,
    /// The same bytes, part by part (split over ranks, this rank's own parts, while `bytes`
    /// adds up every rank's).
    pub held: HeldBytes,
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

/// The stages of a build, each in wall seconds: where a build's time went.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BuildStages {
    /// The cluster tree.
    pub tree: f64,
    /// The near field's set-up (the analytic backend the near pairs call) and the oracle.
    pub near_field: f64,
    /// The top of the refinement expanded into its tasks: the ranks' tasks, or one process's,
    /// which its threads share.
    pub frontier: f64,
    /// The refinement into links, the near pairs' entries and every shadow ray included.
    pub refinement: f64,
    /// The link lists: far links in both their nodes' lists, near links and far pairs once.
    pub lists: f64,
    /// Closure: the rows' sums and their weights.
    pub closure: f64,
}

impl BuildStages {
    /// Each stage with its name, in order.
    pub fn named(&self) -> [(&'static str, f64); 6] {
        [
            ("tree", self.tree),
            ("near field set-up", self.near_field),
            ("frontier", self.frontier),
            ("refinement", self.refinement),
            ("link lists", self.lists),
            ("closure", self.closure),
        ]
    }
}

/// The bytes an operator holds, part by part.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct HeldBytes {
    /// The cluster tree's nodes, its patch order, each patch's leaf and each node's parent.
    pub tree: usize,
    /// The far links' lists (each link in both its nodes' lists, its tally coded) with their
    /// offsets.
    pub far: usize,
    /// The near links' lists (each link once with its value, in its lower patch's list, and
    /// its lower patch again in its higher patch's) with their offsets.
    pub near: usize,
    /// The far pairs' lists, as the near links'.
    pub pairs: usize,
    /// The patches' areas, normals, centroids and closure weights.
    pub patches: usize,
}

impl HeldBytes {
    /// Each part with its name, in order.
    pub fn named(&self) -> [(&'static str, usize); 5] {
        [
            ("tree", self.tree),
            ("far links", self.far),
            ("near links", self.near),
            ("far pairs", self.pairs),
            ("patch data", self.patches),
        ]
    }

    /// Every part's bytes.
    pub fn total(&self) -> usize {
        self.named().iter().map(|(_, b)| b).sum()
    }
}

impl From<HierarchyFigures> for BackendFigures {
    fn from(h: HierarchyFigures) -> BackendFigures {
        let summary = format!(
            "{} nodes, {} far links ({} of them to zeroth order), {} near links ({} of them far pairs of patches), {} \
             shadow rays for far links ({} links occluded, {} seen whole through clear shafts) and {} for near pairs; {} \
             rows capped at 1 by closure \
              (lowest weight {:.3}), {} above 1 by their near links alone",
            h.nodes,
            h.far_links,
            h.zeroth_links,
            h.near_links,
            h.far_pairs,
            h.rays,
            h.occluded,
            h.clear_shafts,
            h.near_rays,
            h.capped,
            h.lowest_weight,
            h.near_above
        );
        let counts = [
            ("nodes", h.nodes as f64),
            ("far links", h.far_links as f64),
            ("zeroth-order links", h.zeroth_links as f64),
            ("near links", h.near_links as f64),
            ("far pairs", h.far_pairs as f64),
            ("shadow rays", h.rays as f64),
            ("near shadow rays", h.near_rays as f64),
            ("occluded links", h.occluded as f64),
            ("clear shafts", h.clear_shafts as f64),
            ("capped rows", h.capped as f64),
            ("rows above 1", h.near_above as f64),
            ("lowest weight", h.lowest_weight),
        ];
        BackendFigures {
            seconds: h.seconds,
            bytes: h.bytes,
            loaded: h.loaded,
            counts: counts.into_iter().map(|(l, v)| (l.to_string(), v)).collect(),
            summary,
            ranks: Vec::new(),
            stages: h.stages.named().iter().map(|&(l, v)| (l.to_string(), v)).collect(),
            parts: h.held.named().iter().map(|&(l, v)| (l.to_string(), v)).collect(),
        }
    }
}
