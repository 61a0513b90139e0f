//! Hidden and overlapping geometry: patches no light can reach, patches touching another
//! surface, and coplanar patches lying on top of each other.
//!
//! Real files are full of surfaces in contact: a box standing on a floor, a cabinet pushed
//! against a wall, a face inside a closed solid, two copies of one face. Such patches cannot
//! exchange light with the rest of the scene, and the form factors of surfaces at zero
//! distance are where quadrature and shadow rays are least accurate, so they are found here,
//! before any form factor is computed, and the hidden ones are left out of the system
//! ([`PreparedScene`](crate::PreparedScene) rebuilds the scene without them).
//!
//! ## The test
//!
//! Each patch is probed at the `k × k` points of a centred grid in its `(s, t)` square
//! ([`Patch::point_at`](radiosity_core::Patch::point_at)). At each point `x`, with normal `n`
//! and the scene diagonal `D`:
//!
//! - **contact**: a ray from `x − δ n` along `n` (`δ = 1e-7 D`, so a surface exactly in the
//!   plane of the patch is met at `t = δ`) whose first hit is the front of a patch facing back
//!   (`n_j · n < −0.999`) within a gap of `τ = 1e-4 D`: something lies against the patch there;
//! - **overlap**: a ray from `x + δ n` along `−n` whose first hit is the front of a patch facing
//!   the same way (`n_j · n > 0.999`) within `2δ`: another patch lies in the same plane, on top
//!   of this one;
//! - **view**: `r` cosine-weighted rays from `x` (seeded by the patch index, so the answer does
//!   not depend on threads), each landing on the front of some patch, on a back, or nowhere.
//!   They are cast after the contact and overlap rays of every point, and only until the
//!   verdict below is known: a patch with a point out of contact (or a far front seen) cannot
//!   be pressed, one with a view ray that met no back cannot be enclosed, and once both hold
//!   no further ray could change the answer. A typical visible patch so needs one view ray, not
//!   `k² r`: 19 probe rays instead of 54 at the default `k = 3`, `r = 4`; the rays reported are
//!   those traced.
//!
//! A patch is **hidden** when no light can arrive on its front:
//!
//! - *pressed*: every probe point is in contact, and no view ray meets the front of a patch
//!   farther than the contact gap from the patch's plane: the patch is pressed face to face
//!   against other surfaces (a box on a floor hides the floor under it, and the floor hides the
//!   box's bottom). The second condition tells a pressed pair from a thin wall modelled as two
//!   coincident faces back to back, whose faces both see the room;
//! - *enclosed*: every view ray meets the back of a patch: the patch faces the inside of a
//!   closed solid.
//!
//! Patches in contact at some probe points but not all are **touching**: they stay in the
//! system and are reported, since they explain rows of `F` that miss 1. Patches with some
//! points overlapped are **overlapping**: a patch seeing two coplanar copies of a face counts
//! its form factor twice, so [`coplanar`](crate::coplanar) resolves them, leaving out what
//! others cover and cutting what they partly cover.
//!
//! The test samples: a hidden patch with a gap narrower than one probe grid cell, or a solid
//! with a leak, may be missed (it then stays in the system, which is what happened before). It
//! never removes a patch some view ray saw the front of another patch from, other than through a
//! contact.

use crate::coplanar::ResolvedOverlaps;
use crate::visibility::Visibility;
use radiosity_core::math::cosine_direction;
use radiosity_core::{Collective, Real, Scene, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

/// Probe offset along the normal, relative to the scene diagonal.
const OFFSET: Real = 1e-7;
/// Widest gap that still counts as contact, relative to the scene diagonal.
const CONTACT_GAP: Real = 1e-4;
/// `|n_i · n_j|` above which two patches count as parallel.
const PARALLEL: Real = 0.999;

/// How hard to look for hidden geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HiddenParams {
    /// Probe points along each side of a patch's `(s, t)` square (`k²` points per patch).
    pub grid: usize,
    /// Cosine-weighted view rays per probe point.
    pub rays_per_point: usize,
}

impl Default for HiddenParams {
    fn default() -> Self {
        HiddenParams { grid: 3, rays_per_point: 4 }
    }
}

/// Why a patch is hidden.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HiddenReason {
    /// Pressed face to face against another surface.
    Pressed,
    /// Facing only the backs of patches: the inside of a closed solid.
    Enclosed,
}

/// A patch no light can reach.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HiddenPatch {
    /// The patch, numbered as in the scene probed.
    pub patch: usize,
    /// The object it belongs to.
    pub object: String,
    /// Its area.
    pub area: Real,
    /// Why it is hidden.
    pub reason: HiddenReason,
    /// The object of the patch it is pressed against (at its first probe point), if pressed.
    pub against: Option<String>,
}

/// A patch in contact with, or overlapped by, another over part of its area.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PartialContact {
    /// The patch.
    pub patch: usize,
    /// The object it belongs to.
    pub object: String,
    /// A patch it touches or overlaps (at the first such probe point); `None` when that patch
    /// is hidden and was left out.
    pub other: Option<usize>,
    /// The object of that patch.
    pub other_object: String,
    /// The share of its probe points in contact or overlapped, in `(0, 1]`.
    pub fraction: Real,
}

/// What the probes found, in the patch indices of the scene they probed.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct HiddenGeometry {
    /// Patches no light can reach, in index order.
    pub hidden: Vec<HiddenPatch>,
    /// Patches in contact with another surface over part of their area (not hidden).
    pub touching: Vec<PartialContact>,
    /// Patches with another coplanar patch facing the same way on top of part of them.
    pub overlapping: Vec<PartialContact>,
    /// Probe rays traced.
    pub rays: usize,
    /// True once the hidden patches were left out of the scene the other fields number
    /// ([`HiddenGeometry::renumbered`]).
    pub left_out: bool,
    /// How the overlapping patches were resolved, numbered as in the scene probed; empty until
    /// they are ([`HiddenGeometry::renumbered`]).
    pub resolved: ResolvedOverlaps,
}

/// What the probes of one patch found, and the rays they traced.
struct Probe {
    verdict: Verdict,
    rays: usize,
}

impl Probe {
    /// The findings as six numbers, to be summed between ranks (patch indices and counts are
    /// exact as reals below 2^53): the verdict (1 pressed, 2 enclosed, 3 visible), the patch
    /// pressed against or touched plus one (0 for none) and the touching share, the patch
    /// overlapped plus one and the overlapped share, the rays.
    fn encode(&self) -> [Real; 6] {
        let id = |p: Option<usize>| p.map_or(0.0, |p| (p + 1) as Real);
        let rays = self.rays as Real;
        match self.verdict {
            Verdict::Hidden(HiddenReason::Pressed, against) => [1.0, id(against), 0.0, 0.0, 0.0, rays],
            Verdict::Hidden(HiddenReason::Enclosed, against) => [2.0, id(against), 0.0, 0.0, 0.0, rays],
            Verdict::Visible { touching, overlapping } => [
                3.0,
                id(touching.map(|t| t.0)),
                touching.map_or(0.0, |t| t.1),
                id(overlapping.map(|o| o.0)),
                overlapping.map_or(0.0, |o| o.1),
                rays,
            ],
        }
    }

    /// The findings [`Probe::encode`] wrote.
    fn decode(v: &[Real]) -> Probe {
        let id = |x: Real| (x > 0.0).then(|| x as usize - 1);
        let verdict = match v[0] as u8 {
            1 => Verdict::Hidden(HiddenReason::Pressed, id(v[1])),
            2 => Verdict::Hidden(HiddenReason::Enclosed, id(v[1])),
            _ => Verdict::Visible { touching: id(v[1]).map(|p| (p, v[2])), overlapping: id(v[3]).map(|p| (p, v[4])) },
        };
        Probe { verdict, rays: v[5] as usize }
    }
}

enum Verdict {
    Hidden(HiddenReason, Option<usize>),
    Visible { touching: Option<(usize, Real)>, overlapping: Option<(usize, Real)> },
}

impl HiddenGeometry {
    /// Probes every patch of `scene` against `visibility` (built over the same scene).
    pub fn find(scene: &Scene, visibility: &Visibility, params: HiddenParams) -> HiddenGeometry {
        HiddenGeometry::find_over(scene, visibility, params, None)
    }

    /// As [`HiddenGeometry::find`], the patches dealt to `ranks` when there are several (patch
    /// `i` to rank `i mod K`, each probed on every thread of its rank) and the findings summed
    /// between them: every rank gets the same findings, one process's, whatever `K`.
    pub fn find_over(
        scene: &Scene,
        visibility: &Visibility,
        params: HiddenParams,
        ranks: Option<&dyn Collective>,
    ) -> HiddenGeometry {
        let grid = params.grid.max(1);
        let rays_per_point = params.rays_per_point.max(1);
        // The scene's scale, once: it is a pass over every vertex.
        let diagonal = scene.diagonal();
        let mine = |i: usize| ranks.is_none_or(|c| c.deals(i));
        let probes: Vec<Option<Probe>> = (0..scene.len())
            .into_par_iter()
            .map(|i| mine(i).then(|| probe(scene, visibility, diagonal, i, grid, rays_per_point)))
            .collect();
        let probes: Vec<Probe> = match ranks {
            None => probes.into_iter().flatten().collect(),
            Some(c) => {
                // Each patch's findings from its own rank, zeros from the others: one sum.
                let mut all: Vec<Real> =
                    probes.iter().flat_map(|p| p.as_ref().map_or([0.0; 6], Probe::encode)).collect();
                c.sum(&mut all);
                all.chunks_exact(6).map(Probe::decode).collect()
            }
        };
        let rays = probes.iter().map(|p| p.rays).sum();
        let mut found = HiddenGeometry { rays, ..Default::default() };
        let object = |i: usize| scene.object_of(i).to_string();
        let contact = |patch: usize, (other, fraction): (usize, Real)| PartialContact {
            patch,
            object: object(patch),
            other: Some(other),
            other_object: object(other),
            fraction,
        };
        for (patch, p) in probes.into_iter().enumerate() {
            match p.verdict {
                Verdict::Hidden(reason, against) => found.hidden.push(HiddenPatch {
                    patch,
                    object: object(patch),
                    area: scene.patches()[patch].area(),
                    reason,
                    against: against.map(object),
                }),
                Verdict::Visible { touching, overlapping } => {
                    found.touching.extend(touching.map(|t| contact(patch, t)));
                    found.overlapping.extend(overlapping.map(|o| contact(patch, o)));
                }
            }
        }
        found
    }

    /// True when nothing was found.
    pub fn is_empty(&self) -> bool {
        self.hidden.is_empty() && self.touching.is_empty() && self.overlapping.is_empty() && self.resolved.is_empty()
    }

    /// How many hidden patches are pressed against another surface (the others are enclosed).
    pub fn pressed(&self) -> usize {
        self.hidden.iter().filter(|h| h.reason == HiddenReason::Pressed).count()
    }

    /// The total area of the hidden patches.
    pub fn hidden_area(&self) -> Real {
        self.hidden.iter().fold(0.0, |a, h| a + h.area)
    }

    /// The same findings in the indices of the scene with the hidden patches left out and the
    /// overlaps `resolved`: `kept[i]` is the new index of old patch `i` (`None` for one left out;
    /// the first of its pieces for one cut). Hidden and resolved patches keep their old indices,
    /// which name patches of the scene as loaded.
    pub fn renumbered(&self, kept: &[Option<usize>], resolved: ResolvedOverlaps) -> HiddenGeometry {
        let map = |list: &[PartialContact]| {
            list.iter()
                .filter_map(|c| {
                    Some(PartialContact { patch: kept[c.patch]?, other: c.other.and_then(|o| kept[o]), ..c.clone() })
                })
                .collect()
        };
        HiddenGeometry {
            hidden: self.hidden.clone(),
            touching: map(&self.touching),
            overlapping: map(&self.overlapping),
            rays: self.rays,
            left_out: true,
            resolved,
        }
    }
}

fn probe(
    scene: &Scene,
    visibility: &Visibility,
    diagonal: Real,
    i: usize,
    grid: usize,
    rays_per_point: usize,
) -> Probe {
    let patch = &scene.patches()[i];
    let n = patch.normal();
    let (delta, gap) = (OFFSET * diagonal, CONTACT_GAP * diagonal);
    let points: Vec<Vec3> = (0..grid * grid)
        .map(|k| patch.point_at(((k / grid) as Real + 0.5) / grid as Real, ((k % grid) as Real + 0.5) / grid as Real))
        .collect();
    let (mut contacts, mut overlaps) = (0, 0);
    let (mut first_contact, mut first_overlap) = (None, None);
    for &x in &points {
        if let Some(h) = visibility.first_hit(x - delta * n, n, Some(i)) {
            let other = scene.patches()[h.patch].normal();
            if h.front && h.t <= delta + gap && other.dot(n) < -PARALLEL {
                contacts += 1;
                first_contact.get_or_insert(h.patch);
            }
        }
        if let Some(h) = visibility.first_hit(x + delta * n, -n, Some(i)) {
            let other = scene.patches()[h.patch].normal();
            if h.front && h.t <= 2.0 * delta && other.dot(n) > PARALLEL {
                overlaps += 1;
                first_overlap.get_or_insert(h.patch);
            }
        }
    }
    // View rays, in point order from the patch's own seed, until the verdict is known: a
    // patch is visible as soon as it can be neither pressed (a point out of contact, or a far
    // front seen) nor enclosed (a ray that met no back), and the rays left could change nothing.
    let mut rng = ChaCha8Rng::seed_from_u64(0x6869_6464_656e ^ i as u64);
    let (mut far_fronts, mut backs, mut view_rays) = (0, 0, 0);
    'points: for &x in &points {
        for _ in 0..rays_per_point {
            if (contacts < points.len() || far_fronts > 0) && backs < view_rays {
                break 'points;
            }
            let d = cosine_direction(n, rng.random::<Real>(), rng.random::<Real>());
            view_rays += 1;
            match visibility.first_hit(x, d, Some(i)) {
                // A front farther above the patch's plane than the contact gap.
                Some(h) if h.front && h.t * d.dot(n) > gap => far_fronts += 1,
                Some(h) if h.front => {}
                Some(_) => backs += 1,
                None => {}
            }
        }
    }
    let points = points.len();
    let rays = 2 * points + view_rays;
    let verdict = if contacts == points && far_fronts == 0 {
        Verdict::Hidden(HiddenReason::Pressed, first_contact)
    } else if backs == view_rays {
        Verdict::Hidden(HiddenReason::Enclosed, None)
    } else {
        let share = |k: usize| k as Real / points as Real;
        Verdict::Visible {
            touching: first_contact.map(|j| (j, share(contacts))),
            overlapping: first_overlap.map(|j| (j, share(overlaps))),
        }
    };
    Probe { verdict, rays }
}
