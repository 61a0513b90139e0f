//! Tests of `SceneTransport`, rays in the scene as a transport sampler: landing frequencies
//! against Howell's closed forms, closed boxes, back faces, uniform origins on any patch shape,
//! and determinism.
//!
//! Statistical tolerances: a landing count over `N` independent rays is binomial, so its
//! frequency has standard error `√(p (1 − p) / N)` with `p` the exact probability; each check
//! allows 4 of them, which a correct sampler exceeds with probability about `6e-5` (normal
//! approximation; the counts here are in the thousands). The rays are drawn from fixed seeds,
//! so a test gives the same numbers on every run.

use super::closed_forms::*;
use super::montecarlo::box_with_inverted_block;
use radiosity_core::{LineTransfers, Material, Real, Scene, Spectrum, TransportSampler, Vec3};
use radiosity_ff::SceneTransport;
use radiosity_ff::ff_point_polygon::point_to_polygon;
use radiosity_geom::{PreparedScene, SceneBuilder, Visibility, load_scene};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// `count` points of `[0, 1)^4` from the stream `seed`.
fn points(seed: u64, count: usize) -> Vec<[Real; 4]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count).map(|_| [rng.random(), rng.random(), rng.random(), rng.random()]).collect()
}

/// The landings of `rays` rays cast from `from`.
fn landings(sampler: &SceneTransport<'_>, from: usize, rays: usize, seed: u64) -> Vec<Option<usize>> {
    points(seed, rays).into_iter().map(|u| sampler.cast(from, u)).collect()
}

/// Asserts that `hits` of `rays` lie within 4 binomial standard errors of probability `p`.
fn assert_binomial(hits: usize, rays: usize, p: Real, what: &str) {
    let frequency = hits as Real / rays as Real;
    let sigma = (p * (1.0 - p) / rays as Real).sqrt();
    assert!((frequency - p).abs() < 4.0 * sigma, "{what}: {frequency} vs {p} (σ {sigma})");
}

#[test]
fn landing_frequencies_match_howells_closed_forms() {
    // One patch per unit square, both directions: a ray from either square lands on the other
    // with probability F (equal areas), else escapes. 10^5 rays: σ ≈ 1.26e-3 (F = 0.1998
    // parallel, 0.2000 perpendicular).
    let rays = 100_000;
    for (scene, exact) in
        [(opposed_squares(1), parallel(1.0, 1.0, 1.0)), (corner(1.0, 1.0, 1.0, 1), perpendicular(1.0, 1.0, 1.0))]
    {
        let vis = Visibility::new(&scene);
        let sampler = SceneTransport::new(&scene, &vis, false);
        assert_eq!(sampler.patch_count(), 2);
        for (from, to) in [(0, 1), (1, 0)] {
            let landed = landings(&sampler, from, rays, from as u64);
            let hits = landed.iter().filter(|&&l| l == Some(to)).count();
            assert_eq!(hits + landed.iter().filter(|l| l.is_none()).count(), rays, "a ray landed on its own patch");
            assert_binomial(hits, rays, exact, scene.name());
        }
        assert_eq!(sampler.row_sum(0), None);
    }
}

#[test]
fn meshed_rectangles_aggregate_to_howells_value() {
    // 3 × 3 patches each (unequal rays per patch area do not matter: equal areas). From a
    // uniformly chosen patch of the first square, the landing frequency on the second is F.
    let m = 3;
    let rays = 90_000;
    let scene = opposed(1.0, 2.0, 0.5, m);
    let vis = Visibility::new(&scene);
    let sampler = SceneTransport::new(&scene, &vis, false);
    let per_patch = rays / (m * m);
    let hits: usize = (0..m * m)
        .map(|from| {
            landings(&sampler, from, per_patch, 10 + from as u64)
                .iter()
                .filter(|l| l.is_some_and(|i| i >= m * m))
                .count()
        })
        .sum();
    // Stratified by patch, the variance is at most that of the binomial with the pooled p.
    assert_binomial(hits, rays, parallel(1.0, 2.0, 0.5), "3 × 3 rectangles");
}

#[test]
fn no_ray_escapes_a_closed_box_and_every_landing_is_a_front_face() {
    // Every wall faces inwards: a ray from a wall meets another wall's front, never its back,
    // so every cast lands, and never on its own patch. The block's faces point outwards.
    for arg in ["furnace:res=2", "furnace:res=2:block=true"] {
        let scene = load_scene(arg).unwrap().scene;
        let vis = Visibility::new(&scene);
        let sampler = SceneTransport::new(&scene, &vis, true);
        for from in 0..scene.len() {
            for (k, u) in points(from as u64, 500).into_iter().enumerate() {
                let landed = sampler.cast(from, u);
                let Some(to) = landed else { panic!("{arg}: ray {k} from {from} was lost") };
                assert_ne!(to, from);
                // The landing is the first hit, on its front side (an independent, brute-force
                // trace of the same ray).
                let (origin, direction) = sampler.ray(from, u);
                let hit = vis.first_hit_brute_force(origin, direction, Some(from)).unwrap();
                assert!(hit.front && hit.patch == to, "{arg}: ray {k} from {from}");
                assert!(scene.patches()[to].normal().dot(direction) < 0.0);
            }
            assert_eq!(sampler.row_sum(from), Some(1.0));
        }
    }
}

#[test]
fn a_back_facing_patch_is_never_landed_on() {
    // The walls' rays that meet the block arrive on its back and are absorbed: they land
    // nowhere (the box is closed, so nothing escapes), and never on the block.
    let scene = box_with_inverted_block();
    let walls = 24;
    let vis = Visibility::new(&scene);
    let sampler = SceneTransport::new(&scene, &vis, false);
    for from in 0..walls {
        let landed = landings(&sampler, from, 1_000, from as u64);
        assert!(landed.iter().all(|l| l.is_none_or(|to| to < walls)), "wall {from} lit the block");
        assert!(landed.iter().any(|l| l.is_none()), "wall {from} never met the block");
    }
    // The block's faces face into it and see only each other's fronts.
    for from in walls..scene.len() {
        assert!(landings(&sampler, from, 1_000, from as u64).iter().all(|l| l.is_some_and(|to| to >= walls)));
    }

    // Opposed squares turned away from each other: nothing lands.
    let flipped = two_rectangles([Vec3::ZERO, Vec3::X, Vec3::Y], [Vec3::new(0.0, 0.0, 1.0), Vec3::X, Vec3::Y], 1);
    let vis = Visibility::new(&flipped);
    let sampler = SceneTransport::new(&flipped, &vis, false);
    assert!(landings(&sampler, 0, 5_000, 0).iter().all(|l| l.is_none()));
    // From the second, rays run away from the first: nothing lands either.
    assert!(landings(&sampler, 1, 5_000, 1).iter().all(|l| l.is_none()));
}

#[test]
fn origins_are_uniform_by_area_on_a_trapezoid() {
    // A trapezoid at z = 0 (facing up) and a unit square at z = 0.5 over its narrow end (facing
    // down). The probability of landing on the square is F_trapezoid→square =
    // (A_square / A_trapezoid) F_square→trapezoid, the latter by a 200 × 200 midpoint rule of
    // Lambert's formula over the square. A bilinear map of the trapezoid would put too many
    // origins at its narrow end, under the square (frequency 0.259 against 0.193). 2·10^5 rays:
    // σ ≈ 8.8e-4.
    let p = |x: Real, y: Real| Vec3::new(x, y, 0.0);
    let trapezoid = [p(0.0, -1.0), p(2.0, -0.2), p(2.0, 0.2), p(0.0, 1.0)];
    let mut b = SceneBuilder::new("trapezoid");
    let grey = b.material(Material::new("grey", Spectrum::grey(0.5), Spectrum::grey(1.0))).unwrap();
    let object = b.object("shapes");
    b.polygon(&trapezoid, grey, object).unwrap();
    let q = |x: Real, y: Real| Vec3::new(x, y, 0.5);
    b.polygon(&[q(1.0, -0.5), q(1.0, 0.5), q(2.0, 0.5), q(2.0, -0.5)], grey, object).unwrap();
    let scene = b.build().unwrap();
    let (shooter, square) = (&scene.patches()[0], &scene.patches()[1]);
    let k = 200;
    let mut square_to_shooter = 0.0;
    for a in 0..k {
        for c in 0..k {
            let x = square.point_at((a as Real + 0.5) / k as Real, (c as Real + 0.5) / k as Real);
            square_to_shooter += point_to_polygon(x, square.normal(), shooter.vertices());
        }
    }
    square_to_shooter /= (k * k) as Real;
    let exact = square.area() / shooter.area() * square_to_shooter;
    let vis = Visibility::new(&scene);
    let sampler = SceneTransport::new(&scene, &vis, false);
    let rays = 200_000;
    let hits = landings(&sampler, 0, rays, 7).iter().filter(|&&l| l == Some(1)).count();
    assert_binomial(hits, rays, exact, "trapezoid");
}

#[test]
fn the_same_point_gives_the_same_landing_whatever_the_threads() {
    let scene = load_scene("furnace:res=2:block=true").unwrap().scene;
    let vis = Visibility::new(&scene);
    let sampler = SceneTransport::new(&scene, &vis, true);
    let u = points(3, 20_000);
    let cast = |threads: usize| -> Vec<Option<usize>> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| u.par_iter().enumerate().map(|(k, &u)| sampler.cast(k % scene.len(), u)).collect())
    };
    let one = cast(1);
    assert_eq!(one, cast(2));
    assert_eq!(one, cast(1));
    let mut batch = vec![None; 100];
    sampler.cast_batch(5, &u[..100], &mut batch);
    assert_eq!(batch, u[..100].iter().map(|&u| sampler.cast(5, u)).collect::<Vec<_>>());
    // Different points land elsewhere.
    assert_ne!(
        one,
        points(4, 20_000).into_iter().enumerate().map(|(k, u)| sampler.cast(k % scene.len(), u)).collect::<Vec<_>>()
    );
}

#[test]
fn a_prepared_scene_is_closed_when_its_analysis_says_so() {
    // The furnace is closed; the Cornell box is open at the front.
    for (arg, closed) in [("furnace:res=2", true), ("cornell:res=2", false)] {
        let prepared = PreparedScene::load(arg).unwrap();
        assert_eq!(prepared.analysis.closure.value.is_closed(), closed, "{arg}");
        let sampler = SceneTransport::from_prepared(&prepared).unwrap();
        assert_eq!(sampler.is_closed(), closed);
        assert_eq!(sampler.patch_count(), prepared.scene().len());
        assert_eq!(sampler.row_sum(0), closed.then_some(1.0), "{arg}");
    }
}

#[test]
fn the_cost_names_the_bvh() {
    let scene = load_scene("furnace:res=2").unwrap().scene;
    let vis = Visibility::new(&scene);
    let cost = SceneTransport::new(&scene, &vis, true).cost();
    assert_eq!(cost.ray, format!("one ray through a BVH of {} triangles (exact f64 tests)", vis.triangle_count()));
    assert!(!cost.constant);
}

/// The transfers of `lines` global lines drawn from the stream `seed`, line by line, with the
/// rays each cost.
fn global_lines(sampler: &SceneTransport<'_>, lines: usize, seed: u64) -> Vec<LineTransfers> {
    points(seed, lines)
        .into_iter()
        .map(|u| {
            let mut line = LineTransfers::default();
            assert!(sampler.global_line(u, &mut line));
            line
        })
        .collect()
}

/// Asserts that the lines' transfers from `from` to `to` (patch sets), times the area each
/// stands for, per line, lie within 4 standard errors of `exact`, when each line gives at most
/// one such transfer (the count per line is then a Bernoulli draw).
fn assert_line_estimate(lines: &[LineTransfers], from: &[usize], to: &[usize], exact: Real, what: &str) {
    let w = lines[0].area;
    let counts: Vec<usize> = lines
        .iter()
        .map(|line| line.transfers.iter().filter(|(a, b)| from.contains(a) && to.contains(b)).count())
        .collect();
    assert!(counts.iter().all(|&c| c <= 1), "{what}: a line crossed a set twice");
    let hits = counts.iter().sum::<usize>();
    let p = exact / w;
    assert!(p < 1.0, "{what}: W = {w} is below A F = {exact}");
    let l = lines.len() as Real;
    let estimate = w * hits as Real / l;
    let sigma = w * (p * (1.0 - p) / l).sqrt();
    assert!((estimate - exact).abs() < 4.0 * sigma, "{what}: {estimate} vs {exact} (σ {sigma})");
}

#[test]
fn global_lines_match_howells_closed_forms() {
    // Each transfer stands for W = 2π R² (R: half the box's diagonal); over L lines, the
    // transfers from a to b times W / L estimate A_a F_ab. Unit squares (R² = 3/4): a line
    // gives the transfer with probability A F / W ≈ 0.042; 2·10^5 lines: σ ≈ 1.1% of A F.
    let lines = 200_000;
    for (scene, exact) in
        [(opposed_squares(1), parallel(1.0, 1.0, 1.0)), (corner(1.0, 1.0, 1.0, 1), perpendicular(1.0, 1.0, 1.0))]
    {
        let vis = Visibility::new(&scene);
        let sampler = SceneTransport::new(&scene, &vis, false);
        let (lo, hi) = scene.bounds();
        assert!((sampler.line_area() - std::f64::consts::TAU * (hi - lo).length_squared() / 4.0).abs() < 1e-12);
        let drawn = global_lines(&sampler, lines, 21);
        assert_line_estimate(&drawn, &[0], &[1], exact, scene.name());
        assert_line_estimate(&drawn, &[1], &[0], exact, scene.name());
        // A line gives both directions or neither; its rays are its crossings and one miss.
        for line in &drawn {
            assert_eq!(line.area, sampler.line_area());
            assert!(
                line.transfers.is_empty() || line.transfers == [(0, 1), (1, 0)] || line.transfers == [(1, 0), (0, 1)]
            );
            assert!((1..=3).contains(&line.rays));
        }
    }
    // 3 × 3 patches on rectangles 1 × 2 at distance 0.5: the sets exchange A F = 2 F(1, 2, 0.5).
    let m = 3;
    let scene = opposed(1.0, 2.0, 0.5, m);
    let vis = Visibility::new(&scene);
    let sampler = SceneTransport::new(&scene, &vis, false);
    let drawn = global_lines(&sampler, lines, 22);
    let (first, second): (Vec<usize>, Vec<usize>) = (0..2 * m * m).partition(|&i| i < m * m);
    assert_line_estimate(&drawn, &first, &second, 2.0 * parallel(1.0, 2.0, 0.5), "3 × 3 rectangles");
}

#[test]
fn global_lines_through_a_closed_box_give_its_area() {
    // Every line that meets the box (convex, facing inwards) enters through a wall's back and
    // leaves through another's front: two transfers, three rays; a line that misses it costs
    // one ray. By Cauchy's formula a line meets the box with probability q = (S/4) / (π R²),
    // so 2 q W = S, the total area (Σ_a A_a Σ_b F_ab with closed rows). The count of lines
    // that meet it is binomial: 10^5 lines, 4 standard errors 2 W √(q (1 − q) / L).
    let scene = load_scene("furnace:res=2").unwrap().scene;
    let vis = Visibility::new(&scene);
    let sampler = SceneTransport::new(&scene, &vis, true);
    let lines = 100_000;
    let drawn = global_lines(&sampler, lines, 23);
    let mut met = 0;
    for line in &drawn {
        match line.transfers.len() {
            0 => assert_eq!(line.rays, 1),
            2 => {
                assert_eq!(line.rays, 3);
                met += 1;
            }
            other => panic!("{other} transfers on one line"),
        }
    }
    let (w, area, l) = (sampler.line_area(), scene.total_area(), lines as Real);
    let q = area / (2.0 * w);
    let estimate = 2.0 * w * met as Real / l;
    let sigma = 2.0 * w * (q * (1.0 - q) / l).sqrt();
    assert!((estimate - area).abs() < 4.0 * sigma, "{estimate} vs {area} (σ {sigma})");
}

#[test]
fn global_lines_join_only_fronts_that_face_each_other() {
    // Furnace with a block facing outwards: every transfer (a, b) pushed first runs along the
    // line from a's front to b's front, and the transfers come in pairs.
    let scene = load_scene("furnace:res=2:block=true").unwrap().scene;
    let vis = Visibility::new(&scene);
    let sampler = SceneTransport::new(&scene, &vis, true);
    let normal = |i: usize| scene.patches()[i].normal();
    let mut block = 0;
    for u in points(24, 20_000) {
        let mut line = LineTransfers::default();
        sampler.global_line(u, &mut line);
        let (_, d) = sampler.line(u);
        assert_eq!(line.transfers.len() % 2, 0);
        assert!(line.rays as usize > line.transfers.len() / 2);
        for pair in line.transfers.chunks(2) {
            let [(a, b), back] = [pair[0], pair[1]];
            assert_eq!(back, (b, a));
            assert!(normal(a).dot(d) > 0.0 && normal(b).dot(d) < 0.0, "{a} → {b} along {d}");
        }
        block += usize::from(line.transfers.len() == 4);
    }
    assert!(block > 0, "no line met the block");

    // The walls see the back of an inverted block: no line joins a wall and the block.
    let scene = box_with_inverted_block();
    let walls = 24;
    let vis = Visibility::new(&scene);
    let sampler = SceneTransport::new(&scene, &vis, false);
    let drawn = global_lines(&sampler, 20_000, 25);
    assert!(drawn.iter().flat_map(|l| &l.transfers).all(|&(a, b)| (a < walls) == (b < walls)));
    assert!(drawn.iter().flat_map(|l| &l.transfers).any(|&(a, _)| a >= walls), "no line joined the block's faces");
    // Squares turned away from each other: no line joins them.
    let flipped = two_rectangles([Vec3::ZERO, Vec3::X, Vec3::Y], [Vec3::new(0.0, 0.0, 1.0), Vec3::X, Vec3::Y], 1);
    let vis = Visibility::new(&flipped);
    let sampler = SceneTransport::new(&flipped, &vis, false);
    assert!(global_lines(&sampler, 20_000, 26).iter().all(|l| l.transfers.is_empty()));
}

#[test]
fn the_same_point_gives_the_same_line() {
    let scene = load_scene("furnace:res=2:block=true").unwrap().scene;
    let vis = Visibility::new(&scene);
    let sampler = SceneTransport::new(&scene, &vis, true);
    let mut line = LineTransfers { transfers: vec![(7, 7)], area: 0.0, rays: 99 };
    let drawn = global_lines(&sampler, 2_000, 27);
    for (u, expected) in points(27, 2_000).into_iter().zip(&drawn) {
        sampler.global_line(u, &mut line);
        assert_eq!(&line, expected);
    }
    assert_ne!(drawn, global_lines(&sampler, 2_000, 28));
}

/// Unit squares facing each other at distance 1 (patches 0, below, and 1, above), and patch 2
/// on patch 1, back to back with it and facing up: a thin wall's two faces, coincident.
/// `start` turns patch 2's vertex list, so that its fan triangles differ from patch 1's. The
/// whole is turned and moved off the axes, so that the two faces' ray parameters differ in
/// rounding.
fn squares_under_a_thin_wall(start: usize) -> Scene {
    let mut b = SceneBuilder::new("thin wall");
    let grey = b.material(Material::new("grey", Spectrum::grey(0.5), Spectrum::grey(1.0))).unwrap();
    let object = b.object("squares");
    // Turned by 0.7 about z, then by 0.4 about x (Rodrigues' formula about each axis).
    let turn = |v: Vec3, axis: Vec3, angle: Real| {
        v * angle.cos() + axis.cross(v) * angle.sin() + axis * axis.dot(v) * (1.0 - angle.cos())
    };
    let p = |x: Real, y: Real, z: Real| {
        turn(turn(Vec3::new(x, y, z), Vec3::Z, 0.7), Vec3::X, 0.4) + Vec3::new(0.3, -1.7, 2.9)
    };
    b.polygon(&[p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(1.0, 1.0, 0.0), p(0.0, 1.0, 0.0)], grey, object).unwrap();
    b.polygon(&[p(0.0, 0.0, 1.0), p(0.0, 1.0, 1.0), p(1.0, 1.0, 1.0), p(1.0, 0.0, 1.0)], grey, object).unwrap();
    let mut up = [p(0.0, 0.0, 1.0), p(1.0, 0.0, 1.0), p(1.0, 1.0, 1.0), p(0.0, 1.0, 1.0)];
    up.rotate_left(start);
    b.polygon(&up, grey, object).unwrap();
    b.build().unwrap()
}

#[test]
fn a_thin_walls_room_side_receives_whichever_face_rounding_puts_first() {
    // Rays from the lower square meet both faces of the wall at parameters equal up to
    // rounding; they land on its lower face with probability F (Howell), never on the upper
    // one. The precondition: first_hit alone returns the upper face's back for a good share of
    // them, so the test bites. 10^5 rays: σ ≈ 1.26e-3.
    let rays = 100_000;
    let exact = parallel(1.0, 1.0, 1.0);
    for start in [0, 1] {
        let scene = squares_under_a_thin_wall(start);
        let vis = Visibility::new(&scene);
        let sampler = SceneTransport::new(&scene, &vis, false);
        let u = points(30 + start as u64, rays);
        let upper_first = u
            .iter()
            .filter(|&&u| {
                let (origin, direction) = sampler.ray(0, u);
                vis.first_hit(origin, direction, Some(0)).is_some_and(|h| h.patch == 2)
            })
            .count();
        assert!(upper_first > rays / 50, "start {start}: the back face came first {upper_first} times");
        let landed: Vec<Option<usize>> = u.iter().map(|&u| sampler.cast(0, u)).collect();
        assert!(landed.iter().all(|&l| l != Some(2)));
        assert_binomial(landed.iter().filter(|&&l| l == Some(1)).count(), rays, exact, "thin wall");
        // The upper face looks at the sky, and the lower one at the square below.
        assert!(landings(&sampler, 2, 5_000, 1).iter().all(|l| l.is_none()));
        assert_binomial(landings(&sampler, 1, rays, 2).iter().filter(|&&l| l == Some(0)).count(), rays, exact, "down");

        // Global lines join the square and the wall's lower face, and nothing else.
        let drawn = global_lines(&sampler, 200_000, 31);
        assert!(drawn.iter().flat_map(|l| &l.transfers).all(|&(a, b)| a != 2 && b != 2));
        assert_line_estimate(&drawn, &[0], &[1], exact, "thin wall, lines");
    }
}
