//! `cargo xtask`: the command line that drives radiosity experiments (DESIGN §7).
//!
//! Each subcommand lives in its own module. Errors reach the user as one sentence on stderr
//! with a non-zero exit code; nothing here panics on bad input.

mod compare;
mod experiment;
mod export;
mod ff;
mod paper;
mod render;
mod scene_report;
mod scenes;
mod shading;
mod solve;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Radiosity experiments: scenes, form factors, solvers and comparisons.
#[derive(Debug, Parser)]
#[command(name = "cargo xtask", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List the built-in scenes, or explain what the pipeline does with one scene or file.
    Scenes(scenes::Args),
    /// Assemble the full form-factor matrix of a scene and report its closure and reciprocity.
    Ff(ff::Args),
    /// Run one solver on a scene and report its error against the reference solution.
    Solve(solve::Args),
    /// Compare solvers on a scene: convergence table, report and plots under results/.
    Compare(compare::Args),
    /// Run the paper's figures 1–3 and set each of its claims beside our measurement.
    Paper(paper::Args),
    /// Render the solved scene to a PNG image.
    Render(render::Args),
    /// Export the solved scene as glTF binary with per-vertex colours.
    Export(export::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Scenes(args) => scenes::run(&args),
        Command::Ff(args) => ff::run(&args),
        Command::Solve(args) => solve::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Paper(args) => paper::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Export(args) => export::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
