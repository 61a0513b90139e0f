//! Tests of subdivision: counts, preserved area, orientation and reproducibility.

use approx::assert_relative_eq;
use radiosity_core::{Material, Patch, PatchShape, Spectrum, Vec3};
use radiosity_geom::SceneBuilder;
use radiosity_geom::mesh::{BoxFace, Facing, divisions, subdivide_quad, subdivide_triangle};

fn v(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x, y, z)
}

fn builder() -> (SceneBuilder, radiosity_core::MaterialId, radiosity_core::ObjectId) {
    let mut b = SceneBuilder::new("test");
    let m = b.material(Material::new("m", Spectrum::grey(0.5), Spectrum::ZERO)).unwrap();
    let o = b.object("o");
    (b, m, o)
}

#[test]
fn divisions_round_up_but_not_on_exact_multiples() {
    assert_eq!(divisions(1.0, 0.25), 4);
    assert_eq!(divisions(1.0, 0.1), 10);
    assert_eq!(divisions(1.0, 0.3), 4);
    assert_eq!(divisions(0.01, 1.0), 1);
    assert_eq!(divisions(5.0, 0.0), 1);
    assert_eq!(divisions(5.0, f64::INFINITY), 1);
}

#[test]
fn quad_grid_tiles_the_quad() {
    let quad = [v(0., 0., 0.), v(4., 0., 0.), v(3., 0., 2.), v(1., 0., 2.)];
    let whole = Patch::quad(quad, Default::default(), Default::default());
    // Winding (x then z at y = 0) gives a normal along -y.
    let whole = whole.unwrap();
    let cells = subdivide_quad(quad, 5, 3);
    assert_eq!(cells.len(), 15);
    let mut area = 0.0;
    for c in &cells {
        let p = Patch::quad(*c, Default::default(), Default::default()).unwrap();
        assert_relative_eq!(p.normal(), whole.normal(), epsilon = 1e-14);
        area += p.area();
    }
    // Trapezoid: (4 + 2) / 2 · 2.
    assert_relative_eq!(area, 6.0, max_relative = 1e-14);
}

#[test]
fn triangle_grid_has_k_squared_similar_triangles() {
    let tri = [v(0., 0., 0.), v(3., 0., 0.), v(0., 0., -3.)];
    for k in 1..=6 {
        let tris = subdivide_triangle(tri, k);
        assert_eq!(tris.len(), k * k);
        let mut area = 0.0;
        for t in &tris {
            let p = Patch::triangle(*t, Default::default(), Default::default()).unwrap();
            assert_relative_eq!(p.normal(), v(0., 1., 0.), epsilon = 1e-14);
            assert_relative_eq!(p.area(), 4.5 / (k * k) as f64, max_relative = 1e-12);
            area += p.area();
        }
        assert_relative_eq!(area, 4.5, max_relative = 1e-13);
    }
}

#[test]
fn sized_subdivision_bounds_edge_length() {
    let (mut b, m, o) = builder();
    b.quad_sized([v(0., 0., 0.), v(1., 0., 0.), v(1., 2.5, 0.), v(0., 2.5, 0.)], 0.3, m, o).unwrap();
    // ceil(1 / 0.3) = 4 by ceil(2.5 / 0.3) = 9.
    assert_eq!(b.patch_count(), 36);
    b.triangle_sized([v(0., 0., 1.), v(1., 0., 1.), v(0., 1., 1.)], 0.5, m, o).unwrap();
    // Longest edge sqrt 2 = 1.414: ceil(1.414 / 0.5) = 3, so 9 triangles.
    assert_eq!(b.patch_count(), 45);
    let scene = b.build().unwrap();
    assert_relative_eq!(scene.total_area(), 2.5 + 0.5, max_relative = 1e-13);
    for p in scene.patches() {
        let v = p.vertices();
        for i in 0..v.len() {
            assert!((v[(i + 1) % v.len()] - v[i]).length() <= 0.5 * 2f64.sqrt() + 1e-12);
        }
    }
}

#[test]
fn non_planar_quads_become_triangles() {
    let (mut b, m, o) = builder();
    let bent = [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.2), v(0., 1., 0.)];
    b.quad_grid(bent, 2, 2, m, o).unwrap();
    let scene = b.build().unwrap();
    assert_eq!(scene.len(), 8);
    assert!(scene.patches().iter().all(|p| p.shape() == PatchShape::Triangle));
    // Split along the shorter diagonal: |v3 - v1|² = 2 < |v2 - v0|² = 2.04, so v1-v3.
    let t1 = 0.5 * (bent[1] - bent[0]).cross(bent[3] - bent[0]).length();
    let t2 = 0.5 * (bent[2] - bent[1]).cross(bent[3] - bent[1]).length();
    assert_relative_eq!(scene.total_area(), t1 + t2, max_relative = 1e-13);
}

#[test]
fn box_faces_point_the_right_way() {
    let (lo, hi) = (v(-1., 0., 2.), v(1., 3., 5.));
    let centre = (lo + hi) * 0.5;
    for (facing, sign) in [(Facing::Outward, 1.0), (Facing::Inward, -1.0)] {
        let (mut b, m, o) = builder();
        b.axis_box([lo, hi], &BoxFace::ALL, facing, 0.7, m, o).unwrap();
        let scene = b.build().unwrap();
        for p in scene.patches() {
            assert!(sign * p.normal().dot(p.centroid() - centre) > 0.0);
        }
        // 2 · 3 + 2 · 3 + 3 · 3 faces worth of area: 2(2·3 + 2·3 + 3·3) = 42.
        assert_relative_eq!(scene.total_area(), 42.0, max_relative = 1e-13);
    }
}

#[test]
fn meshing_is_reproducible_to_the_patch() {
    let build = || {
        let (mut b, m, o) = builder();
        b.axis_box([v(0., 0., 0.), v(1., 2., 3.)], &BoxFace::ALL, Facing::Inward, 0.35, m, o).unwrap();
        b.triangle_sized([v(0., 0., 0.), v(2., 0., 0.), v(0., 2., 1.)], 0.3, m, o).unwrap();
        b.build().unwrap()
    };
    let (a, b) = (build(), build());
    assert_eq!(a.patches(), b.patches());
}
