//! Integration tests of radiosity-eval: `--ff matrix` assembly, reference solutions against closed forms (furnace,
//! two facing patches, the unit cube), the certified bound against true errors, metrics on
//! hand-made vectors, tables under snapshot tests, pictures and glTF files of solved scenes,
//! and the path tracer against closed forms and beside the discrete solution.

mod backends;
mod bench_peer;
mod examples;
mod gltf_export;
mod lab;
mod metrics;
mod node_shooting;
mod operator_distance;
mod path_trace;
mod plot;
mod reference;
mod render;
mod sampled;
mod scenes;
mod shading;
mod table;

use radiosity_core::{Channels, DenseColumns, LinearSystem};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Howell C-11: parallel, directly opposed unit squares at distance 1 (X = Y = 1).
fn ff_opposite_unit_squares() -> f64 {
    let (x, y) = (1.0_f64, 1.0_f64);
    let (x2, y2) = (x * x, y * y);
    2.0 / (std::f64::consts::PI * x * y)
        * ((((1.0 + x2) * (1.0 + y2)) / (1.0 + x2 + y2)).sqrt().ln()
            + x * (1.0 + y2).sqrt() * (x / (1.0 + y2).sqrt()).atan()
            + y * (1.0 + x2).sqrt() * (y / (1.0 + x2).sqrt()).atan()
            - x * x.atan()
            - y * y.atan())
}

/// Howell C-14: perpendicular unit squares sharing an edge (H = W = 1).
fn ff_adjacent_unit_squares() -> f64 {
    let (h, w) = (1.0_f64, 1.0_f64);
    let (h2, w2) = (h * h, w * w);
    let s = h2 + w2;
    let log_arg = (1.0 + w2) * (1.0 + h2) / (1.0 + s)
        * (w2 * (1.0 + s) / ((1.0 + w2) * s)).powf(w2)
        * (h2 * (1.0 + s) / ((1.0 + h2) * s)).powf(h2);
    1.0 / (std::f64::consts::PI * w)
        * (w * (1.0 / w).atan() + h * (1.0 / h).atan() - s.sqrt() * (1.0 / s.sqrt()).atan() + 0.25 * log_arg.ln())
}

/// The unit cube, one patch per face: 0 top, 1 bottom, then sides (2, 3) and (4, 5) facing
/// each other.
fn cube_form_factors() -> DenseColumns {
    let (opposite, adjacent) = (ff_opposite_unit_squares(), ff_adjacent_unit_squares());
    DenseColumns::from_fn(6, |i, j| {
        if i == j {
            0.0
        } else if i / 2 == j / 2 {
            opposite
        } else {
            adjacent
        }
    })
}

/// A random enclosure-like system: areas in [0.5, 2], `F_ij = G_ij / A_i` with `G`
/// symmetric (so reciprocity holds exactly up to round-off), scaled so the largest row sums
/// to `closure`; RGB reflectivities in `[0, rho_max]`, a few emitters.
fn random_system(n: usize, seed: u64, closure: f64, rho_max: f64) -> (LinearSystem, DenseColumns) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let area: Vec<f64> = (0..n).map(|_| 0.5 + 1.5 * rng.random::<f64>()).collect();
    let mut g = vec![0.0; n * n];
    for i in 0..n {
        for j in i + 1..n {
            let v = rng.random::<f64>();
            g[i * n + j] = v;
            g[j * n + i] = v;
        }
    }
    let max_row = (0..n).map(|i| g[i * n..(i + 1) * n].iter().sum::<f64>() / area[i]).fold(0.0, f64::max);
    let rows: Vec<f64> = (0..n * n).map(|idx| g[idx] / area[idx / n] / max_row * closure).collect();
    let f = DenseColumns::from_rows(n, &rows).unwrap();
    let rho: Vec<f64> = (0..3 * n).map(|_| rho_max * rng.random::<f64>()).collect();
    let e: Vec<f64> = (0..3 * n).map(|idx| if (idx / 3) % 7 == 0 { 1.0 + (idx % 3) as f64 } else { 0.0 }).collect();
    (LinearSystem::new(Channels::Rgb, area, rho, e).unwrap(), f)
}
