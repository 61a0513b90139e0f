//! `cargo xtask`: the command line that drives radiosity experiments (docs/cli.md).
//!
//! Each subcommand lives in its own module. Errors reach the user as one sentence on stderr
//! with a non-zero exit code; nothing here panics on bad input.

mod bars;
mod bench;
mod compare;
mod experiment;
mod export;
mod ff;
mod page;
mod paper;
mod ranks;
mod render;
mod scenes;
mod solve;
mod stress;
mod validate;
mod watch;

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
    /// Run a comparison and watch it in the browser: a live page on 127.0.0.1.
    Watch(watch::Args),
    /// Run the paper's figures 1–3 and set each of its claims beside our measurement.
    Paper(paper::Args),
    /// Render the solved scene to a PNG image.
    Render(render::Args),
    /// Export the solved scene as glTF binary with per-vertex colours.
    Export(export::Args),
    /// Run every solver and backend over stiff and extreme scenes and report what fails.
    Stress(stress::Args),
    /// Path-trace each object's mean radiosity and set it beside the discrete solution at
    /// increasing mesh resolution.
    Validate(validate::Args),
    /// Measure columns per second against the ray-tracing limit, matrix assembly, group
    /// solves and end-to-end time and memory to accuracy, as a Markdown report.
    Bench(bench::Args),
}

fn main() -> ExitCode {
    radiosity_eval::return_freed_blocks();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return argument_error(e),
    };
    let (name, distributed, ranks) = match &cli.command {
        Command::Solve(args) => ("solve", true, args.ranks.ranks),
        Command::Compare(args) => ("compare", true, args.ranks.ranks),
        Command::Watch(_) => ("watch", false, None),
        Command::Scenes(_) => ("scenes", false, None),
        Command::Ff(_) => ("ff", false, None),
        Command::Paper(_) => ("paper", false, None),
        Command::Render(_) => ("render", false, None),
        Command::Export(_) => ("export", false, None),
        Command::Stress(_) => ("stress", false, None),
        Command::Validate(_) => ("validate", false, None),
        Command::Bench(_) => ("bench", false, None),
    };
    // `--ranks K`: this command again, as K ranks under mpirun.
    match ranks.map(ranks::launch).transpose() {
        Ok(Some(true)) => return ExitCode::SUCCESS,
        Ok(_) => {}
        // Rank 0 failed as this command fails, and has said why.
        Err(e) if ranks::reported(&e) => return ExitCode::FAILURE,
        Err(e) => return failure(&e),
    }
    let ranks = match ranks::Ranks::start(name, distributed) {
        Ok(world) => world,
        Err(e) => return failure(&e),
    };
    let result = match cli.command {
        Command::Scenes(args) => scenes::run(&args),
        Command::Ff(args) => ff::run(&args),
        Command::Solve(args) => solve::run(&args, &ranks),
        Command::Compare(args) => compare::run(&args, &ranks),
        Command::Watch(args) => watch::run(&args),
        Command::Paper(args) => paper::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Stress(args) => stress::run(&args),
        Command::Validate(args) => validate::run(&args),
        Command::Bench(args) => bench::run(&args),
    };
    let code = match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => failure(&e),
    };
    drop(ranks);
    code
}

/// An error as one sentence on stderr, and the failing exit code.
fn failure(e: &anyhow::Error) -> ExitCode {
    eprintln!("error: {e:#}");
    ExitCode::FAILURE
}

/// Help and version go to stdout as clap writes them; an argument error becomes one sentence
/// on stderr with exit code 1, like every other error (clap would print usage lines too).
fn argument_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        e.exit();
    }
    let rendered = e.render().to_string();
    let sentence: Vec<&str> = rendered
        .lines()
        .map(str::trim)
        .take_while(|line| !line.starts_with("Usage:") && !line.starts_with("For more information"))
        .filter(|line| !line.is_empty())
        .collect();
    let sentence = sentence.join(" ");
    eprintln!("error: {}; see cargo xtask --help", sentence.strip_prefix("error: ").unwrap_or(&sentence));
    ExitCode::FAILURE
}
