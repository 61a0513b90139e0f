//! Integration tests of radiosity-core: patches, spectra, scenes, the linear system and
//! column sources, checked against values computed by hand.

use approx::assert_relative_eq;
use radiosity_core::*;

mod operator;

const M: MaterialId = MaterialId(0);
const O: ObjectId = ObjectId(0);

fn v(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x, y, z)
}

#[test]
fn triangle_area_centroid_normal() {
    let p = Patch::triangle([v(0., 0., 0.), v(2., 0., 0.), v(0., 3., 0.)], M, O).unwrap();
    assert_eq!(p.shape(), PatchShape::Triangle);
    assert_relative_eq!(p.area(), 3.0);
    assert_relative_eq!(p.centroid(), v(2.0 / 3.0, 1.0, 0.0), epsilon = 1e-15);
    assert_relative_eq!(p.normal(), v(0., 0., 1.));
}

#[test]
fn trapezoid_quad_centroid_is_area_weighted() {
    // Trapezoid with parallel sides 4 (y = 0) and 2 (y = 1): area 3; centroid height
    // h (b + 2a) / (3 (a + b)) with a = 2 (top), b = 4 (bottom) gives 8/18 = 4/9.
    let p = Patch::quad([v(0., 0., 0.), v(4., 0., 0.), v(3., 1., 0.), v(1., 1., 0.)], M, O).unwrap();
    assert_relative_eq!(p.area(), 3.0);
    assert_relative_eq!(p.centroid(), v(2.0, 4.0 / 9.0, 0.0), epsilon = 1e-15);
    assert_relative_eq!(p.normal(), v(0., 0., 1.));
    assert_eq!(p.triangles().count(), 2);
}

#[test]
fn clockwise_vertices_flip_the_normal() {
    let p = Patch::quad([v(0., 0., 0.), v(0., 1., 0.), v(1., 1., 0.), v(1., 0., 0.)], M, O).unwrap();
    assert_relative_eq!(p.normal(), v(0., 0., -1.));
}

#[test]
fn invalid_patches_are_refused() {
    let degenerate = Patch::triangle([v(0., 0., 0.), v(1., 0., 0.), v(2., 0., 0.)], M, O);
    assert!(matches!(degenerate, Err(CoreError::DegeneratePatch { .. })));
    let bent = Patch::quad([v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.1), v(0., 1., 0.)], M, O);
    assert!(matches!(bent, Err(CoreError::NonPlanarQuad { .. })));
    let dart = Patch::quad([v(0., 0., 0.), v(2., 0., 0.), v(0.5, 0.5, 0.), v(0., 2., 0.)], M, O);
    assert_eq!(dart, Err(CoreError::NonConvexQuad));
    let bowtie = Patch::quad([v(0., 0., 0.), v(1., 1., 0.), v(1., 0., 0.), v(0., 1., 0.)], M, O);
    assert!(bowtie.is_err());
    let nan = Patch::triangle([v(0., 0., 0.), v(f64::NAN, 0., 0.), v(0., 1., 0.)], M, O);
    assert_eq!(nan, Err(CoreError::NonFiniteVertex));
}

#[test]
fn validation_is_scale_free() {
    // A thin but valid sliver and a slightly bent quad, at scales 1e-4 and 1e4.
    for s in [1e-4, 1.0, 1e4] {
        let sliver = Patch::triangle([v(0., 0., 0.), v(s, 0., 0.), v(0., s * 1e-5, 0.)], M, O).unwrap();
        assert_relative_eq!(sliver.area(), 0.5 * s * s * 1e-5, max_relative = 1e-12);
        let bent = Patch::quad([v(0., 0., 0.), v(s, 0., 0.), v(s, s, s * 1e-6), v(0., s, 0.)], M, O);
        assert!(matches!(bent, Err(CoreError::NonPlanarQuad { .. })), "scale {s}");
    }
}

#[test]
fn point_at_covers_the_patch() {
    let t = Patch::triangle([v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.)], M, O).unwrap();
    assert_relative_eq!(t.point_at(0.0, 0.3), v(0., 0., 0.));
    assert_relative_eq!(t.point_at(1.0, 0.0), v(1., 0., 0.));
    assert_relative_eq!(t.point_at(1.0, 1.0), v(0., 1., 0.));
    // The mean of a uniform grid of samples approaches the centroid.
    let k = 200;
    let mut mean = Vec3::ZERO;
    for a in 0..k {
        for b in 0..k {
            mean += t.point_at((a as f64 + 0.5) / k as f64, (b as f64 + 0.5) / k as f64);
        }
    }
    assert_relative_eq!(mean / (k * k) as f64, t.centroid(), epsilon = 1e-4);
}

#[test]
fn spectrum_arithmetic_and_greyness() {
    let s = Spectrum::rgb(0.2, 0.4, 0.6);
    assert_relative_eq!(s.mean(), 0.4);
    assert_eq!(s.max(), 0.6);
    assert_eq!(s.min(), 0.2);
    assert!(!s.is_grey());
    assert!(Spectrum::grey(0.3).is_grey());
    assert_eq!(s * 2.0, Spectrum::rgb(0.4, 0.8, 1.2));
    assert_eq!(s + Spectrum::grey(1.0), Spectrum::rgb(1.2, 1.4, 1.6));
    assert_eq!(s * Spectrum::rgb(1.0, 0.0, 0.5), Spectrum::rgb(0.2, 0.0, 0.3));
    assert!(!Spectrum::ZERO.is_positive());
    assert!(Spectrum::rgb(0.0, 0.0, 1e-30).is_positive());
    assert_eq!(Channels::Grey.count(), 1);
    assert_eq!(Channels::Rgb.count(), 3);
}

fn unit_square(z: f64, material: u32) -> Patch {
    Patch::quad([v(0., 0., z), v(1., 0., z), v(1., 1., z), v(0., 1., z)], MaterialId(material), O).unwrap()
}

fn two_patch_scene(rho: Spectrum, emission: Spectrum) -> Result<Scene, CoreError> {
    let big = Patch::quad([v(0., 0., 1.), v(0., 2., 1.), v(3., 2., 1.), v(3., 0., 1.)], MaterialId(1), O).unwrap();
    Scene::new(
        "two",
        vec![unit_square(0.0, 0), big],
        vec![Material::new("lamp", Spectrum::ZERO, emission), Material::new("wall", rho, Spectrum::ZERO)],
        vec!["obj".into()],
    )
}

#[test]
fn scene_statistics() {
    let scene = two_patch_scene(Spectrum::rgb(0.3, 0.6, 0.9), Spectrum::grey(5.0)).unwrap();
    assert_eq!(scene.len(), 2);
    assert_relative_eq!(scene.total_area(), 7.0);
    // Area-weighted: (1 · 0 + 6 · 0.6) / 7.
    assert_relative_eq!(scene.mean_reflectivity(), 3.6 / 7.0);
    assert_eq!(scene.max_reflectivity(), 0.9);
    assert_eq!(scene.emitters(), vec![0]);
    assert_eq!(scene.channels(), Channels::Rgb);
    assert_eq!(scene.bounds(), (v(0., 0., 0.), v(3., 2., 1.)));
    assert_relative_eq!(scene.diagonal(), 14f64.sqrt());
    let grey = two_patch_scene(Spectrum::grey(0.5), Spectrum::grey(1.0)).unwrap();
    assert_eq!(grey.channels(), Channels::Grey);
}

#[test]
fn unused_coloured_materials_do_not_make_a_scene_coloured() {
    let scene = Scene::new(
        "one",
        vec![unit_square(0.0, 0)],
        vec![
            Material::new("grey", Spectrum::grey(0.5), Spectrum::ZERO),
            Material::new("red", Spectrum::rgb(0.9, 0.1, 0.1), Spectrum::ZERO),
        ],
        vec!["o".into()],
    )
    .unwrap();
    assert_eq!(scene.channels(), Channels::Grey);
}

#[test]
fn scene_validation_names_the_culprit() {
    let err = two_patch_scene(Spectrum::rgb(0.5, 1.0, 0.5), Spectrum::grey(1.0)).unwrap_err();
    assert!(matches!(&err, CoreError::InvalidReflectivity { material, value } if material == "wall" && *value == 1.0));
    assert!(err.to_string().contains("'wall'"), "{err}");
    let err = two_patch_scene(Spectrum::grey(-0.1), Spectrum::grey(1.0)).unwrap_err();
    assert!(matches!(err, CoreError::InvalidReflectivity { .. }));
    let err = two_patch_scene(Spectrum::grey(f64::NAN), Spectrum::grey(1.0)).unwrap_err();
    assert!(matches!(err, CoreError::InvalidReflectivity { .. }));
    let err = two_patch_scene(Spectrum::grey(0.5), Spectrum::rgb(1.0, -1.0, 0.0)).unwrap_err();
    assert!(matches!(&err, CoreError::InvalidEmission { material, .. } if material == "lamp"));
    let err = two_patch_scene(Spectrum::grey(0.5), Spectrum::grey(f64::INFINITY)).unwrap_err();
    assert!(matches!(err, CoreError::InvalidEmission { .. }));
    let err = Scene::new("none", vec![], vec![], vec![]).unwrap_err();
    assert_eq!(err, CoreError::EmptyScene);
    let err = Scene::new("dangling", vec![unit_square(0.0, 3)], vec![], vec!["o".into()]).unwrap_err();
    assert_eq!(err, CoreError::DanglingReference { patch: 0, what: "material", index: 3, count: 0 });
}

#[test]
fn linear_system_from_scene_is_patch_major() {
    let scene = two_patch_scene(Spectrum::rgb(0.3, 0.6, 0.9), Spectrum::rgb(1.0, 2.0, 3.0)).unwrap();
    let sys = LinearSystem::from_scene(&scene);
    assert_eq!(sys.channels(), Channels::Rgb);
    assert_eq!(sys.len(), 2);
    assert_eq!(sys.areas(), &[1.0, 6.0]);
    assert_eq!(sys.reflectivities(), &[0.0, 0.0, 0.0, 0.3, 0.6, 0.9]);
    assert_eq!(sys.emissions(), &[1.0, 2.0, 3.0, 0.0, 0.0, 0.0]);
    assert_eq!(sys.rho(1, 2), 0.9);
    assert_eq!(sys.e(0, 1), 2.0);

    let grey = two_patch_scene(Spectrum::grey(0.5), Spectrum::grey(4.0)).unwrap();
    let sys = LinearSystem::from_scene(&grey);
    assert_eq!(sys.channels(), Channels::Grey);
    assert_eq!(sys.reflectivities(), &[0.0, 0.5]);
    assert_eq!(sys.emissions(), &[4.0, 0.0]);
}

#[test]
fn linear_system_validates_raw_data() {
    assert!(LinearSystem::new(Channels::Grey, vec![1.0], vec![0.5], vec![1.0]).is_ok());
    assert_eq!(
        LinearSystem::new(Channels::Rgb, vec![1.0], vec![0.5], vec![1.0]).unwrap_err(),
        CoreError::SizeMismatch { what: "reflectivity", expected: 3, found: 1 }
    );
    assert!(matches!(
        LinearSystem::new(Channels::Grey, vec![0.0], vec![0.5], vec![1.0]),
        Err(CoreError::InvalidArea { patch: 0, .. })
    ));
    assert!(matches!(
        LinearSystem::new(Channels::Grey, vec![1.0], vec![1.0], vec![1.0]),
        Err(CoreError::InvalidReflectivity { .. })
    ));
    assert_eq!(LinearSystem::new(Channels::Grey, vec![], vec![], vec![]).unwrap_err(), CoreError::EmptyScene);
}

#[test]
fn dense_columns_serve_columns_of_the_row_major_matrix() {
    let rows = [0.0, 0.25, 0.75, 0.5, 0.0, 0.5, 0.125, 0.875, 0.0];
    let f = DenseColumns::from_rows(3, &rows).unwrap();
    let mut col = vec![f64::NAN; 3];
    f.fill_column(1, &mut col);
    assert_eq!(col, vec![0.25, 0.0, 0.875]);
    assert_eq!(f.get(2, 0), 0.125);
    assert_eq!(f, DenseColumns::from_fn(3, |i, j| rows[i * 3 + j]));
    assert!(f.fill_row(2, &mut col));
    assert_eq!(col, rows[6..9]);
    assert_eq!(
        DenseColumns::from_rows(2, &rows).unwrap_err(),
        CoreError::SizeMismatch { what: "form-factor matrix", expected: 4, found: 9 }
    );
}

#[test]
fn counting_wrapper_counts_columns_across_threads() {
    let f = DenseColumns::from_fn(8, |i, j| (i * 8 + j) as f64);
    let counting = CountingColumns::new(&f);
    std::thread::scope(|s| {
        for t in 0..4 {
            let counting = &counting;
            s.spawn(move || {
                let mut col = vec![0.0; 8];
                for j in 0..5 {
                    counting.fill_column((t + j) % 8, &mut col);
                    assert_eq!(col[3], (3 * 8 + (t + j) % 8) as f64);
                }
            });
        }
    });
    let stats = counting.stats();
    assert_eq!(stats.columns, 20);
    // Time is counted: a source that takes at least 1 ms a column adds at least 1 ms each.
    let slow = CountingColumns::new(Sleepy(&f));
    let mut col = vec![0.0; 8];
    for j in 0..5 {
        slow.fill_column(j, &mut col);
    }
    assert!(slow.stats().seconds >= 0.005, "{:?}", slow.stats());
    // A row counts as a column when the source serves rows, and not at all when it cannot.
    let before = slow.stats().columns;
    assert!(!slow.fill_row(0, &mut col), "Sleepy serves no rows");
    assert_eq!(slow.stats().columns, before);
    counting.reset();
    assert!(counting.fill_row(3, &mut col));
    assert_eq!(col, (24..32).map(|v| v as f64).collect::<Vec<_>>());
    assert_eq!(counting.stats().columns, 1);
    assert_eq!(counting.patch_count(), 8);
    counting.reset();
    assert_eq!(counting.stats(), ColumnStats::default());
}

/// A column source that sleeps 1 ms before each column.
struct Sleepy<'a>(&'a DenseColumns);

impl ColumnSource for Sleepy<'_> {
    fn patch_count(&self) -> usize {
        self.0.patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [f64]) {
        std::thread::sleep(std::time::Duration::from_millis(1));
        self.0.fill_column(j, column);
    }
}
