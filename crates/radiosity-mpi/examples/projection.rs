//! `cargo run -p radiosity-mpi --example projection -- FIT.json… [check CHECK.json…]
//! [cores=C]`: fits the model of `radiosity_mpi::projection` to the `solve --out` runs of one
//! command given first, checks it against the runs given after `check`, which the fit does not
//! see, and prints its projection, phase by phase, for 10 and 100 million patches on 1, 8 and
//! 64 nodes of 32 cores (or `cores=C`), over an InfiniBand-class network (2 µs, 12.5 GB/s) and
//! 10 Gb Ethernet (20 µs, 1.25 GB/s).
//!
//! Each run says its patches, threads and ranks (`solve`'s JSON since 0533c1b), and each phase
//! its CPU seconds, which tell serial code from threads that contend (the module's doc). The fit needs,
//! at its smallest size, runs of one process on one thread, of one process on two threads and
//! of two ranks of one thread each under `mpirun -np 2`, repeated as often as wished (each
//! kind's median is fitted), and may add runs on two threads at a larger size, which fit each
//! phase's growth.
//!
//! The solve's sums come from the fit's two-rank runs: a hierarchical operator's products each
//! sum `3n` values; a solver that samples transport, where the ranks report their rays
//! (stochastic Jacobi dividing every iteration's rays), makes the sums its two-rank run made,
//! each of the bytes a patch it sent, whatever the nodes; random walks' steps each sum their
//! replicates' state, `R (3n + n)` values, with a replicate a node (at least the runs' `R`).
//! docs/distributed.md gives the commands.

use radiosity_mpi::projection::{Model, Network, Run, RunPhase, Sums};
use serde_json::Value;

fn main() {
    if let Err(message) = run() {
        eprintln!("projection: {message}");
        std::process::exit(1);
    }
}

/// A run's JSON, read from `path`.
fn read(path: &str) -> Result<Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {path}: {e}"))?;
    serde_json::from_str(&text).map_err(|e| format!("{path} is not a solve's JSON: {e}"))
}

/// A run's size, configuration, phases and peak (its largest rank's).
fn measured(json: &Value, path: &str) -> Result<Run, String> {
    let list = json["phases"].as_array().ok_or(format!("{path} has no phase table: run solve with --out"))?;
    let mut phases = Vec::new();
    let mut peak: f64 = 0.0;
    for phase in list {
        let name = phase["name"].as_str().ok_or(format!("{path}: a phase without a name"))?;
        let seconds = phase["seconds"].as_f64().ok_or(format!("{path}: phase '{name}' without seconds"))?;
        peak = peak.max(phase["peak_bytes"].as_f64().unwrap_or(0.0));
        phases.push(RunPhase { name: name.to_string(), seconds, cpu: phase["cpu_seconds"].as_f64() });
    }
    for rank in json["stats"]["ranks"].as_array().into_iter().flatten() {
        peak = peak.max(rank["peak_rss"].as_f64().unwrap_or(0.0));
    }
    let number =
        |key: &str| json[key].as_f64().ok_or(format!("{path} does not say its {key}: run solve at 0533c1b or later"));
    let patches = json["patches"].as_array().ok_or(format!("{path} has no patches"))?.len() as f64;
    let ranks = number("ranks")?;
    // What ranks divide, as the program counts it: the hierarchical operator's links.
    let divided_bytes = json["stats"]["operator"]["link_bytes"].as_f64().filter(|_| ranks == 1.0);
    Ok(Run { patches, threads: number("threads")?, ranks, phases, peak, divided_bytes })
}

/// The solve's sums, from a two-rank run's JSON (module doc).
fn sums(two_ranks: &Value, patches: f64) -> Sums {
    let stats = &two_ranks["stats"];
    let rank0 = &stats["ranks"][0];
    let number = |v: &Value| v.as_f64().unwrap_or(0.0);
    if two_ranks["solver"].as_str().is_some_and(|s| s.starts_with("random-walk")) {
        let least = stats["replicates"].as_f64().unwrap_or(4.0).max(1.0);
        Sums::Replicates { count: number(&stats["steps"]), bytes: 8.0 * 4.0, least }
    } else if number(&rank0["run_rays"]) > 0.0 && number(&rank0["run_sums"]) > 0.0 {
        let count = number(&rank0["run_sums"]);
        Sums::Fixed { count, bytes: number(&rank0["run_bytes_sent"]) / count / patches }
    } else {
        Sums::Fixed { count: number(&stats["products"]), bytes: 24.0 }
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cores: f64 = match args.iter().find_map(|a| a.strip_prefix("cores=")) {
        Some(c) => c.parse().map_err(|e| format!("cores: {e}"))?,
        None => 32.0,
    };
    let files: Vec<&String> = args.iter().filter(|a| !a.starts_with("cores=")).collect();
    let split = files.iter().position(|f| *f == "check").unwrap_or(files.len());
    let (fit_files, check_files) = (&files[..split], files.get(split + 1..).unwrap_or_default());
    if fit_files.is_empty() {
        return Err(
            "give the fit's runs (one thread, two threads, two ranks at one size), then `check` and the runs to check"
                .into(),
        );
    }
    let read_all = |list: &[&String]| -> Result<Vec<(Value, Run)>, String> {
        list.iter()
            .map(|f| {
                let json = read(f)?;
                let run = measured(&json, f)?;
                Ok((json, run))
            })
            .collect()
    };
    let (fit, check) = (read_all(fit_files)?, read_all(check_files)?);
    let solver = fit[0].0["solver"].as_str().unwrap_or("?").to_string();
    for ((json, _), file) in fit.iter().chain(&check).zip(fit_files.iter().chain(check_files)) {
        if json["solver"].as_str() != Some(&solver) {
            return Err(format!("{file} is not a run of {solver}, the first run's solver"));
        }
    }
    let runs: Vec<Run> = fit.iter().map(|(_, r)| r.clone()).collect();
    let smallest = runs.iter().map(|r| r.patches).fold(f64::INFINITY, f64::min);
    let two_ranks = fit
        .iter()
        .find(|(_, r)| r.ranks == 2.0 && r.patches == smallest)
        .ok_or(format!("no run of two ranks at {smallest} patches among the fit's runs"))?;
    let sums = sums(&two_ranks.0, smallest);
    let model = Model::fit(&runs, sums).map_err(|e| e.to_string())?;
    println!("{solver}, fitted on {} runs; sums: {sums:?}", runs.len());
    println!("| phase | serial µs a patch | repeated core-µs a patch | divided core-µs a patch | growth exponent |");
    println!("|---|--:|--:|--:|--:|");
    for p in &model.phases {
        let us = |v: f64| v * 1e6;
        println!(
            "| {} | {:.3} | {:.3} | {:.3} | {:.3} |",
            p.name,
            us(p.serial),
            us(p.repeated),
            us(p.divided),
            p.growth
        );
    }
    println!(
        "memory: {:.0} MB a process, {:.0} bytes a patch on every rank, {:.0} divided between them, {:.0} MB more a \
         rank on 2 nodes",
        model.memory_fixed / 1e6,
        model.memory_repeated,
        model.memory_divided,
        model.memory_sums / 1e6
    );
    if !check.is_empty() {
        println!("\nchecks (runs the fit did not see)");
        println!(
            "| patches | threads | ranks | measured | modelled | error | largest phase: measured, modelled | peak | modelled | error |"
        );
        println!("|--:|--:|--:|--:|--:|--:|---|--:|--:|--:|");
        for (_, run) in &check {
            let c = model.check(run);
            let largest = c.phases.iter().max_by(|a, b| a.1.total_cmp(&b.1));
            let largest = largest.map_or(String::new(), |(n, m, p)| format!("{n}: {m:.1} s, {p:.1} s"));
            println!(
                "| {} | {} | {} | {:.1} s | {:.1} s | {:+.1}% | {largest} | {:.2} GB | {:.2} GB | {:+.1}% |",
                run.patches,
                run.threads,
                run.ranks,
                c.total.0,
                c.total.1,
                100.0 * c.error(),
                c.peak.0 / 1e9,
                c.peak.1 / 1e9,
                100.0 * c.memory_error()
            );
        }
    }
    let networks = [
        ("InfiniBand", Network { latency: 2e-6, bandwidth: 12.5e9 }),
        ("10 GbE", Network { latency: 2e-5, bandwidth: 1.25e9 }),
    ];
    println!("\nnodes of {cores} cores");
    let heads: Vec<&str> = model.phases.iter().map(|p| p.name.as_str()).collect();
    println!(
        "| patches | nodes | network | memory a node | {} | sums | total | efficiency | limit |",
        heads.join(" | ")
    );
    println!("|--:|--:|---|--:|{}--:|--:|--:|---|", "--:|".repeat(heads.len()));
    for patches in [1e7, 1e8] {
        for (name, network) in &networks {
            for nodes in [1.0, 8.0, 64.0] {
                if nodes == 1.0 && *name != networks[0].0 {
                    continue;
                }
                let p = model.project(patches, nodes, cores, network);
                let phases: Vec<String> = p.phases.iter().map(|(_, t)| format!("{t:.1} s")).collect();
                println!(
                    "| {:.0e} | {nodes} | {} | {:.1} GB | {} | {:.1} s | {:.0} s | {:.0}% | {} |",
                    patches,
                    if nodes == 1.0 { "" } else { name },
                    p.memory_per_node / 1e9,
                    phases.join(" | "),
                    p.communication,
                    p.total,
                    100.0 * p.efficiency,
                    p.limit
                );
            }
        }
    }
    // The same runs fitted by their wall seconds alone: threads that contend then count as
    // serial code. The two fits bracket what two cores can tell of the serial part.
    let walls: Vec<Run> = runs
        .iter()
        .map(|r| Run { phases: r.phases.iter().map(|p| RunPhase { cpu: None, ..p.clone() }).collect(), ..r.clone() })
        .collect();
    let wall = Model::fit(&walls, sums).map_err(|e| e.to_string())?;
    let serial = |m: &Model| m.phases.iter().map(|p| p.serial).sum::<f64>() * 1e6;
    let (ib, network) = &networks[0];
    let efficiency = |m: &Model, nodes: f64| 100.0 * m.project(1e7, nodes, cores, network).efficiency;
    let overhead = model.excess_as_overhead();
    println!(
        "\non {ib}, 1e7 patches, efficiency on 8 and 64 nodes: {:.0}% and {:.0}% as fitted (serial {:.2} µs a patch); \
         {:.0}% and {:.0}% with the ranks' excess an overhead on divided work; {:.0}% and {:.0}% fitted by wall seconds \
         alone (serial {:.2} µs a patch)",
        efficiency(&model, 8.0),
        efficiency(&model, 64.0),
        serial(&model),
        efficiency(&overhead, 8.0),
        efficiency(&overhead, 64.0),
        efficiency(&wall, 8.0),
        efficiency(&wall, 64.0),
        serial(&wall),
    );
    Ok(())
}
