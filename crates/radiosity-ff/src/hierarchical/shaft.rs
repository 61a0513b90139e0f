//! Shafts between the two ends of a link, and the patches that may lie in them: a link whose
//! shaft holds no patch but its own is clear without a ray.
//!
//! A shaft is the convex hull of the boxes of a link's two nodes, bounded conservatively as
//! Haines & Wallace do: the box of both, and in each of the three coordinate planes the lines
//! through corresponding corners of the two boxes' projections that support both (Haines &
//! Wallace 1994, "Shaft culling for efficient ray-cast radiosity", Photorealistic Rendering in
//! Computer Graphics, Eurographics Workshop on Rendering). Every segment between a point of one
//! end and a point of the other lies in the hull, so a patch outside the shaft blocks none. An
//! end whose patches lie in one plane and the other end wholly in front of that plane adds the
//! plane: every segment leaves it forwards.
//!
//! A patch is outside when its vertices lie on the far side of one of the shaft's planes, or
//! the corners of both boxes on one side of the patch's own plane. Touching counts as outside:
//! a segment between points inside the two ends' patches meets a supporting plane of the hull
//! only where the whole segment lies in it, which needs both ends' patches in that plane, and
//! such pairs face nothing of each other and have no links; it meets an end's own plane only
//! where it starts. The shadow test ([`radiosity_geom::Visibility::unoccluded_between`]) widens
//! each triangle by `1e-12` of its edges within its plane; the tests below widen a patch by as
//! much wherever a plane is not perpendicular to it, so a clear shaft means that every segment
//! the rays could draw is clear, and a link found clear is the link its rays would have made,
//! bit for bit.
//!
//! The patches of a link's own ends lie in its shaft. An end whose patches all lie in one
//! plane and face one way (a wall's cluster) blocks none of its own segments: a segment leaves
//! that plane at its start and never meets it again. So shafts are only searched for links
//! whose two ends are each a patch or such a flat cluster, and the patches of those ends are
//! passed over.
//!
//! The search runs over a tree of its own ([`ShaftTree`]), split by place alone: the cluster
//! tree splits by orientation first, so its upper nodes each span the scene and a search must
//! open them all (measured in `docs/hierarchical.md`). Candidates found for a link are handed
//! to the links it is split into: their shafts lie within its own (their boxes lie within its
//! boxes, and their planes are its planes or cut further), so they search what their parent
//! left.

use super::tree::split_at_median;
use radiosity_core::{Real, Scene, Vec3};

/// How much the shadow test widens a triangle within its plane, relative to its edges
/// (`radiosity_geom`'s `EDGE_MARGIN`, taken four times over to cover a quad's two triangles,
/// the sum of two barycentric margins and a patch's longest edge against its box's diagonal).
const WIDENING: Real = 4e-12;

/// The most planes a shaft has: two ends' planes and four lines in each of three coordinate
/// planes.
const MAX_PLANES: usize = 14;

/// Patches in a leaf of a [`ShaftTree`].
const LEAF_SIZE: usize = 4;

/// The hull of the boxes of a link's two ends, bounded by their common box and by planes.
#[derive(Clone, Debug)]
pub(crate) struct Shaft {
    lo: Vec3,
    hi: Vec3,
    /// Planes `n · p ≤ offset` holding every segment of the link (`n` unit): the first
    /// `count` of them.
    planes: [(Vec3, Real); MAX_PLANES],
    count: usize,
    /// The 16 corners of the two boxes.
    corners: [Vec3; 16],
}

impl Shaft {
    /// The shaft between the boxes `a` and `b` (each lower and upper corner), cut by the planes
    /// `cuts` (`n · p ≥ offset` for every point of every segment, as an end's plane gives),
    /// where given.
    pub fn new(a: (Vec3, Vec3), b: (Vec3, Vec3), cuts: [Option<(Vec3, Real)>; 2]) -> Shaft {
        let mut planes = [(Vec3::ZERO, 0.0); MAX_PLANES];
        let mut count = 0;
        for (n, offset) in cuts.into_iter().flatten() {
            planes[count] = (-n, -offset);
            count += 1;
        }
        for (u, v) in [(0, 1), (1, 2), (2, 0)] {
            for (su, sv) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                let corner = |(lo, hi): (Vec3, Vec3)| {
                    let pick = |s: Real, k: usize| if s > 0.0 { hi[k] } else { lo[k] };
                    (pick(su, u), pick(sv, v))
                };
                let (ca, cb) = (corner(a), corner(b));
                let (du, dv) = (cb.0 - ca.0, cb.1 - ca.1);
                // The line through both corners supports both boxes when its outward normal
                // points into the corners' quadrant: then each corner is its box's farthest
                // point along it. Otherwise one box's corner lies beyond the other's and the
                // common box bounds the hull there.
                let (mut nu, mut nv) = (-dv, du);
                if nu * su < 0.0 || nv * sv < 0.0 {
                    (nu, nv) = (-nu, -nv);
                }
                if nu * su <= 0.0 || nv * sv <= 0.0 {
                    continue;
                }
                let length = (nu * nu + nv * nv).sqrt();
                let mut n = Vec3::ZERO;
                n[u] = nu / length;
                n[v] = nv / length;
                // Both corners are on the line up to rounding: the larger offset holds both.
                let offset = (n[u] * ca.0 + n[v] * ca.1).max(n[u] * cb.0 + n[v] * cb.1);
                planes[count] = (n, offset);
                count += 1;
            }
        }
        let mut corners = [Vec3::ZERO; 16];
        for (k, c) in corners.iter_mut().enumerate() {
            let (lo, hi) = if k < 8 { a } else { b };
            *c = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
        }
        Shaft { lo: a.0.min(b.0), hi: a.1.max(b.1), planes, count, corners }
    }

    /// The planes bounding the shaft besides its box.
    fn planes(&self) -> &[(Vec3, Real)] {
        &self.planes[..self.count]
    }

    /// True when the box `lo`–`hi` of patches, each widened within its plane by at most `w`
    /// along each coordinate, lies outside the shaft.
    fn excludes_box(&self, lo: Vec3, hi: Vec3, w: Vec3) -> bool {
        if (0..3).any(|k| lo[k] - w[k] >= self.hi[k] || hi[k] + w[k] <= self.lo[k]) {
            return true;
        }
        self.planes().iter().any(|&(n, offset)| lowest_along(n, lo, hi) - n.abs().dot(w) >= offset)
    }

    /// True when the patch with vertices `vertices` and normal `normal`, widened by `margin`
    /// within its plane, lies outside the shaft.
    fn excludes_patch(&self, vertices: &[Vec3], normal: Vec3, margin: Real) -> bool {
        let widened = |n: Vec3| margin * (1.0 - n.dot(normal).powi(2)).max(0.0).sqrt();
        for k in 0..3 {
            let (lo, hi) =
                vertices.iter().fold((Real::INFINITY, -Real::INFINITY), |(l, h), v| (l.min(v[k]), h.max(v[k])));
            let w = widened(unit(k));
            if lo - w >= self.hi[k] || hi + w <= self.lo[k] {
                return true;
            }
        }
        if self.planes().iter().any(|&(n, offset)| {
            vertices.iter().map(|v| n.dot(*v)).fold(Real::INFINITY, Real::min) - widened(n) >= offset
        }) {
            return true;
        }
        // The patch's own plane with every corner of both boxes on one side of it.
        let at = normal.dot(vertices[0]);
        let (below, above) = self.corners.iter().fold((Real::INFINITY, -Real::INFINITY), |(l, h), c| {
            (l.min(normal.dot(*c) - at), h.max(normal.dot(*c) - at))
        });
        below >= 0.0 || above <= 0.0
    }
}

/// The smallest `n · p` over the box `lo`–`hi`.
pub(crate) fn lowest_along(n: Vec3, lo: Vec3, hi: Vec3) -> Real {
    n.x * if n.x > 0.0 { lo.x } else { hi.x }
        + n.y * if n.y > 0.0 { lo.y } else { hi.y }
        + n.z * if n.z > 0.0 { lo.z } else { hi.z }
}

/// The unit vector along coordinate `k`.
fn unit(k: usize) -> Vec3 {
    let mut u = Vec3::ZERO;
    u[k] = 1.0;
    u
}

/// A node of a [`ShaftTree`].
#[derive(Clone, Copy, Debug)]
struct ShaftNode {
    /// The box of its patches' vertices.
    lo: Vec3,
    hi: Vec3,
    /// How far the shadow test's widening of its patches reaches beyond the box along each
    /// coordinate: only within the plane of patches that all face one way.
    widening: Vec3,
    /// The first child (the second follows it), or the first patch of a leaf.
    start: u32,
    /// The patches of a leaf; 0 for a node with children.
    count: u32,
}

/// A bounding-volume tree over a scene's patches split by place alone, with leaves of up to
/// four patches: what shafts are searched in.
#[derive(Clone, Debug)]
pub(crate) struct ShaftTree {
    nodes: Vec<ShaftNode>,
    /// The patches in leaf order.
    patches: Vec<u32>,
}

/// The root of a [`ShaftTree`]: the candidates of a shaft searched from the whole scene.
pub(crate) const ROOT: u32 = 0;

impl ShaftTree {
    /// The tree over every patch of `scene`, split at the median centroid along the longest
    /// side of the centroids' box (ties broken by index, so the tree is always the same).
    pub fn new(scene: &Scene) -> ShaftTree {
        let mut patches: Vec<u32> = (0..scene.len() as u32).collect();
        let mut tree = ShaftTree { nodes: Vec::with_capacity(scene.len() / 2 + 1), patches: Vec::new() };
        tree.nodes.push(ShaftTree::bounds(scene, &patches, 0));
        let centroids: Vec<Vec3> = scene.patches().iter().map(|p| p.centroid()).collect();
        tree.split(scene, &centroids, &mut patches, 0, 0);
        tree.patches = patches;
        tree
    }

    /// Splits node `index`, over `patches` (which start at `first` in leaf order).
    fn split(&mut self, scene: &Scene, centroids: &[Vec3], patches: &mut [u32], first: usize, index: usize) {
        if patches.len() <= LEAF_SIZE {
            self.nodes[index].start = first as u32;
            self.nodes[index].count = patches.len() as u32;
            return;
        }
        let mid = split_at_median(patches, centroids);
        let (left, right) = patches.split_at_mut(mid);
        let child = self.nodes.len();
        self.nodes[index].start = child as u32;
        self.nodes.push(ShaftTree::bounds(scene, left, first));
        self.nodes.push(ShaftTree::bounds(scene, right, first + mid));
        self.split(scene, centroids, left, first, child);
        self.split(scene, centroids, right, first + mid, child + 1);
    }

    /// The box and widening of `patches`, as a node whose children are not known yet.
    fn bounds(scene: &Scene, patches: &[u32], first: usize) -> ShaftNode {
        let all = scene.patches();
        let (mut lo, mut hi) = (Vec3::splat(Real::INFINITY), Vec3::splat(-Real::INFINITY));
        for &i in patches {
            for v in all[i as usize].vertices() {
                lo = lo.min(*v);
                hi = hi.max(*v);
            }
        }
        let margin = WIDENING * (hi - lo).length();
        let normal = all[patches[0] as usize].normal();
        let widening = if patches.iter().all(|&i| all[i as usize].normal() == normal) {
            // Within the plane of `normal`: along a coordinate, margin · √(1 − n_k²).
            (Vec3::ONE - normal * normal).max(Vec3::ZERO).map(Real::sqrt) * margin
        } else {
            Vec3::splat(margin)
        };
        ShaftNode { lo, hi, widening, start: first as u32, count: 0 }
    }

    /// Filters `candidates` (nodes of this tree) into `kept`, opening nodes until a patch in
    /// `shaft` other than the link's own (`own`) is found or none is left; candidates after
    /// that patch are kept unopened. `Clear` when no patch is found.
    pub fn search(
        &self,
        scene: &Scene,
        shaft: &Shaft,
        candidates: &[u32],
        own: impl Fn(usize) -> bool,
        kept: &mut Vec<u32>,
    ) -> Search {
        kept.clear();
        let mut stack: Vec<u32> = candidates.iter().rev().copied().collect();
        let mut found = Search::Clear;
        while let Some(k) = stack.pop() {
            let node = &self.nodes[k as usize];
            if shaft.excludes_box(node.lo, node.hi, node.widening) {
                continue;
            }
            if found == Search::Blocked {
                kept.push(k);
            } else if node.count == 0 {
                stack.push(node.start + 1);
                stack.push(node.start);
            } else {
                let margin = WIDENING * (node.hi - node.lo).length();
                let range = node.start as usize..(node.start + node.count) as usize;
                let blocks = |&p: &u32| {
                    let patch = &scene.patches()[p as usize];
                    !own(p as usize) && !shaft.excludes_patch(patch.vertices(), patch.normal(), margin)
                };
                if self.patches[range].iter().any(blocks) {
                    found = Search::Blocked;
                    kept.push(k);
                }
            }
        }
        found
    }
}

/// What a shaft search found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Search {
    /// No patch but the ends' own lies in the shaft.
    Clear,
    /// Some patch may block a segment.
    Blocked,
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    fn random_box(rng: &mut impl Rng, scale: Real) -> (Vec3, Vec3) {
        let corner = Vec3::new(rng.random(), rng.random(), rng.random()) * scale;
        let side = Vec3::new(rng.random(), rng.random(), rng.random());
        (corner, corner + side)
    }

    fn point_in(rng: &mut impl Rng, (lo, hi): (Vec3, Vec3)) -> Vec3 {
        lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random())
    }

    /// Where the segment `p`–`q` crosses the triangle `v`, strictly inside both.
    fn crosses(p: Vec3, q: Vec3, v: [Vec3; 3]) -> bool {
        let (e1, e2, d) = (v[1] - v[0], v[2] - v[0], q - p);
        let h = d.cross(e2);
        let det = e1.dot(h);
        if det.abs() < 1e-14 {
            return false;
        }
        let s = p - v[0];
        let u = s.dot(h) / det;
        let w = s.cross(e1);
        let v2 = d.dot(w) / det;
        let t = e2.dot(w) / det;
        u > 0.0 && v2 > 0.0 && u + v2 < 1.0 && t > 0.0 && t < 1.0
    }

    #[test]
    fn a_shaft_holds_both_boxes_and_cuts_off_what_lies_beside_them() {
        // Boxes at opposite corners of a square: the box beside the diagonal lies within the
        // common box but outside the hull, and only the corner planes exclude it.
        let (a, b) = ((Vec3::ZERO, Vec3::ONE), (Vec3::new(5.0, 5.0, 0.0), Vec3::new(6.0, 6.0, 1.0)));
        let shaft = Shaft::new(a, b, [None, None]);
        let beside = (Vec3::new(0.0, 5.0, 0.0), Vec3::new(1.0, 6.0, 1.0));
        assert!(shaft.excludes_box(beside.0, beside.1, Vec3::ZERO));
        let between = (Vec3::new(2.5, 2.5, 0.25), Vec3::new(3.5, 3.5, 0.75));
        assert!(!shaft.excludes_box(between.0, between.1, Vec3::ZERO));
        // A box touching the hull from outside is outside; widened into it, it is not.
        let touching = (Vec3::new(0.0, 0.0, 1.0), Vec3::new(6.0, 6.0, 2.0));
        assert!(shaft.excludes_box(touching.0, touching.1, Vec3::ZERO));
        assert!(!shaft.excludes_box(touching.0, touching.1, Vec3::splat(1e-9)));

        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        for _ in 0..1000 {
            let (a, b) = (random_box(&mut rng, 4.0), random_box(&mut rng, 4.0));
            let shaft = Shaft::new(a, b, [None, None]);
            for c in shaft.corners {
                for &(n, offset) in shaft.planes() {
                    assert!(n.dot(c) <= offset + 1e-12, "a corner of a box outside its shaft");
                }
            }
        }
    }

    #[test]
    fn no_segment_between_the_boxes_crosses_a_patch_found_outside() {
        // Random triangles about two random boxes: every one the shaft says is outside is
        // crossed by none of 400 segments between random points of the boxes, and the shaft
        // finds some of them outside and some inside.
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let (mut outside, mut inside) = (0, 0);
        for _ in 0..200 {
            let (a, b) = (random_box(&mut rng, 3.0), random_box(&mut rng, 3.0));
            let shaft = Shaft::new(a, b, [None, None]);
            let segments: Vec<(Vec3, Vec3)> =
                (0..400).map(|_| (point_in(&mut rng, a), point_in(&mut rng, b))).collect();
            for _ in 0..20 {
                let v = [0; 3].map(|_| point_in(&mut rng, (Vec3::splat(-1.0), Vec3::splat(5.0))));
                let normal = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
                if shaft.excludes_patch(&v, normal, 0.0) {
                    outside += 1;
                    assert!(!segments.iter().any(|&(p, q)| crosses(p, q, v)), "a segment crosses a patch outside");
                } else {
                    inside += 1;
                }
            }
        }
        assert!(outside > 500 && inside > 500, "{outside} outside, {inside} inside");
    }
}
