//! The hierarchical operator on disk: its links written whole and read back, so that a later
//! run over the same scene and parameters skips the build (the cache of `radiosity-eval`
//! keeps it like a stored matrix).
//!
//! Only the links are written: the cluster tree is rebuilt from the scene, which is
//! deterministic and takes milliseconds, and the file records the tree's node count and a
//! checksum of its patch order, so that links are never read against another tree. The
//! layout: a postcard header (a magic string, the format version, the caller's key, the
//! sizes, the build's figures, the body's length and checksum), then the body, the far, near
//! and pair links as raw little-endian arrays, each link once (far links as their two nodes,
//! `u32`, and their tallies, two `u16`, in increasing order of their ends; near links and far
//! pairs in their lower end's lists: offsets as `u64`, higher ends as `u32` and values as
//! `f32`), and the closure weights (`f64`), read back bit for bit; the lists by either end are
//! worked out again from them.

use super::HierarchicalColumns;
use super::adjacency::{Adjacency, FarLists, Lists, Transfer};
use super::figures::HierarchyFigures;
use super::tree::ClusterTree;
use crate::error::FfError;
use crate::framing::{frame, unframe};
use radiosity_core::{Real, Scene};
use serde::{Deserialize, Serialize};
use xxhash_rust::xxh3::xxh3_64;

const MAGIC: &str = "radiosity hierarchical operator";
/// 6: each link once, in its lower end's list (5: in both ends' lists; 4: near and pair
/// values as `f64`).
const FORMAT_VERSION: u32 = 7;

/// What the header holds besides the magic string and the version.
#[derive(Serialize, Deserialize)]
struct Header {
    key: String,
    patches: u64,
    nodes: u64,
    /// The checksum of the tree's patch order.
    order: u64,
    far_entries: u64,
    near_entries: u64,
    pair_entries: u64,
    figures: HierarchyFigures,
    body_len: [u8; 8],
    body_checksum: [u8; 8],
}

fn order_checksum(order: &[u32]) -> u64 {
    let bytes: Vec<u8> = order.iter().flat_map(|p| p.to_le_bytes()).collect();
    xxh3_64(&bytes)
}

impl HierarchicalColumns {
    /// The operator's links as bytes, under `key` (what it was built from: the scene and the
    /// parameters), for [`HierarchicalColumns::from_bytes`].
    pub fn to_bytes(&self, key: &str) -> Vec<u8> {
        let header = Header {
            key: key.to_string(),
            patches: self.areas.len() as u64,
            nodes: self.tree.nodes.len() as u64,
            order: order_checksum(&self.tree.order),
            far_entries: self.far.len() as u64,
            near_entries: self.near.len() as u64,
            pair_entries: self.pairs.len() as u64,
            figures: self.figures,
            body_len: [0; 8],
            body_checksum: [0; 8],
        };
        let size = self.far.bytes() + self.near.bytes() + self.pairs.bytes() + self.weights.len() * 8 + 256;
        frame(MAGIC, FORMAT_VERSION, &header, size, |mut out| {
            let offsets =
                |out: &mut Vec<u8>, start: &[usize]| start.iter().for_each(|&s| out.extend((s as u64).to_le_bytes()));
            for (a, b, [c, n]) in self.far.links() {
                out.extend(
                    a.to_le_bytes().into_iter().chain(b.to_le_bytes()).chain(c.to_le_bytes()).chain(n.to_le_bytes()),
                );
            }
            for list in [&self.near, &self.pairs] {
                offsets(&mut out, &list.start);
                list.ends().for_each(|(_, o)| out.extend(o.to_le_bytes()));
                list.value.iter().for_each(|v| out.extend(v.to_le_bytes()));
            }
            self.weights.iter().for_each(|w| out.extend(w.to_le_bytes()));
            out
        })
    }

    /// The operator whose links [`HierarchicalColumns::to_bytes`] wrote under `key`, over
    /// `scene` (whose tree is rebuilt and checked against the file's); its figures are the
    /// build's, marked [`HierarchyFigures::loaded`].
    pub fn from_bytes(bytes: &[u8], key: &str, scene: &Scene) -> Result<HierarchicalColumns, FfError> {
        let refuse = |why: String| FfError::StoredOperator(why);
        let (header, body) =
            unframe(bytes, (MAGIC, FORMAT_VERSION), ("a stored operator", "its links"), |h: &Header| {
                (h.body_len, h.body_checksum)
            })
            .map_err(refuse)?;
        if header.key != key {
            return Err(refuse(format!("it was built for '{}', not for '{key}'", header.key)));
        }
        let tree = ClusterTree::new(scene).held();
        if header.patches != scene.len() as u64
            || header.nodes != tree.nodes.len() as u64
            || header.order != order_checksum(&tree.order)
        {
            return Err(refuse(format!(
                "it was built over {} patches and a tree of {} nodes, not this scene's {} and {}",
                header.patches,
                header.nodes,
                scene.len(),
                tree.nodes.len()
            )));
        }
        let mut reader = Body { bytes: body };
        let far = reader.far(tree.nodes.len(), header.far_entries);
        let real = |b: &[u8]| Real::from_le_bytes(b.try_into().expect("slices of 8 bytes"));
        let near = reader.adjacency(scene.len(), header.near_entries);
        let pairs = reader.adjacency(scene.len(), header.pair_entries);
        let weights: Option<Vec<Real>> = reader.take(scene.len() * 8).map(|b| b.chunks_exact(8).map(real).collect());
        let (Some(far), Some(near), Some(pairs), Some(weights)) = (far, near, pairs, weights) else {
            return Err(refuse("its link lists are inconsistent with their sizes".into()));
        };
        if !reader.bytes.is_empty() {
            return Err(refuse("bytes follow its links".into()));
        }
        let figures = HierarchyFigures { loaded: true, ..header.figures };
        Ok(HierarchicalColumns::from_parts(scene, tree, Lists { far, near, pairs, weights }, figures))
    }
}

/// The body of a file, read front to back.
struct Body<'b> {
    bytes: &'b [u8],
}

impl Body<'_> {
    /// `len` bytes, or `None` when fewer are left.
    fn take(&mut self, len: usize) -> Option<&[u8]> {
        (self.bytes.len() >= len).then(|| {
            let (head, tail) = self.bytes.split_at(len);
            self.bytes = tail;
            head
        })
    }

    /// The far lists of `entries` links `(a, b, [clear, count])` over `keys` nodes, or `None`
    /// unless each link's ends are increasing and below `keys` and the links are in
    /// increasing order of their ends.
    fn far(&mut self, keys: usize, entries: u64) -> Option<FarLists> {
        let entries = usize::try_from(entries).ok()?;
        let u32_at = |b: &[u8]| u32::from_le_bytes(b.try_into().expect("slices of 4 bytes"));
        let u16_at = |b: &[u8]| u16::from_le_bytes(b.try_into().expect("slices of 2 bytes"));
        let links: Vec<(u32, u32, [u16; 2])> = self
            .take(entries.checked_mul(12)?)?
            .chunks_exact(12)
            .map(|c| (u32_at(&c[..4]), u32_at(&c[4..8]), [u16_at(&c[8..10]), u16_at(&c[10..])]))
            .collect();
        let ordered = links.iter().all(|&(a, b, _)| a < b && (b as usize) < keys)
            && links.windows(2).all(|w| (w[0].0, w[0].1) < (w[1].0, w[1].1));
        ordered.then(|| FarLists::new(keys, links.into(), |&l| l))
    }

    /// Lists of `keys` keys and `entries` links, each value a [`Transfer`], or `None` unless they
    /// are lists [`Adjacency::from_higher`] takes ([`Adjacency::is_ordered`]).
    fn adjacency(&mut self, keys: usize, entries: u64) -> Option<Adjacency> {
        let entries = usize::try_from(entries).ok()?;
        let start: Vec<usize> = self
            .take((keys + 1).checked_mul(8)?)?
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().expect("chunks of 8 bytes")) as usize)
            .collect();
        let other: Vec<u32> = self
            .take(entries.checked_mul(4)?)?
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().expect("chunks of 4 bytes")))
            .collect();
        if !Adjacency::is_ordered(keys, entries, &start, &other) {
            return None;
        }
        let width = size_of::<Transfer>();
        let transfer = |b: &[u8]| Transfer::from_le_bytes(b.try_into().expect("slices of 4 bytes"));
        let value = self.take(entries.checked_mul(width)?)?.chunks_exact(width).map(transfer).collect();
        Some(Adjacency::from_higher(start, other, value))
    }
}
