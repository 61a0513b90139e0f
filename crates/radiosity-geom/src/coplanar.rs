//! Coplanar overlaps resolved: where patches facing the same way lie on top of each other, every
//! point of their union is kept on exactly one of them.
//!
//! Two coplanar patches facing the same way over the same area receive the light arriving there
//! twice and reflect it twice; a patch that sees them counts their form factor twice, so its
//! row of `F` exceeds 1 (RenderPark's `office.mgf` models its desks' rounded ends as discs laid
//! over the rectangular tops, and its chairs' arm caps as rings on top of the legs' caps: the
//! patches just above such a desk saw it twice, with rows near 1.85). Such duplicates are
//! modelling artefacts, and what the author meant is the union of the surfaces.
//!
//! ## The rule
//!
//! The probes of [`hidden`](crate::hidden) flag patches with a coplanar patch facing the same
//! way on top of them. From each flagged patch, every patch that overlaps it with positive area
//! is found exactly (same facing, `n_i · n_j > 0.999`; every vertex within `10⁻⁶ D` of the
//! plane, `D` the scene diagonal; a positive area of intersection in the plane), and from those
//! the same again, until each group of mutually overlapping patches is complete. In each group
//! the patches are taken in order, emitters first (a lamp laid on a ceiling keeps its area)
//! and then by index, and each keeps only the part of it no patch before it covers:
//!
//! - **covered**: nothing is left; the patch is left out;
//! - **cut**: part is left; the patch is replaced by the convex pieces of that part (quads
//!   where a piece has four corners, fans of triangles otherwise), with its material and object;
//! - otherwise the overlap had no area and the patch is kept as it is.
//!
//! The pieces partition the union, so the area of every surface is kept once; the area
//! removed is exactly the area that was counted twice (less pieces thinner than `10⁻⁹` of their
//! patch, which are dropped and counted in it). Patches are convex (triangles and planar
//! convex quads), so a patch less a patch is at most as many convex pieces as the subtracted
//! patch has edges.
//!
//! Like the probes, this samples where overlaps are looked for: two patches overlapping only
//! between probe points of both are not found.

use glam::DVec2;
use radiosity_core::{Patch, Real, Scene, Vec3};
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet, HashMap};

/// `n_i · n_j` above which two patches face the same way.
const SAME_FACING: Real = 0.999;
/// Largest distance of a vertex from the other patch's plane, relative to the scene diagonal.
const PLANE_GAP: Real = 1e-6;
/// Pieces and overlaps smaller than this fraction of their patch's area do not count.
const SLIVER: Real = 1e-9;
/// Bins of the normal's components when looking up patches by plane.
const NORMAL_BINS: Real = 1024.0;

/// A patch left out because patches kept before it cover it entirely.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CoveredPatch {
    /// The patch, numbered as in the scene probed.
    pub patch: usize,
    /// Its object.
    pub object: String,
    /// Its area.
    pub area: Real,
    /// The object of a patch covering it.
    pub by: String,
}

/// A patch cut to the part no patch kept before it covers.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CutPatch {
    /// The patch, numbered as in the scene probed.
    pub patch: usize,
    /// Its object.
    pub object: String,
    /// The share of its area kept, in `(0, 1)`.
    pub kept: Real,
    /// The patches it was cut into.
    pub pieces: usize,
    /// The object of a patch covering the rest.
    pub by: String,
}

/// How coplanar overlaps were resolved.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ResolvedOverlaps {
    /// Patches left out, covered by others.
    pub covered: Vec<CoveredPatch>,
    /// Patches cut to their uncovered part.
    pub cut: Vec<CutPatch>,
    /// The area removed: what the overlaps counted twice.
    pub area_removed: Real,
}

impl ResolvedOverlaps {
    /// True when no patch was left out or cut.
    pub fn is_empty(&self) -> bool {
        self.covered.is_empty() && self.cut.is_empty()
    }
}

/// What becomes of the patches involved: `None` to leave one out, or the pieces replacing it.
pub type Replacements = BTreeMap<usize, Option<Vec<Patch>>>;

/// Resolves the overlaps among the patches of `scene` reachable from the `flagged` ones (those
/// the probes found overlapping, and what they overlap), ignoring patches marked in `hidden`:
/// what was done, and the replacements.
pub fn resolve(scene: &Scene, flagged: &[usize], hidden: &[bool]) -> (ResolvedOverlaps, Replacements) {
    let mut resolved = ResolvedOverlaps::default();
    let mut replacements = Replacements::new();
    if flagged.is_empty() {
        return (resolved, replacements);
    }
    let gap = PLANE_GAP * scene.diagonal();
    let planes = PlaneIndex::new(scene, hidden, gap);
    // The overlap graph reachable from the flagged patches.
    let mut partners: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    let mut queue: Vec<usize> = flagged.iter().copied().filter(|&i| !hidden[i]).collect();
    queue.sort_unstable();
    queue.dedup();
    let mut seen: BTreeSet<usize> = queue.iter().copied().collect();
    while let Some(i) = queue.pop() {
        let found: Vec<usize> =
            planes.candidates(scene, i).into_iter().filter(|&j| overlap_area(scene, i, j) > 0.0).collect();
        for &j in &found {
            if seen.insert(j) {
                queue.push(j);
            }
        }
        partners.insert(i, found);
    }
    // Each group in order: emitters first, then by index.
    let emits = |i: usize| scene.emission(i).is_positive();
    let rank = |i: usize| (!emits(i), i);
    let mut done = BTreeSet::new();
    for &start in partners.keys() {
        if done.contains(&start) {
            continue;
        }
        let mut group = vec![start];
        done.insert(start);
        let mut k = 0;
        while k < group.len() {
            for &j in &partners[&group[k]] {
                if done.insert(j) {
                    group.push(j);
                }
            }
            k += 1;
        }
        group.sort_by_key(|&i| rank(i));
        for &p in &group {
            let before: Vec<usize> = partners[&p].iter().copied().filter(|&q| rank(q) < rank(p)).collect();
            if before.is_empty() {
                continue;
            }
            let patch = &scene.patches()[p];
            let frame = Frame::of(patch);
            let mut pieces = vec![frame.flatten(patch.vertices())];
            for &q in &before {
                let cutter = frame.flatten(scene.patches()[q].vertices());
                pieces = pieces.iter().flat_map(|piece| subtract(piece, &cutter)).collect();
            }
            let area = patch.area();
            let kept_area: Real = pieces.iter().map(|piece| polygon_area(piece)).sum();
            let by = scene.object_of(before[0]).to_string();
            let object = scene.object_of(p).to_string();
            if kept_area >= (1.0 - SLIVER) * area {
                continue;
            }
            let patches: Vec<Patch> = pieces
                .iter()
                .filter(|piece| polygon_area(piece) > SLIVER * area)
                .flat_map(|piece| frame.patches(piece, patch))
                .collect();
            let left: Real = patches.iter().map(Patch::area).sum();
            resolved.area_removed += area - left;
            if patches.is_empty() {
                resolved.covered.push(CoveredPatch { patch: p, object, area, by });
                replacements.insert(p, None);
            } else {
                resolved.cut.push(CutPatch { patch: p, object, kept: left / area, pieces: patches.len(), by });
                replacements.insert(p, Some(patches));
            }
        }
    }
    resolved.covered.sort_by_key(|c| c.patch);
    resolved.cut.sort_by_key(|c| c.patch);
    (resolved, replacements)
}

/// The patches of a scene by plane, for finding coplanar ones.
struct PlaneIndex {
    bins: HashMap<[i64; 4], Vec<usize>>,
    gap: Real,
}

impl PlaneIndex {
    fn key(n: Vec3, offset: Real, gap: Real) -> [i64; 4] {
        let q = (n * NORMAL_BINS).round();
        [q.x as i64, q.y as i64, q.z as i64, (offset / gap).round() as i64]
    }

    fn new(scene: &Scene, hidden: &[bool], gap: Real) -> PlaneIndex {
        let mut bins: HashMap<[i64; 4], Vec<usize>> = HashMap::new();
        for (i, p) in scene.patches().iter().enumerate().filter(|(i, _)| !hidden[*i]) {
            bins.entry(Self::key(p.normal(), p.normal().dot(p.centroid()), gap)).or_default().push(i);
        }
        PlaneIndex { bins, gap }
    }

    /// The patches other than `i` facing the same way as `i` with every vertex within the gap
    /// of its plane (those whose plane lies in a neighbouring bin of `i`'s).
    fn candidates(&self, scene: &Scene, i: usize) -> Vec<usize> {
        let p = &scene.patches()[i];
        let (n, offset) = (p.normal(), p.normal().dot(p.centroid()));
        let [a, b, c, d] = Self::key(n, offset, self.gap);
        let mut out = Vec::new();
        for da in -1..=1 {
            for db in -1..=1 {
                for dc in -1..=1 {
                    for dd in -1..=1 {
                        let Some(bin) = self.bins.get(&[a + da, b + db, c + dc, d + dd]) else { continue };
                        out.extend(bin.iter().copied().filter(|&j| {
                            let q = &scene.patches()[j];
                            j != i
                                && n.dot(q.normal()) > SAME_FACING
                                && q.vertices().iter().all(|v| (n.dot(*v) - offset).abs() <= self.gap)
                        }));
                    }
                }
            }
        }
        out.sort_unstable();
        out
    }
}

/// The area of the intersection of patches `i` and `j` in `i`'s plane, when it is more than a
/// sliver of the smaller; 0 otherwise.
fn overlap_area(scene: &Scene, i: usize, j: usize) -> Real {
    let (pi, pj) = (&scene.patches()[i], &scene.patches()[j]);
    let frame = Frame::of(pi);
    let (a, b) = (frame.flatten(pi.vertices()), frame.flatten(pj.vertices()));
    let mut inside = a;
    for k in 0..b.len() {
        inside = clip(&inside, b[k], b[(k + 1) % b.len()], true);
    }
    let area = polygon_area(&inside);
    if area > SLIVER * pi.area().min(pj.area()) { area } else { 0.0 }
}

/// A patch's plane: its first vertex and two orthonormal axes, so that the patch's vertices run
/// counter-clockwise.
struct Frame {
    origin: Vec3,
    u: Vec3,
    v: Vec3,
}

impl Frame {
    fn of(patch: &Patch) -> Frame {
        let n = patch.normal();
        let origin = patch.vertices()[0];
        let u = (patch.vertices()[1] - origin).normalize();
        Frame { origin, u, v: n.cross(u) }
    }

    fn flatten(&self, points: &[Vec3]) -> Vec<DVec2> {
        points.iter().map(|p| DVec2::new((*p - self.origin).dot(self.u), (*p - self.origin).dot(self.v))).collect()
    }

    fn lift(&self, p: DVec2) -> Vec3 {
        self.origin + p.x * self.u + p.y * self.v
    }

    /// A convex piece as patches with the material and object of `like`: one quad for four
    /// corners, a fan of triangles otherwise (or when the quad is refused).
    fn patches(&self, piece: &[DVec2], like: &Patch) -> Vec<Patch> {
        let points: Vec<Vec3> = piece.iter().map(|p| self.lift(*p)).collect();
        if let &[a, b, c, d] = points.as_slice()
            && let Ok(quad) = Patch::quad([a, b, c, d], like.material, like.object)
        {
            return vec![quad];
        }
        (1..points.len().saturating_sub(1))
            .filter_map(|k| Patch::triangle([points[0], points[k], points[k + 1]], like.material, like.object).ok())
            .collect()
    }
}

/// Twice the signed area of the triangle `a b c`: positive when counter-clockwise.
fn cross(a: DVec2, b: DVec2, c: DVec2) -> Real {
    (b - a).perp_dot(c - a)
}

/// The area of a polygon (counter-clockwise positive).
fn polygon_area(p: &[DVec2]) -> Real {
    (1..p.len().saturating_sub(1)).map(|k| cross(p[0], p[k], p[k + 1])).sum::<Real>() * 0.5
}

/// The part of the convex polygon `p` on the left of the line `a → b` (`left`) or on its right.
fn clip(p: &[DVec2], a: DVec2, b: DVec2, left: bool) -> Vec<DVec2> {
    let side = |x: DVec2| if left { cross(a, b, x) } else { -cross(a, b, x) };
    let mut out = Vec::with_capacity(p.len() + 1);
    for k in 0..p.len() {
        let (x, y) = (p[k], p[(k + 1) % p.len()]);
        let (sx, sy) = (side(x), side(y));
        if sx >= 0.0 {
            out.push(x);
        }
        if (sx >= 0.0) != (sy >= 0.0) {
            out.push(x + (y - x) * (sx / (sx - sy)));
        }
    }
    if out.len() < 3 { Vec::new() } else { out }
}

/// The convex polygon `p` less the convex polygon `q` (both counter-clockwise): disjoint convex
/// pieces, the `k`-th inside `q`'s first `k` edges and outside its edge `k`.
fn subtract(p: &[DVec2], q: &[DVec2]) -> Vec<Vec<DVec2>> {
    let q: Vec<DVec2> = if polygon_area(q) < 0.0 { q.iter().rev().copied().collect() } else { q.to_vec() };
    let mut pieces = Vec::new();
    let mut rest = p.to_vec();
    for k in 0..q.len() {
        if rest.is_empty() {
            break;
        }
        let (a, b) = (q[k], q[(k + 1) % q.len()]);
        let outside = clip(&rest, a, b, false);
        if !outside.is_empty() {
            pieces.push(outside);
        }
        rest = clip(&rest, a, b, true);
    }
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: Real, y0: Real, s: Real) -> Vec<DVec2> {
        vec![DVec2::new(x0, y0), DVec2::new(x0 + s, y0), DVec2::new(x0 + s, y0 + s), DVec2::new(x0, y0 + s)]
    }

    #[test]
    fn a_square_less_a_square_keeps_exactly_the_uncovered_area() {
        let (p, q) = (square(0.0, 0.0, 2.0), square(1.0, 1.0, 2.0));
        let pieces = subtract(&p, &q);
        let area: Real = pieces.iter().map(|x| polygon_area(x)).sum();
        assert!((area - 3.0).abs() < 1e-12, "{area}");
        assert!(pieces.iter().all(|x| polygon_area(x) > 0.0));
        // Covered entirely, and not at all.
        assert!(subtract(&square(1.0, 1.0, 0.5), &square(0.0, 0.0, 2.0)).is_empty());
        let apart = subtract(&p, &square(5.0, 5.0, 1.0));
        assert!((apart.iter().map(|x| polygon_area(x)).sum::<Real>() - 4.0).abs() < 1e-12);
    }
}
