//! `cargo xtask stress [--out DIR] [--cases …] [--backends …] [--solvers …]`: every solver on
//! every form-factor backend over the stiff and extreme scenes of
//! [`radiosity_eval::stress`], which documents the suite and how a run is judged. Writes
//! `stress.md` (snapshot-tested) and `stress.csv` under `results/stress-<date-time>/` or
//! `--out`, and prints how many runs converged per case and backend.

use crate::bars::Bars;
use crate::experiment::{check_out_dir, default_out};
use anyhow::Result;
use radiosity_eval::stress::{BACKENDS, CASES, StressSuite, select};
use radiosity_solvers::SolverRegistry;
use std::path::PathBuf;

/// Arguments of `stress`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The output folder (default `results/stress-<date-time>/`).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Only these cases, comma-separated (default: all).
    #[arg(long, value_name = "CASES")]
    cases: Option<String>,
    /// Only these backends, by label, comma-separated (default: all).
    #[arg(long, value_name = "BACKENDS")]
    backends: Option<String>,
    /// Only these solvers, comma-separated (default: every point, group and beyond-the-paper
    /// solver).
    #[arg(long, value_name = "SOLVERS")]
    solvers: Option<String>,
}

/// Runs `stress`.
pub fn run(args: &Args) -> Result<()> {
    let registry = SolverRegistry::builtin();
    let mut suite = StressSuite::full(&registry);
    suite.cases = select(args.cases.as_deref(), CASES, |c| c.key, "case")?;
    suite.backends = select(args.backends.as_deref(), BACKENDS, |b| b.label, "backend")?;
    if let Some(list) = &args.solvers {
        suite.solvers = list.split(',').map(str::trim).filter(|s| !s.is_empty()).map(String::from).collect();
    }
    let out = args.out.clone().unwrap_or_else(|| default_out("stress"));
    check_out_dir(&out)?;
    let report = suite.run(&Bars::new())?;
    report.write(&out)?;
    print!("{}", report.summary());
    println!("wrote {} and stress.csv", out.join("stress.md").display());
    Ok(())
}
