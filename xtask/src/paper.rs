//! `cargo xtask paper [--out DIR] [--scenes S1,S2,…] [--ff BACKEND] [--columns HOW]`: the
//! equivalents of Rousselle & Renaud's figures 1–3 ([`radiosity_eval::paper`]), each of their
//! claims set beside our measurement. Each scene gets its own `compare` folder (table, report,
//! plots); `report.md` at the top shows the step plots and the claims.
//!
//! The claims are in shooting steps, and the office's reference assembles all its columns
//! anyway, so by default the solvers read their columns from that stored matrix, each charged
//! the backend's measured cost (`--columns charged`, as `compare` takes it): every seconds
//! figure is then on the `charged` clock, and says so. `--columns computed` computes every
//! column when a solver asks for it, on the measured clock, at several times the cost.

use crate::compare::Plan;
use crate::experiment::{ReferenceArg, check_out_dir, default_out};
use anyhow::{Context, Result, bail};
use radiosity_eval::ColumnCost;
use radiosity_eval::paper::{FIGURES, RULES, header, section};
use std::path::PathBuf;

/// Arguments of `paper`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The output folder (default `results/paper-<date-time>/`).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Which of the paper's scenes to run: multi-cubes, labyrinth, office.
    #[arg(long, default_value = "multi-cubes,labyrinth,office")]
    scenes: String,
    /// The form-factor backend, with `:key=value` parameters: the paper's claims under other
    /// form factors (the paper used analytic ones).
    #[arg(long = "ff", value_name = "BACKEND", default_value = "analytic", long_help = crate::experiment::backend_help())]
    ff: String,
    #[command(flatten)]
    reference: ReferenceArg,
    /// How solvers pay for their columns, which names the clock of every seconds figure:
    /// `charged` (default) reads them from the stored matrix of the reference and charges each
    /// the backend's measured cost; `computed` computes every column when a solver asks for it
    /// (wall time, several times slower). The claims are in steps and hold on either.
    #[arg(long, value_name = "HOW", default_value_t = ColumnCost::Charged, value_parser = crate::compare::parse_columns)]
    columns: ColumnCost,
}

/// Runs `paper`.
pub fn run(args: &Args) -> Result<()> {
    let chosen: Vec<&str> = args.scenes.split(',').map(str::trim).filter(|s| !s.is_empty()).collect();
    if let Some(bad) = chosen.iter().find(|s| !FIGURES.iter().any(|f| f.scene == **s)) {
        bail!("'{bad}' is not one of the paper's scenes; they are multi-cubes, labyrinth and office");
    }
    let figures: Vec<_> = FIGURES.iter().filter(|f| chosen.contains(&f.scene)).collect();
    if figures.is_empty() {
        bail!("--scenes names no scene");
    }
    let kind = args.reference.parse()?;
    let plans = figures
        .iter()
        .map(|f| Ok(Plan::new(f.scene, f.solvers, &args.ff, RULES, kind)?.with_columns(args.columns)))
        .collect::<Result<Vec<_>>>()?;
    let out = args.out.clone().unwrap_or_else(|| default_out("paper"));
    check_out_dir(&out)?;
    let mut md = header(&plans.first().map_or_else(String::new, |p| p.backend().canonical()));
    for (figure, plan) in figures.iter().zip(plans) {
        let comparison = plan.execute(&out.join(figure.scene))?;
        print!("{}", comparison.summary());
        md += &section(figure, &comparison);
    }
    let path = out.join("report.md");
    std::fs::write(&path, md).with_context(|| format!("cannot write {}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}
