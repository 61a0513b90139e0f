//! Tests of the scene-analysis decisions: convex and occluded rooms, open and closed scenes,
//! grey and coloured scenes, emitters, and what is left out.

use radiosity_core::{Channels, Material, Spectrum, Vec3};
use radiosity_geom::mesh::{BoxFace, Facing};
use radiosity_geom::{Closure, SceneAnalysis, SceneBuilder, Visibility, load_scene};

fn analyse(arg: &str) -> SceneAnalysis {
    let scene = load_scene(arg).unwrap().scene;
    SceneAnalysis::new(&scene, &Visibility::new(&scene))
}

#[test]
fn convex_room_needs_no_shadow_rays() {
    let a = analyse("furnace");
    assert!(!a.occlusion.value, "{}", a.occlusion.reason);
    assert!(a.occlusion.reason.contains("6 distinct planes"), "{}", a.occlusion.reason);
    assert!(a.closure.value.is_closed(), "{}", a.closure.reason);
    assert_eq!(a.channels.value, Channels::Grey);
    assert_eq!(a.emitters.value.len(), 96);
    assert_eq!(
        a.left_out(),
        vec!["shadow rays (nothing can occlude)".to_string(), "two of three colour channels (grey scene)".to_string()]
    );
}

#[test]
fn occluded_room_needs_shadow_rays() {
    let a = analyse("furnace:block=true");
    assert!(a.occlusion.value);
    assert!(a.occlusion.reason.contains("'block'") || a.occlusion.reason.contains("'box'"), "{}", a.occlusion.reason);
    assert!(a.closure.value.is_closed());
    let m = analyse("multi-cubes");
    assert!(m.occlusion.value);
    assert!(m.closure.value.is_closed(), "{}", m.closure.reason);
    assert_eq!(m.channels.value, Channels::Rgb);
    assert_eq!(m.emitters.value.len(), 4);
    assert!(m.left_out().is_empty());
}

#[test]
fn open_and_closed_cornell_boxes() {
    let open = analyse("cornell");
    assert!(open.occlusion.value, "the blocks hide parts of the room");
    let Closure::Open { escaped, sampled } = open.closure.value else { panic!("{}", open.closure.reason) };
    // The open front is one of six sides: a sizeable but minor share of rays leave.
    let share = escaped as f64 / sampled as f64;
    assert!((0.02..0.5).contains(&share), "{share}");
    assert_eq!(open.left_out(), vec!["closure checks (open scene: rows of F sum to less than 1)".to_string()]);
    // Closing the front keeps every ray inside, but the blocks have no bottoms: rays from the
    // floor under them meet the blocks' insides, backs where the kernel is zero, so the rows
    // there miss 1 and the box does not count as closed.
    let front = analyse("cornell:front=true");
    let Closure::Open { escaped, sampled } = front.closure.value else { panic!("{}", front.closure.reason) };
    assert!((escaped as f64) < 0.05 * sampled as f64, "{}", front.closure.reason);
    assert!(
        front.closure.reason.contains("meet the back of a patch, the first from patch"),
        "{}",
        front.closure.reason
    );
    assert!(front.closure.reason.contains("of 'floor'"), "{}", front.closure.reason);
}

#[test]
fn open_convex_box_and_coloured_materials() {
    // A box without its top: convex (no occlusion), open, coloured.
    let mut b = SceneBuilder::new("tray");
    let red = b.material(Material::new("red", Spectrum::rgb(0.8, 0.1, 0.1), Spectrum::ZERO)).unwrap();
    let lamp = b.material(Material::new("lamp", Spectrum::ZERO, Spectrum::grey(1.0))).unwrap();
    let o = b.object("tray");
    let faces = [BoxFace::MinX, BoxFace::MaxX, BoxFace::MinZ, BoxFace::MaxZ];
    b.axis_box([Vec3::ZERO, Vec3::ONE], &faces, Facing::Inward, 0.5, red, o).unwrap();
    b.axis_box([Vec3::ZERO, Vec3::ONE], &[BoxFace::MinY], Facing::Inward, 1.0, lamp, o).unwrap();
    let scene = b.build().unwrap();
    let a = SceneAnalysis::new(&scene, &Visibility::new(&scene));
    assert!(!a.occlusion.value, "{}", a.occlusion.reason);
    assert!(!a.closure.value.is_closed());
    assert_eq!(a.channels.value, Channels::Rgb);
    assert!(a.channels.reason.contains("'red'"));
    assert_eq!(a.emitters.value, vec![16]);
    assert_eq!(a.patches, 17);
    assert!((a.mean_reflectivity - (4.0 * 1.0 / 3.0) / 5.0).abs() < 1e-12);
}

/// `f` on a rayon pool of `threads` threads.
fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(f)
}

#[test]
fn the_set_up_is_the_same_on_any_number_of_threads() {
    // The BVH's build, the closure probe and the hidden-geometry probe run on every thread:
    // the tree, every decision and every count are the same on one thread as on three.
    for arg in ["cornell", "office:size=0.6"] {
        let scene = load_scene(arg).unwrap().scene;
        let one = on_threads(1, || Visibility::new(&scene));
        let three = on_threads(3, || Visibility::new(&scene));
        assert!(one == three, "{arg}: the BVH depends on the thread count");
        let analyse = |threads| on_threads(threads, || SceneAnalysis::new(&scene, &one));
        assert_eq!(analyse(1), analyse(3), "{arg}");
    }
}

#[test]
fn the_closure_probe_casts_the_rays_of_one_serial_stream() {
    // Each patch reads its rays at its own place in the seeded stream: the rays, and so the
    // count of lost ones, are those of one pass drawing patch after patch.
    use radiosity_core::Real;
    use radiosity_core::math::cosine_direction;
    use rand::{Rng, SeedableRng};
    let scene = load_scene("cornell:front=true").unwrap().scene;
    let visibility = Visibility::new(&scene);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let mut escaped = 0;
    for (i, patch) in scene.patches().iter().enumerate() {
        for _ in 0..radiosity_geom::analysis::RAYS_PER_PATCH {
            let origin = patch.point_at(rng.random::<Real>(), rng.random::<Real>());
            let direction = cosine_direction(patch.normal(), rng.random::<Real>(), rng.random::<Real>());
            escaped += usize::from(visibility.first_hit(origin, direction, Some(i)).is_none_or(|h| !h.front));
        }
    }
    let a = SceneAnalysis::new(&scene, &visibility);
    let Closure::Open { escaped: found, .. } = a.closure.value else { panic!("{}", a.closure.reason) };
    assert!(escaped > 0);
    assert_eq!(found, escaped);
}

#[test]
fn the_probes_dealt_to_ranks_give_one_process_analysis() {
    // Threads standing in for MPI ranks: each probes its share of the patches for hidden
    // geometry and closure, and one sum each hands every rank one process's findings, on a
    // scene with hidden patches, an open one and a closed one.
    use radiosity_core::InProcessRanks;
    use radiosity_geom::PreparedScene;
    for arg in ["cornell", "cornell:front=true", "furnace:block=true"] {
        let one = PreparedScene::load(arg).unwrap();
        for ranks in [2, 3] {
            let split = InProcessRanks::run(ranks, |c| PreparedScene::load_over(arg, &|_| {}, Some(&*c)).unwrap());
            for (rank, p) in split.iter().enumerate() {
                assert_eq!(p.analysis, one.analysis, "{arg}: rank {rank} of {ranks}");
                assert_eq!(p.scene().len(), one.scene().len(), "{arg}: rank {rank} of {ranks}");
            }
        }
    }
}

#[test]
fn a_prepared_scene_counts_what_it_holds() {
    // The scene holds at least its patches, the BVH at least its exact f64 triangles (two a
    // quad) and a patch index each: the floor of what a process holds per patch.
    use radiosity_core::{Patch, PatchShape};
    use radiosity_geom::PreparedScene;
    let p = PreparedScene::load("office:size=0.6").unwrap();
    let scene = p.scene();
    let triangles: usize = scene.patches().iter().map(|q| if q.shape() == PatchShape::Quad { 2 } else { 1 }).sum();
    let m = p.memory();
    assert!(m.scene >= scene.len() * size_of::<Patch>(), "{m:?}");
    assert!(m.bvh >= triangles * (3 * 3 * 8 + 4), "{m:?}");
    assert!(m.bvh < 4 * triangles * (3 * 3 * 8 + 4), "the tree is a fraction of the triangles: {m:?}");
    assert_eq!(p.report().memory, m);
}
