//! Tests of the analytic backend against Howell's closed forms, closure and reciprocity.

use super::closed_forms::*;
use radiosity_core::Scene;
use radiosity_ff::{AnalyticColumns, AnalyticParams};
use radiosity_geom::{SceneAnalysis, Visibility};

fn analytic_aggregate(scene: &Scene, m: usize, params: AnalyticParams) -> f64 {
    let vis = Visibility::new(scene);
    let analysis = SceneAnalysis::new(scene, &vis);
    let f = AnalyticColumns::new(scene, &vis, &analysis, params);
    assert!(!f.traces_shadow_rays());
    aggregate(scene, &f, m)
}

#[test]
fn explore() {
    for m in [1, 2, 4, 8] {
        for order in [1, 2, 3, 4, 6, 8, 12] {
            let p = AnalyticParams { order, ..Default::default() };
            let a = analytic_aggregate(&opposed_squares(m), m, p);
            let b = analytic_aggregate(&corner(1.0, 1.0, 1.0, m), m, p);
            println!(
                "m={m} order={order}: parallel {:.2e} corner {:.2e}",
                (a / parallel(1.0, 1.0, 1.0) - 1.0).abs(),
                (b / perpendicular(1.0, 1.0, 1.0) - 1.0).abs()
            );
        }
    }
}
