//! The rays a backend traces for one column, listed without computing the column: what
//! `cargo xtask bench` traces straight through the BVH to set the form-factor pipeline against
//! the ray-tracing limit on the same rays.
//!
//! - `analytic` traces shadow-ray **segments** between two patches
//!   ([`AnalyticColumns::shadow_segments`], which runs the backend's own code with each
//!   segment recorded instead of traced);
//! - `hemicube` and `montecarlo` trace **rays** to their first hit, skipping the shooter. Their
//!   rays come from the backends' own generators ([`HemicubeColumns`]'s frame and pixels, the
//!   Monte Carlo batches), in the order the backends trace them; the tests below check that
//!   tracing them gives exactly the backends' rows.
//!
//! A stored matrix traces nothing. Which rays an argument's backend traces is the argument's
//! to say ([`crate::BackendArgument::column_rays`]); [`ColumnRays::new`], which asks a
//! [`crate::BackendSpec`], is defined beside them ([`crate::spec`]), so that this file knows
//! the backends and not their arguments.

use crate::analytic::AnalyticColumns;
use crate::hemicube::HemicubeColumns;
use crate::montecarlo::{MonteCarloParams, batch_rays, batch_sizes};
use crate::rays::{HitRay, TracedRays};
use radiosity_core::{ColumnSource, Scene};

/// Lists the rays each column of one backend traces.
#[derive(Debug)]
pub struct ColumnRays<'a> {
    kind: Kind<'a>,
}

#[derive(Debug)]
enum Kind<'a> {
    Analytic(AnalyticColumns<'a>),
    Hemicube(HemicubeColumns<'a>),
    MonteCarlo { scene: &'a Scene, params: MonteCarloParams },
}

impl<'a> ColumnRays<'a> {
    /// The shadow-ray segments of the analytic backend.
    pub fn analytic(columns: AnalyticColumns<'a>) -> ColumnRays<'a> {
        ColumnRays { kind: Kind::Analytic(columns) }
    }

    /// The rays of the hemicube backend.
    pub fn hemicube(columns: HemicubeColumns<'a>) -> ColumnRays<'a> {
        ColumnRays { kind: Kind::Hemicube(columns) }
    }

    /// The rays of the Monte Carlo backend on `scene`.
    pub fn montecarlo(scene: &'a Scene, params: MonteCarloParams) -> ColumnRays<'a> {
        ColumnRays { kind: Kind::MonteCarlo { scene, params } }
    }

    /// An empty list of the kind this backend traces.
    pub fn empty(&self) -> TracedRays {
        match self.kind {
            Kind::Analytic(_) => TracedRays::Segments(Vec::new()),
            _ => TracedRays::Rays(Vec::new()),
        }
    }

    /// Appends the rays of column `j` to `out` (which must be of the kind [`Self::empty`]
    /// gives; rays of the other kind are not appended). A `j` out of range adds nothing.
    pub fn rays(&self, j: usize, out: &mut TracedRays) {
        match (&self.kind, out) {
            (Kind::Analytic(a), TracedRays::Segments(s)) if j < a.patch_count() => a.shadow_segments(j, s),
            (Kind::Hemicube(columns), TracedRays::Rays(r)) => hemicube_rays(columns, j, r),
            (Kind::MonteCarlo { scene, params }, TracedRays::Rays(r)) => montecarlo_rays(scene, *params, j, r),
            _ => {}
        }
    }
}

/// The rays of the hemicube at shooter `j`, in pixel order (as `HemicubeColumns::row`).
fn hemicube_rays(columns: &HemicubeColumns<'_>, j: usize, out: &mut Vec<HitRay>) {
    let Some((origin, [t, b, n])) = columns.frame(j) else {
        return;
    };
    out.extend(columns.pixels().map(|(d, _)| HitRay { origin, direction: t * d.x + b * d.y + n * d.z, skip: j }));
}

/// The rays of Monte Carlo shooter `j`, batch by batch (as `MonteCarloColumns::tally`).
fn montecarlo_rays(scene: &Scene, params: MonteCarloParams, j: usize, out: &mut Vec<HitRay>) {
    let Some(patch) = scene.patches().get(j) else {
        return;
    };
    let (count, base, extra) = batch_sizes(params.rays);
    for k in 0..count {
        let rays = batch_rays(params.seed, j, patch, k, base + usize::from(k < extra));
        out.extend(rays.map(|(origin, direction)| HitRay { origin, direction, skip: j }));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{AnalyticParams, BackendSpec, FormFactorInput, HemicubeParams, MonteCarloColumns};
    use radiosity_core::Real;
    use radiosity_geom::{SceneAnalysis, Visibility, load_scene};

    fn setup(arg: &str) -> (Scene, Visibility) {
        let scene = load_scene(arg).unwrap().scene;
        let visibility = Visibility::new(&scene);
        (scene, visibility)
    }

    #[test]
    fn analytic_segments_are_those_that_decide_the_column() {
        // One ray per pair: F_ij > 0 exactly where the pair's kernel is non-zero and its one
        // segment is clear, and every such pair has exactly one segment.
        let (scene, visibility) = setup("multi-cubes");
        let analysis = SceneAnalysis::new(&scene, &visibility);
        let input = FormFactorInput { scene: &scene, visibility: visibility.clone(), analysis: &analysis };
        let spec = BackendSpec::parse("analytic:rays=1:budget=0").unwrap();
        let rays = ColumnRays::new(&spec, input).unwrap();
        let backend = AnalyticColumns::new(
            &scene,
            &visibility,
            &analysis,
            *spec.params::<AnalyticParams>().expect("analytic parameters"),
        );
        let mut column = vec![0.0; scene.len()];
        for j in [0, 17, 240, 479] {
            let mut out = rays.empty();
            rays.rays(j, &mut out);
            let TracedRays::Segments(segments) = out else { panic!("analytic traces segments") };
            assert!(!segments.is_empty());
            backend.fill_column(j, &mut column);
            let mut seen = vec![false; scene.len()];
            for s in &segments {
                assert!(s.from == j || s.to == j, "{s:?}");
                let i = if s.from == j { s.to } else { s.from };
                assert!(!seen[i], "two segments for pair ({i}, {j})");
                seen[i] = true;
                let clear = visibility.unoccluded_between(s.p, s.from, s.q, s.to);
                assert_eq!(clear, column[i] > 0.0, "pair ({i}, {j})");
            }
            for (i, &f) in column.iter().enumerate() {
                assert!(f == 0.0 || seen[i], "F_{i}{j} = {f} without a segment");
            }
        }
    }

    #[test]
    fn hemicube_rays_give_the_backend_row() {
        let (scene, visibility) = setup("cornell:res=2");
        let analysis = SceneAnalysis::new(&scene, &visibility);
        let input = FormFactorInput { scene: &scene, visibility: visibility.clone(), analysis: &analysis };
        let spec = BackendSpec::parse("hemicube:res=16:seed=3").unwrap();
        let params = *spec.params::<HemicubeParams>().expect("hemicube parameters");
        let backend = HemicubeColumns::new(&scene, &visibility, params);
        let rays = ColumnRays::new(&spec, input).unwrap();
        let weights: Vec<Real> = backend.pixels().map(|(_, w)| w).collect();
        let mut column = vec![0.0; scene.len()];
        for j in [0, 5, scene.len() - 1] {
            let mut out = rays.empty();
            rays.rays(j, &mut out);
            let TracedRays::Rays(list) = out else { panic!("hemicube traces rays") };
            assert_eq!(list.len(), weights.len());
            let mut row = vec![0.0; scene.len()];
            for (ray, w) in list.iter().zip(&weights) {
                if let Some(hit) = visibility.first_hit(ray.origin, ray.direction, Some(ray.skip)).filter(|h| h.front) {
                    row[hit.patch] += w;
                }
            }
            backend.fill_column(j, &mut column);
            let aj = scene.patches()[j].area();
            for (i, p) in scene.patches().iter().enumerate() {
                let expected = (row[i] * aj / p.area()).clamp(0.0, 1.0);
                assert_eq!(column[i], expected, "F_{i}{j}");
            }
        }
    }

    #[test]
    fn montecarlo_rays_give_the_backend_tally() {
        let (scene, visibility) = setup("cornell:res=2");
        let analysis = SceneAnalysis::new(&scene, &visibility);
        let input = FormFactorInput { scene: &scene, visibility: visibility.clone(), analysis: &analysis };
        // More than one batch, of unequal sizes.
        let spec = BackendSpec::parse("montecarlo:rays=9001:seed=5").unwrap();
        let params = *spec.params::<MonteCarloParams>().expect("Monte Carlo parameters");
        let backend = MonteCarloColumns::new(&scene, &visibility, params);
        let rays = ColumnRays::new(&spec, input).unwrap();
        for j in [0, 7, scene.len() - 1] {
            let mut out = rays.empty();
            rays.rays(j, &mut out);
            let TracedRays::Rays(list) = out else { panic!("montecarlo traces rays") };
            assert_eq!(list.len(), 9001);
            let mut front = vec![0u64; scene.len()];
            for ray in &list {
                if let Some(hit) = visibility.first_hit(ray.origin, ray.direction, Some(ray.skip)).filter(|h| h.front) {
                    front[hit.patch] += 1;
                }
            }
            assert_eq!(front, backend.tally(j).front, "shooter {j}");
        }
    }

    #[test]
    fn a_stored_matrix_traces_nothing() {
        let (scene, visibility) = setup("furnace:res=2");
        let analysis = SceneAnalysis::new(&scene, &visibility);
        let input = FormFactorInput { scene: &scene, visibility: visibility.clone(), analysis: &analysis };
        assert!(ColumnRays::new(&BackendSpec::parse("matrix").unwrap(), input.clone()).is_none());
        // Nothing can occlude in the furnace: the analytic backend traces no segment.
        let rays = ColumnRays::new(&BackendSpec::parse("analytic").unwrap(), input).unwrap();
        let mut out = rays.empty();
        rays.rays(0, &mut out);
        assert!(out.is_empty());
    }
}
