//! The node shooters on real hierarchies (`--ff hierarchical` on the Cornell box, a closed
//! furnace at ρ = 0.99 and a box inside it, occluded, at ρ = 0.99): every one converges to the
//! exact solution of the operator's own system (LU of its columns), the bound it gives holds
//! against the true residual at every round, its cost is counted in links and not in
//! columns, and the groups find what the scenes hold.

use radiosity_core::dense_lu::lu_solve;
use radiosity_core::{ColumnSource, LinearSystem, Real};
use radiosity_ff::{HierarchicalColumns, HierarchicalParams};
use radiosity_geom::{PreparedScene, spatial_order};
use radiosity_solvers::Unit;
use radiosity_solvers::{
    Executor, NODE_SOLVERS, Observer, ObserverMode, Problem, Record, ResidualBound, SolverRegistry, State, StopRules,
    TerminationReason, area_norms,
};

/// The scene's system and its operator, at a coarse threshold so that the small scenes have
/// far links between clusters.
fn operator(scene: &str) -> (PreparedScene, LinearSystem, HierarchicalColumns) {
    let p = PreparedScene::load(scene).unwrap();
    let params = HierarchicalParams { eps: 0.05, ..HierarchicalParams::default() };
    let f = HierarchicalColumns::new(p.scene(), &p.visibility().unwrap(), &p.analysis, params);
    let system = LinearSystem::from_scene(p.scene());
    (p, system, f)
}

/// The operator's matrix, row-major, from its columns.
fn dense(f: &HierarchicalColumns) -> Vec<Real> {
    let n = f.patch_count();
    let (mut rows, mut column) = (vec![0.0; n * n], vec![0.0; n]);
    for j in 0..n {
        f.fill_column(j, &mut column);
        for i in 0..n {
            rows[i * n + j] = column[i];
        }
    }
    rows
}

/// Per channel, `‖E + ρ F B − B‖_A` and `κ_c = max_j Σ_i A_i ρ_ic F_ij / A_j`.
fn residual_and_kappa(system: &LinearSystem, f: &[Real], b: &[Real]) -> Vec<(Real, Real)> {
    let (n, k, area) = (system.len(), system.channels().count(), system.areas());
    (0..k)
        .map(|c| {
            let r: Real = (0..n)
                .map(|i| {
                    let fb: Real = (0..n).map(|j| f[i * n + j] * b[j * k + c]).sum();
                    area[i] * (system.e(i, c) + system.rho(i, c) * fb - b[i * k + c]).abs()
                })
                .sum();
            let kappa = (0..n)
                .map(|j| (0..n).map(|i| area[i] * system.rho(i, c) * f[i * n + j]).sum::<Real>() / area[j])
                .fold(0.0, Real::max);
            (r, kappa)
        })
        .collect()
}

/// Checks the solver's bound against the true residual at every round.
struct Holds<'a> {
    system: &'a LinearSystem,
    f: &'a [Real],
    known: Option<ResidualBound>,
    checked: usize,
}

impl Observer for Holds<'_> {
    fn observe_step(&mut self, state: &State, _: &Record) {
        let bound = self.known.take().expect("every node shooter bounds its residual");
        let norms = area_norms(self.system.areas(), &state.radiosity, state.channels);
        for (c, (r, kappa)) in residual_and_kappa(self.system, self.f, &state.radiosity).into_iter().enumerate() {
            // Exact arithmetic's bound; the invariant drifts by about ε ‖B‖_A a round, and the
            // links' sums differ from the columns' by a few roundings: allowed sixteenfold.
            let drift = 16.0 * Real::EPSILON * norms[c] * (state.step + 1) as Real;
            assert!(r <= bound.residual_norm(c, kappa) + drift, "round {}: {r} above {bound:?}", state.step);
        }
        self.checked += 1;
    }

    fn wants_residual_bound(&self) -> bool {
        true
    }

    fn observe_residual_bound(&mut self, _: &State, bound: Option<&ResidualBound>) {
        self.known = bound.cloned();
    }
}

#[test]
fn every_node_shooter_converges_to_the_operators_own_solution() {
    let registry = SolverRegistry::builtin();
    for scene in ["cornell:res=4", "furnace:res=3:rho=0.99", "inner-box:rho=0.99"] {
        let (p, system, f) = operator(scene);
        let rows = dense(&f);
        let (n, k) = (system.len(), system.channels().count());
        let mut star = vec![0.0; n * k];
        for c in 0..k {
            let a = |i: usize, j: usize| Real::from(i == j) - system.rho(i, c) * rows[i * n + j];
            let x = lu_solve(n, false, a, |i| system.e(i, c)).unwrap();
            (0..n).for_each(|i| star[i * k + c] = x[i]);
        }
        let order = spatial_order(p.scene());
        for name in NODE_SOLVERS {
            let mut solver = registry.build(name).unwrap();
            let problem = Problem::new(&system, &f).unwrap().with_patch_order(&order).unwrap();
            let mut holds = Holds { system: &system, f: &rows, known: None, checked: 0 };
            let rules = StopRules { step_cap: 1e9, ..StopRules::parse("residual=1e-12").unwrap() };
            let run = Executor::new(solver.as_mut(), rules)
                .add_observer(&mut holds, ObserverMode::Always)
                .run(&problem)
                .unwrap();
            assert!(matches!(run.termination, TerminationReason::Residual(_)), "{scene}, {name}: {}", run.termination);
            // The bound's residual below 1e-12 of the emitted power, amplified by at most
            // 1/(1 − ρ) = 100: 1e-10 of the answer, and the links' rounding against the
            // columns' (1e-12 relative): 1e-9 of the largest value.
            let scale = star.iter().fold(0.0, |m: Real, v| m.max(v.abs()));
            let worst = run.state.radiosity.iter().zip(&star).map(|(a, b)| (a - b).abs()).fold(0.0, Real::max);
            assert!(worst <= 1e-9 * scale, "{scene}, {name}: {worst:e} off against {scale}");
            assert!(holds.checked > 2, "{scene}, {name}");
            // Shots through links, not columns (a group's block is read from the links too).
            assert!(
                run.state.cost[Unit::Columns] == 0 && run.state.cost[Unit::Links] > 0,
                "{scene}, {name}: {:?}",
                run.state
            );
        }
    }
}

#[test]
fn a_round_of_every_node_costs_the_links_of_a_product() {
    // In a furnace every patch emits, so every node holds light at the start: h-jacobi's
    // first round shoots every node, exactly the links a product touches, after the start's
    // send shares, which read every link once too.
    let (_, system, f) = operator("furnace:res=3:rho=0.99");
    let first = |name: &str| {
        let problem = Problem::new(&system, &f).unwrap();
        let mut solver = SolverRegistry::builtin().build(name).unwrap();
        Executor::new(solver.as_mut(), StopRules::parse("steps=1").unwrap()).run(&problem).unwrap()
    };
    let (round, product) = (first("h-jacobi"), first("jacobi:sweep=product"));
    assert_eq!(product.state.cost[Unit::Products], 1);
    assert!(round.state.cost[Unit::Links] > 0);
    assert_eq!(round.state.cost[Unit::Links], 2 * product.state.cost[Unit::Links]);
    // And the same radiosity, a few roundings apart: both are B = E + ρ F E.
    for (a, b) in round.state.radiosity.iter().zip(&product.state.radiosity) {
        assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{a} against {b}");
    }
}

#[test]
fn groups_solve_the_exchange_the_scene_holds_and_pay_on_a_stiff_furnace() {
    // Runs of 32 patches of the spatial order hold corners of the furnace, whose faces see
    // each other; solving their exchange at every pull brings the radiosity nearer its
    // answer, E / (1 − ρ) = 100, in the same rounds.
    let (p, system, f) = operator("furnace:res=3:rho=0.99");
    let order = spatial_order(p.scene());
    let registry = SolverRegistry::builtin();
    let run = |name: &str| {
        let problem = Problem::new(&system, &f).unwrap().with_patch_order(&order).unwrap();
        let mut solver = registry.build(name).unwrap();
        Executor::new(solver.as_mut(), StopRules::parse("steps=200").unwrap()).run(&problem).unwrap()
    };
    let (plain, grouped) = (run("h-xu"), run("h-xu:groups=spatial"));
    assert!(grouped.record.count("clustered_patches").unwrap() > 0);
    assert!(grouped.record.count("group_solves").unwrap() > 0);
    let error = |b: &[Real]| b.iter().map(|v| (v - 100.0).abs()).fold(0.0, Real::max);
    let (plain, grouped) = (error(&plain.state.radiosity), error(&grouped.state.radiosity));
    assert!(grouped < plain, "{grouped} with groups, {plain} without");
}

#[test]
fn a_links_rule_stops_a_run_once_it_has_touched_that_many() {
    let (_, system, f) = operator("cornell:res=4");
    let rules = StopRules::parse("links=20000").unwrap();
    assert_eq!(rules.rules[0].to_string(), "links=20000");
    let problem = Problem::new(&system, &f).unwrap();
    let mut solver = SolverRegistry::builtin().build("h-southwell").unwrap();
    let run = Executor::new(solver.as_mut(), rules).run(&problem).unwrap();
    assert!(matches!(run.termination, TerminationReason::Spent(Unit::Links, k) if k >= 20_000), "{}", run.termination);
    // It stopped at the first round that reached the count, not later.
    let rounds: u64 = run.record.count("rounds").unwrap();
    assert!(rounds > 1, "the count needs more than one round on this scene");
    let mut solver = SolverRegistry::builtin().build("h-southwell").unwrap();
    let before = Executor::new(solver.as_mut(), StopRules::parse(&format!("steps={}", rounds - 1)).unwrap())
        .run(&Problem::new(&system, &f).unwrap())
        .unwrap();
    assert!(before.state.cost[Unit::Links] < 20_000, "{} links a round earlier", before.state.cost[Unit::Links]);
}
