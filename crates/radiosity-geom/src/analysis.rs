//! Scene analysis: what the pipeline may leave out for a given scene, and why.
//!
//! Five decisions, each with the reason a user can read (`cargo xtask scenes --explain`):
//!
//! - **Hidden geometry.** Patches no light can reach (pressed face to face against another
//!   surface, or facing the inside of a closed solid) are left out of the system; patches
//!   touching or overlapping others over part of their area are reported
//!   ([`hidden`](crate::hidden) has the test). The other decisions are made on the scene
//!   without the hidden patches.
//! - **Occlusion.** If every patch lies in the closed front half-space of every other patch's
//!   plane (the scene is the inside of a convex shell, like an empty room), no patch can block
//!   the view between two others: a segment between two points in front of a plane can meet
//!   that plane only if it lies in it, where the cosines, and so the form factors, vanish.
//!   Shadow rays are then left out. The test is exact up to a tolerance of `1e-9` times the
//!   scene diagonal, and it is sufficient, not necessary: a non-convex scene without actual
//!   occluders is still traced.
//! - **Channels.** If every material in use is grey, the scene is solved as one channel.
//! - **Emitters.** Patches with positive emission in some channel; shooting methods shoot them
//!   first.
//! - **Closure.** Whether every ray leaving a patch meets the front of another patch, so that
//!   each row of the form-factor matrix should sum to 1 (a ray that meets a back is lost, since
//!   the kernel is zero behind a patch). Measured, not assumed: `RAYS_PER_PATCH` cosine-weighted
//!   rays per patch from seeded random points ([`ChaCha8Rng`], seed 0), traced against the BVH
//!   on every thread (each patch's rays are read from the one stream at its own position, so
//!   they are the same whatever the thread count). One escaping ray makes the scene open, with the escaping fraction reported; closure
//!   checks (rows summing to 1) apply only to closed scenes.

use crate::hidden::{HiddenGeometry, HiddenParams};
use crate::visibility::Visibility;
use radiosity_core::math::cosine_direction;
use radiosity_core::{Channels, Collective, Real, Scene};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::collections::HashSet;

/// Rays traced per patch by the closure test.
pub const RAYS_PER_PATCH: usize = 4;
/// Out-of-plane tolerance of the convexity test, relative to the scene diagonal.
const PLANE_TOLERANCE: Real = 1e-9;

/// A decision with the reason for it.
#[derive(Clone, Debug, PartialEq)]
pub struct Decision<T> {
    /// What was decided.
    pub value: T,
    /// Why, as one sentence.
    pub reason: String,
}

/// Whether rays leaving the scene's patches all come back to a patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Closure {
    /// Every sampled ray met the front of a patch: rows of F should sum to 1.
    Closed {
        /// Rays traced.
        sampled: usize,
    },
    /// Some rays were lost: rows of F sum to less than 1.
    Open {
        /// Rays that hit nothing or the back of a patch.
        escaped: usize,
        /// Rays traced.
        sampled: usize,
    },
}

impl Closure {
    /// True for [`Closure::Closed`].
    pub fn is_closed(&self) -> bool {
        matches!(self, Closure::Closed { .. })
    }
}

/// The decisions of the analysis, with the scene's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneAnalysis {
    /// Number of patches.
    pub patches: usize,
    /// Total surface area.
    pub total_area: Real,
    /// Area-weighted mean reflectivity over the three channels.
    pub mean_reflectivity: Real,
    /// Largest reflectivity in any channel.
    pub max_reflectivity: Real,
    /// True when patches can occlude each other, so visibility must be tested.
    pub occlusion: Decision<bool>,
    /// The channels to solve.
    pub channels: Decision<Channels>,
    /// Indices of emitting patches.
    pub emitters: Decision<Vec<usize>>,
    /// Whether the scene is closed.
    pub closure: Decision<Closure>,
    /// The hidden patches left out (numbered as in the scene as loaded), and the touching and
    /// overlapping ones kept (numbered as in `scene`).
    pub hidden: Decision<HiddenGeometry>,
}

impl SceneAnalysis {
    /// Analyses `scene`, using `visibility` (built over the same scene) for the closure test and
    /// the search for hidden geometry. Hidden patches are reported, not removed:
    /// [`PreparedScene`](crate::PreparedScene) leaves them out.
    pub fn new(scene: &Scene, visibility: &Visibility) -> SceneAnalysis {
        let hidden = HiddenGeometry::find(scene, visibility, HiddenParams::default());
        SceneAnalysis::with_hidden(scene, visibility, hidden)
    }

    /// Analyses `scene` as [`SceneAnalysis::new`] does, with the hidden geometry already found:
    /// by [`HiddenGeometry::find`] on this scene, or on the scene as loaded and then
    /// [renumbered](HiddenGeometry::renumbered) for `scene`, which leaves the hidden patches out.
    pub fn with_hidden(scene: &Scene, visibility: &Visibility, hidden: HiddenGeometry) -> SceneAnalysis {
        SceneAnalysis::with_hidden_over(scene, visibility, hidden, None)
    }

    /// As [`SceneAnalysis::with_hidden`], the closure probe's patches dealt to `ranks` when
    /// there are several (patch `i` to rank `i mod K`) and its counts summed between them:
    /// every rank gets one process's analysis.
    pub fn with_hidden_over(
        scene: &Scene,
        visibility: &Visibility,
        hidden: HiddenGeometry,
        ranks: Option<&dyn Collective>,
    ) -> SceneAnalysis {
        SceneAnalysis {
            hidden: hidden_decision(scene, hidden),
            patches: scene.len(),
            total_area: scene.total_area(),
            mean_reflectivity: scene.mean_reflectivity(),
            max_reflectivity: scene.max_reflectivity(),
            occlusion: occlusion(scene),
            channels: channels(scene),
            emitters: emitters(scene),
            closure: closure(scene, visibility, ranks),
        }
    }

    /// What the pipeline leaves out for this scene, one sentence each.
    pub fn left_out(&self) -> Vec<String> {
        let mut out = Vec::new();
        let hidden = &self.hidden.value.hidden;
        if self.hidden.value.left_out && !hidden.is_empty() {
            out.push(format!(
                "{} hidden patches (pressed against other surfaces or inside closed solids)",
                hidden.len()
            ));
        }
        let resolved = &self.hidden.value.resolved;
        if !resolved.is_empty() {
            out.push(format!(
                "the second copy of overlapping coplanar area (patches: {} covered, {} cut to what none covers)",
                resolved.covered.len(),
                resolved.cut.len()
            ));
        }
        if !self.occlusion.value {
            out.push("shadow rays (nothing can occlude)".to_string());
        }
        if self.channels.value == Channels::Grey {
            out.push("two of three colour channels (grey scene)".to_string());
        }
        if !self.closure.value.is_closed() {
            out.push("closure checks (open scene: rows of F sum to less than 1)".to_string());
        }
        out
    }
}

fn hidden_decision(scene: &Scene, found: HiddenGeometry) -> Decision<HiddenGeometry> {
    let (hidden_area, pressed) = (found.hidden_area(), found.pressed());
    let mut reason = if found.hidden.is_empty() {
        format!("no patch is hidden ({} probe rays)", found.rays)
    } else {
        let (what, total) = match found.left_out {
            true => ("are hidden and left out", hidden_area + scene.total_area()),
            false => ("are hidden", scene.total_area()),
        };
        format!(
            "{} patches, {:.3}% of the area, {what}: {pressed} pressed face to face against another surface, {} \
             facing the inside of a closed solid ({} probe rays)",
            found.hidden.len(),
            100.0 * hidden_area / total,
            found.hidden.len() - pressed,
            found.rays
        )
    };
    if !found.touching.is_empty() {
        reason += &format!("; {} patches touch another surface over part of their area", found.touching.len());
    }
    if !found.overlapping.is_empty() {
        reason += &format!("; {} patches overlap a coplanar patch", found.overlapping.len());
    }
    let r = &found.resolved;
    if !r.is_empty() {
        reason += &format!(
            "; overlapping coplanar patches facing the same way: {} left out as covered by others, {} cut to the part \
             none covers, so the {:.4e} of area they counted twice is counted once",
            r.covered.len(),
            r.cut.len(),
            r.area_removed
        );
    }
    Decision { value: found, reason }
}

fn describe(scene: &Scene, patch: usize) -> String {
    format!("patch {patch} of '{}'", scene.object_of(patch))
}

fn occlusion(scene: &Scene) -> Decision<bool> {
    let tolerance = PLANE_TOLERANCE * scene.diagonal();
    let quantum = scene.diagonal() * 1e-7;
    // Distinct planes, each with a patch that spans it; coplanar patches share one test.
    let mut seen = HashSet::new();
    let mut planes = Vec::new();
    for (i, p) in scene.patches().iter().enumerate() {
        let (n, d) = (p.normal(), p.normal().dot(p.centroid()));
        let key = ((n * 1e7).round().as_i64vec3(), (d / quantum).round() as i64);
        if seen.insert(key) {
            planes.push((i, n, d));
        }
    }
    for &(i, n, d) in &planes {
        for (k, other) in scene.patches().iter().enumerate() {
            if other.vertices().iter().any(|v| n.dot(*v) - d < -tolerance) {
                return Decision {
                    value: true,
                    reason: format!(
                        "{} reaches behind the plane of {}, so patches may hide one another and shadow rays are traced",
                        describe(scene, k),
                        describe(scene, i)
                    ),
                };
            }
        }
    }
    Decision {
        value: false,
        reason: format!(
            "every patch lies in front of the planes of all others ({} distinct planes checked), so no patch can hide another",
            planes.len()
        ),
    }
}

fn channels(scene: &Scene) -> Decision<Channels> {
    match scene.channels() {
        Channels::Grey => Decision {
            value: Channels::Grey,
            reason: "every material's reflectivity and emission are grey, so one channel gives the answer".to_string(),
        },
        Channels::Rgb => {
            let coloured = scene
                .materials()
                .iter()
                .find(|m| !(m.reflectivity.is_grey() && m.emission.is_grey()))
                .map_or("?", |m| m.name.as_str());
            Decision {
                value: Channels::Rgb,
                reason: format!("material '{coloured}' is coloured, so red, green and blue are solved"),
            }
        }
    }
}

fn emitters(scene: &Scene) -> Decision<Vec<usize>> {
    let list = scene.emitters();
    let reason = if list.is_empty() {
        "no patch emits, so the solution is zero".to_string()
    } else {
        let area: Real = list.iter().map(|&i| scene.patches()[i].area()).sum();
        format!(
            "{} patches emit, {:.3}% of the area; shooting methods shoot them first",
            list.len(),
            100.0 * area / scene.total_area()
        )
    };
    Decision { value: list, reason }
}

fn closure(scene: &Scene, visibility: &Visibility, ranks: Option<&dyn Collective>) -> Decision<Closure> {
    // One seeded stream, as if drawn patch after patch: patch `i` starts where patch `i − 1`
    // ends (four draws of two words a ray), so the patches run on every thread and the rays
    // are those of one serial pass, whatever the thread count.
    let stream = ChaCha8Rng::seed_from_u64(0);
    let words = (RAYS_PER_PATCH * 4 * 2) as u128;
    let lost = |(i, patch): (usize, &radiosity_core::Patch)| {
        let mut rng = stream.clone();
        rng.set_word_pos(words * i as u128);
        (0..RAYS_PER_PATCH)
            .filter(|_| {
                let origin = patch.point_at(rng.random::<Real>(), rng.random::<Real>());
                let direction = cosine_direction(patch.normal(), rng.random::<Real>(), rng.random::<Real>());
                // A ray that meets the back of a patch is lost too: the kernel is zero behind
                // a patch, so the row of F misses what such rays carry.
                visibility.first_hit(origin, direction, Some(i)).is_none_or(|h| !h.front)
            })
            .count()
    };
    let mine = |i: usize| ranks.is_none_or(|c| c.deals(i));
    let mut per_patch: Vec<usize> =
        scene.patches().par_iter().enumerate().map(|(i, p)| if mine(i) { lost((i, p)) } else { 0 }).collect();
    if let Some(c) = ranks {
        // Each patch's count from its own rank, zeros from the others.
        let mut all: Vec<Real> = per_patch.iter().map(|&k| k as Real).collect();
        c.sum(&mut all);
        per_patch = all.into_iter().map(|k| k as usize).collect();
    }
    let escaped: usize = per_patch.iter().sum();
    let first_escape = per_patch.iter().position(|&k| k > 0);
    let sampled = scene.len() * RAYS_PER_PATCH;
    match first_escape {
        None => Decision {
            value: Closure::Closed { sampled },
            reason: format!("each of {sampled} sampled rays meets the front of a patch, so rows of F should sum to 1"),
        },
        Some(i) => Decision {
            value: Closure::Open { escaped, sampled },
            reason: format!(
                "{escaped} of {sampled} sampled rays ({:.2}%) leave the scene or meet the back of a patch, the first \
                 from {}",
                100.0 * escaped as Real / sampled as Real,
                describe(scene, i)
            ),
        },
    }
}
