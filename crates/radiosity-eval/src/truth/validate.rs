//! Validation against a continuous truth: each object's path-traced mean radiosity set beside
//! the discrete reference solution at increasing mesh resolution, which separates the error of
//! discretization from the error of solvers (`cargo xtask validate` prints it).
//!
//! The reference solution is exact for the *discrete* system, so it says nothing about how
//! far piecewise-constant radiosity on this mesh is from the radiosity of the surfaces. The
//! path tracer ([`path_trace`](mod@crate::truth::path_trace)) estimates the latter without a mesh.
//! As the mesh is refined, each object's discrete area mean `Σ A_i B_i / Σ A_i` should
//! approach the path-traced one, until the difference is within the tracer's noise (and the
//! form factors' own accuracy).
//!
//! ## The resolutions
//!
//! The scene is solved as given and then refined [`ValidateParams::refinements`] times by the
//! one parameter that changes its mesh and nothing else ([`Refinement::for_scene`]): `res`
//! doubled for `cornell`, `furnace` and `inner-box`; `size` halved for `office`, `labyrinth`
//! and for files given a `size` above 0. `multi-cubes` has no such parameter (`divisions` also
//! moves the edges of its light), nor has a file meshed at `size=0`; they are solved at the
//! given resolution only. Refining stops before a scene of more than
//! [`ValidateParams::max_patches`] patches, and the result says so.
//!
//! The path tracer runs on the finest scene solved (the surfaces are the same at every
//! resolution; only their patches differ). Objects are matched by name across resolutions;
//! objects that share a name are one object.
//!
//! ## The whole surface
//!
//! Means are taken over each object's whole surface as loaded. Preparing a scene leaves out
//! the patches it finds hidden (the floor under a block, a face inside a closed solid), and
//! which patches are entirely hidden depends on the mesh: the coarse Cornell box keeps floor
//! patches that reach under the blocks, the fine one leaves more of the floor out. Light
//! from the rest of the scene reaches no hidden point, so the discrete mean counts the
//! emission there (what the pipeline leaves out is taken to receive nothing). The path tracer
//! traces the scene as loaded, where a ray from such a point meets the back of the surface
//! over it and finds nothing either.

use crate::error::LabError;
use crate::lab::options::LabOptions;
use crate::lab::run::rgb;
use crate::lab::setup::Lab;
use crate::progress::Progress;
use crate::reference::cache::Cache;
use crate::truth::path_trace::{ObjectEstimate, PathTraceError, PathTraceParams, path_trace};
use radiosity_core::{Channels, Real, Scene};
use radiosity_ff::{AnalyticParams, BackendSpec};
use radiosity_geom::{GeomError, LoadedScene, SceneSpec, Visibility};
use serde::Serialize;
use std::time::Instant;
use thiserror::Error;

/// How a validation is run.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct ValidateParams {
    /// How the path tracer samples.
    pub path_trace: PathTraceParams,
    /// How many times the mesh is refined beyond the given scene (default 2).
    pub refinements: usize,
    /// No refined scene has more patches than this (default 6000); the given scene is always
    /// solved.
    pub max_patches: usize,
    /// The form factors of the discrete system (default `analytic`).
    pub backend: BackendSpec,
    /// Where reference solutions are cached; none by default.
    pub cache: Option<Cache>,
}

impl Default for ValidateParams {
    fn default() -> Self {
        ValidateParams {
            path_trace: PathTraceParams::default(),
            refinements: 2,
            max_patches: 6000,
            backend: BackendSpec::new(AnalyticParams::default()),
            cache: None,
        }
    }
}

impl ValidateParams {
    /// Sets [`ValidateParams::path_trace`].
    pub fn with_path_trace(mut self, path_trace: PathTraceParams) -> Self {
        self.path_trace = path_trace;
        self
    }

    /// Sets [`ValidateParams::refinements`].
    pub fn with_refinements(mut self, refinements: usize) -> Self {
        self.refinements = refinements;
        self
    }

    /// Sets [`ValidateParams::max_patches`].
    pub fn with_max_patches(mut self, max_patches: usize) -> Self {
        self.max_patches = max_patches;
        self
    }

    /// Sets [`ValidateParams::backend`].
    pub fn with_backend(mut self, backend: BackendSpec) -> Self {
        self.backend = backend;
        self
    }

    /// Sets [`ValidateParams::cache`].
    pub fn with_cache(mut self, cache: Option<Cache>) -> Self {
        self.cache = cache;
        self
    }
}

/// What stops a validation.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ValidateError {
    /// The scene could not be loaded.
    #[error(transparent)]
    Scene(#[from] GeomError),
    /// The discrete reference could not be set up or solved.
    #[error(transparent)]
    Lab(#[from] LabError),
    /// The path tracer refused its input.
    #[error(transparent)]
    PathTrace(#[from] PathTraceError),
}

/// How a scene's mesh is made finer without changing its surfaces.
#[derive(Clone, Debug, PartialEq)]
pub enum Refinement {
    /// An integer parameter (patches per edge), doubled at each step.
    Double {
        /// The parameter.
        key: &'static str,
        /// Its value in the given scene.
        base: usize,
    },
    /// A real parameter (the largest patch edge), halved at each step.
    Halve {
        /// The parameter.
        key: &'static str,
        /// Its value in the given scene.
        base: Real,
    },
}

/// The built-in scenes whose mesh one parameter refines, and how.
const REFINED_BY: &[(&str, &str, bool)] = &[
    ("cornell", "res", true),
    ("furnace", "res", true),
    ("inner-box", "res", true),
    ("office", "size", false),
    ("labyrinth", "size", false),
];

impl Refinement {
    /// How `scene` is refined, or why it cannot be.
    pub fn for_scene(scene: &SceneSpec) -> Result<Refinement, String> {
        let Some(builtin) = scene.builtin() else {
            let size = scene.params().get("size").and_then(|v| v.trim().parse::<Real>().ok());
            return match size {
                Some(base) if base > 0.0 && base.is_finite() => Ok(Refinement::Halve { key: "size", base }),
                _ => Err(format!(
                    "{} is meshed one patch per face (size=0), which cannot be refined; give it size=… to refine it",
                    scene.head()
                )),
            };
        };
        let name = builtin.name;
        let Some(&(_, key, double)) = REFINED_BY.iter().find(|(n, _, _)| *n == name) else {
            return Err(match name {
                "multi-cubes" => "multi-cubes has no parameter that refines its mesh alone (divisions also moves the \
                                  edges of its light), so it is solved at the given resolution only"
                    .to_string(),
                _ => format!("{name} has no parameter that refines its mesh alone, so it is solved as given only"),
            });
        };
        let default = builtin.params.iter().find(|d| d.key == key).map(|d| d.default).unwrap_or_default();
        let value = scene.params().get(key).unwrap_or(default);
        let bad = || format!("{key}={value} of {name} is not a valid {key}, so the scene cannot be refined");
        Ok(if double {
            Refinement::Double { key, base: value.parse().map_err(|_| bad())? }
        } else {
            Refinement::Halve { key, base: value.parse().map_err(|_| bad())? }
        })
    }

    /// The parameter varied.
    pub fn key(&self) -> &'static str {
        match self {
            Refinement::Double { key, .. } | Refinement::Halve { key, .. } => key,
        }
    }

    /// How it varies: `res doubled`, `size halved`.
    pub fn describe(&self) -> String {
        match self {
            Refinement::Double { key, .. } => format!("{key} doubled"),
            Refinement::Halve { key, .. } => format!("{key} halved"),
        }
    }

    /// `scene` refined `step` times (`step = 0` is `scene` itself), or `None` when the value
    /// overflows.
    pub fn refined(&self, scene: &SceneSpec, step: u32) -> Option<SceneSpec> {
        if step == 0 {
            return Some(scene.clone());
        }
        let value = match self {
            Refinement::Double { base, .. } => base.checked_mul(2usize.checked_pow(step)?)?.to_string(),
            Refinement::Halve { base, .. } => (base / Real::from(2u32).powi(step as i32)).to_string(),
        };
        scene.with_param(self.key(), &value).ok()
    }
}

/// One resolution solved.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Resolution {
    /// The scene argument.
    pub scene: String,
    /// Its patches.
    pub patches: usize,
    /// How the reference was solved.
    pub reference: String,
    /// The area-weighted relative L1 difference of the objects' discrete means from the
    /// path-traced ones: `Σ_o Σ_c A_o |D_oc − T_oc| / Σ_o Σ_c A_o T_oc`.
    pub difference: Real,
    /// The same sum over the standard errors, `Σ_o Σ_c A_o σ_oc / Σ_o Σ_c A_o T_oc`: how much
    /// of [`Resolution::difference`] the tracer's noise can explain.
    pub noise: Real,
    /// Seconds to set the scene up and obtain its reference.
    pub seconds: Real,
}

/// An object's discrete area mean at one resolution.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DiscreteMean {
    /// The scene argument of the resolution.
    pub scene: String,
    /// The object's patches in the system at this resolution.
    pub patches: usize,
    /// Its patches left out of the system as hidden (pressed against another surface or
    /// inside a closed solid), whose radiosity is their emission since no light reaches them.
    pub left_out: usize,
    /// The area-mean radiosity of the reference solution, per RGB channel.
    pub mean: [Real; 3],
    /// `(mean − path traced) / stderr` per channel (0 where both agree exactly; not finite,
    /// and null in JSON, where the standard error is 0 and they differ).
    pub sigmas: [Real; 3],
    /// `100 (mean − path traced) / path traced` per channel (0 where both are 0).
    pub percent: [Real; 3],
}

/// One object: its path-traced mean and its discrete means.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectValidation {
    /// The object's name.
    pub name: String,
    /// Its area.
    pub area: Real,
    /// The path-traced area-mean radiosity per RGB channel.
    pub path_traced: [Real; 3],
    /// Its standard error per channel.
    pub stderr: [Real; 3],
    /// Paths drawn.
    pub samples: u64,
    /// The discrete means, coarsest first.
    pub discrete: Vec<DiscreteMean>,
}

/// How the path tracer ran.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TraceSummary {
    /// The scene argument traced (the finest resolution).
    pub scene: String,
    /// Paths per object.
    pub samples_per_object: u64,
    /// The seed.
    pub seed: u64,
    /// Rays traced.
    pub rays: u64,
    /// Paths cut at the bounce cap (a bias; zero in any sensible run).
    pub truncated: u64,
    /// Wall-clock seconds.
    pub seconds: Real,
}

/// A validation: every object's path-traced mean beside its discrete means.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Validation {
    /// The scene argument as given.
    pub scene: String,
    /// Whether every material is grey (the three channels equal).
    pub grey: bool,
    /// The parameter varied and how (`res doubled`), if any.
    pub varied: Option<String>,
    /// Why the scene was refined less than asked, if it was.
    pub note: Option<String>,
    /// The resolutions solved, coarsest first.
    pub resolutions: Vec<Resolution>,
    /// How the path tracer ran.
    pub path_trace: TraceSummary,
    /// One entry per object (by name), in the traced scene's order.
    pub objects: Vec<ObjectValidation>,
}

/// Sets every object's path-traced mean radiosity beside the discrete reference solution of
/// `scene` at its given resolution and at up to [`ValidateParams::refinements`] finer ones.
pub fn validate(
    scene: &SceneSpec,
    params: &ValidateParams,
    progress: &dyn Progress,
) -> Result<Validation, ValidateError> {
    // Before any geometry: a bad sample count should not wait for the references.
    params.path_trace.check()?;
    let base = scene.load()?;
    for w in &base.warnings {
        progress.warn(w);
    }
    let grey = base.scene.channels() == Channels::Grey;
    let mut refined: Vec<(String, LoadedScene)> = Vec::new();
    let (varied, note) = match Refinement::for_scene(scene) {
        Err(why) => (None, (params.refinements > 0).then_some(why)),
        Ok(refinement) => {
            let mut note = None;
            for step in 1..=params.refinements as u32 {
                let Some(arg) = refinement.refined(scene, step) else {
                    note = Some(format!("{} cannot be refined further", refinement.key()));
                    break;
                };
                let loaded = match arg.load() {
                    Ok(loaded) => loaded,
                    Err(e) => {
                        note = Some(format!("stopped refining before {arg}: {e}"));
                        break;
                    }
                };
                if loaded.scene.len() > params.max_patches {
                    note = Some(format!(
                        "stopped refining before {arg}: it has {} patches, more than the {} allowed",
                        loaded.scene.len(),
                        params.max_patches
                    ));
                    break;
                }
                refined.push((arg.to_string(), loaded));
            }
            (Some(refinement.describe()), note)
        }
    };

    let (resolution, means, mut finest) = solve_discrete(scene.to_string(), base, params, progress)?;
    let mut discrete = vec![(resolution, means)];
    for (arg, loaded) in refined {
        let (resolution, means, prepared) = solve_discrete(arg, loaded, params, progress)?;
        discrete.push((resolution, means));
        finest = prepared;
    }
    // The whole surface as loaded, hidden patches included: the same at every resolution.
    let visibility = Visibility::new(&finest);
    let traced = path_trace(&finest, &visibility, &params.path_trace, progress)?;
    let estimates = estimates_by_name(&traced.objects);

    let objects: Vec<ObjectValidation> = estimates
        .into_iter()
        .map(|e| {
            let discrete = discrete
                .iter()
                .filter_map(|(resolution, means)| {
                    let m = means.iter().find(|m| m.name == e.name)?;
                    Some(DiscreteMean {
                        scene: resolution.scene.clone(),
                        patches: m.patches,
                        left_out: m.left_out,
                        mean: m.mean,
                        sigmas: std::array::from_fn(|c| sigmas(m.mean[c] - e.mean[c], e.stderr[c])),
                        percent: std::array::from_fn(|c| percent(m.mean[c] - e.mean[c], e.mean[c])),
                    })
                })
                .collect();
            ObjectValidation {
                name: e.name,
                area: e.area,
                path_traced: e.mean,
                stderr: e.stderr,
                samples: e.samples,
                discrete,
            }
        })
        .collect();

    let resolutions = discrete
        .into_iter()
        .map(|(mut resolution, _)| {
            let (mut difference, mut noise, mut scale) = (0.0, 0.0, 0.0);
            for o in &objects {
                if let Some(d) = o.discrete.iter().find(|d| d.scene == resolution.scene) {
                    for c in 0..3 {
                        difference += o.area * (d.mean[c] - o.path_traced[c]).abs();
                        noise += o.area * o.stderr[c];
                        scale += o.area * o.path_traced[c].abs();
                    }
                }
            }
            if scale > 0.0 {
                resolution.difference = difference / scale;
                resolution.noise = noise / scale;
            }
            resolution
        })
        .collect();

    Ok(Validation {
        scene: scene.to_string(),
        grey,
        varied,
        note,
        resolutions,
        path_trace: TraceSummary {
            scene: finest.name().to_string(),
            samples_per_object: params.path_trace.samples_per_object,
            seed: params.path_trace.seed,
            rays: traced.rays,
            truncated: traced.truncated,
            seconds: traced.seconds,
        },
        objects,
    })
}

/// Prepares `loaded` (the scene argument `arg`) and solves its discrete reference: the
/// resolution, its objects' means over their whole surface as loaded, and that surface.
fn solve_discrete(
    arg: String,
    loaded: LoadedScene,
    params: &ValidateParams,
    progress: &dyn Progress,
) -> Result<(Resolution, Vec<NamedMean>, Scene), ValidateError> {
    let start = Instant::now();
    let surface = loaded.scene.clone();
    let prepared = loaded.prepare();
    let options = LabOptions::default().with_residuals(false).with_cache(params.cache.clone());
    let (means, reference) = {
        let lab = Lab::new(&prepared, &params.backend, options, progress)?;
        let means = object_means(&surface, prepared.scene(), &rgb(&lab.reference_state()?));
        (means, lab.reference().map(|r| r.method().to_string()).unwrap_or_default())
    };
    let resolution = Resolution {
        scene: arg,
        patches: prepared.scene().len(),
        reference,
        difference: 0.0,
        noise: 0.0,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok((resolution, means, surface))
}

/// `difference / stderr`, 0 where both are 0.
fn sigmas(difference: Real, stderr: Real) -> Real {
    if difference == 0.0 { 0.0 } else { difference / stderr }
}

/// `100 difference / value`, 0 where the difference is 0.
fn percent(difference: Real, value: Real) -> Real {
    if difference == 0.0 { 0.0 } else { 100.0 * difference / value }
}

/// An object's discrete area mean over its whole surface.
#[derive(Clone, Debug, PartialEq)]
struct NamedMean {
    name: String,
    patches: usize,
    left_out: usize,
    mean: [Real; 3],
}

/// Per object name, in order of first appearance: patches, area, `Σ A E` and `Σ A B`.
#[derive(Clone, Debug, Default)]
struct ObjectSums {
    name: String,
    patches: usize,
    area: Real,
    emitted: [Real; 3],
    radiosity: [Real; 3],
}

fn object_sums(scene: &Scene, rgb: Option<&[[Real; 3]]>) -> Vec<ObjectSums> {
    let mut sums: Vec<ObjectSums> = Vec::new();
    let mut slot_of_object: Vec<Option<usize>> = vec![None; scene.objects().len()];
    for (i, patch) in scene.patches().iter().enumerate() {
        let object = patch.object.0 as usize;
        let slot = *slot_of_object[object].get_or_insert_with(|| {
            let name = &scene.objects()[object];
            sums.iter().position(|s| &s.name == name).unwrap_or_else(|| {
                sums.push(ObjectSums { name: name.clone(), ..ObjectSums::default() });
                sums.len() - 1
            })
        });
        let entry = &mut sums[slot];
        let a = patch.area();
        let e = scene.emission(i).0;
        entry.patches += 1;
        entry.area += a;
        for c in 0..3 {
            entry.emitted[c] += a * e[c];
            entry.radiosity[c] += a * rgb.map_or(0.0, |b| b[i][c]);
        }
    }
    sums
}

/// The area mean of the discrete radiosity `rgb` of `solved` over each object's whole
/// `surface`: the patches `solved` left out as hidden receive no light, so their radiosity is
/// their emission, `Σ_surface A E − Σ_solved A E` in all.
fn object_means(surface: &Scene, solved: &Scene, rgb: &[[Real; 3]]) -> Vec<NamedMean> {
    let solved = object_sums(solved, Some(rgb));
    object_sums(surface, None)
        .into_iter()
        .map(|whole| {
            let kept = solved.iter().find(|s| s.name == whole.name).cloned().unwrap_or_default();
            NamedMean {
                mean: std::array::from_fn(|c| (kept.radiosity[c] + whole.emitted[c] - kept.emitted[c]) / whole.area),
                name: whole.name,
                patches: kept.patches,
                left_out: whole.patches - kept.patches.min(whole.patches),
            }
        })
        .collect()
}

/// The estimates of objects that share a name merged into one, area-weighted (the standard
/// errors combined as those of independent means), in order of first appearance.
fn estimates_by_name(estimates: &[ObjectEstimate]) -> Vec<ObjectEstimate> {
    let mut merged: Vec<ObjectEstimate> = Vec::new();
    for e in estimates {
        let Some(m) = merged.iter_mut().find(|m| m.name == e.name) else {
            merged.push(e.clone());
            continue;
        };
        let area = m.area + e.area;
        let (wa, wb) = (m.area / area, e.area / area);
        for c in 0..3 {
            m.mean[c] = wa * m.mean[c] + wb * e.mean[c];
            m.stderr[c] = ((wa * m.stderr[c]).powi(2) + (wb * e.stderr[c]).powi(2)).sqrt();
        }
        m.area = area;
        m.patches += e.patches;
        m.samples += e.samples;
    }
    merged
}
