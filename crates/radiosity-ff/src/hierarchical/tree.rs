//! The cluster tree of the hierarchical operator: a binary tree over the scene's patches, each
//! node with a bounding sphere, a cone bounding its patches' normals and its area.
//!
//! Nodes holding patches of more than one orientation class are first split between classes,
//! at the class boundary nearest the middle; below, nodes are split at the median centroid
//! along the longest side of their centroids' box, so the tree is balanced and the same
//! whatever the thread count: ties are broken by patch index.
//!
//! A class is a face of the cube the normal points through (its largest component and that
//! component's sign) cut into 3 × 3 by the two other components over it, at `±tan 20°`
//! ([`class`]): 54 classes. A far link needs every patch of both its nodes facing the other
//! ([`super::links`]), so a node's cone of normals bounds how coarse its links can be. Patches
//! facing along an axis all fall in their face's centre class, so a scene of boxes is split as
//! by the six faces alone; the patches of curved objects (the cylinders, cones and spheres of
//! MGF furniture) are grouped by the way they face to within about 20° instead of 55°, and
//! their clusters link far at coarser levels (measured in `docs/hierarchical.md`).
//!
//! Nodes are stored in pre-order, so a parent comes before its children (a pass forward pushes
//! down, a pass backward gathers up), and the patches of a node are a contiguous range of
//! [`ClusterTree::order`].

use radiosity_core::{Real, Scene, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// A node: the patches `order[first .. first + count]`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Node {
    /// The centre of the bounding sphere of the patches' vertices.
    pub centre: Vec3,
    /// Its radius.
    pub radius: Real,
    /// The largest distance from the centre to a patch's centroid: far links evaluate their
    /// kernel at the centroids, so this bounds the offsets the kernel's first-order terms see.
    pub centroid_radius: Real,
    /// The axis of the cone of the patches' normals (unit).
    pub axis: Vec3,
    /// The cone's half-angle in radians (π when the normals point every way).
    pub spread: Real,
    /// The lower corner of the box of the patches' vertices.
    pub lo: Vec3,
    /// Its upper corner.
    pub hi: Vec3,
    /// The smallest and largest `axis · v` over the vertices: the planes of the patches lie
    /// between them when they all face along `axis` (`spread` 0).
    pub offsets: (Real, Real),
    /// The first patch, in tree order.
    pub first: u32,
    /// How many patches.
    pub count: u32,
    /// The two children, or none for a leaf (one patch).
    pub children: Option<[u32; 2]>,
}

impl Node {
    /// True for a leaf: one patch.
    pub fn is_leaf(&self) -> bool {
        self.children.is_none()
    }

    /// The smallest `n · d` over the normals of the node's patches, bounded through the cone:
    /// `cos(min(π, ∠(axis, d) + spread))`.
    pub fn min_cos(&self, d: Vec3) -> Real {
        let angle = self.axis.dot(d).clamp(-1.0, 1.0).acos();
        (angle + self.spread).min(PI).cos()
    }
}

/// The tree over a scene's patches, as the refinement reads it.
#[derive(Clone, Debug)]
pub(crate) struct ClusterTree {
    /// The nodes, in pre-order; the root is node 0.
    pub nodes: Vec<Node>,
    /// The patches in tree order: the leaves of each node are a contiguous range.
    pub order: Vec<u32>,
    /// The leaf node of every patch.
    pub leaf: Vec<u32>,
}

impl ClusterTree {
    /// Builds the tree over every patch of `scene` (at least one), subtrees on rayon's
    /// threads: the same tree whatever their number.
    pub fn new(scene: &Scene) -> ClusterTree {
        let n = scene.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let centroids: Vec<Vec3> = scene.patches().par_iter().map(|p| p.centroid()).collect();
        let classes: Vec<u8> = (0..n as u32).into_par_iter().map(|i| class(scene, i)).collect();
        // A node over `m` patches heads a subtree of `2m − 1` nodes (every split is in two):
        // each subtree's place in pre-order is known before it is built.
        let mut nodes = vec![Node::default(); (2 * n).saturating_sub(1)];
        if n > 0 {
            Subtree { scene, centroids: &centroids, classes: &classes }.fill(&mut order, 0, &mut nodes, 0);
        }
        let mut leaf = vec![0; n];
        for (k, node) in nodes.iter().enumerate() {
            if node.is_leaf() {
                leaf[order[node.first as usize] as usize] = k as u32;
            }
        }
        ClusterTree { nodes, order, leaf }
    }

    /// The patches of node `k`, in tree order.
    #[cfg(test)]
    pub fn patches_of(&self, k: u32) -> &[u32] {
        let node = &self.nodes[k as usize];
        &self.order[node.first as usize..(node.first + node.count) as usize]
    }

    /// The tree as the operator holds it once its links are made ([`HeldTree`]).
    pub fn held(self) -> HeldTree {
        let nodes = self.nodes.iter().map(|n| HeldNode { centre: n.centre, first: n.first, count: n.count }).collect();
        HeldTree { nodes, order: self.order, leaf: self.leaf }
    }
}

/// A node as the operator holds it: its centre, which its far links' geometry is worked out
/// from, and its patches. 32 bytes, where the refinement's [`Node`] takes 160.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct HeldNode {
    /// The centre of the bounding sphere of the patches' vertices.
    pub centre: Vec3,
    /// The first patch, in tree order.
    pub first: u32,
    /// How many patches.
    pub count: u32,
}

impl HeldNode {
    /// True for a leaf: one patch.
    pub fn is_leaf(&self) -> bool {
        self.count == 1
    }
}

/// The cluster tree as the operator holds it: what a product, a column and a shot read of it
/// (the nodes' centres and patches, in the same pre-order), without the bounds that only the
/// refinement asks.
#[derive(Clone, Debug)]
pub(crate) struct HeldTree {
    /// The nodes, in pre-order; the root is node 0.
    pub nodes: Vec<HeldNode>,
    /// The patches in tree order.
    pub order: Vec<u32>,
    /// The leaf node of every patch.
    pub leaf: Vec<u32>,
}

impl HeldTree {
    /// The two children of node `k`, or none for a leaf. In pre-order, the first follows `k`
    /// and the second follows the first's subtree of `2m − 1` nodes over its `m` patches.
    pub fn children(&self, k: usize) -> Option<[u32; 2]> {
        (!self.nodes[k].is_leaf()).then(|| [k as u32 + 1, k as u32 + 2 * self.nodes[k + 1].count])
    }

    /// The patches of node `k`, in tree order.
    pub fn patches_of(&self, k: u32) -> &[u32] {
        let node = &self.nodes[k as usize];
        &self.order[node.first as usize..(node.first + node.count) as usize]
    }
}

/// What building a subtree reads: the scene, its patches' centroids and classes.
struct Subtree<'s> {
    scene: &'s Scene,
    centroids: &'s [Vec3],
    classes: &'s [u8],
}

/// Subtrees over more patches than this are built beside each other on rayon's threads.
const PARALLEL_PATCHES: usize = 4096;

impl Subtree<'_> {
    /// Writes the node over `patches` (which start at `first` in tree order) and its subtree
    /// into `nodes` (exactly `2 · patches.len() − 1` of them, in pre-order), the node's index
    /// in the whole tree being `index`. Patches of more than one orientation class are split
    /// between classes first, at the class boundary nearest the middle: clusters that face
    /// one way can link far more often (every cosine of a far link must be non-negative).
    fn fill(&self, patches: &mut [u32], first: usize, nodes: &mut [Node], index: u32) {
        debug_assert_eq!(nodes.len(), 2 * patches.len() - 1);
        let mut node = bounds(self.scene, patches, first);
        if patches.len() > 1 {
            let classes = self.classes;
            let mid = if patches.iter().any(|&i| classes[i as usize] != classes[patches[0] as usize]) {
                patches.sort_unstable_by_key(|&i| (classes[i as usize], i));
                let boundaries =
                    (1..patches.len()).filter(|&k| classes[patches[k - 1] as usize] != classes[patches[k] as usize]);
                boundaries.min_by_key(|&k| k.abs_diff(patches.len() / 2)).unwrap()
            } else {
                split_at_median(patches, self.centroids)
            };
            let (left, right) = patches.split_at_mut(mid);
            let (here, below) = nodes.split_first_mut().unwrap();
            let (left_nodes, right_nodes) = below.split_at_mut(2 * mid - 1);
            let (a, b) = (index + 1, index + 2 * mid as u32);
            node.children = Some([a, b]);
            *here = node;
            if left.len() + right.len() > PARALLEL_PATCHES {
                rayon::join(|| self.fill(left, first, left_nodes, a), || self.fill(right, first + mid, right_nodes, b));
            } else {
                self.fill(left, first, left_nodes, a);
                self.fill(right, first + mid, right_nodes, b);
            }
        } else {
            nodes[0] = node;
        }
    }
}

/// Where the two minor components of a normal, over its largest, are cut into bins:
/// `tan 20°`.
const BIN_EDGE: Real = 0.363_970_234_266_202_4;

/// The class of a patch's orientation (module documentation): its normal's largest component
/// and that component's sign (a face of the cube), and the bin of each of the two other
/// components over it (below `−tan 20°`, within, above): 54 classes.
fn class(scene: &Scene, i: u32) -> u8 {
    let n = scene.patches()[i as usize].normal();
    let a = n.abs();
    let axis = largest_axis(a);
    let face = 2 * axis as u8 + u8::from(n[axis] < 0.0);
    let bin = |c: Real| {
        let t = c / a[axis];
        if t < -BIN_EDGE {
            0
        } else if t > BIN_EDGE {
            2
        } else {
            1
        }
    };
    9 * face + 3 * bin(n[(axis + 1) % 3]) + bin(n[(axis + 2) % 3])
}

/// Orders `patches` (at least two) about their median centroid along the longest side of
/// their centroids' box, ties broken by index, and returns where the upper half starts: the
/// same split whatever the order they came in.
pub(crate) fn split_at_median(patches: &mut [u32], centroids: &[Vec3]) -> usize {
    let (lo, hi) = patches.iter().fold((Vec3::splat(Real::INFINITY), Vec3::splat(-Real::INFINITY)), |b, &i| {
        (b.0.min(centroids[i as usize]), b.1.max(centroids[i as usize]))
    });
    let axis = largest_axis(hi - lo);
    let mid = patches.len() / 2;
    patches.select_nth_unstable_by(mid, |&a, &b| {
        centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis]).then(a.cmp(&b))
    });
    mid
}

/// The index of `v`'s largest component, the first of equal ones.
fn largest_axis(v: Vec3) -> usize {
    if v.x >= v.y && v.x >= v.z {
        0
    } else if v.y >= v.z {
        1
    } else {
        2
    }
}

/// True when every patch of `patches` has the class of the first.
#[cfg(test)]
fn one_class(scene: &Scene, patches: &[u32]) -> bool {
    let first = class(scene, patches[0]);
    patches.iter().all(|&i| class(scene, i) == first)
}

/// A node over `patches` without children yet.
fn bounds(scene: &Scene, patches: &[u32], first: usize) -> Node {
    let all = scene.patches();
    let (mut lo, mut hi) = (Vec3::splat(Real::INFINITY), Vec3::splat(-Real::INFINITY));
    let (mut area, mut normal) = (0.0, Vec3::ZERO);
    for &i in patches {
        let p = &all[i as usize];
        for v in p.vertices() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
        area += p.area();
        normal += p.area() * p.normal();
    }
    let centre = 0.5 * (lo + hi);
    let radius = patches
        .iter()
        .flat_map(|&i| all[i as usize].vertices().iter())
        .map(|v| (*v - centre).length())
        .fold(0.0, Real::max);
    let centroid_radius = patches.iter().map(|&i| (all[i as usize].centroid() - centre).length()).fold(0.0, Real::max);
    let length = normal.length();
    let (axis, spread) = if length > 1e-9 * area {
        let axis = normal / length;
        // The angle as atan2(|a × b|, a · b): exact near 0, where acos is not.
        let spread = patches
            .iter()
            .map(|&i| {
                let n = all[i as usize].normal();
                n.cross(axis).length().atan2(n.dot(axis))
            })
            .fold(0.0, Real::max);
        (axis, spread)
    } else {
        (Vec3::Z, PI)
    };
    let offsets = patches
        .iter()
        .flat_map(|&i| all[i as usize].vertices().iter())
        .fold((Real::INFINITY, -Real::INFINITY), |(a, b), v| (a.min(axis.dot(*v)), b.max(axis.dot(*v))));
    Node {
        centre,
        radius,
        centroid_radius,
        axis,
        spread,
        lo,
        hi,
        offsets,
        first: first as u32,
        count: patches.len() as u32,
        children: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use radiosity_core::{Material, Spectrum};
    use radiosity_geom::SceneBuilder;

    /// The sides of a cylinder of 72 facets about the z axis, facing out: their normals turn
    /// through every horizontal direction.
    fn cylinder() -> Scene {
        let mut b = SceneBuilder::new("cylinder");
        let m = b.material(Material::new("grey", Spectrum::grey(0.5), Spectrum::ZERO)).unwrap();
        let o = b.object("cylinder");
        let at = |k: usize, z: Real| {
            let angle = 2.0 * PI * k as Real / 72.0;
            Vec3::new(angle.cos(), angle.sin(), z)
        };
        for k in 0..72 {
            b.polygon(&[at(k, 0.0), at(k + 1, 0.0), at(k + 1, 1.0), at(k, 1.0)], m, o).unwrap();
        }
        b.build().unwrap()
    }

    #[test]
    fn the_held_tree_finds_every_node_s_children_and_patches_where_the_tree_has_them() {
        let tree = ClusterTree::new(&cylinder());
        let held = tree.clone().held();
        for (k, node) in tree.nodes.iter().enumerate() {
            assert_eq!(held.children(k), node.children, "node {k}");
            assert_eq!(held.patches_of(k as u32), tree.patches_of(k as u32), "node {k}");
            assert_eq!(held.nodes[k].centre, node.centre);
        }
    }

    #[test]
    fn nodes_of_one_class_face_one_way_within_twenty_degrees() {
        // Horizontal normals fall in three classes of each of the four side faces, 40° wide at
        // most (between ±20° and ±45° of the face's axis): every node within a class has a
        // cone of at most about 20°. By the face alone, it would be 45°.
        let scene = cylinder();
        let tree = ClusterTree::new(&scene);
        let mut within = 0;
        for (k, node) in tree.nodes.iter().enumerate() {
            let patches = tree.patches_of(k as u32);
            if one_class(&scene, patches) {
                within += 1;
                assert!(node.spread <= 20.5_f64.to_radians(), "node {k}: cone {}°", node.spread.to_degrees());
            }
        }
        assert_eq!(tree.order.len(), 72);
        assert!(within >= 72, "{within} nodes of one class");
    }
}
