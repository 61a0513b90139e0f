//! Visibility between points of the scene: a BVH over all patches (obvhs CWBVH) and exact
//! `f64` segment tests.
//!
//! ## How
//!
//! Every patch is split into its fan triangles and put into an obvhs compressed wide BVH
//! (rather than its BVH2; the bench's `columns` section measures the rays traced,
//! docs/bench-office.md), built on every thread with `BvhBuildParams::very_fast_build()`
//! ([`BvhBuild`]): on the million-patch office its tree traces rays as fast as the slowest
//! preset's, built in a quarter of the time (docs/scale.md). Occlusion
//! queries use `ray_traverse_miss`, which stops at the first hit (`ray_traverse_anyhit` would
//! call back on every hit).
//!
//! The BVH is `f32`. To keep its precision independent of where and how large the scene is,
//! it is built in a normalised frame: centred on the scene's bounding box and scaled to unit
//! half-extent. Candidate triangles found by the traversal are then tested exactly in `f64`,
//! in scene coordinates, with Möller–Trumbore (Möller & Trumbore 1997, "Fast, minimum storage
//! ray-triangle intersection").
//!
//! ## Robustness without an absolute epsilon
//!
//! A segment `p → q` is parametrised as `p + t (q − p)`, `t ∈ [0, 1]`, so every tolerance is
//! relative and the same at every scene scale:
//!
//! - hits with `t ≤ 1e-9` or `t ≥ 1 − 1e-9` are the endpoints' own surfaces, not occluders;
//! - when the endpoints' patches are known ([`Visibility::unoccluded_between`]), those patches
//!   are ignored outright, so a point on a patch never shadows itself, however grazing;
//! - barycentric bounds are inclusive with a `1e-12` margin, so a segment through the shared
//!   edge of two triangles is caught by at least one.
//!
//! The structure is immutable after construction and `Sync`: queries are safe from any number
//! of threads.

use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;
use radiosity_core::{Real, Scene, Vec3};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Duration;

/// Parametric margin at both ends of a segment (relative, so scale-free).
const T_MARGIN: Real = 1e-9;
/// Barycentric margin that makes edges inclusive.
const EDGE_MARGIN: Real = 1e-12;
/// How far behind the true origin BVH rays start, in BVH units (half the scene's extent):
/// twice obvhs's fixed node-entry epsilon of `1e-4`.
const BVH_BACKOFF: Real = 2e-4;

/// How far each BVH triangle is pushed out from its centroid, in BVH units.
///
/// obvhs's slab test replaces direction components below `f32::EPSILON` by `±1/f32::EPSILON`
/// and clamps entry distances to `1e-4`, so a ray running along (or nearly along) the maximum
/// face of a node's box can be rejected. Boxes `1e-6` units larger than their triangles keep
/// such rays inside: the exit distance is then at least `1e-6 / f32::EPSILON ≈ 8` units, more
/// than the scene's extent. The exact `f64` test decides the hit, so nothing else changes.
const BVH_INFLATE: Real = 1e-6;

/// True for a finite, non-zero vector: one that can be a ray direction.
fn is_nonzero(d: Vec3) -> bool {
    d.is_finite() && d != Vec3::ZERO
}

/// Maps a true ray parameter to the parameter along the BVH ray.
#[derive(Clone, Copy)]
struct BvhParam {
    scale: Real,
}

impl BvhParam {
    fn to_bvh(self, t: Real) -> f32 {
        (t * self.scale + BVH_BACKOFF) as f32
    }
}

/// A hit found by [`Visibility::first_hit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// The patch hit.
    pub patch: usize,
    /// The ray parameter: the hit point is `origin + t · direction`.
    pub t: Real,
    /// Whether the ray arrived on the patch's front side.
    pub front: bool,
}

/// A BVH over the scene's patches answering occlusion and ray queries.
///
/// A handle: a clone shares the tree, so that whatever traces rays holds its own and the tree
/// is freed when the last handle goes ([`crate::PreparedScene::release_visibility`]).
#[derive(Clone, PartialEq)]
pub struct Visibility(Arc<Tree>);

/// What a [`Visibility`] shares between its handles.
#[derive(PartialEq)]
struct Tree {
    bvh: CwBvh,
    triangles: Vec<[Vec3; 3]>,
    triangle_patch: Vec<u32>,
    centre: Vec3,
    inv_scale: Real,
    diagonal: Real,
}

impl std::fmt::Debug for Visibility {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Visibility").field("triangles", &self.0.triangles.len()).finish_non_exhaustive()
    }
}

/// How much a BVH build invests in the tree's quality (obvhs's presets, from the fastest
/// build to the fastest traversal): `cargo run --release -p radiosity-geom --example
/// bvh_presets` measures each build's seconds beside its rays per second (docs/scale.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum BvhBuild {
    /// `BvhBuildParams::fastest_build`.
    Fastest,
    /// `BvhBuildParams::very_fast_build`: the default.
    #[default]
    VeryFast,
    /// `BvhBuildParams::fast_build`.
    Fast,
    /// `BvhBuildParams::medium_build`.
    Medium,
    /// `BvhBuildParams::slow_build`.
    Slow,
    /// `BvhBuildParams::very_slow_build`.
    VerySlow,
}

impl BvhBuild {
    /// Every preset, from the fastest build.
    pub const ALL: [BvhBuild; 6] =
        [BvhBuild::Fastest, BvhBuild::VeryFast, BvhBuild::Fast, BvhBuild::Medium, BvhBuild::Slow, BvhBuild::VerySlow];

    /// The preset's name, as obvhs's function without `_build`.
    pub fn name(self) -> &'static str {
        match self {
            BvhBuild::Fastest => "fastest",
            BvhBuild::VeryFast => "very_fast",
            BvhBuild::Fast => "fast",
            BvhBuild::Medium => "medium",
            BvhBuild::Slow => "slow",
            BvhBuild::VerySlow => "very_slow",
        }
    }

    fn params(self) -> BvhBuildParams {
        match self {
            BvhBuild::Fastest => BvhBuildParams::fastest_build(),
            BvhBuild::VeryFast => BvhBuildParams::very_fast_build(),
            BvhBuild::Fast => BvhBuildParams::fast_build(),
            BvhBuild::Medium => BvhBuildParams::medium_build(),
            BvhBuild::Slow => BvhBuildParams::slow_build(),
            BvhBuild::VerySlow => BvhBuildParams::very_slow_build(),
        }
    }
}

impl Visibility {
    /// Builds the BVH over every patch of `scene`, with the default preset
    /// ([`BvhBuild::default`]).
    pub fn new(scene: &Scene) -> Visibility {
        Visibility::with_build(scene, BvhBuild::default())
    }

    /// Builds the BVH over every patch of `scene` with the preset `build`, on every thread of
    /// the current rayon pool; the tree is the same whatever the thread count.
    pub fn with_build(scene: &Scene, build: BvhBuild) -> Visibility {
        let (lo, hi) = scene.bounds();
        let centre = (lo + hi) * 0.5;
        let half = ((hi - lo) * 0.5).max_element();
        let inv_scale = if half > 0.0 { 1.0 / half } else { 1.0 };
        let mut triangles = Vec::with_capacity(scene.len() * 2);
        let mut triangle_patch = Vec::with_capacity(scene.len() * 2);
        for (i, patch) in scene.patches().iter().enumerate() {
            for tri in patch.triangles() {
                triangles.push(tri);
                triangle_patch.push(i as u32);
            }
        }
        let bvh_tris: Vec<Triangle> = triangles
            .par_iter()
            .map(|t| {
                let t = t.map(|v| (v - centre) * inv_scale);
                let c = (t[0] + t[1] + t[2]) / 3.0;
                let out = |v: Vec3| Vec3A::from((v + (v - c).normalize_or_zero() * BVH_INFLATE).as_vec3());
                Triangle { v0: out(t[0]), v1: out(t[1]), v2: out(t[2]) }
            })
            .collect();
        let bvh = build_cwbvh_from_tris(&bvh_tris, build.params(), &mut Duration::default());
        Visibility(Arc::new(Tree { bvh, triangles, triangle_patch, centre, inv_scale, diagonal: scene.diagonal() }))
    }

    /// Whether another handle shares this one's tree.
    pub fn is_shared(&self) -> bool {
        Arc::strong_count(&self.0) > 1
    }

    /// The bytes the structure holds on the heap: the exact `f64` triangles, the patch of each,
    /// and obvhs's tree (its nodes and primitive indices).
    pub fn heap_bytes(&self) -> usize {
        self.0.triangles.capacity() * size_of::<[Vec3; 3]>()
            + self.0.triangle_patch.capacity() * size_of::<u32>()
            + self.0.bvh.nodes.capacity() * size_of::<obvhs::cwbvh::node::CwBvhNode>()
            + self.0.bvh.primitive_indices.capacity() * size_of::<u32>()
            + self.0.bvh.exact_node_aabbs.as_ref().map_or(0, |a| a.capacity() * size_of::<obvhs::aabb::Aabb>())
    }

    /// The number of triangles in the BVH (one per triangle patch, two per quad).
    pub fn triangle_count(&self) -> usize {
        self.0.triangles.len()
    }

    /// The BVH-space ray for `origin + t · direction`, `t ∈ [0, tmax]`, and the map from `t`
    /// to the BVH ray's parameter.
    ///
    /// obvhs clamps the entry distance of every node test to a fixed `1e-4` (`cwbvh::node::
    /// EPSILON`), so a node closer than that to the ray origin would be skipped. The BVH ray
    /// therefore has a unit direction and starts [`BVH_BACKOFF`] units behind the true origin;
    /// our exact `f64` tests still use the true ray and reject what lies behind it.
    fn bvh_ray(&self, origin: Vec3, direction: Vec3, tmax: Real) -> (Ray, BvhParam) {
        let d = direction * self.0.inv_scale;
        let len = d.length();
        let unit = d / len;
        let o = (origin - self.0.centre) * self.0.inv_scale - unit * BVH_BACKOFF;
        let map = BvhParam { scale: len };
        // Adding +0 turns a −0 component into +0: obvhs takes the octant of a ray from the sign
        // bits of its direction, and a −0 component (as in `-Vec3::Y`) put the ray in an octant
        // its slab test disagreed with, so rays straight down missed the floor.
        let unit = Vec3A::from(unit.as_vec3()) + Vec3A::ZERO;
        let ray = Ray::new(Vec3A::from(o.as_vec3()), unit, 0.0, map.to_bvh(tmax));
        (ray, map)
    }

    /// Exact ray-triangle test in `f64`: the parameter `t` and whether the front side was hit.
    #[inline(always)]
    fn intersect(&self, tri: usize, origin: Vec3, direction: Vec3) -> Option<(Real, bool)> {
        let [a, b, c] = self.0.triangles[tri];
        let e1 = b - a;
        let e2 = c - a;
        let pvec = direction.cross(e2);
        let det = e1.dot(pvec);
        if det == 0.0 {
            return None;
        }
        let inv = 1.0 / det;
        let s = origin - a;
        let u = s.dot(pvec) * inv;
        if !(-EDGE_MARGIN..=1.0 + EDGE_MARGIN).contains(&u) {
            return None;
        }
        let qvec = s.cross(e1);
        let v = direction.dot(qvec) * inv;
        if v < -EDGE_MARGIN || u + v > 1.0 + EDGE_MARGIN {
            return None;
        }
        // det = e1 · (d × e2) = −d · (e1 × e2): positive when the ray runs against the
        // triangle's normal, i.e. arrives on its front.
        Some((e2.dot(qvec) * inv, det > 0.0))
    }

    /// True when no patch blocks the open segment between the free points `p` and `q`.
    pub fn unoccluded(&self, p: Vec3, q: Vec3) -> bool {
        self.segment_clear(p, q, u32::MAX, u32::MAX)
    }

    /// True when no patch other than `from` and `to` blocks the segment from `p` (a point on
    /// patch `from`) to `q` (a point on patch `to`).
    pub fn unoccluded_between(&self, p: Vec3, from: usize, q: Vec3, to: usize) -> bool {
        self.segment_clear(p, q, from as u32, to as u32)
    }

    fn segment_clear(&self, p: Vec3, q: Vec3, skip_a: u32, skip_b: u32) -> bool {
        let d = q - p;
        if !is_nonzero(d) {
            return true;
        }
        let (ray, _) = self.bvh_ray(p, d, 1.0);
        self.0.bvh.ray_traverse_miss(ray, |_, id| {
            let tri = self.0.bvh.primitive_indices[id] as usize;
            let patch = self.0.triangle_patch[tri];
            if patch == skip_a || patch == skip_b {
                return f32::INFINITY;
            }
            match self.intersect(tri, p, d) {
                Some((t, _)) if t > T_MARGIN && t < 1.0 - T_MARGIN => 0.0,
                _ => f32::INFINITY,
            }
        })
    }

    /// The smallest ray parameter that counts as a hit in [`Visibility::first_hit`] and
    /// [`Visibility::escapes`]: `1e-9` scene diagonals along `direction`.
    pub fn ray_margin(&self, direction: Vec3) -> Real {
        T_MARGIN * self.0.diagonal / direction.length()
    }

    /// The closest patch hit by the ray `origin + t · direction`, ignoring patch `skip` (the
    /// patch the ray leaves from, if any) and hits closer than `1e-9` scene diagonals.
    pub fn first_hit(&self, origin: Vec3, direction: Vec3, skip: Option<usize>) -> Option<RayHit> {
        let skip = skip.map_or(u32::MAX, |s| s as u32);
        if !is_nonzero(direction) {
            return None;
        }
        let margin = self.ray_margin(direction);
        let (ray, map) = self.bvh_ray(origin, direction, Real::INFINITY);
        let mut best: Option<RayHit> = None;
        let mut closest = obvhs::ray::RayHit::none();
        self.0.bvh.ray_traverse(ray, &mut closest, |_, id| {
            let tri = self.0.bvh.primitive_indices[id] as usize;
            let patch = self.0.triangle_patch[tri];
            if patch == skip {
                return f32::INFINITY;
            }
            match self.intersect(tri, origin, direction) {
                Some((t, front)) if t > margin && best.is_none_or(|b| t < b.t) => {
                    best = Some(RayHit { patch: patch as usize, t, front });
                    map.to_bvh(t)
                }
                _ => f32::INFINITY,
            }
        });
        best
    }

    /// True when the ray `origin + t · direction` hits no patch other than `skip`, ignoring
    /// hits closer than `1e-9` scene diagonals.
    pub fn escapes(&self, origin: Vec3, direction: Vec3, skip: Option<usize>) -> bool {
        let skip = skip.map_or(u32::MAX, |s| s as u32);
        if !is_nonzero(direction) {
            return true;
        }
        let margin = self.ray_margin(direction);
        let (ray, _) = self.bvh_ray(origin, direction, Real::INFINITY);
        self.0.bvh.ray_traverse_miss(ray, |_, id| {
            let tri = self.0.bvh.primitive_indices[id] as usize;
            if self.0.triangle_patch[tri] == skip {
                return f32::INFINITY;
            }
            match self.intersect(tri, origin, direction) {
                Some((t, _)) if t > margin => 0.0,
                _ => f32::INFINITY,
            }
        })
    }

    /// The closest hit by testing every triangle, without the BVH: a slow reference for tests
    /// and diagnostics.
    pub fn first_hit_brute_force(&self, origin: Vec3, direction: Vec3, skip: Option<usize>) -> Option<RayHit> {
        let margin = self.ray_margin(direction);
        (0..self.0.triangles.len())
            .filter(|&k| Some(self.0.triangle_patch[k] as usize) != skip)
            .filter_map(|k| {
                let (t, front) = self.intersect(k, origin, direction)?;
                (t > margin).then_some(RayHit { patch: self.0.triangle_patch[k] as usize, t, front })
            })
            .min_by(|a, b| a.t.total_cmp(&b.t))
    }
}

/// The BVH of a [`Visibility`] traversed with obvhs's own `f32` ray-triangle test: the
/// ray-tracing limit that `cargo xtask bench` sets form-factor backends against.
///
/// It answers the same two questions as [`Visibility::unoccluded_between`] and
/// [`Visibility::first_hit`], skipping the same patches, over the same tree and with the same
/// BVH-space rays, but tests candidate triangles with obvhs's `Triangle::intersect` in `f32`
/// (the triangles in the normalised frame, not inflated) instead of the exact `f64` test in
/// scene coordinates. The difference in speed between the two is what exactness costs; the
/// answers may differ on grazing rays and at shared edges, so it is for measuring only.
pub struct RawTracer<'v> {
    visibility: &'v Visibility,
    /// Every triangle in the BVH's frame, indexed like `Visibility::triangles`.
    triangles: Vec<Triangle>,
}

impl std::fmt::Debug for RawTracer<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RawTracer").field("triangles", &self.triangles.len()).finish_non_exhaustive()
    }
}

impl Visibility {
    /// The same BVH with obvhs's `f32` triangle test, for measuring ([`RawTracer`]).
    pub fn raw_tracer(&self) -> RawTracer<'_> {
        let triangles = self
            .0
            .triangles
            .iter()
            .map(|t| {
                let v = t.map(|v| Vec3A::from(((v - self.0.centre) * self.0.inv_scale).as_vec3()));
                Triangle { v0: v[0], v1: v[1], v2: v[2] }
            })
            .collect();
        RawTracer { visibility: self, triangles }
    }
}

impl RawTracer<'_> {
    /// Like [`Visibility::unoccluded_between`]: true when no patch other than `from` and `to`
    /// blocks the segment from `p` to `q`, hits within `1e-9` of either end ignored.
    pub fn unoccluded_between(&self, p: Vec3, from: usize, q: Vec3, to: usize) -> bool {
        let vis = self.visibility;
        let d = q - p;
        if !is_nonzero(d) {
            return true;
        }
        let (mut ray, map) = vis.bvh_ray(p, d, 1.0);
        ray.tmin = map.to_bvh(T_MARGIN);
        ray.tmax = map.to_bvh(1.0 - T_MARGIN);
        let (from, to) = (from as u32, to as u32);
        vis.0.bvh.ray_traverse_miss(ray, |ray, id| {
            let tri = vis.0.bvh.primitive_indices[id] as usize;
            let patch = vis.0.triangle_patch[tri];
            if patch == from || patch == to { f32::INFINITY } else { self.triangles[tri].intersect(ray) }
        })
    }

    /// Like [`Visibility::first_hit`], reduced to the patch hit: the closest patch other than
    /// `skip` along the ray `origin + t · direction`.
    pub fn first_hit_patch(&self, origin: Vec3, direction: Vec3, skip: Option<usize>) -> Option<usize> {
        let vis = self.visibility;
        if !is_nonzero(direction) {
            return None;
        }
        let skip = skip.map_or(u32::MAX, |s| s as u32);
        let (mut ray, map) = vis.bvh_ray(origin, direction, Real::INFINITY);
        ray.tmin = map.to_bvh(vis.ray_margin(direction));
        let mut hit = obvhs::ray::RayHit::none();
        vis.0
            .bvh
            .ray_traverse(ray, &mut hit, |ray, id| {
                let tri = vis.0.bvh.primitive_indices[id] as usize;
                if vis.0.triangle_patch[tri] == skip { f32::INFINITY } else { self.triangles[tri].intersect(ray) }
            })
            .then(|| vis.0.triangle_patch[vis.0.bvh.primitive_indices[hit.primitive_id as usize] as usize] as usize)
    }
}

#[cfg(test)]
mod raw_tracer_tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn the_raw_tracer_answers_as_the_exact_queries_but_for_rare_grazing_cases() {
        let scene = crate::load_scene("multi-cubes").unwrap().scene;
        let vis = Visibility::new(&scene);
        let raw = vis.raw_tracer();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let n = scene.len();
        let (mut segments, mut rays, mut traced, mut clear) = (0, 0, 0, 0);
        for _ in 0..4000 {
            let (a, b) = (rng.random_range(0..n), rng.random_range(0..n));
            let p = scene.patches()[a].point_at(rng.random(), rng.random());
            let q = scene.patches()[b].point_at(rng.random(), rng.random());
            let exact = vis.unoccluded_between(p, a, q, b);
            clear += usize::from(exact);
            segments += usize::from(raw.unoccluded_between(p, a, q, b) == exact);
            // Rays leave a patch on its front, as the backends' do; rays in the patch's own
            // plane, which no backend traces, graze coplanar neighbours and are left out.
            let normal = scene.patches()[a].normal();
            let d = if normal.dot(q - p) < 0.0 { p - q } else { q - p };
            if normal.dot(d) > 1e-3 * d.length() {
                traced += 1;
                rays +=
                    usize::from(raw.first_hit_patch(p, d, Some(a)) == vis.first_hit(p, d, Some(a)).map(|h| h.patch));
            }
        }
        assert!(clear > 400 && clear < 3600, "{clear} of 4000 segments clear: not a useful test");
        assert!(segments >= 3960, "{segments} of 4000 segments agree");
        assert!(traced > 2000 && rays as f64 >= 0.99 * traced as f64, "{rays} of {traced} rays agree");
    }
}
