//! A stochastic solver's rays per second against the raw rate of obvhs on the same rays, the
//! same scene and the same threads, measured in one run: a stochastic run is a ray caster, and
//! its rays are its cost.
//!
//! `cargo run --release -p radiosity-eval --example stochastic_rays -- [--scene SCENE]
//! [--solver SOLVER] [--rays N] [--threads T] [--repeats K]`
//!
//! Defaults: `office:size=0.0158` (956,319 patches), `stochastic-jacobi:seq=sobol`, `3e7` rays,
//! 2 threads, 3 repeats. The solver runs once with every ray it casts recorded (a patch's rays
//! together, in the order they are cast), then `K` times in turn with three rates, each by the
//! wall clock on a pool of `T` threads, whose medians are compared:
//!
//! 1. **the solver**: its rays over the seconds of its run (every step, its sums and its
//!    bookkeeping included; the scene's load and analysis left out);
//! 2. **raw obvhs**: the recorded rays (their origins and directions worked out beforehand,
//!    not timed) through the same BVH with obvhs's own `f32` triangle test
//!    ([`RawTracer::first_hit_patch`]);
//! 3. **exact cast**: the same rays through [`SceneTransport`]'s cast, the exact `f64` test and
//!    the thin-wall rule the solver calls.
//!
//! Solver over raw obvhs is the share of the ray-tracing limit the solver reaches; exact cast
//! over raw obvhs is what exactness costs, solver over exact cast what the rest of the solver
//! costs. Rays of global lines (`lines=global`) are not recorded.
//!
//! [`RawTracer::first_hit_patch`]: radiosity_geom::visibility::RawTracer::first_hit_patch

use radiosity_core::{LineTransfers, LinearSystem, Real, SampleCost, TransportSampler};
use radiosity_ff::SceneTransport;
use radiosity_geom::PreparedScene;
use radiosity_solvers::{Executor, Problem, SolverRegistry, StopRules, Unit};
use rayon::prelude::*;
use std::error::Error;
use std::sync::Mutex;
use std::time::Instant;

/// The value after `flag` among the arguments, if given.
fn argument(flag: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1).cloned())
}

/// Rays traced at a time.
const CHUNK: usize = 2_000_000;

/// A sampler that lists every ray it casts, by the patch it leaves and its point.
struct Recording<'t> {
    inner: &'t SceneTransport<'t>,
    rays: Mutex<Vec<(u32, [Real; 4])>>,
}

impl TransportSampler for Recording<'_> {
    fn patch_count(&self) -> usize {
        self.inner.patch_count()
    }

    fn cast(&self, from: usize, u: [Real; 4]) -> Option<usize> {
        self.rays.lock().expect("no recording thread panicked").push((from as u32, u));
        self.inner.cast(from, u)
    }

    /// A patch's rays are listed together, as they are cast.
    fn cast_batch(&self, from: usize, u: &[[Real; 4]], landings: &mut [Option<usize>]) {
        self.rays.lock().expect("no recording thread panicked").extend(u.iter().map(|&u| (from as u32, u)));
        self.inner.cast_batch(from, u, landings);
    }

    fn ray_weight(&self, from: usize) -> Real {
        self.inner.ray_weight(from)
    }

    fn row_sum(&self, i: usize) -> Option<Real> {
        self.inner.row_sum(i)
    }

    fn global_line(&self, u: [Real; 4], line: &mut LineTransfers) -> bool {
        self.inner.global_line(u, line)
    }

    fn cost(&self) -> SampleCost {
        self.inner.cost()
    }
}

fn main() -> Result<(), Box<dyn Error + Send + Sync>> {
    let scene = argument("--scene").unwrap_or_else(|| "office:size=0.0158".into());
    let solver_name = argument("--solver").unwrap_or_else(|| "stochastic-jacobi:seq=sobol".into());
    let rays: f64 = argument("--rays").map_or(Ok(3e7), |s| s.parse())?;
    let threads: usize = argument("--threads").map_or(Ok(2), |s| s.parse())?;
    let repeats: usize = argument("--repeats").map_or(Ok(3), |s| s.parse())?;
    if repeats == 0 {
        return Err("--repeats must be at least 1".into());
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;

    pool.install(|| -> Result<(), Box<dyn Error + Send + Sync>> {
        let prepared = PreparedScene::load(&scene)?;
        let n = prepared.scene().len();
        println!("{scene}: {n} patches, {threads} threads, {solver_name}, rays={rays:e}");

        let system = LinearSystem::from_scene(prepared.scene());
        let transport = SceneTransport::from_prepared(&prepared)?;
        // One timed run of the solver; the same seed gives the same rays every time.
        let solve = |sampler: &dyn TransportSampler| -> Result<(u64, f64), Box<dyn Error + Send + Sync>> {
            let problem = Problem::sampled(&system, sampler)?;
            let mut solver = SolverRegistry::builtin().build(&solver_name)?;
            let start = Instant::now();
            let run = Executor::new(solver.as_mut(), StopRules::parse(&format!("rays={rays}"))?).run(&problem)?;
            Ok((run.state.cost[Unit::Rays], start.elapsed().as_secs_f64()))
        };
        // Its rays, recorded in a run of their own (not timed).
        let recording = Recording { inner: &transport, rays: Mutex::new(Vec::new()) };
        let (cast, _) = solve(&recording)?;
        let recorded = recording.rays.into_inner().map_err(|_| "a recording thread panicked")?;
        assert_eq!(recorded.len() as u64, cast, "the recorded run cast other rays");
        let visibility = prepared.visibility()?;
        let raw = visibility.raw_tracer();
        let lists: Vec<Vec<_>> = recorded
            .chunks(CHUNK)
            .map(|chunk| {
                chunk.par_iter().map(|&(from, u)| (from as usize, u, transport.ray(from as usize, u))).collect()
            })
            .collect();
        drop(recorded);

        // The three rates in turn, `repeats` times: the machine's speed drifts over a minute.
        let mut rates = [Vec::new(), Vec::new(), Vec::new()];
        for _ in 0..repeats {
            let (again, seconds) = solve(&transport)?;
            assert_eq!(again, cast, "the solver cast other rays");
            rates[0].push(cast as f64 / seconds);
            // The same rays in the order they were cast (a patch's rays together), through
            // the same BVH with obvhs's `f32` test, then with the exact cast.
            let t = Instant::now();
            let hit: usize = lists
                .iter()
                .map(|l| {
                    l.par_iter().filter(|(from, _, (o, d))| raw.first_hit_patch(*o, *d, Some(*from)).is_some()).count()
                })
                .sum();
            rates[1].push(cast as f64 / t.elapsed().as_secs_f64());
            let t = Instant::now();
            let landed: usize = lists
                .iter()
                .map(|l| l.par_iter().filter(|(from, u, _)| transport.cast(*from, *u).is_some()).count())
                .sum();
            rates[2].push(cast as f64 / t.elapsed().as_secs_f64());
            println!(
                "solver {:.3}, raw obvhs {:.3} ({:.1}% hit), exact cast {:.3} ({:.1}% landed) M rays/s",
                rates[0].last().unwrap() / 1e6,
                rates[1].last().unwrap() / 1e6,
                100.0 * hit as f64 / cast as f64,
                rates[2].last().unwrap() / 1e6,
                100.0 * landed as f64 / cast as f64
            );
        }
        let [solver, raw, exact] = rates.map(|mut r| {
            r.sort_by(f64::total_cmp);
            r[r.len() / 2]
        });
        println!(
            "medians of {repeats}, {cast} rays each: solver {:.3}, raw obvhs {:.3}, exact cast {:.3} M rays/s",
            solver / 1e6,
            raw / 1e6,
            exact / 1e6
        );
        println!(
            "solver / raw obvhs: {:.2}; exact cast / raw obvhs: {:.2}; solver / exact cast: {:.2}",
            solver / raw,
            exact / raw,
            solver / exact
        );
        Ok(())
    })?;
    Ok(())
}
