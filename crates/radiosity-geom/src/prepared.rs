//! A scene ready for the later stages: the loaded scene, its BVH and its analysis, with the
//! time each took, and the report of it that `scenes` prints and every experiment quotes.

use crate::analysis::{Closure, SceneAnalysis};
use crate::error::GeomError;
use crate::visibility::Visibility;
use crate::{LoadedScene, load_scene};
use radiosity_core::{Channels, PatchShape};
use serde::Serialize;
use std::time::Instant;

/// Where the time of preparing a scene went, in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SetupSeconds {
    /// Loading (or generating) the scene.
    pub load: f64,
    /// Building its BVH.
    pub bvh: f64,
    /// The scene analysis.
    pub analysis: f64,
}

/// A scene with its BVH and analysis: what form-factor backends and experiments start from.
#[derive(Debug)]
pub struct PreparedScene {
    /// The scene and its load warnings.
    pub loaded: LoadedScene,
    /// Its BVH.
    pub visibility: Visibility,
    /// What the pipeline may leave out, and why.
    pub analysis: SceneAnalysis,
    /// How long each stage took.
    pub seconds: SetupSeconds,
}

impl LoadedScene {
    /// Builds the BVH and analyses the scene.
    pub fn prepare(self) -> PreparedScene {
        PreparedScene::from_loaded(self, 0.0)
    }
}

impl PreparedScene {
    /// Loads the scene argument `arg` ([`load_scene`]), builds its BVH and analyses it.
    pub fn load(arg: &str) -> Result<PreparedScene, GeomError> {
        let start = Instant::now();
        let loaded = load_scene(arg)?;
        Ok(PreparedScene::from_loaded(loaded, start.elapsed().as_secs_f64()))
    }

    fn from_loaded(loaded: LoadedScene, load: f64) -> PreparedScene {
        let start = Instant::now();
        let visibility = Visibility::new(&loaded.scene);
        let bvh = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let analysis = SceneAnalysis::new(&loaded.scene, &visibility);
        let analysis_seconds = start.elapsed().as_secs_f64();
        PreparedScene { loaded, visibility, analysis, seconds: SetupSeconds { load, bvh, analysis: analysis_seconds } }
    }

    /// The scene.
    pub fn scene(&self) -> &radiosity_core::Scene {
        &self.loaded.scene
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
                format!("open ({:.2}% of rays escape)", 100.0 * escaped as f64 / sampled as f64)
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
            left_out: a.left_out(),
            warnings: self.loaded.warnings.clone(),
            seconds: self.seconds,
        }
    }
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
    /// What the pipeline leaves out, one item each.
    pub left_out: Vec<String>,
    /// The loader's warnings.
    pub warnings: Vec<String>,
    /// Where the preparation time went.
    pub seconds: SetupSeconds,
}

impl SceneReport {
    /// What was left out, as one phrase (`nothing` when every stage is needed).
    pub fn left_out_phrase(&self) -> String {
        if self.left_out.is_empty() { "nothing".into() } else { self.left_out.join("; ") }
    }
}
