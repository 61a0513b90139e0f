//! Each BVH preset's build seconds beside the rays per second its tree traces, on one scene.
//!
//! `cargo run --release -p radiosity-geom --example bvh_presets -- [SCENE] [RAYS_PER_PATCH]`
//! (default `office:size=0.0158`, 956,319 patches, and 4 rays a patch): every preset of
//! [`BvhBuild`] builds the scene's BVH on every thread, then traces the same cosine-weighted
//! rays from seeded points of every patch, as the closure probe does, on every thread. A
//! build pays once; its rays are paid by every probe, shadow ray and stochastic iteration after.

use radiosity_core::Real;
use radiosity_core::math::cosine_direction;
use radiosity_geom::{BvhBuild, Visibility, load_scene};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let arg = args.next().unwrap_or_else(|| "office:size=0.0158".into());
    let per_patch: usize = args.next().map_or(Ok(4), |a| a.parse())?;
    let scene = load_scene(&arg)?.scene;
    let n = scene.len();
    println!("{arg}: {n} patches, {} rays a patch, {} threads", per_patch, rayon::current_num_threads());
    println!("| preset | build (s) | rays/s | hits |");
    println!("|---|--:|--:|--:|");
    for build in BvhBuild::ALL {
        let start = Instant::now();
        let visibility = Visibility::with_build(&scene, build);
        let seconds = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let hits: usize = (0..n)
            .into_par_iter()
            .map(|i| {
                let patch = &scene.patches()[i];
                let mut rng = ChaCha8Rng::seed_from_u64(i as u64);
                (0..per_patch)
                    .filter(|_| {
                        let x = patch.point_at(rng.random::<Real>(), rng.random::<Real>());
                        let d = cosine_direction(patch.normal(), rng.random::<Real>(), rng.random::<Real>());
                        visibility.first_hit(x, d, Some(i)).is_some()
                    })
                    .count()
            })
            .sum();
        let rate = (n * per_patch) as f64 / start.elapsed().as_secs_f64();
        println!("| {} | {seconds:.2} | {:.3e} | {hits} |", build.name(), rate);
    }
    Ok(())
}
