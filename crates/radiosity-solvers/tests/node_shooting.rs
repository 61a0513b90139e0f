//! The node shooters over a stored matrix, taken as one level (every patch a node, its column
//! its links): they converge to the LU solution, the bound they give holds at every step (the
//! residual_bound tests' checker), their names parse and refuse as the other families', and
//! groups of clusters are refused without a hierarchy. On a real hierarchy they are tested in radiosity-eval
//! (`node_shooting`).

use super::residual_bound::check;
use super::{furnace, twelve};
use radiosity_core::dense_lu::lu_solve;
use radiosity_core::{DenseColumns, LinearSystem, Real};
use radiosity_solvers::*;

/// The names run here: every node shooter, and groups of the paper's rule (clusters need a
/// hierarchy).
const NAMES: [&str; 8] = [
    "h-southwell",
    "h-pr",
    "h-xu",
    "h-jacobi",
    "h-gauss-seidel",
    "h-pr:groups=unshot:g=4",
    "h-xu:groups=spatial:g=4",
    "h-southwell:share=1",
];

/// The solution of `(I − ρ F) B = E`, channel by channel, by LU.
fn exact(system: &LinearSystem, f: &DenseColumns) -> Vec<Real> {
    let (n, k) = (system.len(), system.channels().count());
    let mut b = vec![0.0; n * k];
    for c in 0..k {
        let x =
            lu_solve(n, false, |i, j| Real::from(i == j) - system.rho(i, c) * f.get(i, j), |i| system.e(i, c)).unwrap();
        for i in 0..n {
            b[i * k + c] = x[i];
        }
    }
    b
}

#[test]
fn every_node_shooter_converges_to_the_lu_solution_and_its_bound_holds() {
    // ρ up to 0.9 in three channels, and a closed furnace at ρ = 0.99 whose answer is
    // E / (1 − ρ) = 100.
    let systems = [twelve(), furnace(vec![1.0; 6], 0.99, |i, j| if i == j { 0.0 } else { 0.2 })];
    for (system, f) in &systems {
        let star = exact(system, f);
        for name in NAMES {
            let mut solver = solver_by_name(name).unwrap();
            // A patch order for the spatial groups: runs of four in reverse.
            let order: Vec<usize> = (0..system.len()).rev().collect();
            let problem = Problem::new(system, f).unwrap().with_patch_order(&order).unwrap();
            let rules = StopRules { step_cap: 1e6, ..StopRules::parse("residual=1e-13").unwrap() };
            let run = Executor::new(solver.as_mut(), rules).run(&problem).unwrap();
            assert!(matches!(run.termination, TerminationReason::Residual(_)), "{name}: {}", run.termination);
            // The bound against the true residual at every one of the first 40 rounds (the
            // residual_bound tests' checker, with the same patch order).
            assert_eq!(check(name, system, f, "steps=40").missing, 0, "{name}");
            // The residual power below 1e-13 (relative to the emitted power), amplified by at
            // most 1/(1 − ρ) = 100: 1e-10 of the largest value, and rounding.
            let scale = star.iter().fold(0.0, |m: Real, v| m.max(v.abs()));
            for (got, want) in run.state.radiosity.iter().zip(&star) {
                assert!((got - want).abs() <= 1e-9 * scale, "{name}: {got} against {want}");
            }
            // Over one level every shot is a column; no link is shown.
            assert!(run.state.cost[Unit::Columns] > 0 && run.state.cost[Unit::Links] == 0, "{name}: {:?}", run.state);
        }
    }
}

#[test]
fn jacobi_on_the_nodes_is_jacobi_by_products() {
    // One level, every node shooting every round: the residual after round k is (ρF)^k ρ F E,
    // as Jacobi's by products, so the radiosity is the same after every round.
    let (system, f) = twelve();
    for rounds in [1, 3, 8] {
        let rules = format!("steps={rounds}");
        let nodes = solve_named("h-jacobi", &system, &f, &rules);
        let products = solve_named("jacobi:sweep=product", &system, &f, &rules);
        for (a, b) in nodes.state.radiosity.iter().zip(&products.state.radiosity) {
            assert!((a - b).abs() <= 1e-13 * b.abs().max(1.0), "after {rounds} rounds: {a} against {b}");
        }
    }
}

fn solve_named(name: &str, system: &LinearSystem, f: &DenseColumns, rules: &str) -> Run {
    let mut solver = solver_by_name(name).unwrap();
    let problem = Problem::new(system, f).unwrap();
    Executor::new(solver.as_mut(), StopRules::parse(rules).unwrap()).run(&problem).unwrap()
}

#[test]
fn clusters_need_a_hierarchy_and_spatial_groups_an_order_and_say_so() {
    let (system, f) = twelve();
    let problem = Problem::new(&system, &f).unwrap();
    for (name, says) in [
        ("h-xu:groups=clusters", "groups=clusters needs a hierarchy, and these form factors show no links"),
        ("h-xu:groups=spatial", "groups=spatial needs a spatially coherent order of the patches"),
    ] {
        let mut solver = solver_by_name(name).unwrap();
        let rules = StopRules::parse("steps=3").unwrap();
        let e = Executor::new(solver.as_mut(), rules).run(&problem).unwrap_err().to_string();
        assert!(e.contains(says), "{name}: {e}");
    }
}

#[test]
fn names_parse_keep_their_canonical_form_and_refuse_clearly() {
    for name in NODE_SOLVERS.into_iter().chain(["h-pr:share=0.25", "h-gauss-seidel:blocks=4", "h-xu:groups=unshot:g=8"])
    {
        assert_eq!(solver_by_name(name).unwrap().name(), name);
    }
    let p: NodeShootingParams = "h-xu:groups=clusters:g=16".parse().unwrap();
    assert_eq!((p.order, p.overshoot, p.grouping), (NodeOrder::Progressive, true, Grouping::Clusters { size: 16 }));
    for (bad, says) in [
        ("h-pr:share=0", "share must be in (0, 1]"),
        ("h-pr:share=x", "share takes a number"),
        ("h-jacobi:share=0.5", "'share' is not a parameter of h-jacobi"),
        ("h-pr:blocks=2", "'blocks' is not a parameter of h-pr"),
        ("h-gauss-seidel:blocks=0", "blocks must be at least 1"),
        ("h-pr:groups=sizes", "groups takes clusters, spatial or unshot"),
        ("h-pr:g=8", "g= needs groups=clusters, spatial or unshot"),
        ("h-pr:groups=unshot:g=1", "g must be between 2 and 1024"),
    ] {
        let e = solver_by_name(bad).err().unwrap().to_string();
        assert!(e.starts_with(&format!("solver '{bad}'")) && e.contains(says), "{bad}: {e}");
    }
}
