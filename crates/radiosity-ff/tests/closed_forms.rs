//! Howell's closed forms for rectangle pairs (Howell, *A Catalog of Radiation Heat Transfer
//! Configuration Factors*, cases C-11 and C-14), and test scenes made of meshed rectangles.

use radiosity_core::{ColumnSource, Material, Real, Scene, Spectrum, Vec3};

use radiosity_geom::SceneBuilder;
use std::f64::consts::PI;

/// Parallel, directly opposed rectangles `a × b` at distance `c` (C-11).
pub fn parallel(a: Real, b: Real, c: Real) -> Real {
    let (x, y) = (a / c, b / c);
    let (x2, y2) = (x * x, y * y);
    2.0 / (PI * x * y)
        * (((1.0 + x2) * (1.0 + y2) / (1.0 + x2 + y2)).sqrt().ln()
            + x * (1.0 + y2).sqrt() * (x / (1.0 + y2).sqrt()).atan()
            + y * (1.0 + x2).sqrt() * (y / (1.0 + x2).sqrt()).atan()
            - x * x.atan()
            - y * y.atan())
}

/// Perpendicular rectangles sharing an edge of length `l`: from the one of width `w` to the
/// one of height `h` (C-14).
pub fn perpendicular(l: Real, w: Real, h: Real) -> Real {
    let (hh, ww) = (h / l, w / l);
    let (h2, w2) = (hh * hh, ww * ww);
    let s = h2 + w2;
    let log = ((1.0 + w2) * (1.0 + h2) / (1.0 + s)).ln()
        + w2 * (w2 * (1.0 + s) / ((1.0 + w2) * s)).ln()
        + h2 * (h2 * (1.0 + s) / ((1.0 + h2) * s)).ln();
    (ww * (1.0 / ww).atan() + hh * (1.0 / hh).atan() - s.sqrt() * (1.0 / s.sqrt()).atan() + 0.25 * log) / (PI * ww)
}

/// Two rectangles meshed `m × m`: `first` (patches `0..m²`) and `second` (`m²..2m²`), each
/// given by an origin and two edge vectors, its normal along `u × v`.
pub fn two_rectangles(first: [Vec3; 3], second: [Vec3; 3], m: usize) -> Scene {
    let mut b = SceneBuilder::new("rectangles");
    let grey = b.material(Material::new("grey", Spectrum::grey(0.5), Spectrum::grey(1.0))).unwrap();
    for (k, [o, u, v]) in [first, second].into_iter().enumerate() {
        let object = b.object(format!("rectangle {k}"));
        b.quad_grid([o, o + u, o + u + v, o + v], m, m, grey, object).unwrap();
    }
    b.build().unwrap()
}

/// `F_{S1→S2} = Σ_{i∈S1} Σ_{j∈S2} A_i F_ij / A_{S1}` from columns of `source`, with S1 the
/// first `m²` patches and S2 the rest.
pub fn aggregate(scene: &Scene, source: &impl ColumnSource, m: usize) -> Real {
    let n = scene.len();
    let mut column = vec![0.0; n];
    let mut flux = 0.0;
    for j in m * m..n {
        source.fill_column(j, &mut column);
        flux += (0..m * m).map(|i| scene.patches()[i].area() * column[i]).sum::<Real>();
    }
    flux / (0..m * m).map(|i| scene.patches()[i].area()).sum::<Real>()
}

/// Unit squares at distance 1, facing each other.
pub fn opposed_squares(m: usize) -> Scene {
    opposed(1.0, 1.0, 1.0, m)
}

/// Rectangles `a × b` at distance `c`, facing each other.
pub fn opposed(a: Real, b: Real, c: Real, m: usize) -> Scene {
    two_rectangles(
        [Vec3::ZERO, Vec3::new(a, 0.0, 0.0), Vec3::new(0.0, b, 0.0)],
        [Vec3::new(0.0, 0.0, c), Vec3::new(0.0, b, 0.0), Vec3::new(a, 0.0, 0.0)],
        m,
    )
}

/// Perpendicular rectangles sharing the edge of length `l` along x: the first of width `w`
/// in the floor (facing up), the second of height `h` standing on it (facing the floor's side).
pub fn corner(l: Real, w: Real, h: Real, m: usize) -> Scene {
    two_rectangles(
        [Vec3::ZERO, Vec3::new(0.0, 0.0, w), Vec3::new(l, 0.0, 0.0)],
        [Vec3::ZERO, Vec3::new(l, 0.0, 0.0), Vec3::new(0.0, h, 0.0)],
        m,
    )
}

/// Every column of `source`, computed inside a rayon pool of `threads` threads (backends that
/// parallelise inside a column use that pool).
pub fn all_columns(source: &impl ColumnSource, threads: usize) -> Vec<Vec<Real>> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let n = source.patch_count();
    pool.install(|| {
        (0..n)
            .map(|j| {
                let mut column = vec![0.0; n];
                source.fill_column(j, &mut column);
                column
            })
            .collect()
    })
}

/// Checks that `source` gives the same columns on 1 and 2 rayon threads and from plain
/// threads computing them concurrently in reverse order; returns the columns.
pub fn assert_thread_independent(source: &impl ColumnSource) -> Vec<Vec<Real>> {
    let one = all_columns(source, 1);
    assert_eq!(one, all_columns(source, 2));
    let n = source.patch_count();
    let mut reversed = vec![Vec::new(); n];
    std::thread::scope(|s| {
        for (j, slot) in reversed.iter_mut().enumerate().rev() {
            s.spawn(move || {
                *slot = vec![0.0; n];
                source.fill_column(j, slot);
            });
        }
    });
    assert_eq!(one, reversed);
    one
}

#[test]
fn the_closed_forms_give_the_published_values() {
    assert!((parallel(1.0, 1.0, 1.0) - 0.1998249).abs() < 5e-8);
    assert!((perpendicular(1.0, 1.0, 1.0) - 0.2000438).abs() < 5e-8);
}

#[test]
fn documented_defaults_are_the_defaults() {
    use radiosity_ff::BackendSpec;
    use radiosity_ff::builtins::{ANALYTIC_PARAMS, HEMICUBE_PARAMS, MATRIX_PARAMS, MONTECARLO_PARAMS};
    for (name, docs) in [
        ("analytic", ANALYTIC_PARAMS),
        ("hemicube", HEMICUBE_PARAMS),
        ("montecarlo", MONTECARLO_PARAMS),
        ("matrix", MATRIX_PARAMS),
    ] {
        let bare = BackendSpec::parse(name).unwrap();
        for d in docs {
            let explicit = BackendSpec::parse(&format!("{name}:{}={}", d.key, d.default)).unwrap();
            assert_eq!(explicit, bare, "{name}:{}={}", d.key, d.default);
        }
    }
}

#[test]
fn bad_backend_arguments_are_clear_errors() {
    use radiosity_ff::BackendSpec;
    let err = |arg: &str| BackendSpec::parse(arg).unwrap_err().to_string();
    let e = err("radiance");
    assert!(
        e.contains("unknown form-factor backend 'radiance'")
            && e.contains("analytic, hemicube, montecarlo, hierarchical, matrix"),
        "{e}"
    );
    let e = err("analytic:order=0");
    assert!(e.contains("form-factor backend 'analytic'") && e.contains("order=0"), "{e}");
    let e = err("analytic:tol=0");
    assert!(e.contains("tol=0"), "{e}");
    let e = err("hemicube:res=33");
    assert!(e.contains("res=33") && e.contains("even"), "{e}");
    let e = err("montecarlo:samples=5");
    assert!(e.contains("no parameter 'samples'") && e.contains("rays, seed"), "{e}");
    let e = err("matrix:of=matrix");
    assert!(e.contains("matrix"), "{e}");
    let e = err("matrix:of=hemicube:order=3");
    assert!(e.contains("form-factor backend 'hemicube'") && e.contains("no parameter 'order'"), "{e}");
    assert_eq!(
        BackendSpec::parse("hierarchical").unwrap().canonical(),
        "hierarchical:eps=3e-3:shadows=0.03:rays=14:trust=1.5:budget=512:order=8:tol=1e-3:seed=0:oracle=flux:floor=0.1:passes=1:closure=true"
    );
    // The near pairs' quadrature is the analytic backend's, with its bounds.
    assert_eq!(
        BackendSpec::parse("hierarchical:order=2:tol=0.1").unwrap().canonical(),
        "hierarchical:eps=3e-3:shadows=0.03:rays=14:trust=1.5:budget=512:order=2:tol=1e-1:seed=0:oracle=flux:floor=0.1:passes=1:closure=true"
    );
    let e = err("hierarchical:order=33");
    assert!(e.contains("form-factor backend 'hierarchical'") && e.contains("order=33"), "{e}");
    let e = err("hierarchical:trust=0");
    assert!(e.contains("trust=0") && e.contains("(0, 4096]"), "{e}");
    let e = err("hierarchical:tol=2");
    assert!(e.contains("tol=2") && e.contains("(0, 1]"), "{e}");
    assert_eq!(
        BackendSpec::parse("matrix:of=hemicube:res=64").unwrap().canonical(),
        "matrix:of=hemicube:rebalance=false:res=64:seed=0"
    );
}
