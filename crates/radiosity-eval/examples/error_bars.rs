//! Whether the stochastic solvers' standard errors cover their true errors on a scene, over
//! seeds, at one ray budget: the table of docs/stochastic.md ([`radiosity_eval::Calibration`]).
//!
//! `cargo run --release -p radiosity-eval --example error_bars -- [--scene SCENE]
//! [--until RULES] [--seeds S] [--solvers A,B,…]` (defaults: RenderPark's classroom,
//! `rays=111100`, 8 seeds, the stochastic solvers of the table).

use radiosity_eval::{Cache, Lab, LabOptions, NoProgress};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::StopRules;
use std::error::Error;

/// The value after `flag` among the arguments, if given.
fn argument(flag: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1).cloned())
}

fn main() -> Result<(), Box<dyn Error>> {
    let scene = argument("--scene").unwrap_or_else(|| "mgf/salon/classroom.mgf".into());
    let until = argument("--until").unwrap_or_else(|| "rays=111100".into());
    let seeds: u64 = argument("--seeds").map_or(Ok(8), |s| s.parse())?;
    let solvers =
        argument("--solvers").unwrap_or_else(|| "stochastic-jacobi,stochastic-jacobi:seq=sobol,random-walk".into());
    let prepared = PreparedScene::load(&scene)?;
    let cache = Cache::from_env(concat!(env!("CARGO_MANIFEST_DIR"), "/../../target/ff-cache"));
    let options = LabOptions::default().with_cache(Some(cache));
    let lab = Lab::new(&prepared, &BackendSpec::parse("analytic")?, options, &NoProgress)?;
    let rules = StopRules::parse(&until)?;
    println!("{scene}, --until {until}, {seeds} seeds");
    println!("| solver | rays | seeds | mean e_rms² / mean SE² | seeds within 2 SE | mean e_rms | mean SE |");
    println!("|---|--:|--:|--:|--:|--:|--:|");
    for solver in solvers.split(',') {
        let c = lab.calibrate(solver, &rules, seeds)?;
        println!(
            "| `{}` | {:.0} | {} | {:.2} | {}/{} | {:.2e} | {:.2e} |",
            c.solver,
            c.rays,
            c.seeds,
            c.ratio,
            (c.within_two * c.seeds as f64).round(),
            c.seeds,
            c.e_rms,
            c.standard_error
        );
    }
    Ok(())
}
