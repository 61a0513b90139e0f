//! `split-operator-check SCENE EPS OUT_DIR`: run under `mpirun`, each rank builds its part of the
//! hierarchical operator of `SCENE` (threshold `EPS`) split over the ranks through [`MpiWorld`],
//! multiplies a fixed vector, solves the radiosity system with `gmres-30` over it, and writes to
//! `OUT_DIR/rank-R.txt` its links, the product and the solution (each `f64` as hexadecimal
//! bits). On one rank the operator is the single process's, so a test (tests/operator.rs) checks
//! the ranks' links against one rank's, and the results bit for bit between ranks and to 1e-12
//! against one rank.

use radiosity_core::{ColumnSource, LinearSystem};
use radiosity_ff::{HierarchicalColumns, HierarchicalParams, HierarchyLink};
use radiosity_geom::PreparedScene;
use radiosity_mpi::MpiWorld;
use radiosity_solvers::{Executor, Problem, StopRules, solver_by_name};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;

/// Refinement tasks a rank: many, so that the frontier every rank expands settles links too.
const TASKS_PER_RANK: usize = 64;

fn main() {
    if let Err(message) = run() {
        eprintln!("split-operator-check: {message}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, eps, out_dir] = args.as_slice() else {
        return Err("usage: split-operator-check SCENE EPS OUT_DIR".into());
    };
    let eps: f64 = eps.parse().map_err(|e| format!("EPS: {e}"))?;
    let world = Arc::new(MpiWorld::init().map_err(|e| e.to_string())?);
    let prepared = PreparedScene::load(scene).map_err(|e| e.to_string())?;
    let params = HierarchicalParams { eps, ..HierarchicalParams::default() };
    let f = HierarchicalColumns::new_distributed(
        prepared.scene(),
        &prepared.visibility().map_err(|e| e.to_string())?,
        &prepared.analysis,
        params,
        &|_| {},
        world.clone(),
        TASKS_PER_RANK,
    );
    let mut report = String::new();
    for link in f.links() {
        let line = match link {
            HierarchyLink::Far(a, b) => format!("far {a} {b}"),
            HierarchyLink::Near(i, j) => format!("near {i} {j}"),
            HierarchyLink::FarPair(i, j) => format!("pair {i} {j}"),
        };
        writeln!(report, "{line}").map_err(|e| e.to_string())?;
    }
    let product = product(&f);
    writeln!(report, "product {}", bits(&product)).map_err(|e| e.to_string())?;
    let system = LinearSystem::from_scene(prepared.scene());
    let solution = solve(&system, &f)?;
    writeln!(report, "solution {}", bits(&solution)).map_err(|e| e.to_string())?;
    let path = PathBuf::from(out_dir).join(format!("rank-{}.txt", radiosity_core::Collective::rank(&*world)));
    std::fs::write(&path, report).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    drop(f);
    Ok(())
}

/// `F x` for a fixed `x` of three channels.
fn product(f: &dyn ColumnSource) -> Vec<f64> {
    let n = f.patch_count();
    let x: Vec<f64> = (0..3 * n).map(|k| 1.0 + ((k * 7919) % 97) as f64 / 50.0).collect();
    let mut out = vec![0.0; 3 * n];
    if !f.multiply(&x, 3, &mut out) {
        radiosity_core::multiply(f, &x, 3, &mut out);
    }
    out
}

/// The radiosity after 40 steps of `gmres-30`.
fn solve(system: &LinearSystem, f: &dyn ColumnSource) -> Result<Vec<f64>, String> {
    let mut solver = solver_by_name("gmres-30").map_err(|e| e.to_string())?;
    let problem = Problem::new(system, f).map_err(|e| e.to_string())?;
    let rules = StopRules::parse("steps=40").map_err(|e| e.to_string())?;
    let run = Executor::new(solver.as_mut(), rules).run(&problem).map_err(|e| e.to_string())?;
    Ok(run.state.radiosity)
}

/// The hexadecimal bits of each value.
fn bits(values: &[f64]) -> String {
    values.iter().map(|v| format!("{:016x}", v.to_bits())).collect::<Vec<_>>().join(" ")
}
