//! Links of the hierarchical operator, refined from the root's link with itself.
//!
//! A link joins two disjoint nodes `A`, `B` of the [cluster tree](super::tree). It is one of:
//!
//! - **dropped**, when every patch of one side faces away from every direction to the other
//!   (bounded through the normal cones and the spheres), or when its shadow rays all meet
//!   something: no light passes, exactly or as far as the rays tell;
//! - **far**: the spheres are apart, every patch of `A` faces the centre-to-centre direction `d`
//!   and every patch of `B` faces `−d` (cosines bounded below by `α`, `β` through the cones),
//!   `αβ (1 − 2ρ) ≥ ρ (α + β)` with `ρ = (R_A + R_B) / r`, and the error estimate is within
//!   `eps`. Then `F_ij = A_j · g · κ_ij` for `i`, `j` on either side, with `g = V / (π r²)`, `r`
//!   the distance between the centres, `V` the fraction of `rays` segments between
//!   area-sampled points of both that are clear, and `κ` the kernel's cosines and `r²/|y − x|²`
//!   to first order about the centres (the module root's `kernel_factor`). `κ` is symmetric
//!   in the two ends, so `A_i F_ij = A_j F_ji` holds by construction, and its first-order
//!   terms are at most `ρ (2αβ + α + β)` against `αβ`, so the condition above keeps every
//!   entry non-negative;
//! - **near**: both are single patches and the link is not far: the analytic backend's entry
//!   ([`AnalyticColumns::pair`]), stored as `A_i F_ij`;
//! - otherwise **split**: the larger node (by radius) that can be split is replaced by its
//!   children. A link with partly visible rays is split too, while its transfer could exceed
//!   `eps`: it is subdivided rather than trusted.
//!
//! The error estimate of a far link bounds what it adds to one row of `F`,
//! `max(A_A, A_B) / (π r²)`, times the second-order variation of the kernel over the link,
//! `(2 (ρ + asin ρ))²`: the first-order terms are in `κ` (Hanrahan, Salzman & Aupperle 1991,
//! "A rapid hierarchical radiosity algorithm", SIGGRAPH; Sillion 1995, "A unified hierarchical
//! algorithm for global illumination with scattering volumes and object clusters", IEEE TVCG
//! 1(3)). This is a geometric oracle; one weighted by the radiosity `B` (Hanrahan's BF
//! refinement) is the next step. The visible fraction of a far link comes from `rays`
//! segments, which limits the operator's accuracy where links are partly occluded.

use super::tree::ClusterTree;
use crate::analytic::AnalyticColumns;
use radiosity_core::{Real, Scene, Vec3};
use radiosity_geom::Visibility;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::PI;

/// A far link between nodes `a` and `b`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FarLink {
    /// The first node.
    pub a: u32,
    /// The second node.
    pub b: u32,
    /// The unit direction from `a`'s centre to `b`'s.
    pub d: Vec3,
    /// The distance between the centres.
    pub r: Real,
    /// `V / (π r²)`.
    pub g: Real,
}

/// A near link: two patches and `A_i F_ij`.
#[derive(Clone, Copy, Debug)]
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
    pub far: Vec<FarLink>,
    pub near: Vec<NearLink>,
    /// Shadow rays traced for far links.
    pub rays: u64,
    /// Links dropped as fully occluded by their rays.
    pub occluded: u64,
}

impl Links {
    fn append(&mut self, mut other: Links) {
        self.far.append(&mut other.far);
        self.near.append(&mut other.near);
        self.rays += other.rays;
        self.occluded += other.occluded;
    }
}

/// What the segments of a link found.
struct Sampled {
    count: usize,
    clear: usize,
}

/// What refinement reads.
pub(crate) struct Refiner<'a> {
    pub scene: &'a Scene,
    pub tree: &'a ClusterTree,
    /// Visibility, when the scene can occlude.
    pub visibility: Option<&'a Visibility>,
    /// The near field.
    pub analytic: &'a AnalyticColumns<'a>,
    /// The error threshold.
    pub eps: Real,
    /// Shadow rays per far link.
    pub rays: usize,
    /// The seed of the rays.
    pub seed: u64,
    /// What counts as on a plane: a length relative to the scene diagonal.
    pub tolerance: Real,
    /// The cumulative area of the patches in tree order (`cumulative[k]` is the area of the
    /// first `k`), for sampling points by area.
    pub cumulative: Vec<Real>,
}

/// Nodes with more patches than this refine their links on other threads.
const PARALLEL_COUNT: u32 = 256;

impl Refiner<'_> {
    /// Every link, refined from the root's link with itself. The order of the links is fixed
    /// by the tree, not by the threads.
    pub fn refine_all(&self) -> Links {
        let mut links = Links::default();
        self.refine_self(0, &mut links);
        links
    }

    /// The links within node `k`.
    fn refine_self(&self, k: u32, out: &mut Links) {
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
                    self.refine_pair(a, b, &mut l);
                    l
                },
            );
            x.append(y);
            x.append(z);
            out.append(x);
        } else {
            self.refine_self(a, out);
            self.refine_self(b, out);
            self.refine_pair(a, b, out);
        }
    }

    /// The links between the disjoint nodes `a` and `b`.
    fn refine_pair(&self, a: u32, b: u32, out: &mut Links) {
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
        if (spread < PI && (away(na.axis, na.spread, d) || away(nb.axis, nb.spread, -d)))
            || self.behind_plane(a, b)
            || self.behind_plane(b, a)
        {
            return;
        }
        let (leaf_a, leaf_b) = (na.is_leaf(), nb.is_leaf());
        let (alpha, beta, rho) = (na.min_cos(d), nb.min_cos(-d), reach / r);
        // The kernel to first order stays non-negative for every pair of the link: its
        // first-order terms are at most ρ (2αβ + α + β) against αβ.
        if r > reach && alpha > 0.0 && beta > 0.0 && alpha * beta * (1.0 - 2.0 * rho) >= rho * (alpha + beta) {
            let bound = na.area.max(nb.area) / (PI * r * r);
            let error = bound * (2.0 * (rho + spread)).powi(2);
            if error <= self.eps {
                let sampled = self.sample(a, b, out);
                if sampled.clear == 0 {
                    out.occluded += 1;
                    return;
                }
                // Partly visible links are split while their transfer could exceed eps.
                if sampled.clear == sampled.count || bound <= self.eps || (leaf_a && leaf_b) {
                    let visible = sampled.clear as Real / sampled.count as Real;
                    out.far.push(FarLink { a, b, d, r, g: visible / (PI * r * r) });
                    return;
                }
            }
        }
        if leaf_a && leaf_b {
            let (i, j) = (self.tree.order[na.first as usize], self.tree.order[nb.first as usize]);
            let f = self.analytic.pair(i as usize, j as usize);
            if f > 0.0 {
                out.near.push(NearLink { i, j, transfer: self.scene.patches()[i as usize].area() * f });
            }
            return;
        }
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
        if na.count + nb.count > PARALLEL_COUNT {
            let (mut x, y) = rayon::join(
                || {
                    let mut l = Links::default();
                    self.refine_pair(p0.0, p0.1, &mut l);
                    l
                },
                || {
                    let mut l = Links::default();
                    self.refine_pair(p1.0, p1.1, &mut l);
                    l
                },
            );
            x.append(y);
            out.append(x);
        } else {
            self.refine_pair(p0.0, p0.1, out);
            self.refine_pair(p1.0, p1.1, out);
        }
    }

    /// True when every patch of `a` faces one way and all of `b` lies on or behind the plane of
    /// each of them: `a` sees nothing of `b`, and `b` nothing of `a`.
    fn behind_plane(&self, a: u32, b: u32) -> bool {
        let (na, nb) = (&self.tree.nodes[a as usize], &self.tree.nodes[b as usize]);
        if na.spread > 1e-12 {
            return false;
        }
        // The largest axis · y over b's box.
        let n = na.axis;
        let far = n.x * if n.x > 0.0 { nb.hi.x } else { nb.lo.x }
            + n.y * if n.y > 0.0 { nb.hi.y } else { nb.lo.y }
            + n.z * if n.z > 0.0 { nb.hi.z } else { nb.lo.z };
        far <= na.offsets.0 + self.tolerance
    }

    /// `rays` segments between points of `a` and `b` drawn by area (stratified), each traced
    /// when the scene can occlude (all clear otherwise); the stream is keyed by the pair.
    fn sample(&self, a: u32, b: u32, out: &mut Links) -> Sampled {
        let k = self.rays.max(1);
        let Some(visibility) = self.visibility else { return Sampled { count: k, clear: k } };
        let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(key ^ self.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let mut clear = 0;
        for s in 0..k {
            let u = (s as Real + rng.random::<Real>()) / k as Real;
            let v = (((s * 7 + 3) % k) as Real + rng.random::<Real>()) / k as Real;
            let (x, i) = self.point_in(a, u, &mut rng);
            let (y, j) = self.point_in(b, v, &mut rng);
            if visibility.unoccluded_between(x, i, y, j) {
                clear += 1;
            }
        }
        out.rays += k as u64;
        Sampled { count: k, clear }
    }

    /// The point of node `k` at the fraction `u` of its area, and its patch.
    fn point_in(&self, k: u32, u: Real, rng: &mut impl Rng) -> (Vec3, usize) {
        let node = &self.tree.nodes[k as usize];
        let (first, last) = (node.first as usize, (node.first + node.count) as usize);
        let target = self.cumulative[first] + u * (self.cumulative[last] - self.cumulative[first]);
        let at = self.cumulative[first..=last].partition_point(|&c| c <= target).clamp(1, last - first) + first - 1;
        let patch = self.tree.order[at] as usize;
        let point = self.scene.patches()[patch].point_at(rng.random(), rng.random());
        (point, patch)
    }
}
