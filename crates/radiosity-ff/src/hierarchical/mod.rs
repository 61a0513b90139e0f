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
//! ## Where each job lives
//!
//! - `params`: the parameters and their defaults;
//! - `tree`, `brightness`, `links`, `shaft` and `build`: the cluster tree, the oracle, the
//!   refinement into links, shafts, and the build with its passes and figures (also as the
//!   [`BackendFigures`](crate::BackendFigures) reports print);
//! - `closure`: every row held to at most 1, reciprocity kept;
//! - `share` and `distribution`: the refinement dealt to ranks, and the operator split over
//!   them, each product, column and row one collective sum;
//! - `adjacency`: the link lists (compressed sparse rows);
//! - `product`: products, columns and rows, and what the operator can do as a
//!   [`FormFactorBackend`](crate::FormFactorBackend);
//! - `nodal`: its links shown to solvers that shoot from its nodes
//!   ([`LinkSource`](radiosity_core::LinkSource));
//! - `stored`: the operator as bytes, for the lab's cache.
//!
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

mod adjacency;
mod brightness;
mod build;
mod closure;
mod distribution;
mod figures;
mod links;
mod nodal;
mod packed;
mod params;
mod product;
mod shaft;
mod share;
mod stored;
mod tree;

use adjacency::{Adjacency, FarLists};
pub use brightness::Oracle;
pub use build::HierarchyLink;
pub use distribution::{Distribution, RankFigures};
pub use figures::{BuildStages, HeldBytes, HierarchyFigures};
pub use links::BuildProgress;
pub use params::{HIERARCHICAL_PARAMS, HierarchicalParams};
use radiosity_core::{Real, Vec3};
pub use share::TASKS_PER_RANK;
use tree::HeldTree;

/// The hierarchical operator over a scene.
#[derive(Debug)]
pub struct HierarchicalColumns {
    tree: HeldTree,
    parent: Vec<u32>,
    /// Far links by node, each in the lists of both its nodes: the other nodes and the rays
    /// found clear of the link's rays.
    far: FarLists,
    /// Near links by patch, each held once: the other patches and the links' `A_p F_pq`, the
    /// analytic backend's, rounded to `f32` ([`Transfer`]).
    near: Adjacency,
    /// Far links between two patches, like `near`, with the far kernel's `A_p F_pq`.
    pairs: Adjacency,
    /// Each patch's closure weight: its far links' and far pairs' entries are weighed by the
    /// weights of both their patches (`closure`).
    weights: Vec<Real>,
    areas: Vec<Real>,
    normals: Vec<Vec3>,
    centroids: Vec<Vec3>,
    figures: HierarchyFigures,
    /// The ranks the operator is split over, when it is (`distribution`).
    distribution: Option<Distribution>,
}
