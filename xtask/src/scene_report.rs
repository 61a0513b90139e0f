//! Loading a scene argument and describing it: the figures and decisions shown by `scenes`
//! and reused by every command that starts from a scene.

use anyhow::Result;
use radiosity_core::{Channels, PatchShape};
use radiosity_ff::FormFactorInput;
use radiosity_geom::{Closure, LoadedScene, SceneAnalysis, Visibility, load_scene};
use serde::Serialize;
use std::time::Instant;

/// A decision as shown to users.
#[derive(Debug, Serialize)]
pub struct DecisionReport {
    /// The decision in a word or two.
    pub value: String,
    /// Why.
    pub reason: String,
}

/// Everything `scenes` says about one scene; serialised as is for `--json`.
#[derive(Debug, Serialize)]
pub struct SceneReport {
    pub scene: String,
    pub patches: usize,
    pub quads: usize,
    pub triangles: usize,
    pub total_area: f64,
    pub bounds: [[f64; 3]; 2],
    pub mean_reflectivity: f64,
    pub max_reflectivity: f64,
    pub emitters: usize,
    pub channels: usize,
    pub occlusion: DecisionReport,
    pub colour: DecisionReport,
    pub emission: DecisionReport,
    pub closure: DecisionReport,
    pub left_out: Vec<String>,
    pub warnings: Vec<String>,
    pub seconds: SetupSeconds,
}

/// Where the time of preparing the scene went.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SetupSeconds {
    pub load: f64,
    pub bvh: f64,
    pub analysis: f64,
}

/// A scene with its BVH and analysis, ready for later stages.
pub struct PreparedScene {
    pub loaded: LoadedScene,
    pub visibility: Visibility,
    pub analysis: SceneAnalysis,
    pub seconds: SetupSeconds,
}

/// Loads `arg`, builds its BVH and analyses it.
pub fn prepare(arg: &str) -> Result<PreparedScene> {
    let start = Instant::now();
    let loaded = load_scene(arg)?;
    let load = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let visibility = Visibility::new(&loaded.scene);
    let bvh = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let analysis = SceneAnalysis::new(&loaded.scene, &visibility);
    let analysis_seconds = start.elapsed().as_secs_f64();
    Ok(PreparedScene { loaded, visibility, analysis, seconds: SetupSeconds { load, bvh, analysis: analysis_seconds } })
}

impl PreparedScene {
    /// What form-factor backends are built from: the scene, its BVH and its analysis.
    pub fn ff_input(&self) -> FormFactorInput<'_> {
        FormFactorInput { scene: &self.loaded.scene, visibility: &self.visibility, analysis: &self.analysis }
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

/// Prints the load warnings of a scene to stderr.
pub fn print_warnings(report: &SceneReport) {
    for w in &report.warnings {
        // File loaders name the file in their warnings already.
        eprintln!("warning: {w}");
    }
}
