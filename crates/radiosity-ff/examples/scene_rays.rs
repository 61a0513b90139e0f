//! Rays per second of [`SceneTransport`] on a scene: `cast` on one thread and on a rayon pool,
//! the same rays through the BVH with obvhs's `f32` triangle test ([`RawTracer`], the bench's
//! ray-tracing limit), global lines, and the time to load the scene and build its BVH.
//!
//! `cargo run --release -p radiosity-ff --example scene_rays -- [SCENE] [RAYS] [THREADS]`
//!
//! Defaults: `mgf/salon/classroom.mgf` (from the third-party scenes folder,
//! `RADIOSITY_SCENES`), `2000000` rays, 2 threads. Ray `k` leaves patch `k mod n` with a
//! ChaCha8 point drawn beforehand, so drawing is not timed. Rates are given per second on the
//! CPU (run time from Linux's `schedstat` files, where they exist), which other processes
//! sharing the cores do not inflate, and per wall second.
//!
//! [`RawTracer`]: radiosity_geom::visibility::RawTracer

use radiosity_core::{LineTransfers, Real, TransportSampler, Vec3};
use radiosity_ff::SceneTransport;
use radiosity_geom::PreparedScene;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::error::Error;
use std::hint::black_box;
use std::time::Instant;

/// Time on the CPU in seconds from a `schedstat` file, where Linux has one.
fn schedstat_seconds(path: &std::path::Path) -> Option<f64> {
    let stat = std::fs::read_to_string(path).ok()?;
    Some(stat.split_whitespace().next()?.parse::<f64>().ok()? * 1e-9)
}

/// This thread's time on the CPU.
fn thread_cpu_seconds() -> Option<f64> {
    schedstat_seconds("/proc/thread-self/schedstat".as_ref())
}

/// The time on the CPU of this process's live threads, summed.
fn process_cpu_seconds() -> Option<f64> {
    let tasks = std::fs::read_dir("/proc/self/task").ok()?;
    tasks.map(|task| schedstat_seconds(&task.ok()?.path().join("schedstat"))).sum()
}

/// Wall and (where known) on-CPU seconds of a run: this thread's, and all threads'.
struct Seconds {
    wall: f64,
    cpu: Option<f64>,
    all_threads: Option<f64>,
}

impl Seconds {
    /// `count` items per second: on this thread's CPU time, then by the wall clock.
    fn rate(&self, count: usize, unit: &str) -> String {
        let per = |s: f64| count as f64 / s / 1e6;
        match self.cpu {
            Some(cpu) => format!("{:.3} {unit}/s on the CPU ({:.3} by the wall clock)", per(cpu), per(self.wall)),
            None => format!("{:.3} {unit}/s by the wall clock", per(self.wall)),
        }
    }

    /// This thread's CPU time where known, else the wall time.
    fn best(&self) -> f64 {
        self.cpu.unwrap_or(self.wall)
    }
}

/// Runs `f` and returns its result with its seconds.
fn timed<T>(f: impl FnOnce() -> T) -> (T, Seconds) {
    let (start, cpu, all) = (Instant::now(), thread_cpu_seconds(), process_cpu_seconds());
    let out = f();
    let wall = start.elapsed().as_secs_f64();
    let cpu = cpu.zip(thread_cpu_seconds()).map(|(a, b)| b - a);
    let all_threads = all.zip(process_cpu_seconds()).map(|(a, b)| b - a);
    (out, Seconds { wall, cpu, all_threads })
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene_arg = args.first().map_or("mgf/salon/classroom.mgf", String::as_str);
    let rays: usize = args.get(1).map_or(Ok(2_000_000), |a| a.parse())?;
    let threads: usize = args.get(2).map_or(Ok(2), |a| a.parse())?;

    let (prepared, load) = timed(|| PreparedScene::load(scene_arg));
    let prepared = prepared?;
    let s = prepared.seconds;
    let n = prepared.scene().len();
    println!(
        "{scene_arg}: {n} patches, {} BVH triangles, closed: {}",
        prepared.visibility().unwrap().triangle_count(),
        prepared.analysis.closure.value.is_closed()
    );
    println!(
        "PreparedScene::load: {:.3} s wall, {} (load {:.3} s, BVH {:.3} s, analysis {:.3} s, wall)",
        load.wall,
        load.all_threads.map_or("CPU time unknown".into(), |c| format!("{c:.3} s on the CPUs")),
        s.load,
        s.bvh,
        s.analysis
    );

    let sampler = SceneTransport::from_prepared(&prepared)?;
    println!("{}", sampler.cost().ray);
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let u: Vec<[Real; 4]> = (0..rays).map(|_| [rng.random(), rng.random(), rng.random(), rng.random()]).collect();

    let cast_all = |u: &[[Real; 4]], first: usize| -> usize {
        u.iter().enumerate().filter(|(k, u)| sampler.cast((first + k) % n, **u).is_some()).count()
    };
    let (landed, one) = timed(|| cast_all(&u, 0));
    println!(
        "cast, 1 thread: {} ({rays} rays, {:.1}% landed)",
        one.rate(rays, "Mrays"),
        100.0 * landed as f64 / rays as f64
    );
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let chunk = 4096;
    let (landed_par, par) =
        timed(|| pool.install(|| u.par_chunks(chunk).enumerate().map(|(c, u)| cast_all(u, c * chunk)).sum::<usize>()));
    assert_eq!(landed, landed_par);
    println!(
        "cast, {threads} threads: {:.3} Mrays/s by the wall clock ({:.2}× one thread's wall rate){}",
        rays as f64 / par.wall / 1e6,
        one.wall / par.wall,
        par.all_threads.map_or(String::new(), |c| format!(", {:.3} Mrays a CPU second", rays as f64 / c / 1e6))
    );

    // The parts of a cast: its origin and direction, then first_hit alone on the same rays,
    // and obvhs's f32 triangle test over the same BVH.
    let (_, drawing) = timed(|| {
        let mut sum = Vec3::ZERO;
        for (k, &u) in u.iter().enumerate() {
            let (o, d) = sampler.ray(k % n, u);
            sum += o + d;
        }
        black_box(sum)
    });
    println!("origin and direction alone: {:.1} ns a ray on the CPU", drawing.best() / rays as f64 * 1e9);
    let ray_list: Vec<_> = u.iter().enumerate().map(|(k, &u)| (k % n, sampler.ray(k % n, u))).collect();
    let vis = &prepared.visibility().unwrap();
    let (exact_landed, exact) = timed(|| {
        ray_list.iter().filter(|(from, (o, d))| vis.first_hit(*o, *d, Some(*from)).is_some_and(|h| h.front)).count()
    });
    // A cast also lands the rays whose first hit is a thin wall's back face with its front
    // face within the margin (SceneTransport's module doc).
    assert!(exact_landed <= landed);
    println!("rays landed on a thin wall's other face: {} of {rays}", landed - exact_landed);
    let raw_tracer = vis.raw_tracer();
    let (_, raw) = timed(|| {
        ray_list.iter().filter(|(from, (o, d))| raw_tracer.first_hit_patch(*o, *d, Some(*from)).is_some()).count()
    });
    println!("first_hit alone, 1 thread: {}", exact.rate(rays, "Mrays"));
    println!("RawTracer (obvhs f32 test), 1 thread: {}", raw.rate(rays, "Mrays"));
    println!(
        "cast / RawTracer: {:.2}; first_hit / RawTracer: {:.2} (on the CPU)",
        raw.best() / one.best(),
        raw.best() / exact.best()
    );

    let lines = rays / 4;
    let ((segments, transfers), seconds) = timed(|| {
        let mut line = LineTransfers::default();
        let (mut segments, mut transfers) = (0u64, 0usize);
        for u in &u[..lines] {
            sampler.global_line(*u, &mut line);
            segments += line.rays;
            transfers += line.transfers.len();
        }
        (segments, transfers)
    });
    println!(
        "global lines, 1 thread: {}, {} ({:.2} segments and {:.2} transfers a line)",
        seconds.rate(lines, "Mlines"),
        seconds.rate(segments as usize, "Msegments"),
        segments as f64 / lines as f64,
        transfers as f64 / lines as f64
    );
    Ok(())
}
