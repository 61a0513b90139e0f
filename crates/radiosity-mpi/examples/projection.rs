//! `cargo run -p radiosity-mpi --example projection -- ONE.json TWO.json RANKS.json
//! [LARGER_TWO.json [LARGER_RANKS.json]] [cores=C]`: fits the model of
//! `radiosity_mpi::projection` to the phase tables of three `solve --json` runs of one command
//! at one size (one process on one thread, on two threads, and two ranks of one thread each
//! under `mpirun -np 2`), its times rescaled to a larger run on two threads and its memory taken
//! from that run and the same on two ranks, where they are given, and prints its projection, phase by phase, for 10 and 100
//! million patches on 1, 8 and 64 nodes of 32 cores (or `cores=C`), over an InfiniBand-class
//! network (2 µs, 12.5 GB/s) and 10 Gb Ethernet (20 µs, 1.25 GB/s).
//!
//! The solve's sums come from the runs: a hierarchical operator's products each sum `3n`
//! values; a solver that samples transport, where the two ranks report their rays (stochastic
//! Jacobi dividing every iteration's rays), makes the sums its two-rank run made, each of the
//! bytes a patch it sent, whatever the nodes (its sparse sums, which grow with the nodes, taken
//! as they were on two); in older runs, stochastic Jacobi's steps each sum its replicates'
//! state, `R (3n + n)` values, with a replicate a node (at least the runs' `R`).
//! docs/distributed.md gives the commands.

use radiosity_mpi::projection::{Measured, Model, Network, PhaseRuns, Sums};
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

/// The phases of a run: names and seconds, and its peak resident bytes.
fn phases(run: &Value, path: &str) -> Result<(Vec<(String, f64)>, f64), String> {
    let list = run["phases"].as_array().ok_or(format!("{path} has no phase table: run solve with --json"))?;
    let mut out = Vec::new();
    let mut peak: f64 = 0.0;
    for phase in list {
        let name = phase["name"].as_str().ok_or(format!("{path}: a phase without a name"))?;
        let seconds = phase["seconds"].as_f64().ok_or(format!("{path}: phase '{name}' without seconds"))?;
        peak = peak.max(phase["peak_bytes"].as_f64().unwrap_or(0.0));
        out.push((name.to_string(), seconds));
    }
    Ok((out, peak))
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cores: f64 = match args.iter().find_map(|a| a.strip_prefix("cores=")) {
        Some(c) => c.parse().map_err(|e| format!("cores: {e}"))?,
        None => 32.0,
    };
    let files: Vec<&String> = args.iter().filter(|a| !a.starts_with("cores=")).collect();
    if !(3..=5).contains(&files.len()) {
        return Err("give three runs' JSON (one thread, two threads, two ranks), then a larger run's on two threads and on two ranks".into());
    }
    let runs: Vec<Value> = files.iter().map(|f| read(f)).collect::<Result<_, _>>()?;
    // A run's patches: the length of its list of patches.
    let count = |run: &Value| run["patches"].as_array().map(|p| p.len() as f64);
    let patches = count(&runs[0]).ok_or("the first run has no patches")?;
    for (run, file) in runs.iter().zip(&files).take(3) {
        if count(run) != Some(patches) || run["solver"] != runs[0]["solver"] {
            return Err(format!("{file} is not a run of the first one's scene and solver"));
        }
    }
    let tables: Vec<(Vec<(String, f64)>, f64)> =
        runs.iter().zip(&files).map(|(r, f)| phases(r, f)).collect::<Result<_, _>>()?;
    let names: Vec<&String> = tables[0].0.iter().map(|(name, _)| name).collect();
    let seconds_of = |table: &[(String, f64)], name: &str| table.iter().find(|(n, _)| n == name).map(|(_, s)| *s);
    let mut fitted = Vec::new();
    for name in &names {
        let mut seconds = [0.0; 3];
        for (k, (table, _)) in tables.iter().take(3).enumerate() {
            seconds[k] = seconds_of(table, name).ok_or(format!("{} has no phase '{name}'", files[k]))?;
        }
        fitted.push(PhaseRuns { name: name.to_string(), seconds });
    }
    let larger = match tables.get(3) {
        Some((table, _)) => {
            let n = count(&runs[3]).ok_or("the larger run has no patches")?;
            let seconds: Vec<f64> = names
                .iter()
                .map(|name| seconds_of(table, name).ok_or(format!("{} has no phase '{name}'", files[3])))
                .collect::<Result<_, _>>()?;
            Some((n, seconds))
        }
        None => None,
    };
    let stats = &runs[1]["stats"];
    // The two ranks' own account of their sums, where the run reports each rank's rays (since
    // stochastic Jacobi divides every iteration's rays, 66c51ee): how many, and the bytes a
    // rank sent, which on two ranks are the values each sum carried.
    let rank0 = &runs[2]["stats"]["ranks"][0];
    let measured_sums = match (rank0["run_rays"].as_f64(), rank0["run_sums"].as_f64()) {
        (Some(_), Some(count)) if count > 0.0 => {
            Some(Sums::Fixed { count, bytes: rank0["run_bytes_sent"].as_f64().unwrap_or(0.0) / count / patches })
        }
        _ => None,
    };
    let sampled = stats["rays"].as_f64().unwrap_or(0.0) > 0.0;
    let sums = if let Some(sums) = measured_sums.filter(|_| sampled) {
        sums
    } else if sampled {
        let replicates = stats["replicates"].as_f64().unwrap_or(4.0).max(1.0);
        Sums::Replicates { count: stats["steps"].as_f64().unwrap_or(0.0), bytes: 8.0 * 4.0, least: replicates }
    } else {
        Sums::Fixed { count: stats["products"].as_f64().unwrap_or(0.0), bytes: 24.0 }
    };
    let peaks = match (tables.get(3), tables.get(4)) {
        (Some((_, two)), Some((_, ranks))) => ([*two, *ranks], count(&runs[3]).unwrap_or(patches)),
        _ => ([tables[1].1, tables[2].1], patches),
    };
    let measured = Measured { patches, phases: fitted, peaks, sums, larger };
    let model = Model::fit(&measured);
    println!("{}, {} patches; sums: {sums:?}", runs[0]["solver"].as_str().unwrap_or("?"), patches);
    println!("| phase | serial µs a patch | repeated core-µs a patch | divided core-µs a patch |");
    println!("|---|--:|--:|--:|");
    for p in &model.phases {
        println!("| {} | {:.3} | {:.3} | {:.3} |", p.name, p.serial * 1e6, p.repeated * 1e6, p.divided * 1e6);
    }
    println!(
        "memory: {:.0} bytes a patch on every rank, {:.0} divided between them, {:.0} more a rank for the sums on 2 nodes",
        model.memory_repeated, model.memory_divided, model.memory_sums
    );
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
    Ok(())
}
