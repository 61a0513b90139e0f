//! A Monte Carlo path tracer estimating each object's area-mean radiosity: a truth of the
//! continuous problem that the discrete solution is measured against
//! ([`validate`](mod@crate::truth::validate)).
//!
//! ## What is estimated
//!
//! For a diffuse surface the radiosity (W/m², the quantity `B` of the discrete system
//! `B = E + diag(ρ) F B`) satisfies
//!
//! ```text
//! B(x) = E(x) + ρ(x) ∫_{H(x)} B(y(x, ω)) cos θ / π dω,
//! ```
//!
//! the diffuse form of the rendering equation (Kajiya 1986), where `y(x, ω)` is the first
//! surface point seen from `x` in direction `ω`. Surfaces are one-sided, as in the discrete
//! model, whose form-factor kernel is zero behind a patch: a ray that escapes the scene or
//! arrives on the back of a patch sees `B = 0`. This module estimates, per object `o` of the
//! scene, the area mean `B̄_o = (1/A_o) ∫_o B(x) dA`, in every RGB channel (a grey scene has
//! equal channels). The mesh plays no part beyond carrying the surface: the estimate is the
//! same, up to noise, at every resolution, so the discrete means converge to it as the mesh is
//! refined.
//!
//! ## The estimator
//!
//! One sample of `B̄_o` is one path (Kajiya 1986; Dutré, Bala & Bekaert 2006), a random walk
//! `x₀, x₁, …` with weights `W₀ = 1` and `W_{k+1} = W_k ρ(x_k) / q_k` per channel (`q_k`, the
//! survival probability, below):
//!
//! 1. the start point `x₀` is uniform by area on the object: a fan triangle of one of its
//!    patches drawn by area from a cumulative table, then a uniform point of that triangle
//!    (`(1 − √u) a + √u (1 − v) b + √u v c`, Osada et al. 2002). The emitted part of `B̄_o`,
//!    the area mean of `E` over the object, is known exactly and added as it is, so a sample
//!    is that mean plus the light `x₀` reflects, and an object that is partly an emitter
//!    draws no variance from where its paths start;
//! 2. from each vertex `x_k` a cosine-weighted direction about the patch normal
//!    ([`radiosity_core::math::cosine_direction`], Malley's method) finds `x_{k+1}`; its
//!    density `p_cos = cos θ_x / π` cancels the kernel, so the next vertex adds
//!    `W_{k+1} E(x_{k+1})`;
//! 3. with next-event estimation ([`PathTraceParams::next_event`], the default), each vertex
//!    also draws a point `y` on the emitters, with density per unit area proportional to its
//!    largest emission channel (`p_A`), and traces a shadow ray to it. The two ways of
//!    reaching an emitter are combined by the balance heuristic of multiple importance
//!    sampling (Veach & Guibas 1995): with `p_light = p_A(y) r² / cos θ_y`, the emitter
//!    sample adds `W_k ρ(x_k) E(y) p_cos / (p_light + p_cos)` when `y` faces `x_k` and is
//!    visible, and an emitter hit by the cosine ray adds `W_{k+1} E(x_{k+1}) p_cos / (p_cos +
//!    p_light)`. The weights sum to 1 for every direction, so the estimator stays unbiased,
//!    and small bright emitters (the Cornell box's light, 0.7% of its area) no longer make
//!    rare, huge samples; close to an emitter, where `p_light` tends to 0 and a light sample
//!    alone would have unbounded variance, the cosine rays take over.
//!
//! Paths end by Russian roulette (Arvo & Kirk 1990), which keeps the estimator unbiased: the
//! first [`PathTraceParams::roulette_after`] bounces always continue (`q_k = 1`); afterwards a
//! path continues from `x_k` with probability `q_k = max_c ρ_c(x_k)` (below 1, since every
//! reflectivity is), and the weight is divided by it. In a grey scene `ρ / q = 1` exactly, so
//! the weight stays constant and the path is the analogue random walk; this is what keeps a
//! furnace with `ρ = 0.999` unbiased, at an expected 1000 bounces a path. A hard cap of
//! [`PathTraceParams::max_bounces`] bounces guards against pathological inputs; a path cut
//! there is counted ([`PathTraced::truncated`]) because the cut is a (downward) bias. With the
//! default cap of 10⁶ bounces a path of `ρ = 0.999` is cut with probability `e^{-1000}`.
//!
//! The standard error of each mean is `√(s² / N)` with `s²` the sample variance of the `N`
//! paths, per channel.
//!
//! ## Determinism
//!
//! Samples are drawn in batches of [`PathTraceParams::batch_size`] paths. Each (object,
//! batch) draws from its own ChaCha8 stream, keyed by the seed with stream number
//! `object · 2³² + batch`; batches run on rayon's threads and are merged in a fixed order
//! (Chan, Golub & LeVeque 1979, the pairwise update of means and sums of squared deviations).
//! The numbers depend on the seed and the parameters only, never on the thread count.
//!
//! ## References
//!
//! - J. T. Kajiya, "The rendering equation", *Computer Graphics (SIGGRAPH '86)* 20(4),
//!   143–150, 1986.
//! - J. Arvo and D. Kirk, "Particle transport and image synthesis", *Computer Graphics
//!   (SIGGRAPH '90)* 24(4), 63–66, 1990 (Russian roulette).
//! - E. Veach and L. J. Guibas, "Optimally combining sampling techniques for Monte Carlo
//!   rendering", *Proceedings of SIGGRAPH '95*, 419–428, 1995 (the balance heuristic).
//! - P. Dutré, K. Bala and P. Bekaert, *Advanced Global Illumination*, 2nd ed., A K Peters,
//!   2006 (the radiosity equation as an integral equation; path tracing; random walks).
//! - R. Osada, T. Funkhouser, B. Chazelle and D. Dobkin, "Shape distributions", *ACM
//!   Transactions on Graphics* 21(4), 807–832, 2002 (uniform points in a triangle).
//! - T. F. Chan, G. H. Golub and R. J. LeVeque, "Updating formulae and a pairwise algorithm
//!   for computing sample variances", Stanford report STAN-CS-79-773, 1979.

use crate::progress::Progress;
use radiosity_core::math::cosine_direction;
use radiosity_core::{Real, Scene, Spectrum, Vec3};
use radiosity_geom::Visibility;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;
use thiserror::Error;

/// Paths per object by default: the Cornell box traces them in a few seconds on two cores,
/// with standard errors of a few tenths of a percent of each object's mean.
pub const DEFAULT_SAMPLES_PER_OBJECT: u64 = 200_000;

/// How the path tracer samples.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct PathTraceParams {
    /// Paths per object (at least 2, so that the standard error can be estimated).
    pub samples_per_object: u64,
    /// Seed of the random streams.
    pub seed: u64,
    /// Paths per batch: the unit of parallel work, of progress and of random streams. The
    /// numbers depend on it (each batch has its own stream), not on the thread count.
    pub batch_size: u64,
    /// Next-event estimation: at every vertex, also draw a point on the emitters and trace a
    /// shadow ray to it, combining both ways of finding emitters by the balance heuristic
    /// (default). Without it, emitters are found only by the cosine-distributed rays.
    pub next_event: bool,
    /// Bounces that always continue before Russian roulette starts.
    pub roulette_after: u32,
    /// The most bounces a path may take; paths cut here are counted as truncated.
    pub max_bounces: u32,
}

impl Default for PathTraceParams {
    fn default() -> Self {
        PathTraceParams {
            samples_per_object: DEFAULT_SAMPLES_PER_OBJECT,
            seed: 0,
            batch_size: 1024,
            next_event: true,
            roulette_after: 3,
            max_bounces: 1_000_000,
        }
    }
}

impl PathTraceParams {
    /// Sets [`PathTraceParams::samples_per_object`].
    pub fn with_samples(mut self, samples_per_object: u64) -> Self {
        self.samples_per_object = samples_per_object;
        self
    }

    /// Sets [`PathTraceParams::seed`].
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Sets [`PathTraceParams::batch_size`].
    pub fn with_batch_size(mut self, batch_size: u64) -> Self {
        self.batch_size = batch_size;
        self
    }

    /// Sets [`PathTraceParams::next_event`].
    pub fn with_next_event(mut self, next_event: bool) -> Self {
        self.next_event = next_event;
        self
    }

    /// Checks the parameters: what [`path_trace`] refuses before any work.
    pub fn check(&self) -> Result<(), PathTraceError> {
        let invalid =
            |name, value: u64, reason| Err(PathTraceError::InvalidParameter { name, value: value.to_string(), reason });
        if self.samples_per_object < 2 {
            return invalid(
                "samples_per_object",
                self.samples_per_object,
                "at least 2 paths per object are needed to estimate a standard error",
            );
        }
        if self.batch_size == 0 {
            return invalid("batch_size", 0, "a batch holds at least one path");
        }
        if self.samples_per_object.div_ceil(self.batch_size) > u64::from(u32::MAX) {
            return invalid("batch_size", self.batch_size, "at most 2^32 batches per object are possible");
        }
        Ok(())
    }
}

/// What stops a path-traced estimate.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum PathTraceError {
    /// Parameters that make no sense.
    #[error("invalid path-tracing parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// Its value, as given.
        value: String,
        /// What is required of it.
        reason: &'static str,
    },
    /// Nothing emits, so every radiosity is zero and there is nothing to estimate.
    #[error("scene '{0}' emits no light (no patch has an emission above 0), so its radiosity is zero everywhere")]
    NoEmitters(String),
}

/// The path-traced area-mean radiosity of one object.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectEstimate {
    /// The object's name.
    pub name: String,
    /// Its area (the sum of its patches' areas).
    pub area: Real,
    /// How many patches carry it in the traced scene.
    pub patches: usize,
    /// The estimated area-mean radiosity per RGB channel.
    pub mean: [Real; 3],
    /// The standard error of [`ObjectEstimate::mean`] per channel.
    pub stderr: [Real; 3],
    /// The paths drawn.
    pub samples: u64,
}

/// The path-traced estimates of every object of a scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PathTraced {
    /// The scene traced.
    pub scene: String,
    /// One estimate per object that has patches, in the scene's object order.
    pub objects: Vec<ObjectEstimate>,
    /// Rays traced, in all.
    pub rays: u64,
    /// Paths cut at [`PathTraceParams::max_bounces`] (a bias; zero in any sensible run).
    pub truncated: u64,
    /// Wall-clock seconds.
    pub seconds: Real,
}

/// Estimates the area-mean radiosity of every object of `scene` by path tracing over
/// `visibility` (its BVH), reporting progress over batches.
///
/// For a prepared scene, pass `prepared.scene()` and `&prepared.visibility()?`; a scene of one's
/// own needs a [`Visibility::new`] of it.
pub fn path_trace(
    scene: &Scene,
    visibility: &Visibility,
    params: &PathTraceParams,
    progress: &dyn Progress,
) -> Result<PathTraced, PathTraceError> {
    params.check()?;
    if !(0..scene.len()).any(|i| scene.emission(i).is_positive()) {
        return Err(PathTraceError::NoEmitters(scene.name().to_string()));
    }
    let start = Instant::now();
    let tracer = Tracer::new(scene, visibility, params);
    let objects = ObjectSurface::all(scene);
    let per_object = params.samples_per_object.div_ceil(params.batch_size);
    let jobs: Vec<(usize, u64)> = (0..objects.len()).flat_map(|k| (0..per_object).map(move |b| (k, b))).collect();

    progress.begin("path tracing", jobs.len() as u64, "batches");
    let done = AtomicU64::new(0);
    let batches: Vec<Batch> = jobs
        .par_iter()
        .map(|&(k, b)| {
            let surface = &objects[k];
            let first = b * params.batch_size;
            let count = params.batch_size.min(params.samples_per_object - first);
            let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
            rng.set_stream(((surface.object as u64) << 32) | b);
            let batch = tracer.batch(surface, count, &mut rng);
            let position = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress.advance(position, &surface.name);
            batch
        })
        .collect();
    progress.end();

    let mut rays = 0;
    let mut truncated = 0;
    let estimates = objects
        .iter()
        .zip(batches.chunks(per_object as usize))
        .map(|(surface, chunk)| {
            let mut total = Moments::default();
            for batch in chunk {
                total.merge(&batch.moments);
                rays += batch.rays;
                truncated += batch.truncated;
            }
            ObjectEstimate {
                name: surface.name.clone(),
                area: surface.area,
                patches: surface.patches,
                mean: total.mean,
                stderr: total.stderr(),
                samples: total.count,
            }
        })
        .collect();
    Ok(PathTraced {
        scene: scene.name().to_string(),
        objects: estimates,
        rays,
        truncated,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Fan triangles of some patches with a cumulative table of weights, to draw a point with
/// probability proportional to weight × area.
struct TriangleTable {
    /// `(patch, triangle)` for each fan triangle.
    triangles: Vec<(usize, [Vec3; 3])>,
    /// The weighted area of triangles `0..=k`.
    cumulative: Vec<Real>,
}

impl TriangleTable {
    /// The fan triangles of `patches`, each weighted by `weight(patch)` times its area;
    /// patches of weight 0 are left out.
    fn new(scene: &Scene, patches: &[usize], weight: impl Fn(usize) -> Real) -> TriangleTable {
        let mut table = TriangleTable { triangles: Vec::new(), cumulative: Vec::new() };
        let mut total = 0.0;
        for &i in patches {
            let w = weight(i);
            if w <= 0.0 {
                continue;
            }
            for t in scene.patches()[i].triangles() {
                total += w * 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
                table.triangles.push((i, t));
                table.cumulative.push(total);
            }
        }
        table
    }

    /// The sum of weight × area.
    fn total(&self) -> Real {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// A point drawn with density proportional to weight (uniform by area within a patch), and
    /// its patch: a triangle from the cumulative table, then a uniform point of it. The table
    /// must not be empty.
    fn sample(&self, rng: &mut ChaCha8Rng) -> (usize, Vec3) {
        let target = rng.random::<Real>() * self.total();
        let k = self.cumulative.partition_point(|&c| c <= target).min(self.triangles.len() - 1);
        let (patch, [a, b, c]) = self.triangles[k];
        let r = rng.random::<Real>().sqrt();
        let v = rng.random::<Real>();
        (patch, a * (1.0 - r) + b * (r * (1.0 - v)) + c * (r * v))
    }
}

/// One object's surface: its patches' fan triangles, drawn by area.
struct ObjectSurface {
    object: usize,
    name: String,
    area: Real,
    patches: usize,
    table: TriangleTable,
    /// The area mean of the emission over the object.
    emission: Spectrum,
}

impl ObjectSurface {
    /// The surfaces of every object that has patches, in the scene's object order.
    fn all(scene: &Scene) -> Vec<ObjectSurface> {
        let mut by_object: Vec<Vec<usize>> = vec![Vec::new(); scene.objects().len()];
        for (i, patch) in scene.patches().iter().enumerate() {
            by_object[patch.object.0 as usize].push(i);
        }
        by_object
            .into_iter()
            .enumerate()
            .filter_map(|(object, patches)| {
                let table = TriangleTable::new(scene, &patches, |_| 1.0);
                (table.total() > 0.0).then(|| ObjectSurface {
                    object,
                    name: scene.objects()[object].clone(),
                    area: patches.iter().map(|&i| scene.patches()[i].area()).sum(),
                    patches: patches.len(),
                    table,
                    emission: mean_emission(scene, &patches),
                })
            })
            .collect()
    }
}

/// The area mean of the emission over `patches`.
fn mean_emission(scene: &Scene, patches: &[usize]) -> Spectrum {
    let (mut emitted, mut area) = (Spectrum::ZERO, 0.0);
    for &i in patches {
        let a = scene.patches()[i].area();
        emitted += scene.emission(i) * a;
        area += a;
    }
    if area > 0.0 { emitted * (1.0 / area) } else { Spectrum::ZERO }
}

/// Running mean and sum of squared deviations per channel.
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    count: u64,
    mean: [Real; 3],
    m2: [Real; 3],
}

impl Moments {
    /// Adds one sample (Welford's update).
    fn push(&mut self, x: Spectrum) {
        self.count += 1;
        let n = self.count as Real;
        for c in 0..3 {
            let delta = x.0[c] - self.mean[c];
            self.mean[c] += delta / n;
            self.m2[c] += delta * (x.0[c] - self.mean[c]);
        }
    }

    /// Adds the samples of `other` (Chan, Golub & LeVeque's pairwise update).
    fn merge(&mut self, other: &Moments) {
        if other.count == 0 {
            return;
        }
        if self.count == 0 {
            *self = *other;
            return;
        }
        let (na, nb) = (self.count as Real, other.count as Real);
        let n = na + nb;
        for c in 0..3 {
            let delta = other.mean[c] - self.mean[c];
            self.mean[c] += delta * nb / n;
            self.m2[c] += other.m2[c] + delta * delta * na * nb / n;
        }
        self.count += other.count;
    }

    /// The standard error of the mean: `√(s² / N)`.
    fn stderr(&self) -> [Real; 3] {
        let n = self.count as Real;
        self.m2.map(|m2| if self.count > 1 { (m2.max(0.0) / (n - 1.0) / n).sqrt() } else { Real::INFINITY })
    }
}

/// What one batch of paths gave.
struct Batch {
    moments: Moments,
    rays: u64,
    truncated: u64,
}

/// The scene's materials and normals per patch, the emitters' sampling table and the BVH.
struct Tracer<'p> {
    visibility: &'p Visibility,
    reflectivity: Vec<Spectrum>,
    emission: Vec<Spectrum>,
    normal: Vec<Vec3>,
    /// Emitter triangles weighted by their largest emission channel.
    emitters: TriangleTable,
    /// The density per unit area with which [`Tracer::emitters`] draws a point of each patch.
    light_density: Vec<Real>,
    next_event: bool,
    roulette_after: u32,
    max_bounces: u32,
}

impl<'p> Tracer<'p> {
    fn new(scene: &Scene, visibility: &'p Visibility, params: &PathTraceParams) -> Tracer<'p> {
        let emission: Vec<Spectrum> = (0..scene.len()).map(|i| scene.emission(i)).collect();
        let all: Vec<usize> = (0..scene.len()).collect();
        let emitters = TriangleTable::new(scene, &all, |i| emission[i].max());
        let total = emitters.total();
        let light_density = emission.iter().map(|e| if total > 0.0 { e.max() / total } else { 0.0 }).collect();
        Tracer {
            visibility,
            reflectivity: (0..scene.len()).map(|i| scene.reflectivity(i)).collect(),
            emission,
            normal: scene.patches().iter().map(|p| p.normal()).collect(),
            emitters,
            light_density,
            next_event: params.next_event,
            roulette_after: params.roulette_after,
            max_bounces: params.max_bounces,
        }
    }

    fn batch(&self, surface: &ObjectSurface, count: u64, rng: &mut ChaCha8Rng) -> Batch {
        let mut batch = Batch { moments: Moments::default(), rays: 0, truncated: 0 };
        for _ in 0..count {
            let (patch, point) = surface.table.sample(rng);
            let path = self.path(patch, point, rng);
            batch.moments.push(surface.emission + path.value);
            batch.rays += path.rays;
            batch.truncated += u64::from(path.truncated);
        }
        batch
    }

    /// The solid-angle density with which light sampling draws the direction from a point to
    /// `y` on `patch`, at distance² `r2` and cosine `cos_y` at `y`.
    fn light_pdf(&self, patch: usize, r2: Real, cos_y: Real) -> Real {
        self.light_density[patch] * r2 / cos_y
    }

    /// The emission that reaches `point` of `patch` directly from a point drawn on the
    /// emitters, per unit reflectivity, weighted by the balance heuristic against cosine
    /// sampling; and whether a shadow ray was traced.
    fn direct(&self, patch: usize, point: Vec3, rng: &mut ChaCha8Rng) -> (Spectrum, bool) {
        let (light, y) = self.emitters.sample(rng);
        let d = y - point;
        let r2 = d.length_squared();
        if light == patch || r2 <= 0.0 {
            return (Spectrum::ZERO, false);
        }
        let direction = d / r2.sqrt();
        let cos_x = self.normal[patch].dot(direction);
        let cos_y = -self.normal[light].dot(direction);
        if cos_x <= 0.0 || cos_y <= 0.0 {
            return (Spectrum::ZERO, false);
        }
        if !self.visibility.unoccluded_between(point, patch, y, light) {
            return (Spectrum::ZERO, true);
        }
        let cosine_pdf = cos_x / PI;
        (self.emission[light] * (cosine_pdf / (self.light_pdf(light, r2, cos_y) + cosine_pdf)), true)
    }

    /// One sample of the light reflected at `point` of `patch` (`B − E` there): the collision
    /// estimator along a random walk.
    fn path(&self, mut patch: usize, mut point: Vec3, rng: &mut ChaCha8Rng) -> Path {
        let mut value = Spectrum::ZERO;
        let mut weight = Spectrum::grey(1.0);
        let mut rays = 0;
        for bounce in 0.. {
            let rho = self.reflectivity[patch];
            let q = rho.max();
            if q <= 0.0 {
                break;
            }
            if self.next_event {
                let (direct, traced) = self.direct(patch, point, rng);
                value += weight * rho * direct;
                rays += u64::from(traced);
            }
            let survival = if bounce < self.roulette_after {
                1.0
            } else {
                if rng.random::<Real>() >= q {
                    break;
                }
                q
            };
            if bounce >= self.max_bounces {
                return Path { value, rays, truncated: true };
            }
            weight = weight * rho * (1.0 / survival);
            let normal = self.normal[patch];
            let direction = cosine_direction(normal, rng.random(), rng.random());
            rays += 1;
            match self.visibility.first_hit(point, direction, Some(patch)) {
                Some(hit) if hit.front => {
                    patch = hit.patch;
                    point += direction * hit.t;
                    if self.emission[patch].is_positive() {
                        let mis = if self.next_event {
                            let length = direction.length();
                            let cosine_pdf = normal.dot(direction) / length / PI;
                            let cos_y = -self.normal[patch].dot(direction) / length;
                            let r2 = (hit.t * length).powi(2);
                            cosine_pdf / (cosine_pdf + self.light_pdf(patch, r2, cos_y))
                        } else {
                            1.0
                        };
                        value += weight * self.emission[patch] * mis;
                    }
                }
                // Escaped, or arrived behind a one-sided patch: it sees nothing.
                _ => break,
            }
        }
        Path { value, rays, truncated: false }
    }
}

/// One path's sample.
struct Path {
    value: Spectrum,
    rays: u64,
    truncated: bool,
}
