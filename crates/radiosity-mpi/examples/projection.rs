//! `cargo run -p radiosity-mpi --example projection -- KEY=VALUE…`: fits the model of
//! `radiosity_mpi::projection` to measured runs (`patches`, `products`, `single_load`,
//! `single_build`, `single_product`, `single_peak`, the same four `split_…`,
//! `small_build_1`, `small_build_2`, `small_product_1`, `small_product_2`) and prints
//! its projection for 10 and 100 million patches on 1, 8 and 64 nodes of 32 cores (or
//! `cores=C`), over an
//! InfiniBand-class network (2 µs, 12.5 GB/s) and 10 Gb Ethernet (20 µs, 1.25 GB/s), and the
//! number of nodes from which the products' sums take longer than their own work.
//! docs/distributed.md gives the command with the values it measured.

use radiosity_mpi::projection::{Measured, Model, Network, Run};

fn main() {
    if let Err(message) = run() {
        eprintln!("projection: {message}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let mut values = std::collections::HashMap::new();
    for arg in std::env::args().skip(1) {
        let (key, value) = arg.split_once('=').ok_or(format!("'{arg}' is not KEY=VALUE"))?;
        let value: f64 = value.parse().map_err(|e| format!("{key}: {e}"))?;
        values.insert(key.to_string(), value);
    }
    let get = |key: &str| values.get(key).copied().ok_or(format!("{key}= is missing"));
    println!("nodes of {} cores", values.get("cores").copied().unwrap_or(32.0));
    let run = |prefix: &str| -> Result<Run, String> {
        Ok(Run {
            load: get(&format!("{prefix}_load"))?,
            build: get(&format!("{prefix}_build"))?,
            product: get(&format!("{prefix}_product"))?,
            peak: get(&format!("{prefix}_peak"))?,
        })
    };
    let measured = Measured {
        patches: get("patches")?,
        products: get("products")?,
        single: run("single")?,
        split: run("split")?,
        small_build: [get("small_build_1")?, get("small_build_2")?],
        small_product: [get("small_product_1")?, get("small_product_2")?],
    };
    let model = Model::fit(&measured);
    println!("{model:#?}");
    // The one figure of the runs the fit does not use: a product on two ranks of one thread.
    let shared = Network { latency: 0.0, bandwidth: f64::INFINITY };
    let two = model.project(measured.patches, 2.0, 1.0, &shared);
    println!(
        "a product on two ranks of one thread: {:.3} s measured, {:.3} s modelled (its sum left out)",
        measured.split.product,
        two.products / measured.products
    );
    let networks = [
        ("InfiniBand (2 µs, 12.5 GB/s)", Network { latency: 2e-6, bandwidth: 12.5e9 }),
        ("10 Gb Ethernet (20 µs, 1.25 GB/s)", Network { latency: 2e-5, bandwidth: 1.25e9 }),
    ];
    // Cores a node: `cores=` (default 32; 2 is this machine).
    let cores = values.get("cores").copied().unwrap_or(32.0);
    println!("| patches | nodes | network | memory per node | load | build | products | sums | total | efficiency |");
    println!("|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|");
    for patches in [1e7, 1e8] {
        for (name, network) in &networks {
            for nodes in [1.0, 8.0, 64.0] {
                let p = model.project(patches, nodes, cores, network);
                println!(
                    "| {:.0e} | {nodes} | {name} | {:.1} GB | {:.0} s | {:.0} s | {:.1} s | {:.1} s | {:.0} s | {:.0}% |",
                    patches,
                    p.memory_per_node / 1e9,
                    p.load,
                    p.build,
                    p.products,
                    p.communication,
                    p.total,
                    100.0 * p.efficiency
                );
            }
        }
    }
    for (name, network) in &networks {
        for patches in [1e7, 1e8] {
            let dominates = (1..=16).map(|k| f64::from(1u32 << k)).find(|&nodes| {
                let p = model.project(patches, nodes, cores, network);
                p.communication > p.products
            });
            match dominates {
                Some(nodes) => println!(
                    "{name}, {patches:.0e} patches: the sums outweigh the products' own work from {nodes} nodes"
                ),
                None => println!(
                    "{name}, {patches:.0e} patches: the sums stay below the products' own work up to 65,536 nodes"
                ),
            }
        }
    }
    Ok(())
}
