//! The `analytic` backend: Lambert's point-to-polygon formula integrated over the receiving
//! patch, times a visibility estimated with jittered shadow rays.
//!
//! ## Rule
//!
//! `F_ij = V_ij · (1/A_i) Σ_q w_q F(dA_{x_q} → P_j)`, with `(x_q, w_q)` the order-`q` rule on
//! patch `i` ([`crate::quadrature`]) and `F(dA → P)` the clipped Lambert formula
//! ([`crate::ff_point_polygon`]; Baum, Rushmeier & Winget 1989). As the order grows this
//! converges to the exact area-to-area form factor of an unoccluded pair; the tests measure
//! it against Howell's closed forms. Points behind `P_j`'s plane see its back and contribute
//! nothing; pairs entirely behind each other's planes are skipped before any work.
//!
//! The inner integral is analytic, so the `1/r²` singularity of the area-to-area kernel
//! never appears: patches touching along an edge give finite, accurate values.
//!
//! ## Visibility
//!
//! When the scene analysis says nothing can occlude, no ray is traced (`V_ij = 1`).
//! Otherwise `k = rays` segments join jittered points of the two patches, stratified by Latin
//! hypercube sampling on each patch, and
//! `V_ij = Σ_r K_r v_r / Σ_r K_r`, with `v_r ∈ {0, 1}` the segment's visibility and
//! `K_r = cos θ_i cos θ_j / d²` the point-to-point kernel: a ratio estimator of the
//! kernel-weighted visibility, consistent as `k` grows (with `k = 1` it is the one ray's
//! answer). The samples are drawn from a ChaCha8 stream keyed by the seed and the unordered
//! pair, so `V_ij = V_ji` exactly and every column is the same whatever the thread that
//! computes it.

use crate::ff_point_polygon::point_to_polygon;
use crate::guard::ClampCounter;
use crate::quadrature::patch_rule;
use crate::spec::AnalyticParams;
use radiosity_core::{ColumnSource, Patch, Real, Scene, Vec3};
use radiosity_geom::{SceneAnalysis, Visibility};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Relative tolerance (of the scene diagonal) for "behind a plane".
const PLANE_TOLERANCE: Real = 1e-9;

/// Analytic form-factor columns of one scene.
#[derive(Debug)]
pub struct AnalyticColumns<'a> {
    scene: &'a Scene,
    visibility: Option<&'a Visibility>,
    rules: Vec<Vec<(Vec3, Real)>>,
    params: AnalyticParams,
    tolerance: Real,
    clamped: ClampCounter,
}

impl<'a> AnalyticColumns<'a> {
    /// Prepares the backend: quadrature points on every patch, and visibility only when the
    /// analysis says something can occlude.
    pub fn new(
        scene: &'a Scene,
        visibility: &'a Visibility,
        analysis: &SceneAnalysis,
        params: AnalyticParams,
    ) -> AnalyticColumns<'a> {
        AnalyticColumns {
            scene,
            visibility: analysis.occlusion.value.then_some(visibility),
            rules: scene.patches().iter().map(|p| patch_rule(p, params.order)).collect(),
            params,
            tolerance: PLANE_TOLERANCE * scene.diagonal(),
            clamped: ClampCounter::default(),
        }
    }

    /// Whether shadow rays are traced.
    pub fn traces_shadow_rays(&self) -> bool {
        self.visibility.is_some()
    }

    /// Entries clamped into `[0, 1]` so far.
    pub fn clamped(&self) -> u64 {
        self.clamped.count()
    }

    /// `F_ij` before clamping.
    pub fn pair(&self, i: usize, j: usize) -> Real {
        if i == j {
            return 0.0;
        }
        let (pi, pj) = (&self.scene.patches()[i], &self.scene.patches()[j]);
        if behind(pj, pi, self.tolerance) || behind(pi, pj, self.tolerance) {
            return 0.0;
        }
        let unoccluded = self.unoccluded(i, pi, pj);
        if unoccluded == 0.0 {
            return 0.0;
        }
        match self.visibility {
            Some(vis) => unoccluded * self.visible_fraction(vis, i, j),
            None => unoccluded,
        }
    }

    /// `(1/A_i) Σ_q w_q F(dA_{x_q} → P_j)`.
    fn unoccluded(&self, i: usize, pi: &Patch, pj: &Patch) -> Real {
        let (nj, oj) = (pj.normal(), pj.vertices()[0]);
        let mut sum = 0.0;
        for &(x, w) in &self.rules[i] {
            if nj.dot(x - oj) > 0.0 {
                sum += w * point_to_polygon(x, pi.normal(), pj.vertices());
            }
        }
        sum / pi.area()
    }

    /// The kernel-weighted fraction of `rays` jittered segments between the patches that no
    /// other patch blocks.
    fn visible_fraction(&self, vis: &Visibility, i: usize, j: usize) -> Real {
        let (lo, hi) = (i.min(j), i.max(j));
        let (plo, phi) = (&self.scene.patches()[lo], &self.scene.patches()[hi]);
        let mut rng = ChaCha8Rng::seed_from_u64(self.params.seed);
        rng.set_stream(((lo as u64) << 32) | hi as u64);
        let k = self.params.rays;
        if k == 1 {
            let p = plo.point_at(rng.random(), rng.random());
            let q = phi.point_at(rng.random(), rng.random());
            return if vis.unoccluded_between(p, lo, q, hi) { 1.0 } else { 0.0 };
        }
        let mut strata: [Vec<usize>; 4] = std::array::from_fn(|_| (0..k).collect());
        for s in &mut strata {
            s.shuffle(&mut rng);
        }
        let jitter = |stratum: usize, rng: &mut ChaCha8Rng| (stratum as Real + rng.random::<Real>()) / k as Real;
        let (mut weighted, mut total, mut hits) = (0.0, 0.0, 0usize);
        for r in 0..k {
            let p = plo.point_at(jitter(strata[0][r], &mut rng), jitter(strata[1][r], &mut rng));
            let q = phi.point_at(jitter(strata[2][r], &mut rng), jitter(strata[3][r], &mut rng));
            let d = q - p;
            let d2 = d.length_squared();
            let kernel = if d2 > 0.0 {
                (plo.normal().dot(d).max(0.0) * (-phi.normal().dot(d)).max(0.0)) / (d2 * d2)
            } else {
                0.0
            };
            let visible = vis.unoccluded_between(p, lo, q, hi);
            total += kernel;
            if visible {
                weighted += kernel;
                hits += 1;
            }
        }
        // Every sampled pair grazing (zero kernel): fall back to the plain fraction.
        if total > 0.0 { weighted / total } else { hits as Real / k as Real }
    }
}

/// True when every vertex of `a` lies on or behind the plane of `b`.
fn behind(a: &Patch, b: &Patch, tolerance: Real) -> bool {
    let (n, o) = (b.normal(), b.centroid());
    a.vertices().iter().all(|v| n.dot(*v - o) <= tolerance)
}

impl ColumnSource for AnalyticColumns<'_> {
    fn patch_count(&self) -> usize {
        self.scene.len()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        for (i, f) in column.iter_mut().enumerate() {
            *f = self.pair(i, j);
        }
        self.clamped.clamp(column);
    }
}
