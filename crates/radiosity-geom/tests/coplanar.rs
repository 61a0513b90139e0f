//! Tests of coplanar overlaps resolved on a crafted room: rugs overlapping each other and the
//! floor, an exact copy of a rug and a lamp laid on the ceiling. Every surface keeps the area
//! of its union once, worked out by hand.

use radiosity_core::{Real, Scene};
use radiosity_geom::{PreparedScene, SceneAnalysis, Visibility};
use std::collections::BTreeMap;

use crate::{fixture, load};

/// The area per object.
fn areas(scene: &Scene) -> BTreeMap<String, Real> {
    let mut out = BTreeMap::new();
    for (i, p) in scene.patches().iter().enumerate() {
        *out.entry(scene.object_of(i).to_string()).or_insert(0.0) += p.area();
    }
    out
}

#[test]
fn overlapping_coplanar_patches_keep_their_union_once() {
    let arg = fixture("mgf/coplanar_overlap.mgf");
    // As loaded: the rugs and the lamp are counted on top of the floor and the ceiling.
    let loaded = load(&arg).scene;
    assert!((loaded.total_area() - (96.0 + 4.0 + 2.25 + 4.0 + 1.0)).abs() < 1e-12, "{}", loaded.total_area());
    let raw = SceneAnalysis::new(&loaded, &Visibility::new(&loaded));
    assert!(raw.hidden.value.overlapping.len() >= 5, "{:?}", raw.hidden.value.overlapping);

    let prepared = PreparedScene::load(&arg).unwrap();
    let scene = prepared.scene();
    assert!((scene.total_area() - 96.0).abs() < 1e-9, "{}", scene.total_area());
    let a = areas(scene);
    // rug a first and whole; rug b less its 1 m² under a; the copy of a gone; the floor less
    // both rugs; the ceiling less the lamp, which emits and so keeps its area.
    let expected = [("rug_a", 4.0), ("rug_b", 1.25), ("floor", 16.0 - 4.0 - 1.25), ("ceiling", 15.0), ("lamp", 1.0)];
    for (object, area) in expected {
        assert!((a[object] - area).abs() < 1e-9, "{object}: {} m², expected {area}", a[object]);
    }
    assert!(!a.contains_key("rug_c"), "{a:?}");
    assert_eq!(scene.emitters().len(), 1);

    let resolved = &prepared.analysis.hidden.value.resolved;
    let covered: Vec<(&str, &str)> = resolved.covered.iter().map(|c| (c.object.as_str(), c.by.as_str())).collect();
    assert_eq!(covered, [("rug_c", "rug_a")]);
    let mut cut: Vec<(&str, Real)> = resolved.cut.iter().map(|c| (c.object.as_str(), c.kept)).collect();
    cut.sort_by(|x, y| x.0.cmp(y.0));
    assert_eq!(cut.iter().map(|c| c.0).collect::<Vec<_>>(), ["ceiling", "floor", "rug_b"]);
    assert!((cut[2].1 - 1.25 / 2.25).abs() < 1e-12, "{cut:?}");
    assert!((resolved.area_removed - 11.25).abs() < 1e-9, "{}", resolved.area_removed);
    // Said in the report, and left in no list of overlaps.
    let report = prepared.report();
    assert!(prepared.analysis.hidden.value.overlapping.is_empty());
    assert_eq!((report.geometry.covered, report.geometry.cut), (1, 3));
    assert!(report.geometry.reason.contains("1 left out as covered by others, 3 cut to the part none covers"));
    assert!(report.left_out.iter().any(|l| l.starts_with("the second copy of overlapping coplanar area")));
}
