//! Links of the hierarchical operator, refined from the root's link with itself.
//!
//! A link joins two disjoint nodes `A`, `B` of the [cluster tree](super::tree). It is one of:
//!
//! - **dropped**, when every patch of one side faces away from every direction to the other
//!   (bounded through the normal cones and the spheres), or when its shadow rays all meet
//!   something: no light passes, exactly or as far as the rays tell;
//! - **far**: the spheres are apart, every patch of `A` faces the centre-to-centre direction `d`
//!   and every patch of `B` faces `−d` (cosines bounded below by `α`, `β` through the cones),
//!   `αβ (1 − 2ρ_c) ≥ ρ_c (α + β)` with `ρ_c = (C_A + C_B) / r` and `C` a node's largest
//!   distance from its centre to a patch's centroid, and the error estimate is within `eps`.
//!   Then `F_ij = A_j · g · κ_ij` for `i`, `j` on either side, with `g = V / (π r²)`, `r`
//!   the distance between the centres, `V` the fraction of the link's segments between
//!   area-sampled points of both that are clear, and `κ` the kernel's cosines and `r²/|y − x|²`
//!   to first order about the centres, evaluated at the patches' centroids (the module root's
//!   `kernel_factor`). `κ` is symmetric in the two ends, so `A_i F_ij = A_j F_ji` holds by
//!   construction, and its first-order terms are at most `ρ_c (2αβ + α + β)` against `αβ`, so
//!   the condition above keeps every entry non-negative. Where that condition fails (grazing
//!   links, where one cosine is small), the link may still be far to **zeroth order**:
//!   `κ = (n · d)(−m · d)`, the cosines with the link's direction alone, non-negative wherever
//!   `α, β > 0`, its error estimate adding the first-order terms (at most `4ρ_c`) and held to a
//!   quarter of `eps` (`ZEROTH_SHARE`);
//! - **near**: both are single patches and the link is not far: the analytic backend's entry
//!   ([`AnalyticColumns::pair`], with the operator's `budget` of shadow rays and its `order`
//!   and `tol` of quadrature), stored as `A_i F_ij`. A far link between two single patches is stored the same way, as the entry
//!   it gives (`A_i A_j g κ_ij`), so products and columns read one number for it instead of
//!   its kernel's expansion;
//! - otherwise **split**: the larger node (by radius) that can be split is replaced by its
//!   children.
//!
//! **Visibility.** A link that passes the geometric test first traces a quarter of its `rays`
//! (a probe), in an order whose every prefix is spread over both areas ([`strata_order`]). A
//! link is *small* when its weighted transfer bound (below) is at most `shadows` (the parameter
//! times `eps`) or both ends are patches. A small link keeps what its probe saw: dropped when
//! every ray is blocked, otherwise the probe's visible fraction. A larger link is only trusted
//! when its rays agree: any disagreement splits it, and one whose probe agrees traces more and
//! is kept or dropped when all still agree.
//!
//! **How many agreeing rays a larger link needs** (sequential testing, `trust`). A larger link
//! whose bound is `q` times `shadows` would leak at most `q · shadows · f` through a blocked
//! share `f` of its pairs that its rays all missed, and `n` agreeing rays miss it with chance
//! `(1 − f)^n`: the expected leak, `q · shadows · f (1 − f)^n`, is largest at `f = 1/(n + 1)`,
//! below `q · shadows / (e (n + 1))`. So the rays a link needs to hold that expectation to
//! `shadows` grow with `q`: a larger link is trusted after `⌈trust · q⌉` agreeing rays, its
//! segments inherited from its ancestors included, no fewer than its probe and no more than
//! `rays`. The expectation alone asks `trust = 1/e`; leaks add up over the links of a row, and
//! the default, 1.5, was chosen by measurement (docs/hierarchical.md). At the defaults a link
//! just above `shadows` stops at its probe (3 rays) and one carrying 10 times as much traces
//! all 14, as every larger link did before (`trust=4096`).
//!
//! **Segments handed down.** A split link hands the segments it traced to its children, each to
//! the child its end lies in. A larger child counts them all among its rays (uniform over its
//! areas, as its own are), so a child that inherits a disagreement is split without a ray, and
//! one that inherits agreement traces only the rest. A small child counts only the segments of
//! its ancestors' probes, which are traced whole, a fixed number whatever they see: the rays
//! after a probe stop at their first disagreement (the rest could not change the split), so
//! those are selected by their outcome, and a kept fraction counted from them would lean
//! towards the sibling's side. The visible fraction is one number for every pair of
//! the link, so a partly visible link misplaces light between its lit and shadowed pairs (a
//! light leak): `shadows` bounds how much of a row one link may misplace that way. A small
//! link's fraction is noisy, but the noise is unbiased and averages over the hundreds of links
//! of a row, so a small link does not trace all `rays`. (Each choice was measured:
//! docs/hierarchical.md.)
//!
//! **Shafts** (`shafts=true`, off by default). A larger link between two patches or flat
//! clusters whose probe is all clear, and a near pair that would trace at least
//! `SEARCH_FROM` rays, first searches its shaft for patches ([`super::shaft`]); when there is
//! none, every segment its remaining rays could draw is clear, and it takes the tally they
//! would give without tracing them. The operator is the same link for link and bit for bit
//! (tested). It is off by default because the search has cost more than the rays it saves
//! (docs/hierarchical.md, "Shafts").
//!
//! The error estimate of a far link (to first order) bounds what it adds to the radiosity of
//! one receiver, relative to the RMS radiosity: the [brightness](super::brightness) bound
//! `max(ρ_A Φ_B, ρ_B Φ_A) / (π r²)` (with `oracle=area`, `max(A_A, A_B) / (π r²)`, a row of `F`),
//! times the second-order variation of the kernel over the link, `(2 (ρ + asin ρ))²` with
//! `ρ = (R_A + R_B) / r` over the bounding spheres: the first-order terms are in `κ` (Hanrahan,
//! Salzman & Aupperle 1991, "A rapid hierarchical radiosity algorithm", SIGGRAPH; Sillion 1995,
//! "A unified hierarchical algorithm for global illumination with scattering volumes and object
//! clusters", IEEE TVCG 1(3)).

use super::adjacency::Gathered;
use super::brightness::Brightness;
use super::shaft::{ROOT, Search, Shaft, ShaftTree, lowest_along};
use super::tree::ClusterTree;
use crate::analytic::AnalyticColumns;
use radiosity_core::{Real, Scene, Vec3};
use radiosity_geom::Visibility;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};

/// A far link between nodes `a` and `b`: 12 bytes, its geometry worked out again from the
/// nodes' centres when it is used ([`Span::new`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct FarLink {
    /// The first node.
    pub a: u32,
    /// The second node.
    pub b: u32,
    /// Of the link's shadow rays, those found clear.
    pub clear: u16,
    /// The link's shadow rays (1 when the scene cannot occlude), with [`ZEROTH`] set when the
    /// link's kernel is taken to zeroth order.
    pub count: u16,
}

/// The bit of [`FarLink::count`] that marks a link whose kernel is the product of the cosines
/// with its direction alone, `κ = (n · e)(−m · e)` (rays are at most 4096, below this bit).
pub(crate) const ZEROTH: u16 = 1 << 15;

/// The share of `eps` a link to zeroth order may take. Its error is of first order, the same
/// sign over every link a receiver sees on one side, so it does not average out over a row as
/// the second-order error of a first-order link partly does: on `office` (eps 3e-3) the whole
/// of `eps` gave an exact solution 2.4e-3 from the analytic one, a quarter 1.8e-3, a tenth
/// 1.8e-3 (`docs/hierarchical.md`).
const ZEROTH_SHARE: Real = 0.25;

/// The smallest cosine bound a far link is made with: the bounds through the normal cones are
/// a few roundings from the cosines they bound, and a zeroth-order link must not turn a cosine
/// of `−1e-17` into a negative entry.
const MIN_COSINE: Real = 1e-9;

/// What a far link's kernel needs: its direction, length and `g = V / (π r²)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Span {
    /// The unit direction from `a`'s centre to `b`'s.
    pub d: Vec3,
    /// The distance between the centres.
    pub r: Real,
    /// `V / (π r²)`.
    pub g: Real,
    /// Whether the kernel is expanded to first order in the patches' offsets (otherwise the
    /// product of the cosines with `d`).
    pub first: bool,
}

impl Span {
    /// The geometry of a far link from a node centred at `a` to one centred at `b`, `clear` of
    /// its `count` rays clear (`count` with its [`ZEROTH`] bit). Seen from `b`, `d` is exactly
    /// `−d` and the rest the same.
    pub fn new(a: Vec3, b: Vec3, clear: u16, count: u16) -> Span {
        let between = b - a;
        let r = between.length();
        let rays = (count & !ZEROTH) as Real;
        Span { d: between / r, r, g: (clear as Real / rays) / (PI * r * r), first: count & ZEROTH == 0 }
    }
}

/// A near link: two patches and `A_i F_ij`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct NearLink {
    /// The first patch.
    pub i: u32,
    /// The second patch.
    pub j: u32,
    /// `A_i F_ij = A_j F_ji`.
    pub transfer: Real,
}

/// The links of a scene, and what building them cost.
#[derive(Clone, Debug, Default)]
pub(crate) struct Links {
    pub far: Gathered<FarLink>,
    /// Near links with the analytic backend's entry.
    pub near: Gathered<NearLink>,
    /// Far links between two patches, stored as the entry their kernel gives.
    pub pairs: Gathered<NearLink>,
    /// Shadow rays traced for far links.
    pub rays: u64,
    /// Shadow rays traced for near pairs' analytic entries.
    pub near_rays: u64,
    /// Links dropped as fully occluded by their rays.
    pub occluded: u64,
    /// Links found clear by their shafts, without a ray: far links and near pairs.
    pub clear: u64,
    /// Of the far links, those to zeroth order.
    pub zeroth: u64,
    /// Pairs of patches settled and links made since they were last reported ([`Watch`]).
    unreported: (u64, u64),
}

impl Links {
    pub(super) fn append(&mut self, mut other: Links) {
        self.far.append(&mut other.far);
        self.near.append(&mut other.near);
        self.pairs.append(&mut other.pairs);
        self.rays += other.rays;
        self.near_rays += other.near_rays;
        self.occluded += other.occluded;
        self.clear += other.clear;
        self.zeroth += other.zeroth;
        self.unreported = (self.unreported.0 + other.unreported.0, self.unreported.1 + other.unreported.1);
    }
}

/// What the segments of a link found.
struct Sampled {
    count: usize,
    clear: usize,
}

/// A shadow segment traced for a link: its ends' patches (by position in the tree's order, on
/// the link's first node and on its second) and whether it was clear. A split link hands its
/// segments to its children (module doc).
#[derive(Clone, Copy, Debug)]
pub(super) struct Segment {
    from: u32,
    to: u32,
    clear: bool,
    /// Traced in a probe, which is traced whole whatever its rays see: a small descendant may
    /// count it towards its own probe (module doc).
    probe: bool,
}

/// A link split in two: each half's nodes and the segments it inherits, and where their
/// shafts' patches may be ([`Refiner::step`]).
pub(super) struct Split<'c> {
    pub halves: [(u32, u32, Vec<Segment>); 2],
    pub candidates: &'c [u32],
}

/// What a link's rays tell.
enum Seen {
    /// Every ray is blocked: the link is dropped.
    Occluded,
    /// The rays disagree on a link too large to trust its visible fraction.
    Split,
    /// Some rays are clear: how many, of how many.
    Visible { clear: u16, count: u16 },
}

/// What refinement reports as it goes ([`BuildProgress`]): the pairs of patches settled
/// (linked, or dropped as unseen), and the links made, to an observer, every thousandth of the
/// pairs. Each task counts in its own [`Links`] and adds to the shared counts a thousandth at a
/// time, so that the threads do not contend; counting does not touch the links, so the build
/// stays deterministic.
pub(crate) struct Watch<'a> {
    pairs: AtomicU64,
    links: AtomicU64,
    /// `n (n − 1) / 2`.
    total: u64,
    observe: &'a (dyn Fn(BuildProgress) + Sync),
}

impl<'a> Watch<'a> {
    /// A watch over the pairs of `patches` patches.
    pub fn new(patches: usize, observe: &'a (dyn Fn(BuildProgress) + Sync)) -> Watch<'a> {
        let n = patches as u64;
        Watch::over(n * n.saturating_sub(1) / 2, observe)
    }

    /// A watch over `total` pairs of patches: a rank's share of them.
    pub fn over(total: u64, observe: &'a (dyn Fn(BuildProgress) + Sync)) -> Watch<'a> {
        Watch { pairs: AtomicU64::new(0), links: AtomicU64::new(0), total, observe }
    }

    /// The `pairs` pairs of a link settled into `out`, `linked` when a link was kept for them.
    fn settle(&self, out: &mut Links, pairs: u64, linked: bool) {
        out.unreported = (out.unreported.0 + pairs, out.unreported.1 + u64::from(linked));
        if out.unreported.0 >= self.total / 1000 {
            self.flush(out);
        }
    }

    /// Adds what `out` has not reported to the shared counts, and reports each thousandth of
    /// the pairs crossed.
    pub(super) fn flush(&self, out: &mut Links) {
        let (pairs, linked) = std::mem::take(&mut out.unreported);
        let links = self.links.fetch_add(linked, Ordering::Relaxed) + linked;
        let before = self.pairs.fetch_add(pairs, Ordering::Relaxed);
        let permille = |p: u64| (p as u128 * 1000 / self.total.max(1) as u128) as u64;
        if permille(before + pairs) > permille(before) {
            (self.observe)(BuildProgress { settled: (before + pairs) as Real / self.total.max(1) as Real, links });
        }
    }
}

/// What refinement reads.
pub(crate) struct Refiner<'a> {
    pub scene: &'a Scene,
    pub tree: &'a ClusterTree,
    /// Visibility, when the scene can occlude.
    pub visibility: Option<&'a Visibility>,
    /// The near field.
    pub analytic: &'a AnalyticColumns<'a>,
    /// What the oracle weighs links by.
    pub brightness: Brightness,
    /// The error threshold.
    pub eps: Real,
    /// The largest transfer bound of a partly visible far link.
    pub shadows: Real,
    /// Agreeing rays a larger link needs per unit of its transfer bound over `shadows`
    /// (module doc).
    pub trust: Real,
    /// The strata of a far link's rays (as many as its rays) in the order they are traced:
    /// for each ray, its stratum of one end's area and its stratum of the other's
    /// ([`strata_order`]).
    pub strata: Vec<[usize; 2]>,
    /// The seed of the rays.
    pub seed: u64,
    /// Where links between patches or flat clusters search their shafts before tracing rays
    /// ([`super::shaft`]), when they do (only in scenes that can occlude).
    pub shafts: Option<&'a ShaftTree>,
    /// What counts as on a plane: a length relative to the scene diagonal.
    pub tolerance: Real,
    /// The cumulative area of the patches in tree order (`cumulative[k]` is the area of the
    /// first `k`), for sampling points by area.
    pub cumulative: Vec<Real>,
    /// Where progress is reported.
    pub watch: Watch<'a>,
}

/// The fewest shadow rays a near pair must stand to trace for its shaft to be searched first:
/// a search costs about as much as a few rays.
const SEARCH_FROM: usize = 12;

/// Nodes with more patches than this refine their links on other threads.
const PARALLEL_COUNT: u32 = 256;

impl Refiner<'_> {
    /// Every link, refined from the root's link with itself. The order of the links is fixed
    /// by the tree, not by the threads.
    #[cfg(test)]
    pub fn refine_all(&self) -> Links {
        let mut links = Links::default();
        self.refine_self(0, &mut links);
        self.watch.flush(&mut links);
        links
    }

    /// This refiner with another watch, for part of the refinement.
    pub fn watched<'b>(&'b self, watch: Watch<'b>) -> Refiner<'b> {
        Refiner {
            brightness: self.brightness.clone(),
            cumulative: self.cumulative.clone(),
            strata: self.strata.clone(),
            watch,
            ..*self
        }
    }

    /// The links within node `k`.
    pub(super) fn refine_self(&self, k: u32, out: &mut Links) {
        let Some([a, b]) = self.tree.nodes[k as usize].children else { return };
        if self.tree.nodes[k as usize].count > PARALLEL_COUNT {
            let ((mut x, y), z) = rayon::join(
                || {
                    rayon::join(
                        || {
                            let mut l = Links::default();
                            self.refine_self(a, &mut l);
                            l
                        },
                        || {
                            let mut l = Links::default();
                            self.refine_self(b, &mut l);
                            l
                        },
                    )
                },
                || {
                    let mut l = Links::default();
                    self.refine_pair(a, b, Vec::new(), &[ROOT], &mut l);
                    l
                },
            );
            x.append(y);
            x.append(z);
            out.append(x);
        } else {
            self.refine_self(a, out);
            self.refine_self(b, out);
            self.refine_pair(a, b, Vec::new(), &[ROOT], out);
        }
    }

    /// The links between the disjoint nodes `a` and `b`, given the segments traced between
    /// them for links they were split from and the nodes that may hold patches in their shaft
    /// (`candidates`, nodes of the [`ShaftTree`]).
    pub(super) fn refine_pair(&self, a: u32, b: u32, traced: Vec<Segment>, candidates: &[u32], out: &mut Links) {
        let mut kept = Vec::new();
        let Some(Split { halves: [(a0, b0, t0), (a1, b1, t1)], candidates }) =
            self.step(a, b, traced, candidates, &mut kept, out)
        else {
            return;
        };
        let (na, nb) = (&self.tree.nodes[a as usize], &self.tree.nodes[b as usize]);
        if na.count + nb.count > PARALLEL_COUNT {
            let (mut x, y) = rayon::join(
                || {
                    let mut l = Links::default();
                    self.refine_pair(a0, b0, t0, candidates, &mut l);
                    l
                },
                || {
                    let mut l = Links::default();
                    self.refine_pair(a1, b1, t1, candidates, &mut l);
                    l
                },
            );
            x.append(y);
            out.append(x);
        } else {
            self.refine_pair(a0, b0, t0, candidates, out);
            self.refine_pair(a1, b1, t1, candidates, out);
        }
    }

    /// The link between the disjoint nodes `a` and `b` settled into `out` (kept or dropped),
    /// or, when it must be split, the two links it is split into ([`Split`]); `kept` holds
    /// what a shaft search leaves for the children.
    pub(super) fn step<'c>(
        &self,
        a: u32,
        b: u32,
        mut traced: Vec<Segment>,
        candidates: &'c [u32],
        kept: &'c mut Vec<u32>,
        out: &mut Links,
    ) -> Option<Split<'c>> {
        let (na, nb) = (&self.tree.nodes[a as usize], &self.tree.nodes[b as usize]);
        let between = nb.centre - na.centre;
        let r = between.length();
        let reach = na.radius + nb.radius;
        // Directions from A to B lie within `spread` of d when the spheres are apart.
        let (d, spread) = if r > reach { (between / r, (reach / r).asin()) } else { (Vec3::Z, PI) };
        // One side faces away from every direction to the other: its largest n · u over its
        // cone of normals and the cone of directions is at most 0 (the angle between the axes
        // less both half-angles is at least π/2); or the other side lies on or behind the
        // common plane of a side whose patches all face one way.
        let away = |axis: Vec3, cone: Real, towards: Vec3| {
            axis.dot(towards).clamp(-1.0, 1.0).acos() - cone - spread >= 0.5 * PI
        };
        let pairs = u64::from(na.count) * u64::from(nb.count);
        if (spread < PI && (away(na.axis, na.spread, d) || away(nb.axis, nb.spread, -d)))
            || self.behind_plane(a, b)
            || self.behind_plane(b, a)
        {
            return self.settled(out, pairs, false);
        }
        let (leaf_a, leaf_b) = (na.is_leaf(), nb.is_leaf());
        // The shaft is searched for links whose ends cannot block their own segments, once.
        let shafts = self.shafts.filter(|_| self.is_flat(a) && self.is_flat(b));
        let mut clear = None;
        let mut shaft_clear = |kept: &mut Vec<u32>| match shafts {
            Some(shafts) => *clear.get_or_insert_with(|| self.search(shafts, a, b, candidates, kept) == Search::Clear),
            None => false,
        };
        if let Some((order, bound)) = self.far_order(a, b) {
            let small = bound <= self.shadows || (leaf_a && leaf_b);
            // The agreeing rays a larger link needs (module doc; `as` saturates), none for a small one.
            let needs = if small { 0 } else { ((self.trust * bound / self.shadows).ceil() as usize).max(1) };
            let mut shaft = || shaft_clear(kept);
            let seen = self.visible_fraction(a, b, needs, &mut traced, out, &mut shaft);
            let visible = match seen {
                Seen::Occluded => return self.settled(out, pairs, false),
                Seen::Split => None,
                Seen::Visible { clear, count } => Some((clear, count | order)),
            };
            if let Some((clear, count)) = visible {
                let link = FarLink { a, b, clear, count };
                if leaf_a && leaf_b {
                    let span = Span::new(na.centre, nb.centre, clear, count);
                    // Two patches: the entry the far link gives, stored as one number, so
                    // that products and columns read it like a near link's.
                    let (i, j) = (self.tree.order[na.first as usize], self.tree.order[nb.first as usize]);
                    let (p, q) = (&self.scene.patches()[i as usize], &self.scene.patches()[j as usize]);
                    let kappa = kernel_factor(
                        &span,
                        (p.normal(), p.centroid() - na.centre),
                        (q.normal(), q.centroid() - nb.centre),
                    );
                    out.pairs.push(NearLink { i, j, transfer: p.area() * q.area() * span.g * kappa });
                } else {
                    out.zeroth += u64::from(order == ZEROTH);
                    out.far.push(link);
                }
                return self.settled(out, pairs, true);
            }
        }
        if leaf_a && leaf_b {
            let (i, j) = (self.tree.order[na.first as usize], self.tree.order[nb.first as usize]);
            let (f, rays) = self.analytic.pair_unless_clear(i as usize, j as usize, |rays| {
                let clear = rays >= SEARCH_FROM && shaft_clear(kept);
                out.clear += u64::from(clear);
                clear
            });
            out.near_rays += rays;
            if f > 0.0 {
                out.near.push(NearLink { i, j, transfer: self.scene.patches()[i as usize].area() * f });
            }
            return self.settled(out, 1, f > 0.0);
        }
        // The children's candidates: what this link's search left, or its parent's.
        let candidates = if clear.is_some() { &kept[..] } else { candidates };
        // Split the larger node that can be split.
        let split_a = !leaf_a && (leaf_b || na.radius >= nb.radius);
        let (keep, [c0, c1]) = match split_a {
            true => (b, na.children.unwrap()),
            false => (a, nb.children.unwrap()),
        };
        let (p0, p1) = match split_a {
            true => ((c0, keep), (c1, keep)),
            false => ((keep, c0), (keep, c1)),
        };
        // Each segment goes with the child its end on the split side lies in.
        let (mut t0, mut t1) = (Vec::new(), Vec::new());
        let split = &self.tree.nodes[c0 as usize];
        for segment in traced {
            let at = if split_a { segment.from } else { segment.to };
            if at < split.first + split.count { t0.push(segment) } else { t1.push(segment) }
        }
        Some(Split { halves: [(p0.0, p0.1, t0), (p1.0, p1.1, t1)], candidates })
    }

    /// The `pairs` pairs of a link settled into `out`, `linked` when a link was kept for them:
    /// nothing left to split.
    fn settled(&self, out: &mut Links, pairs: u64, linked: bool) -> Option<Split<'static>> {
        self.watch.settle(out, pairs, linked);
        None
    }

    /// The order a far link between `a` and `b` may take and its weighted transfer bound, or
    /// `None` when it may not be far (module doc).
    fn far_order(&self, a: u32, b: u32) -> Option<(u16, Real)> {
        let (na, nb) = (&self.tree.nodes[a as usize], &self.tree.nodes[b as usize]);
        let between = nb.centre - na.centre;
        let (r, reach) = (between.length(), na.radius + nb.radius);
        if r <= reach {
            return None;
        }
        let (d, rho) = (between / r, reach / r);
        let spread = rho.asin();
        let (alpha, beta) = (na.min_cos(d), nb.min_cos(-d));
        // Cosines below `MIN_COSINE` are taken as zero: the cones bound them to a few roundings.
        if alpha <= MIN_COSINE || beta <= MIN_COSINE {
            return None;
        }
        // The kernel to first order, evaluated at the patches' centroids, stays non-negative for
        // every pair of the link: its first-order terms are at most ρ_c (2αβ + α + β) against
        // αβ, with ρ_c the centroids' largest offsets from the centres over r.
        let rho_c = (na.centroid_radius + nb.centroid_radius) / r;
        let bound = self.brightness.bound(a, b, r);
        let second = (2.0 * (rho + spread)).powi(2);
        // To first order where that stays non-negative, otherwise to zeroth order (the cosines
        // with d alone, non-negative wherever every patch faces the other side), whose error
        // adds the first-order terms, at most 4ρ_c, within a share of eps.
        if alpha * beta * (1.0 - 2.0 * rho_c) >= rho_c * (alpha + beta) && bound * second <= self.eps {
            Some((0, bound))
        } else if bound * (4.0 * rho_c + second) <= ZEROTH_SHARE * self.eps {
            Some((ZEROTH, bound))
        } else {
            None
        }
    }

    /// A refinement pass under this refiner's brightness over the far links `far` of an
    /// earlier one: a link that may still be far is kept with its rays' tally (not traced
    /// again), at the order now allowed; any other is refined from its two nodes. The order of the links is fixed by
    /// `far`, not by the threads.
    pub fn refine_again(&self, far: &[FarLink]) -> Links {
        far.par_chunks(4096)
            .map(|chunk| {
                let mut out = Links::default();
                for link in chunk {
                    match self.far_order(link.a, link.b) {
                        Some((order, _)) => {
                            out.zeroth += u64::from(order == ZEROTH);
                            out.far.push(FarLink { count: (link.count & !ZEROTH) | order, ..*link });
                        }
                        None => self.refine_pair(link.a, link.b, Vec::new(), &[ROOT], &mut out),
                    }
                }
                out
            })
            .reduce(Links::default, |mut x, y| {
                x.append(y);
                x
            })
    }

    /// What the rays of the link between `a` and `b` tell (module doc): a small link (`needs`
    /// 0) keeps what its probe saw, counting its ancestors' probes' segments among `traced`; a
    /// larger one is split as soon as its rays disagree and is trusted after `needs` agreeing
    /// rays otherwise (between its probe and `rays`), counting the segments `traced` for the
    /// links it was split from; when its probe is all clear and `shaft_clear` says its shaft
    /// is, it takes the rest as clear without tracing them. When it is split, `traced` holds
    /// every segment traced between `a` and `b`.
    fn visible_fraction(
        &self,
        a: u32,
        b: u32,
        needs: usize,
        traced: &mut Vec<Segment>,
        out: &mut Links,
        shaft_clear: &mut dyn FnMut() -> bool,
    ) -> Seen {
        let order = &self.strata;
        let total = order.len();
        let probe = (total / 4).max(1);
        let mut rng = self.rays_of(a, b);
        let unanimous = |s: &Sampled| s.clear == 0 || s.clear == s.count;
        if needs == 0 {
            let mut seen = Sampled { count: 0, clear: 0 };
            for segment in traced.iter().filter(|s| s.probe).take(probe) {
                seen.count += 1;
                seen.clear += usize::from(segment.clear);
            }
            let fresh = probe - seen.count;
            self.sample(a, b, &order[..fresh], total, &mut rng, &mut seen, None, out);
            return match seen.clear {
                0 => {
                    out.occluded += 1;
                    Seen::Occluded
                }
                clear => Seen::Visible { clear: clear as u16, count: seen.count as u16 },
            };
        }
        // A larger link is split at its first ray that disagrees with the others, the segments
        // traced for its ancestors included: the rays after it could not change that.
        let clear = traced.iter().filter(|s| s.clear).count();
        let mut seen = Sampled { count: traced.len(), clear };
        if unanimous(&seen) {
            let fresh = needs.clamp(probe, total).saturating_sub(traced.len());
            let (first, rest) = order[..fresh].split_at(probe.min(fresh));
            self.sample(a, b, first, total, &mut rng, &mut seen, Some((traced, true)), out);
            if seen.clear == seen.count && !rest.is_empty() && shaft_clear() {
                // Every segment the rest of the rays would draw is clear: their tally.
                out.clear += 1;
                let count = (seen.count + rest.len()) as u16;
                return Seen::Visible { clear: count, count };
            }
            if unanimous(&seen) {
                self.sample(a, b, rest, total, &mut rng, &mut seen, Some((traced, false)), out);
            }
        }
        if !unanimous(&seen) {
            Seen::Split
        } else if seen.clear == 0 {
            out.occluded += 1;
            Seen::Occluded
        } else {
            Seen::Visible { clear: seen.clear as u16, count: seen.count as u16 }
        }
    }

    /// True when node `k` is a patch, or patches that face one way in one plane: none of them
    /// blocks a segment from another ([`super::shaft`]).
    fn is_flat(&self, k: u32) -> bool {
        let node = &self.tree.nodes[k as usize];
        node.is_leaf() || (node.spread <= 1e-12 && node.offsets.1 - node.offsets.0 <= self.tolerance)
    }

    /// Searches the shaft between `a` and `b` (each a patch or a flat cluster) from
    /// `candidates`, the patches of both passed over, leaving the candidates that remain in
    /// `kept`.
    fn search(&self, shafts: &ShaftTree, a: u32, b: u32, candidates: &[u32], kept: &mut Vec<u32>) -> Search {
        let (na, nb) = (&self.tree.nodes[a as usize], &self.tree.nodes[b as usize]);
        // An end's plane bounds every segment when the other end lies wholly in front of it:
        // segments leave it forwards.
        let cut = |from: &super::tree::Node, to: &super::tree::Node| {
            (lowest_along(from.axis, to.lo, to.hi) >= from.offsets.1).then_some((from.axis, from.offsets.0))
        };
        let shaft = Shaft::new((na.lo, na.hi), (nb.lo, nb.hi), [cut(na, nb), cut(nb, na)]);
        let within = |node: &super::tree::Node, at: u32| (node.first..node.first + node.count).contains(&at);
        let own = |p: usize| {
            let at = self.tree.nodes[self.tree.leaf[p] as usize].first;
            within(na, at) || within(nb, at)
        };
        shafts.search(self.scene, &shaft, candidates, own, kept)
    }

    /// True when every patch of `a` faces one way and all of `b` lies on or behind the plane of
    /// each of them: `a` sees nothing of `b`, and `b` nothing of `a`.
    fn behind_plane(&self, a: u32, b: u32) -> bool {
        let (na, nb) = (&self.tree.nodes[a as usize], &self.tree.nodes[b as usize]);
        if na.spread > 1e-12 {
            return false;
        }
        // The largest axis · y over b's box.
        let far = -lowest_along(-na.axis, nb.lo, nb.hi);
        far <= na.offsets.0 + self.tolerance
    }

    /// The random stream of the link between `a` and `b`, keyed by the pair and the seed.
    fn rays_of(&self, a: u32, b: u32) -> Xoshiro256PlusPlus {
        let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
        Xoshiro256PlusPlus::seed_from_u64(key ^ self.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15))
    }

    /// Adds to `seen` the segments `strata` of `total` between points of `a` and `b` drawn by
    /// area (stratified: each with its stratum of `a`'s area and of `b`'s), each traced when the
    /// scene can occlude (all clear otherwise). With `traced`, records each segment there, and
    /// unless they are a probe (`true`, traced whole) stops at the first that disagrees with
    /// those before it.
    #[allow(clippy::too_many_arguments)]
    fn sample(
        &self,
        a: u32,
        b: u32,
        strata: &[[usize; 2]],
        total: usize,
        rng: &mut Xoshiro256PlusPlus,
        seen: &mut Sampled,
        mut traced: Option<(&mut Vec<Segment>, bool)>,
        out: &mut Links,
    ) {
        for &[s, t] in strata {
            seen.count += 1;
            let Some(visibility) = self.visibility else {
                seen.clear += 1;
                continue;
            };
            let u = (s as Real + rng.random::<Real>()) / total as Real;
            let v = (t as Real + rng.random::<Real>()) / total as Real;
            let (x, from) = self.point_in(a, u, rng);
            let (y, to) = self.point_in(b, v, rng);
            let (i, j) = (self.tree.order[from] as usize, self.tree.order[to] as usize);
            let clear = visibility.unoccluded_between(x, i, y, j);
            seen.clear += usize::from(clear);
            out.rays += 1;
            if let Some((traced, probe)) = traced.as_mut() {
                traced.push(Segment { from: from as u32, to: to as u32, clear, probe: *probe });
                if !*probe && seen.clear != 0 && seen.clear != seen.count {
                    return;
                }
            }
        }
    }

    /// The point of node `k` at the fraction `u` of its area, and its patch's position in the
    /// tree's order.
    fn point_in(&self, k: u32, u: Real, rng: &mut impl Rng) -> (Vec3, usize) {
        let node = &self.tree.nodes[k as usize];
        let (first, last) = (node.first as usize, (node.first + node.count) as usize);
        let target = self.cumulative[first] + u * (self.cumulative[last] - self.cumulative[first]);
        let at = self.cumulative[first..=last].partition_point(|&c| c <= target).clamp(1, last - first) + first - 1;
        let patch = self.tree.order[at] as usize;
        let point = self.scene.patches()[patch].point_at(rng.random(), rng.random());
        (point, at)
    }
}

/// The strata of `total` rays in the order they are traced, so that every prefix is spread
/// over both nodes' areas: one end's stratum `s` bit-reversed for a power of two (0, 8, 4, 12,
/// 2, … of 16), otherwise by a step coprime with `total`; the other end's `(s · step + 3) mod
/// total`, a permutation, so that the two ends' strata are not paired in order.
pub(crate) fn strata_order(total: usize) -> Vec<[usize; 2]> {
    let step = stride_of(total);
    let permuted = |s: usize| [s, (s * step + 3) % total];
    if total.is_power_of_two() {
        let bits = total.trailing_zeros();
        (0..total).map(|k| permuted(if bits == 0 { 0 } else { k.reverse_bits() >> (usize::BITS - bits) })).collect()
    } else {
        (0..total).map(|k| permuted((k * step) % total)).collect()
    }
}

/// A step coprime with `total`, so that `s ↦ (s · step + 3) mod total` permutes the strata.
fn stride_of(total: usize) -> usize {
    let gcd = |mut a: usize, mut b: usize| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    [7, 5, 3, 11, 13].into_iter().find(|&m| gcd(m, total) == 1).unwrap_or(1)
}

/// How far a build has come ([`crate::HierarchicalColumns::new_observed`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildProgress {
    /// The share of the pairs of patches settled: covered by a link, or dropped as unseen. It
    /// ends at 1; it is not a share of the time, since links high in the tree settle many
    /// pairs at once.
    pub settled: Real,
    /// Links made so far.
    pub links: u64,
}

/// The kernel of a far link to first order about the centres, without its `1 / (π r²)`:
/// for `x` on `a`'s side (normal `n`, offset `a` from `a`'s centre) and `y` on `b`'s (normal
/// `m`, offset `b`), with `e` the link's direction, `P = I − e eᵀ`, `Δ = b − a`, `α = n · e`,
/// `β = −m · e`:
/// `κ = αβ (1 − 2 e · Δ / r) + (β n · PΔ − α m · PΔ) / r`. It is symmetric in the two ends (swap
/// them and `e`), and non-negative wherever the link was made.
pub(super) fn kernel_factor(span: &Span, (n, a): (Vec3, Vec3), (m, b): (Vec3, Vec3)) -> Real {
    let e = span.d;
    if !span.first {
        return n.dot(e) * -m.dot(e);
    }
    let delta = b - a;
    let p_delta = delta - e * e.dot(delta);
    let (alpha, beta) = (n.dot(e), -m.dot(e));
    alpha * beta * (1.0 - 2.0 * e.dot(delta) / span.r) + (beta * n.dot(p_delta) - alpha * m.dot(p_delta)) / span.r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analytic::AnalyticParams;
    use crate::hierarchical::params::HierarchicalParams;
    use radiosity_geom::PreparedScene;

    /// The links of `arg` at threshold `eps` with `trust`, and the refiner that made them.
    fn refined(arg: &str, eps: Real, trust: Real, check: impl Fn(&Refiner, &Links)) {
        let p = PreparedScene::load(arg).unwrap();
        let params = HierarchicalParams { eps, trust, ..HierarchicalParams::default() };
        let scene = p.scene();
        let tree = ClusterTree::new(scene);
        let near = AnalyticParams { budget: params.budget, ..AnalyticParams::default() };
        let visibility = p.visibility().unwrap();
        let analytic = AnalyticColumns::new(scene, &visibility, &p.analysis, near);
        let mut cumulative = vec![0.0];
        for &k in &tree.order {
            cumulative.push(cumulative.last().unwrap() + scene.patches()[k as usize].area());
        }
        let refiner = Refiner {
            scene,
            tree: &tree,
            visibility: p.analysis.occlusion.value.then_some(&visibility),
            analytic: &analytic,
            brightness: Brightness::estimate(scene, &tree, params.oracle, params.floor),
            eps: params.eps,
            shadows: params.shadows * params.eps,
            trust: params.trust,
            strata: strata_order(params.rays),
            seed: params.seed,
            shafts: None,
            tolerance: 1e-9 * scene.diagonal(),
            cumulative,
            watch: Watch::new(scene.len(), &|_| {}),
        };
        let links = refiner.refine_all();
        // Cut into tasks at the top, as a process and its ranks refine, the same links.
        let tasks = refiner.refine_share((0, 1), 16, &|_| {}).links;
        let far = |l: &Links| {
            let mut f: Vec<_> = l.far.iter().map(|f| (f.a, f.b, f.clear, f.count)).collect();
            f.sort_unstable();
            f
        };
        let near = |l: &Gathered<NearLink>| {
            let mut n: Vec<_> = l.iter().map(|n| (n.i, n.j, n.transfer.to_bits())).collect();
            n.sort_unstable();
            n
        };
        assert_eq!(far(&tasks), far(&links), "{arg}: far links");
        assert_eq!(near(&tasks.near), near(&links.near), "{arg}: near links");
        assert_eq!(near(&tasks.pairs), near(&links.pairs), "{arg}: far pairs");
        assert_eq!(
            (tasks.rays, tasks.near_rays, tasks.occluded),
            (links.rays, links.near_rays, links.occluded),
            "{arg}"
        );
        check(&refiner, &links);
    }

    #[test]
    fn a_larger_link_is_trusted_only_after_as_many_agreeing_rays_as_its_bound_asks() {
        // Scenes whose far links are blocked in part: boxes on a floor, a maze.
        for (arg, eps) in [("cornell:res=8", 0.02), ("labyrinth:cells=4:size=0.5", 1e-2)] {
            for trust in [0.5, 1.5, 4.0] {
                refined(arg, eps, trust, |r, links| {
                    let (total, probe) = (r.strata.len(), (r.strata.len() / 4).max(1));
                    let (mut small, mut larger, mut short) = (0, 0, 0);
                    for link in links.far.iter() {
                        let (_, bound) = r.far_order(link.a, link.b).unwrap();
                        let count = usize::from(link.count & !ZEROTH);
                        let clear = usize::from(link.clear);
                        if bound <= r.shadows {
                            // A small link keeps its probe, inherited or traced.
                            assert_eq!(count, probe, "{arg}: a small link of {count} rays");
                            small += 1;
                        } else {
                            // A larger one only when every ray agrees, after the rays its bound asks.
                            let asked = ((trust * bound / r.shadows).ceil() as usize).clamp(probe, total);
                            assert_eq!(clear, count, "{arg}, trust {trust}: a larger link kept on disagreeing rays");
                            assert!(
                                (asked..=total).contains(&count),
                                "{arg}, trust {trust}: {count} rays where its bound asks {asked}"
                            );
                            larger += 1;
                            short += usize::from(count < total);
                        }
                    }
                    // Both kinds are made, and some larger links stop before every ray.
                    assert!(
                        small > 0 && larger > 0 && short > 0,
                        "{arg}, trust {trust}: {small} small, {larger} larger, {short} short"
                    );
                });
            }
        }
    }

    #[test]
    fn near_pairs_count_the_shadow_rays_of_their_entries() {
        // Every kept near link's entry traced the rays the analytic backend traces for it alone
        // (its stream is keyed by the pair); the pairs whose entries came out zero traced more.
        refined("cornell:res=8", 0.02, 1.5, |r, links| {
            let kept: u64 =
                links.near.iter().map(|l| r.analytic.pair_counting_rays(l.i as usize, l.j as usize).1 as u64).sum();
            assert!(kept > 0 && links.rays > 0);
            assert!(links.near_rays >= kept, "{} near rays counted, {kept} traced by the kept links", links.near_rays);
        });
    }

    #[test]
    fn near_and_pair_entries_in_f32_move_no_row_of_a_product_by_a_millionth() {
        // The lists hold each near link's and far pair's `A_i F_ij` as `f32`: every row's sum
        // over them, against a positive vector, stays within 1e-6 of the same sum over the
        // `f64` entries the refinement computed (each rounding is at most 6e-8 of its entry).
        use crate::hierarchical::adjacency::{Adjacency, Transfer};
        refined("cornell:res=8", 0.02, 1.5, |r, links| {
            let n = r.scene.len();
            let x: Vec<Real> = (0..n).map(|i| 0.1 + ((i * 7919) % 101) as Real / 101.0).collect();
            assert!(!links.near.is_empty() && !links.pairs.is_empty());
            for list in [&links.near, &links.pairs] {
                let narrow = Adjacency::new(n, list.clone(), |l| (l.i, l.j, l.transfer as Transfer));
                let mut exact = vec![0.0; n];
                for l in list.iter() {
                    exact[l.i as usize] += l.transfer * x[l.j as usize];
                    exact[l.j as usize] += l.transfer * x[l.i as usize];
                }
                for (i, &exact) in exact.iter().enumerate() {
                    let rounded: Real = narrow.of(i).map(|(j, t)| Real::from(t) * x[j as usize]).sum();
                    assert!((rounded - exact).abs() <= 1e-6 * exact, "row {i}: {rounded} against {exact}");
                }
            }
        });
    }
}
