//! A scene ready for the later stages: the loaded scene, its BVH and its analysis, with the
//! time each took, and the report of it that `scenes` prints and every experiment quotes.

use crate::analysis::{Closure, SceneAnalysis};
use crate::coplanar::{self, Replacements};
use crate::error::GeomError;
use crate::hidden::{HiddenGeometry, HiddenParams, HiddenReason};
use crate::visibility::Visibility;
use crate::{LoadedScene, load_scene};
use radiosity_core::{Channels, Collective, PatchShape, Scene};
use serde::Serialize;
use std::sync::Mutex;
use std::time::Instant;

/// Where the time of preparing a scene went, in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SetupSeconds {
    /// Loading (or generating) the scene.
    pub load: f64,
    /// Building its BVH (twice when hidden patches were left out).
    pub bvh: f64,
    /// The scene analysis, the search for hidden geometry included.
    pub analysis: f64,
}

/// What a prepared scene holds on the heap, in bytes ([`PreparedScene::memory`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SceneMemory {
    /// The scene: patches, materials, object names.
    pub scene: usize,
    /// The BVH: exact triangles, their patches, obvhs's tree.
    pub bvh: usize,
}

/// A scene with its BVH and analysis: what form-factor backends and experiments start from.
#[derive(Debug)]
pub struct PreparedScene {
    /// The scene and its load warnings.
    pub loaded: LoadedScene,
    /// Its BVH, until it is released ([`PreparedScene::release_visibility`]).
    visibility: Mutex<Option<Visibility>>,
    /// What the pipeline may leave out, and why.
    pub analysis: SceneAnalysis,
    /// How long each stage took.
    pub seconds: SetupSeconds,
}

impl LoadedScene {
    /// Builds the BVH and analyses the scene.
    pub fn prepare(self) -> PreparedScene {
        PreparedScene::from_loaded(self, 0.0, &|_| {}, None)
    }
}

impl PreparedScene {
    /// Loads the scene argument `arg` ([`load_scene`]), builds its BVH and analyses it.
    pub fn load(arg: &str) -> Result<PreparedScene, GeomError> {
        PreparedScene::load_reporting(arg, &|_| {})
    }

    /// As [`PreparedScene::load`], calling `stage` with the name of each stage as it begins
    /// (`loading`, `building the BVH`, `probing for hidden geometry`, `analysing the scene`):
    /// each takes seconds at `10⁵` patches, and a command line shows them.
    pub fn load_reporting(arg: &str, stage: &dyn Fn(&str)) -> Result<PreparedScene, GeomError> {
        PreparedScene::load_over(arg, stage, None)
    }

    /// As [`PreparedScene::load_reporting`], on one of several `ranks` when there are: every
    /// rank loads the scene and builds its BVH, and the probes of the analysis (hidden
    /// geometry, closure) are dealt between them, patch `i` to rank `i mod K`, their findings
    /// summed, so that every rank holds one process's prepared scene. Every rank calls it with
    /// the same argument.
    pub fn load_over(
        arg: &str,
        stage: &dyn Fn(&str),
        ranks: Option<&dyn Collective>,
    ) -> Result<PreparedScene, GeomError> {
        let start = Instant::now();
        stage("loading");
        let loaded = load_scene(arg)?;
        Ok(PreparedScene::from_loaded(loaded, start.elapsed().as_secs_f64(), stage, ranks))
    }

    fn from_loaded(
        mut loaded: LoadedScene,
        load: f64,
        stage: &dyn Fn(&str),
        ranks: Option<&dyn Collective>,
    ) -> PreparedScene {
        let start = Instant::now();
        stage("building the BVH");
        let mut visibility = Visibility::new(&loaded.scene);
        let mut bvh = start.elapsed().as_secs_f64();
        let start = Instant::now();
        stage("probing for hidden geometry");
        let mut hidden = HiddenGeometry::find_over(&loaded.scene, &visibility, HiddenParams::default(), ranks);
        let mut is_hidden = vec![false; loaded.scene.len()];
        for h in &hidden.hidden {
            is_hidden[h.patch] = true;
        }
        let flagged: Vec<usize> = hidden.overlapping.iter().flat_map(|c| [Some(c.patch), c.other]).flatten().collect();
        let (resolved, replacements) = coplanar::resolve(&loaded.scene, &flagged, &is_hidden);
        // Every overlap the probes flagged is now resolved, or was found to have no area.
        hidden.overlapping.clear();
        let mut analysis_seconds = start.elapsed().as_secs_f64();
        if !hidden.hidden.is_empty() || !replacements.is_empty() {
            match rebuilt(&loaded.scene, &is_hidden, &replacements) {
                Some((scene, kept)) => {
                    loaded.scene = scene;
                    hidden = hidden.renumbered(&kept, resolved);
                    let start = Instant::now();
                    visibility = Visibility::new(&loaded.scene);
                    bvh += start.elapsed().as_secs_f64();
                }
                None => {
                    loaded.warnings.push(format!(
                        "every one of the {} patches looks hidden (pressed against another or inside a closed \
                         solid), so none was left out",
                        hidden.hidden.len()
                    ));
                    hidden.hidden.clear();
                }
            }
        }
        let start = Instant::now();
        stage("analysing the scene");
        let analysis = SceneAnalysis::with_hidden_over(&loaded.scene, &visibility, hidden, ranks);
        analysis_seconds += start.elapsed().as_secs_f64();
        PreparedScene {
            loaded,
            visibility: Mutex::new(Some(visibility)),
            analysis,
            seconds: SetupSeconds { load, bvh, analysis: analysis_seconds },
        }
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.loaded.scene
    }

    /// The scene's BVH: a handle sharing it, which keeps it alive as long as it is held.
    /// `wanted` says what needs the rays, for the error when the BVH was released.
    pub fn visibility_for(&self, wanted: &str) -> Result<Visibility, GeomError> {
        self.held().clone().ok_or_else(|| GeomError::VisibilityReleased { wanted: wanted.to_string() })
    }

    /// [`PreparedScene::visibility_for`], for code that runs before any release (the tests,
    /// examples, and what builds a backend).
    pub fn visibility(&self) -> Result<Visibility, GeomError> {
        self.visibility_for("tracing rays")
    }

    /// Frees the scene's BVH when nothing else holds it: a run whose operator is built and
    /// that traces no more rays needs 320 bytes a patch less (3.4 GB at ten million patches).
    /// Returns the bytes freed: 0 when it was released before, or when a backend or another
    /// holder shares the tree, which is then kept. Once it is freed, every later
    /// [`PreparedScene::visibility_for`] is an error.
    pub fn release_visibility(&self) -> usize {
        let mut held = self.held();
        match held.as_ref() {
            Some(visibility) if !visibility.is_shared() => {
                let bytes = visibility.heap_bytes();
                *held = None;
                bytes
            }
            _ => 0,
        }
    }

    /// Whether the BVH is still held ([`PreparedScene::release_visibility`]).
    pub fn has_visibility(&self) -> bool {
        self.held().is_some()
    }

    fn held(&self) -> std::sync::MutexGuard<'_, Option<Visibility>> {
        // A holder that panicked left the handle as it was.
        self.visibility.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// What the scene and its BVH hold on the heap (the analysis's lists are small beside
    /// them: a few values a hidden, touching or overlapping patch, and the emitters' indices).
    /// A released BVH counts 0.
    pub fn memory(&self) -> SceneMemory {
        SceneMemory {
            scene: self.loaded.scene.heap_bytes(),
            bvh: self.held().as_ref().map_or(0, Visibility::heap_bytes),
        }
    }

    /// The report of this scene.
    pub fn report(&self) -> SceneReport {
        let scene = &self.loaded.scene;
        let a = &self.analysis;
        let quads = scene.patches().iter().filter(|p| p.shape() == PatchShape::Quad).count();
        let (lo, hi) = scene.bounds();
        let closure = match a.closure.value {
            Closure::Closed { .. } => "closed".to_string(),
            Closure::Open { escaped, sampled } => {
                format!("open ({:.2}% of rays lost)", 100.0 * escaped as f64 / sampled as f64)
            }
        };
        SceneReport {
            scene: scene.name().to_string(),
            patches: scene.len(),
            quads,
            triangles: scene.len() - quads,
            total_area: scene.total_area(),
            bounds: [lo.to_array(), hi.to_array()],
            mean_reflectivity: a.mean_reflectivity,
            max_reflectivity: a.max_reflectivity,
            emitters: a.emitters.value.len(),
            channels: a.channels.value.count(),
            occlusion: DecisionReport {
                value: if a.occlusion.value { "shadow rays traced" } else { "no shadow rays" }.to_string(),
                reason: a.occlusion.reason.clone(),
            },
            colour: DecisionReport {
                value: match a.channels.value {
                    Channels::Grey => "grey, one channel",
                    Channels::Rgb => "rgb, three channels",
                }
                .to_string(),
                reason: a.channels.reason.clone(),
            },
            emission: DecisionReport {
                value: format!("{} emitters", a.emitters.value.len()),
                reason: a.emitters.reason.clone(),
            },
            closure: DecisionReport { value: closure, reason: a.closure.reason.clone() },
            geometry: GeometryReport::new(&a.hidden.value, a.hidden.reason.clone()),
            left_out: a.left_out(),
            warnings: self.loaded.warnings.clone(),
            seconds: self.seconds,
            memory: self.memory(),
        }
    }
}

/// `scene` without the hidden patches and with the `replacements` of overlapping ones, and the
/// new index of every old patch (`None` for one left out, the first piece of one cut); `None`
/// when nothing is left.
fn rebuilt(scene: &Scene, hidden: &[bool], replacements: &Replacements) -> Option<(Scene, Vec<Option<usize>>)> {
    let mut kept = vec![None; scene.len()];
    let mut patches = Vec::with_capacity(scene.len());
    for (i, k) in kept.iter_mut().enumerate() {
        if hidden[i] {
            continue;
        }
        match replacements.get(&i) {
            None => {
                *k = Some(patches.len());
                patches.push(scene.patches()[i].clone());
            }
            Some(Some(pieces)) => {
                *k = Some(patches.len());
                patches.extend(pieces.iter().cloned());
            }
            Some(None) => {}
        }
    }
    let reduced = Scene::new(scene.name(), patches, scene.materials().to_vec(), scene.objects().to_vec()).ok()?;
    Some((reduced, kept))
}

/// A decision as shown to users.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DecisionReport {
    /// The decision in a word or two.
    pub value: String,
    /// Why.
    pub reason: String,
}

/// Everything `scenes` says about one scene; serialised as is for `--json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneReport {
    /// The scene's name.
    pub scene: String,
    /// Patches.
    pub patches: usize,
    /// Of which quads.
    pub quads: usize,
    /// Of which triangles.
    pub triangles: usize,
    /// The total patch area.
    pub total_area: f64,
    /// The bounding box, lower and upper corners.
    pub bounds: [[f64; 3]; 2],
    /// The area-weighted mean reflectivity.
    pub mean_reflectivity: f64,
    /// The largest reflectivity.
    pub max_reflectivity: f64,
    /// Patches that emit.
    pub emitters: usize,
    /// Channels solved.
    pub channels: usize,
    /// Whether shadow rays are traced.
    pub occlusion: DecisionReport,
    /// Grey or RGB.
    pub colour: DecisionReport,
    /// The emitters.
    pub emission: DecisionReport,
    /// Closed or open.
    pub closure: DecisionReport,
    /// Hidden, touching and overlapping patches.
    pub geometry: GeometryReport,
    /// What the pipeline leaves out, one item each.
    pub left_out: Vec<String>,
    /// The loader's warnings.
    pub warnings: Vec<String>,
    /// Where the preparation time went.
    pub seconds: SetupSeconds,
    /// What the scene and its BVH hold, in bytes.
    pub memory: SceneMemory,
}

/// Hidden, touching and overlapping geometry as shown to users: counts, and a few examples
/// each with the objects involved.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GeometryReport {
    /// Patches left out as hidden.
    pub hidden: usize,
    /// Of which pressed face to face against another surface.
    pub pressed: usize,
    /// Of which facing the inside of a closed solid.
    pub enclosed: usize,
    /// Their total area.
    pub hidden_area: f64,
    /// Patches touching another surface over part of their area (kept).
    pub touching: usize,
    /// Patches overlapped by a coplanar patch facing the same way and not resolved (none once
    /// the scene is prepared).
    pub overlapping: usize,
    /// Patches left out because coplanar patches facing the same way cover them.
    pub covered: usize,
    /// Patches cut to the part no coplanar patch facing the same way covers.
    pub cut: usize,
    /// The area those overlaps counted twice, now counted once.
    pub area_removed: f64,
    /// Up to three examples of each kind, one sentence each.
    pub examples: Vec<String>,
    /// The decision in one sentence.
    pub reason: String,
}

/// Examples shown per kind of finding.
const EXAMPLES: usize = 3;

impl GeometryReport {
    fn new(found: &HiddenGeometry, reason: String) -> GeometryReport {
        let pressed = found.pressed();
        let mut examples = Vec::new();
        for h in found.hidden.iter().filter(|h| h.reason == HiddenReason::Pressed).take(EXAMPLES) {
            let against = h.against.as_deref().unwrap_or("?");
            examples.push(format!("hidden: patch {} of '{}' is pressed against '{against}'", h.patch, h.object));
        }
        for h in found.hidden.iter().filter(|h| h.reason == HiddenReason::Enclosed).take(EXAMPLES) {
            examples.push(format!("hidden: patch {} of '{}' faces the inside of a closed solid", h.patch, h.object));
        }
        for c in found.touching.iter().take(EXAMPLES) {
            examples.push(format!(
                "touching: patch {} of '{}' touches '{}' over {:.0}% of its probe points",
                c.patch,
                c.object,
                c.other_object,
                100.0 * c.fraction
            ));
        }
        for c in found.overlapping.iter().take(EXAMPLES) {
            examples.push(format!(
                "overlap: patch {} of '{}' lies on top of a coplanar patch of '{}' over {:.0}% of its probe points",
                c.patch,
                c.object,
                c.other_object,
                100.0 * c.fraction
            ));
        }
        for c in found.resolved.covered.iter().take(EXAMPLES) {
            examples.push(format!(
                "covered: patch {} of '{}' lies under a coplanar patch of '{}' and is left out",
                c.patch, c.object, c.by
            ));
        }
        for c in found.resolved.cut.iter().take(EXAMPLES) {
            examples.push(format!(
                "cut: patch {} of '{}' keeps the {:.0}% of its area no patch of '{}' covers, in {} piece{}",
                c.patch,
                c.object,
                100.0 * c.kept,
                c.by,
                c.pieces,
                if c.pieces == 1 { "" } else { "s" }
            ));
        }
        GeometryReport {
            covered: found.resolved.covered.len(),
            cut: found.resolved.cut.len(),
            area_removed: found.resolved.area_removed,
            hidden: found.hidden.len(),
            pressed,
            enclosed: found.hidden.len() - pressed,
            hidden_area: found.hidden_area(),
            touching: found.touching.len(),
            overlapping: found.overlapping.len(),
            examples,
            reason,
        }
    }
}

impl SceneReport {
    /// What was left out, as one phrase (`nothing` when every stage is needed).
    pub fn left_out_phrase(&self) -> String {
        if self.left_out.is_empty() { "nothing".into() } else { self.left_out.join("; ") }
    }
}
