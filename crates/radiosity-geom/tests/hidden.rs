//! Tests of hidden-geometry detection on constructed rooms: a box standing on the floor, a box
//! pressed against a wall, an open-bottomed box, a thin two-sided partition and a duplicated
//! face, each with the patches it must (and must not) leave out. Partial overlaps are in
//! `coplanar.rs`.

use radiosity_core::{Material, Scene, Spectrum, Vec3};
use radiosity_geom::mesh::{BoxFace, Facing};
use radiosity_geom::{HiddenReason, LoadedScene, PreparedScene, SceneBuilder, load_scene};

/// A closed 4 m room (inward faces cut into 1 m patches) with a 1 m box on the floor, its bottom
/// `lift` above it, and a 1 m box pressed against the wall at x = 4, both cut into 0.5 m patches
/// and facing out; `bottom` says whether the floor box has a bottom face.
fn room(lift: f64, bottom: bool, extra: impl FnOnce(&mut SceneBuilder)) -> Scene {
    let mut b = SceneBuilder::new("room");
    let paint = b.material(Material::new("paint", Spectrum::grey(0.5), Spectrum::ZERO)).unwrap();
    let lamp = b.material(Material::new("lamp", Spectrum::ZERO, Spectrum::grey(1.0))).unwrap();
    let walls = b.object("walls");
    let ceiling = b.object("ceiling");
    let on_floor = b.object("box on the floor");
    let at_wall = b.object("box at the wall");
    let sides = [BoxFace::MinX, BoxFace::MaxX, BoxFace::MinY, BoxFace::MinZ, BoxFace::MaxZ];
    b.axis_box([Vec3::ZERO, Vec3::splat(4.0)], &sides, Facing::Inward, 1.0, paint, walls).unwrap();
    b.axis_box([Vec3::ZERO, Vec3::splat(4.0)], &[BoxFace::MaxY], Facing::Inward, 1.0, lamp, ceiling).unwrap();
    let faces: Vec<BoxFace> = BoxFace::ALL.into_iter().filter(|&f| bottom || f != BoxFace::MinY).collect();
    let floor_box = [Vec3::new(1.0, lift, 1.0), Vec3::new(2.0, 1.0 + lift, 2.0)];
    b.axis_box(floor_box, &faces, Facing::Outward, 0.5, paint, on_floor).unwrap();
    let wall_box = [Vec3::new(3.0, 1.0, 1.0), Vec3::new(4.0, 2.0, 2.0)];
    b.axis_box(wall_box, &BoxFace::ALL, Facing::Outward, 0.5, paint, at_wall).unwrap();
    extra(&mut b);
    b.build().unwrap()
}

fn prepare(scene: Scene) -> PreparedScene {
    LoadedScene { scene, warnings: Vec::new() }.prepare()
}

/// The hidden patches as (object, reason) pairs, sorted.
fn hidden(p: &PreparedScene) -> Vec<(String, HiddenReason)> {
    let mut list: Vec<_> = p.analysis.hidden.value.hidden.iter().map(|h| (h.object.clone(), h.reason)).collect();
    list.sort_by(|a, b| a.0.cmp(&b.0));
    list
}

fn pressed(object: &str, count: usize) -> Vec<(String, HiddenReason)> {
    vec![(object.to_string(), HiddenReason::Pressed); count]
}

#[test]
fn boxes_on_the_floor_and_against_a_wall_hide_what_they_press_on() {
    let scene = room(0.0, true, |_| {});
    let loaded = scene.len();
    let p = prepare(scene);
    // Each box hides the one 1 m patch under it and its own four 0.5 m patches facing it.
    let expected = [pressed("box at the wall", 4), pressed("box on the floor", 4), pressed("walls", 2)].concat();
    assert_eq!(hidden(&p), expected);
    assert_eq!(p.scene().len(), loaded - 10, "the hidden patches are left out of the system");
    let g = &p.report().geometry;
    assert_eq!((g.hidden, g.pressed, g.enclosed), (10, 10, 0));
    assert!((g.hidden_area - 2.0 - 2.0).abs() < 1e-9, "{}", g.hidden_area);
    assert!(g.examples.iter().any(|e| e.contains("'box on the floor' is pressed against 'walls'")), "{:?}", g.examples);
    assert!(p.analysis.left_out()[0].starts_with("10 hidden patches"), "{:?}", p.analysis.left_out());
    // Nothing left in the system touches anything: the contacts were exactly the hidden patches.
    assert!(p.analysis.hidden.value.touching.is_empty(), "{:?}", p.analysis.hidden.value.touching);
    // The room stays closed without them: the hole they leave is sealed by the boxes.
    assert!(p.analysis.closure.value.is_closed(), "{}", p.analysis.closure.reason);
}

#[test]
fn a_thin_air_gap_is_still_contact_and_a_wide_one_is_not() {
    let narrow = prepare(room(1e-6, true, |_| {}));
    assert_eq!(hidden(&narrow).len(), 10, "{:?}", hidden(&narrow));
    // At 1 cm (1.4e-3 of the diagonal) the box bottom and the floor see each other across a gap.
    let wide = prepare(room(0.01, true, |_| {}));
    assert_eq!(hidden(&wide), [pressed("box at the wall", 4), pressed("walls", 1)].concat());
}

#[test]
fn a_box_without_a_bottom_hides_the_floor_inside_it() {
    let p = prepare(room(0.0, false, |_| {}));
    let h = hidden(&p);
    assert!(h.contains(&("walls".to_string(), HiddenReason::Enclosed)), "{h:?}");
    assert_eq!(h.len(), 6, "{h:?}");
}

#[test]
fn a_thin_two_sided_partition_stays_in_the_system_and_a_duplicated_face_is_kept_once() {
    let p = prepare(room(0.0, true, |b| {
        let paint = radiosity_core::MaterialId(0);
        let partition = b.object("partition");
        // Two coincident faces back to back at z = 3, each seeing half of the room.
        let front =
            [Vec3::new(0.5, 2.5, 3.0), Vec3::new(1.5, 2.5, 3.0), Vec3::new(1.5, 3.5, 3.0), Vec3::new(0.5, 3.5, 3.0)];
        let mut back = front;
        back.reverse();
        b.polygon(&front, paint, partition).unwrap();
        b.polygon(&back, paint, partition).unwrap();
        // A second copy of one ceiling patch, facing down into the room like the ceiling.
        let copy = b.object("copy");
        let ceiling =
            [Vec3::new(0.0, 4.0, 0.0), Vec3::new(1.0, 4.0, 0.0), Vec3::new(1.0, 4.0, 1.0), Vec3::new(0.0, 4.0, 1.0)];
        b.polygon(&ceiling, paint, copy).unwrap();
    }));
    assert_eq!(hidden(&p).len(), 10, "{:?}", hidden(&p));
    let found = &p.analysis.hidden.value;
    let touching: Vec<&str> = found.touching.iter().map(|c| c.object.as_str()).collect();
    assert_eq!(touching, ["partition", "partition"]);
    assert!(found.touching.iter().all(|c| c.fraction == 1.0));
    // The copy, written after the ceiling, lies wholly under it and is left out.
    assert!(found.overlapping.is_empty(), "{:?}", found.overlapping);
    let covered: Vec<(&str, &str)> =
        found.resolved.covered.iter().map(|c| (c.object.as_str(), c.by.as_str())).collect();
    assert_eq!(covered, [("copy", "ceiling")]);
    assert!(found.resolved.cut.is_empty(), "{:?}", found.resolved.cut);
    assert!((found.resolved.area_removed - 1.0).abs() < 1e-12, "{}", found.resolved.area_removed);
    assert!(
        p.scene()
            .objects()
            .iter()
            .enumerate()
            .all(|(k, o)| o != "copy" || p.scene().patches().iter().all(|q| q.object.0 as usize != k))
    );
    assert!(p.report().geometry.examples.iter().any(|e| e.starts_with("covered: patch ")));
}

#[test]
fn built_in_scenes_hide_nothing_but_the_floor_under_the_cornell_blocks() {
    for arg in ["multi-cubes", "furnace:block=true", "inner-box", "office:size=0.6", "labyrinth"] {
        let p = load_scene(arg).unwrap().prepare();
        assert!(p.analysis.hidden.value.is_empty(), "{arg}: {}", p.analysis.hidden.reason);
    }
    // The Cornell blocks have no bottom faces: the floor patches wholly under them face their
    // insides.
    let p = load_scene("cornell").unwrap().prepare();
    let h = &p.analysis.hidden.value.hidden;
    assert!(!h.is_empty() && h.iter().all(|h| h.object == "floor" && h.reason == HiddenReason::Enclosed), "{h:?}");
}
