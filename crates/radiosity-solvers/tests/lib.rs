//! Tests of radiosity-solvers on small in-memory systems with exact answers: the furnace
//! identity, the two-patch closed form, the unit cube, and the accounting and stop rules (and
//! the clock they read, `clock`); the random walks over the stored matrix sampled exactly
//! (`random_walk`); and what the executor hands the observers of a solver that samples
//! transport (`sampled`); and solvers over a source split over ranks (`split`).

use radiosity_core::{Channels, DenseColumns, LinearSystem, Real};
use radiosity_solvers::*;

mod clock;
mod krylov;
mod node_shooting;
mod random_walk;
mod residual_bound;
mod sampled;
mod split;
mod stochastic_jacobi;

/// Howell's form factors between unit squares: directly opposed at distance 1, and
/// perpendicular sharing an edge (C-11 and C-14, evaluated in f64).
fn cube_form_factors() -> (Real, Real) {
    let pi = std::f64::consts::PI;
    let opposite =
        2.0 / pi * ((4.0f64 / 3.0).sqrt().ln() + 2.0 * 2f64.sqrt() * (1.0 / 2f64.sqrt()).atan() - 2.0 * 1f64.atan());
    let s = 2.0f64;
    let log = (4.0f64 / 3.0).ln() + 2.0 * (3.0f64 / 4.0).ln();
    let adjacent = (2.0 * 1f64.atan() - s.sqrt() * (1.0 / s.sqrt()).atan() + 0.25 * log) / pi;
    (opposite, adjacent)
}

/// The unit cube, one patch per face; faces 0/1 are bottom/top, 2..6 the sides. Its form
/// factors state their reciprocity (unit areas, a symmetric matrix).
fn cube() -> DenseColumns {
    let (opposite, adjacent) = cube_form_factors();
    let opposite_of = |i: usize| i ^ 1;
    DenseColumns::from_fn(6, |i, j| {
        if i == j {
            0.0
        } else if j == opposite_of(i) {
            opposite
        } else {
            adjacent
        }
    })
    .with_measured_reciprocity(&[1.0; 6])
    .unwrap()
}

/// Every point solver, the group solvers with groups of 3, under-relaxed SOR and relaxation,
/// group acceleration at every step, and the Krylov solvers (with a restart shorter than n).
fn solvers() -> Vec<String> {
    let groups = GROUP_SOLVERS.iter().map(|s| s.replace("g30", "g3"));
    POINT_SOLVERS
        .iter()
        .map(|s| s.to_string())
        .chain(groups)
        .chain(["sor-0.8", "relax-0.8", "pr-g2:f=1"].map(String::from))
        .chain(KRYLOV_SOLVERS.iter().map(|s| s.to_string()))
        .chain(["gmres-2".to_string()])
        .chain(["h-southwell", "h-xu", "h-gauss-seidel", "h-pr:groups=unshot:g=3"].map(String::from))
        .collect()
}

/// Runs `name` under `rules`, with a step cap of 2000n: these systems are tiny, and the
/// default cap of 20n steps is too short for reflectivities near 1.
fn solve(name: &str, system: &LinearSystem, f: &DenseColumns, rules: &str) -> Run {
    solve_capped(name, system, f, rules, 2000.0)
}

fn solve_capped(name: &str, system: &LinearSystem, f: &DenseColumns, rules: &str, cap: f64) -> Run {
    let mut solver = solver_by_name(name).unwrap();
    let problem = Problem::new(system, f).unwrap();
    let rules = StopRules { step_cap: cap, ..StopRules::parse(rules).unwrap() };
    Executor::new(solver.as_mut(), rules).run(&problem).unwrap()
}

#[test]
fn the_cube_form_factors_are_howells_values() {
    let (opposite, adjacent) = cube_form_factors();
    assert!((opposite - 0.1998249).abs() < 5e-8);
    assert!((adjacent - 0.2000438).abs() < 5e-8);
    assert!((opposite + 4.0 * adjacent - 1.0).abs() < 1e-12, "a closed cube's rows sum to 1");
}

#[test]
fn furnace_identity_per_channel() {
    // Uniform ρ and E in a closed box: B = E / (1 − ρ), with a different ρ per channel.
    let rho = [0.9, 0.5, 0.0];
    let e = [1.0, 2.0, 3.0];
    let system = LinearSystem::new(Channels::Rgb, vec![1.0; 6], rho.repeat(6), e.repeat(6)).unwrap();
    let f = cube();
    for name in solvers().iter().map(String::as_str) {
        let run = solve(name, &system, &f, "residual=1e-13");
        assert!(
            matches!(run.termination, TerminationReason::Residual(_) | TerminationReason::RoundOff),
            "{name}: {}",
            run.termination
        );
        for i in 0..6 {
            for c in 0..3 {
                let exact = e[c] / (1.0 - rho[c]);
                let got = run.state.radiosity[i * 3 + c];
                assert!((got / exact - 1.0).abs() < 1e-10, "{name}: patch {i} channel {c}: {got} against {exact}");
            }
        }
    }
}

#[test]
fn two_patches_match_their_closed_form() {
    // A1 = 1, A2 = 2, F12 = 0.4, so F21 = 0.2 by reciprocity.
    let (a, b) = (0.4, 0.2);
    let (r1, r2, e1, e2) = (0.7, 0.3, 1.5, 0.25);
    let system = LinearSystem::new(Channels::Grey, vec![1.0, 2.0], vec![r1, r2], vec![e1, e2]).unwrap();
    let f = DenseColumns::from_rows(2, &[0.0, a, b, 0.0]).unwrap().with_measured_reciprocity(&[1.0, 2.0]).unwrap();
    let d = 1.0 - r1 * r2 * a * b;
    let exact = [(e1 + r1 * a * e2) / d, (e2 + r2 * b * e1) / d];
    for name in solvers().iter().map(String::as_str) {
        let run = solve(name, &system, &f, "residual=1e-14");
        for (i, exact) in exact.iter().enumerate() {
            assert!((run.state.radiosity[i] / exact - 1.0).abs() < 1e-12, "{name}: patch {i}");
        }
    }
}

#[test]
fn the_unit_cube_with_an_emitting_top() {
    // Top emits 1, ρ everywhere; values from the issue, to 6 decimals.
    for (rho, top, bottom, side) in [(0.5, 1.090909, 0.181746, 0.181836), (0.9, 2.372881, 1.525311, 1.525452)] {
        let mut e = vec![0.0; 6];
        e[1] = 1.0;
        let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![rho; 6], e).unwrap();
        let f = cube();
        for name in solvers().iter().map(String::as_str) {
            let b = solve(name, &system, &f, "residual=1e-14").state.radiosity;
            for (i, expected) in [(1, top), (0, bottom), (2, side), (5, side)] {
                assert!((b[i] - expected).abs() < 5e-7, "{name}, ρ = {rho}: patch {i} is {} not {expected}", b[i]);
            }
        }
    }
}

#[test]
fn accounting_counts_one_column_a_step() {
    let system =
        LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    let f = cube();
    for name in POINT_SOLVERS.into_iter().chain(["sor-0.8", "relax-0.8"]) {
        let run = solve(name, &system, &f, "steps=2n");
        assert_eq!(run.termination, TerminationReason::Steps(12), "{name}");
        assert_eq!(run.state.cost[Unit::Columns], 12, "{name}");
        let run = solve(name, &system, &f, "columns=7,steps=100");
        assert_eq!(run.termination, TerminationReason::Spent(Unit::Columns, 7), "{name}");
        assert_eq!(run.solver, name);
    }
}

/// A column source that sleeps 1 ms before each column.
struct Sleepy<'a>(&'a DenseColumns);

impl radiosity_core::ColumnSource for Sleepy<'_> {
    fn patch_count(&self) -> usize {
        radiosity_core::ColumnSource::patch_count(self.0)
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        std::thread::sleep(std::time::Duration::from_millis(1));
        radiosity_core::ColumnSource::fill_column(self.0, j, column);
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        radiosity_core::ColumnSource::reciprocity_bound(self.0)
    }
}

#[test]
fn column_time_is_form_factor_time() {
    // 12 columns of at least 1 ms each: at least 12 ms of form factors, and none of it
    // counted as solving (a 6-patch step takes microseconds).
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let f = cube();
    let slow = Sleepy(&f);
    for name in solvers().iter().map(String::as_str) {
        let mut solver = solver_by_name(name).unwrap();
        let problem = Problem::new(&system, &slow).unwrap();
        let run = Executor::new(solver.as_mut(), StopRules::parse("steps=12").unwrap()).run(&problem).unwrap();
        assert!(run.state.cost.ff_seconds >= 0.012, "{name}: {}", run.state.cost.ff_seconds);
        assert!(
            run.state.cost.solve_seconds < run.state.cost.ff_seconds,
            "{name}: {} s solving",
            run.state.cost.solve_seconds
        );
    }
}

#[test]
fn runs_end_at_round_off_or_at_the_step_cap_unless_timed() {
    // No rule: PR converges to round-off on the cube well before 20n steps.
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let f = cube();
    let run = solve("pr", &system, &f, "");
    assert_eq!(run.termination, TerminationReason::RoundOff);
    // A slowly converging system (ρ = 0.999) hits the cap of 20n = 120 steps.
    let slow = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.999; 6], vec![1.0; 6]).unwrap();
    let run = solve_capped("jacobi", &slow, &f, "", StopRules::default().step_cap);
    assert_eq!(run.termination, TerminationReason::StepCap(120));
    assert_eq!(run.state.step, 120);
    // An explicit rule beyond the cap raises it.
    let run = solve_capped("jacobi", &slow, &f, "steps=50n", StopRules::default().step_cap);
    assert_eq!(run.termination, TerminationReason::Steps(300));
    // A `time=` rule lifts the cap: the run goes on to its residual, far past 120 steps
    // (Jacobi at ρ = 0.999 contracts the residual by 0.999 a step at best).
    let run = solve_capped("jacobi", &slow, &f, "residual=1e-2,time=300s", StopRules::default().step_cap);
    assert!(matches!(run.termination, TerminationReason::Residual(_)), "{}", run.termination);
    assert!(run.state.step > 1000, "{} steps", run.state.step);
    // Nothing emitted: nothing to do.
    let dark = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![0.0; 6]).unwrap();
    assert_eq!(solve("southwell", &dark, &f, "").termination, TerminationReason::RoundOff);
}

#[test]
fn pr_shoots_by_area_and_southwell_by_value() {
    // Patch 0: small area, large unshot; patch 1: large area, smaller unshot.
    let system = LinearSystem::new(Channels::Grey, vec![1.0, 10.0, 10.0], vec![0.5; 3], vec![5.0, 1.0, 0.0]).unwrap();
    let f = DenseColumns::from_fn(3, |i, j| if i == j { 0.0 } else { 0.1 });
    let first_shooter = |name: &str| {
        let run = solve(name, &system, &f, "steps=1");
        (0..2).find(|&i| run.state.unshot[i] == 0.0).unwrap()
    };
    assert_eq!(first_shooter("pr"), 1, "A·|ΔB|: 10 > 5");
    assert_eq!(first_shooter("southwell"), 0, "|ΔB|: 5 > 1");
}

/// e_rms against `star`, as a monitor.
fn rms(star: Vec<Real>) -> impl FnMut(&State) -> Option<Real> {
    move |state: &State| {
        let num: Real = state.radiosity.iter().zip(&star).map(|(b, x)| (b - x).powi(2)).sum();
        let den: Real = star.iter().map(|x| x * x).sum();
        Some((num / den).sqrt())
    }
}

#[test]
fn the_rms_rule_uses_the_monitor() {
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let f = cube();
    let mut solver = solver_by_name("gauss-seidel").unwrap();
    let problem = Problem::new(&system, &f).unwrap();
    let mut monitor = rms(vec![2.0; 6]);
    let run = Executor::new(solver.as_mut(), StopRules::parse("rms=1e-6").unwrap())
        .monitor(&mut monitor)
        .run(&problem)
        .unwrap();
    let TerminationReason::Rms(e) = run.termination else { panic!("{}", run.termination) };
    assert!(e <= 1e-6);
}

#[test]
fn stop_rules_parse_and_refuse_clearly() {
    let rules = StopRules::parse("columns=2n, steps=100, rms=1e-3, residual=1e-4, time=30s").unwrap();
    assert_eq!(rules.rules.len(), 5);
    assert_eq!(rules.rules[0], StopRule::Spent(Unit::Columns, Count::PerPatch(2.0)));
    assert_eq!(Count::PerPatch(2.0).resolve(480), 960);
    assert_eq!(StopRules::parse("time=250ms").unwrap().rules[0], StopRule::Time(std::time::Duration::from_millis(250)));
    assert_eq!(StopRules::parse("time=2min").unwrap().rules[0], StopRule::Time(std::time::Duration::from_secs(120)));
    assert_eq!(StopRules::parse("steps=n").unwrap().rules[0], StopRule::Steps(Count::PerPatch(1.0)));
    assert!(StopRules::parse("").unwrap().rules.is_empty());
    for (bad, words) in [
        ("columns", "expected key=value"),
        ("columns=-3", "positive integer"),
        ("columns=0", "positive integer"),
        ("columns=xn", "number before n"),
        ("rms=0", "positive number"),
        ("rms=abc", "positive number"),
        ("time=30", "unit"),
        ("colums=5", "unknown rule (did you mean 'columns'?)"),
    ] {
        let e = StopRules::parse(bad).unwrap_err().to_string();
        assert!(e.contains(bad) && e.contains(words) && e.contains("columns=2n"), "{bad}: {e}");
    }
}

#[test]
fn errors_are_reported_not_panicked() {
    assert!(matches!(solver_by_name("xu-q30").err(), Some(SolverError::UnknownSolver { .. })));
    for bad in ["sor-2.5", "relax-2", "pr-g0", "southwell-g30", "pr-g30:f=0"] {
        let e = solver_by_name(bad).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.starts_with(&format!("solver '{bad}': ")), "{bad}: {e}");
    }
    let typo = solver_by_name("xu-q30").err().unwrap().to_string();
    assert!(typo.contains("unknown solver 'xu-q30' (did you mean 'xu-g30'?)"), "{typo}");
    for (bad, words) in [
        ("xu-g30-m10", "must hold at least a group"),
        ("pr-g0", "at least one patch"),
        ("group-pr-g0", "at least one patch"),
        ("pr-g30:f=0", "f ≥ 1"),
        ("pr-g30:f=often", "f ≥ 1"),
        ("pr-g30:target=-1", "positive number"),
        ("pr-g30:speed=2", "not a parameter"),
        ("southwell-g30", "not to southwell"),
        ("group-relax-2.5-g30", "0 < ω < 2"),
        ("group-magic-g30", "unknown solver"),
        ("pr:f=10", "takes no parameters"),
    ] {
        let e = solver_by_name(bad).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains(words), "{bad}: {e}");
    }
    for good in ["pr-g30", "xu-g30-m480:f=10", "pr-g30:f=auto:target=0.1", "group-southwell-g5", "relax-1.2-g8-m16"] {
        assert_eq!(solver_by_name(good).unwrap().name(), good);
    }
    assert!(solver_by_name("sor-2.5").err().unwrap().to_string().contains("0 < ω < 2"));
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 2], vec![0.5; 2], vec![1.0; 2]).unwrap();
    let f = cube();
    assert!(matches!(Problem::new(&system, &f), Err(SolverError::SizeMismatch { columns: 6, system: 2 })));
    // A form factor that is not finite stops the run at the first step that uses it (within
    // the first sweep or the first two shots), naming a patch.
    // (An infinite entry has no reciprocity to state, so `cg` refuses it before any step.)
    let broken = DenseColumns::from_rows(2, &[0.0, 0.5, f64::INFINITY, 0.0]).unwrap();
    let measured = broken.clone().with_measured_reciprocity(&[1.0; 2]).unwrap();
    assert_eq!(radiosity_core::ColumnSource::reciprocity_bound(&measured), Some(Real::INFINITY));
    for name in solvers().iter().map(String::as_str) {
        let mut solver = solver_by_name(name).unwrap();
        let problem = Problem::new(&system, &broken).unwrap();
        let err = Executor::new(solver.as_mut(), StopRules::default()).run(&problem).unwrap_err();
        if name == "cg" {
            assert!(matches!(err, SolverError::NotApplicable { .. }), "{err:?}");
            continue;
        }
        assert!(
            matches!(err, SolverError::NonFinite { step: 1 | 2, .. } | SolverError::SingularGroup { step: 1 | 2, .. }),
            "{name}: {err:?}"
        );
        assert!(err.to_string().starts_with("step "), "{err}");
    }
}

#[test]
fn a_column_served_from_memory_costs_no_column_and_is_counted_apart() {
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let f = cube();
    let problem = Problem::new(&system, &f).unwrap();
    let mut memory = ColumnMemory::new(6, 2);
    let mut scratch = Vec::new();
    assert_eq!(memory.column(&problem, 0, &mut scratch), f.column(0));
    assert_eq!(memory.column(&problem, 1, &mut scratch), f.column(1));
    assert_eq!(memory.column(&problem, 0, &mut scratch), f.column(0));
    assert_eq!((problem.spent(Unit::Columns), problem.spent(Unit::Reused)), (2, 1));
    // Full: 2 is stored in place of the least recently used, 1; 0 stays.
    assert_eq!(memory.column(&problem, 2, &mut scratch), f.column(2));
    assert!(memory.contains(0) && memory.contains(2) && !memory.contains(1));
    assert_eq!(memory.peek(2), Some(f.column(2)));
    assert_eq!(memory.peek(1), None);
    assert_eq!(memory.column(&problem, 1, &mut scratch), f.column(1));
    assert_eq!((problem.spent(Unit::Columns), problem.spent(Unit::Reused)), (4, 1));
    assert_eq!(memory.len(), 2);
    // No capacity: every column is computed.
    let mut none = ColumnMemory::new(6, 0);
    assert_eq!(none.column(&problem, 3, &mut scratch), f.column(3));
    assert_eq!(none.column(&problem, 3, &mut scratch), f.column(3));
    assert_eq!((problem.spent(Unit::Columns), problem.spent(Unit::Reused)), (6, 1));
    assert!(none.is_empty());
}

/// A 12-patch enclosure-like system with exact reciprocity and unequal areas: `F_ij = G_ij /
/// A_i` for a symmetric `G` scaled so rows sum to at most 0.95, RGB, three emitters.
fn twelve() -> (LinearSystem, DenseColumns) {
    enclosure(12)
}

/// [`twelve`]'s system on `n` patches, one in four emitting.
fn enclosure(n: usize) -> (LinearSystem, DenseColumns) {
    let area: Vec<Real> = (0..n).map(|i| 1.0 + (i % 5) as Real * 0.3).collect();
    let g = |i: usize, j: usize| if i == j { 0.0 } else { 1.0 + ((i * 7 + j * 7 + i * j) % 11) as Real };
    let max_row = (0..n).map(|i| (0..n).map(|j| g(i, j)).sum::<Real>() / area[i]).fold(0.0, Real::max);
    let f = DenseColumns::from_fn(n, |i, j| 0.95 * g(i, j) / area[i] / max_row);
    let rho: Vec<Real> = (0..3 * n).map(|idx| 0.3 + 0.6 * ((idx * 5) % 7) as Real / 7.0).collect();
    let e: Vec<Real> = (0..3 * n).map(|idx| if (idx / 3) % 4 == 1 { 1.0 + (idx % 3) as Real } else { 0.0 }).collect();
    (LinearSystem::new(Channels::Rgb, area, rho, e).unwrap(), f)
}

/// `E + ρ F x − x` for the shot radiosity `x = B − ΔB`.
fn residual_of_shot(system: &LinearSystem, f: &DenseColumns, state: &State) -> Vec<Real> {
    let (n, k) = (system.len(), state.channels);
    let x: Vec<Real> = state.radiosity.iter().zip(&state.unshot).map(|(b, u)| b - u).collect();
    (0..n * k)
        .map(|idx| {
            let (i, c) = (idx / k, idx % k);
            let fx: Real = (0..n).map(|j| f.get(i, j) * x[j * k + c]).sum();
            system.e(i, c) + system.rho(i, c) * fx - x[idx]
        })
        .collect()
}

const SHOOTING: [&str; 13] = [
    "xu-g4-m8:f=2:inner=gs",
    "pr-g4-m12:f=2:groups=interaction",
    "xu-g4-m12:f=2:adaptive=0.2",
    "southwell",
    "pr",
    "xu",
    "shao",
    "relax-1.5",
    "group-pr-g4",
    "group-xu-g4",
    "group-southwell-g3",
    "pr-g4:f=2",
    "xu-g3-m8:f=1",
];

#[test]
fn shooting_keeps_the_unshot_radiosity_equal_to_the_residual_of_the_shot_one() {
    // Whatever the overshoot and the group, ΔB stays exactly the residual of x = B − ΔB.
    let (system, f) = twelve();
    for name in SHOOTING {
        for steps in [1, 5, 17] {
            let run = solve(name, &system, &f, &format!("steps={steps}"));
            let r = residual_of_shot(&system, &f, &run.state);
            for (idx, (r, u)) in r.iter().zip(&run.state.unshot).enumerate() {
                assert!((r - u).abs() < 1e-13, "{name} after {steps} steps, entry {idx}: residual {r}, unshot {u}");
            }
        }
    }
}

#[test]
fn a_group_step_leaves_zero_unshot_in_the_group_or_minus_the_overshoot() {
    let (system, f) = twelve();
    let k = 3;
    // Group PR: the group holds exactly zero unshot after its step. The first group is the 3
    // emitters (no other patch has unshot radiosity); the second, 4 patches, which leaves
    // exactly 4 zeros (the emitters received light again).
    let zeros = |state: &State| (0..12).filter(|&i| (0..k).all(|c| state.unshot[i * k + c] == 0.0)).count();
    let run = solve("group-pr-g4", &system, &f, "steps=1");
    assert_eq!((zeros(&run.state), run.state.cost[Unit::Columns]), (3, 3), "{:?}", run.state.unshot);
    let run = solve("group-pr-g4", &system, &f, "steps=2");
    assert_eq!(zeros(&run.state), 4, "{:?}", run.state.unshot);
    // Group relaxation: the group holds exactly −ΔB⁺ = −(ω − 1) ΔB. The first group is the
    // 3 emitters.
    let run = solve("group-relax-1.5-g4", &system, &f, "steps=1");
    for i in 0..12 {
        for c in 0..k {
            let expected = if system.e(i, c) > 0.0 { -0.5 * system.e(i, c) } else { 0.0 };
            let got = run.state.unshot[i * k + c];
            assert!(system.e(i, c) == 0.0 || got == expected, "patch {i}: {got} against {expected}");
        }
    }
    // Group Feda: the overshoot anticipates light from outside the group only; with every
    // emitter in the group nothing is outside, so the group holds exactly zero.
    let run = solve("group-feda-g4", &system, &f, "steps=1");
    assert_eq!(zeros(&run.state), 4, "{:?}", run.state.unshot);
}

#[test]
fn group_acceleration_stores_columns_and_reuses_them() {
    let (system, f) = twelve();
    // Emitters that reflect nothing shoot once, and their columns are not kept; the other 9
    // columns are computed once and then served from a memory that holds them all.
    let rho: Vec<Real> = (0..36)
        .map(|idx| if system.emissions()[idx - idx % 3] > 0.0 { 0.0 } else { system.reflectivities()[idx] })
        .collect();
    let dark_emitters =
        LinearSystem::new(Channels::Rgb, system.areas().to_vec(), rho, system.emissions().to_vec()).unwrap();
    let run = solve("pr-g4-m12:f=3", &dark_emitters, &f, "steps=200");
    assert_eq!(run.state.cost[Unit::Columns], 12);
    assert!(run.state.cost[Unit::Reused] > 0);
    assert_eq!(run.state.cost[Unit::Columns] + run.state.cost[Unit::Reused], run.state.step);
    assert!(run.state.cost.group_seconds > 0.0 && run.state.cost.group_seconds <= run.state.cost.solve_seconds);
    // Group shooting with the group's columns kept: a member chosen again costs nothing. The
    // first group is the 3 emitters, every later one has 4 patches.
    let run = solve("group-pr-g4", &system, &f, "steps=30");
    assert_eq!(run.state.cost[Unit::Columns] + run.state.cost[Unit::Reused], 4 * run.state.step - 1);
}

/// Runs `name` on `problem` under `rules`, with the step cap of [`solve`].
fn solve_problem(name: &str, problem: &Problem<'_>, rules: &str) -> Result<Run, SolverError> {
    let mut solver = solver_by_name(name)?;
    let rules = StopRules { step_cap: 2000.0, ..StopRules::parse(rules).unwrap() };
    Executor::new(solver.as_mut(), rules).run(problem)
}

/// The largest relative difference between two radiosity vectors.
fn max_relative(a: &[Real], b: &[Real]) -> Real {
    a.iter().zip(b).map(|(x, y)| (x - y).abs() / y.abs().max(1e-300)).fold(0.0, Real::max)
}

#[test]
fn one_group_holding_every_patch_solves_the_system_in_one_step() {
    // The unit cube with an emitting top, ρ = 0.9, and the 12-patch RGB system: with m = n
    // the one group's LU is the whole solve.
    let mut e = vec![0.0; 6];
    e[1] = 1.0;
    let cube_system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.9; 6], e).unwrap();
    let (twelve_system, twelve_f) = twelve();
    for (system, f, name) in [(&cube_system, &cube(), "group-gs-g6"), (&twelve_system, &twelve_f, "group-gs-g12")] {
        let exact = solve("gauss-seidel", system, f, "residual=1e-15").state.radiosity;
        for solver in [name.to_string(), name.replace("gs", "jacobi"), format!("{name}0")] {
            let run = solve(&solver, system, f, "steps=1");
            assert_eq!((run.state.step, run.state.cost[Unit::Columns]), (1, system.len() as u64), "{solver}");
            let error = max_relative(&run.state.radiosity, &exact);
            assert!(error < 1e-12, "{solver}: {error:e} from Gauss–Seidel");
            assert!(run.state.cost.group_seconds > 0.0 && run.state.cost.group_seconds <= run.state.cost.solve_seconds);
        }
    }
    // The cube's closed form (to 6 decimals, as above).
    let b = solve("group-gs-g6", &cube_system, &cube(), "steps=1").state.radiosity;
    for (i, expected) in [(1, 2.372881), (0, 1.525311), (2, 1.525452)] {
        assert!((b[i] - expected).abs() < 5e-7, "patch {i}: {}", b[i]);
    }
}

#[test]
fn group_gathering_converges_to_gauss_seidel_a_group_of_columns_a_step() {
    let (system, f) = twelve();
    let exact = solve("gauss-seidel", &system, &f, "residual=1e-15").state.radiosity;
    for name in ["group-jacobi-g4", "group-gs-g4", "group-gs-g5", "group-jacobi-g4:groups=index"] {
        let run = solve(name, &system, &f, "residual=1e-13");
        assert!(matches!(run.termination, TerminationReason::Residual(_)), "{name}: {}", run.termination);
        let error = max_relative(&run.state.radiosity, &exact);
        assert!(error < 1e-12, "{name}: {error:e} from Gauss–Seidel after {} steps", run.state.step);
        if name.contains("g4") {
            // 12 = 3 × 4: every step gathers a whole group of 4 rows.
            assert_eq!(run.state.cost[Unit::Columns], 4 * run.state.step, "{name}");
        }
        // The unshot radiosity keeps each patch's last change, as for point gathering.
        assert!(run.state.unshot.iter().all(|u| u.is_finite()));
        assert_eq!(run.solver, name.trim_end_matches(":groups=index"));
    }
    // Groups of 5 over 12 patches: 5 + 5 + 2, so a sweep is 3 steps and 12 columns.
    let run = solve("group-gs-g5", &system, &f, "steps=3");
    assert_eq!(run.state.cost[Unit::Columns], 12);
    // Group Gauss–Seidel needs no more sweeps than point Gauss–Seidel, and group Jacobi no more
    // than point Jacobi.
    let columns = |name: &str| solve(name, &system, &f, "residual=1e-10").state.cost[Unit::Columns];
    assert!(columns("group-gs-g4") <= columns("gauss-seidel"));
    assert!(columns("group-jacobi-g4") <= columns("jacobi"));
}

#[test]
fn spatial_groups_follow_the_order_the_problem_carries() {
    let (system, f) = twelve();
    let exact = solve("gauss-seidel", &system, &f, "residual=1e-15").state.radiosity;
    let reversed: Vec<usize> = (0..12).rev().collect();
    let problem = Problem::new(&system, &f).unwrap().with_patch_order(&reversed).unwrap();
    assert_eq!(problem.patch_order(), Some(&reversed[..]));
    for name in ["group-gs-g4:groups=spatial", "group-jacobi-g4:groups=spatial"] {
        let first = solve_problem(name, &problem, "steps=1").unwrap();
        // The first group is patches 11, 10, 9, 8: they alone changed.
        let changed: Vec<usize> = (0..12)
            .filter(|&i| first.state.radiosity[i * 3..i * 3 + 3] != system.emissions()[i * 3..i * 3 + 3])
            .collect();
        assert_eq!(changed, vec![8, 9, 10, 11], "{name}");
        let run = solve_problem(name, &problem, "residual=1e-13").unwrap();
        assert!(matches!(run.termination, TerminationReason::Residual(_)), "{name}: {}", run.termination);
        assert_eq!(run.solver, name);
        let error = max_relative(&run.state.radiosity, &exact);
        assert!(error < 1e-12, "{name}: {error:e} from Gauss–Seidel");
    }
    // Point solvers and index groups ignore the order.
    let plain = solve("group-gs-g4", &system, &f, "steps=5").state.radiosity;
    assert_eq!(solve_problem("group-gs-g4", &problem, "steps=5").unwrap().state.radiosity, plain);
    // Without an order: a clear error at the start of the run, not a panic.
    let bare = Problem::new(&system, &f).unwrap();
    let err = solve_problem("group-gs-g30:groups=spatial", &bare, "steps=1").unwrap_err();
    assert!(matches!(err, SolverError::BadParams(_)), "{err:?}");
    assert_eq!(
        err.to_string(),
        "group-gs-g30:groups=spatial needs a spatial patch order, which the caller did not give"
    );
    // An order that is not a permutation of 0..n is refused.
    for (bad, words) in [
        (vec![0, 1, 2], "3 entries"),
        ((0..11).chain([3]).collect::<Vec<_>>(), "patch 3, is repeated"),
        ((0..11).chain([12]).collect::<Vec<_>>(), "patch 12, is out of range"),
    ] {
        let err = Problem::new(&system, &f).unwrap().with_patch_order(&bad).err().unwrap();
        assert!(matches!(err, SolverError::BadParams(_)) && err.to_string().contains(words), "{bad:?}: {err}");
    }
    // Names and parameters.
    for (bad, words) in [
        ("group-gs-g0", "at least one patch"),
        ("group-jacobi-g30:groups=random", "groups=index or groups=spatial"),
        ("group-gs-g30:f=10", "not a parameter"),
    ] {
        let e = solver_by_name(bad).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains(words), "{bad}: {e}");
    }
    assert_eq!(solver_by_name("group-gs-g30:groups=index").unwrap().name(), "group-gs-g30");
    assert_eq!(solver_by_name("group-jacobi-g8:groups=spatial").unwrap().name(), "group-jacobi-g8:groups=spatial");
}

#[test]
fn inner_gauss_seidel_solves_the_group_as_lu_does() {
    // Large groups solved iteratively: the same radiosity as LU, to the inner tolerance.
    let (system, f) = twelve();
    for name in ["xu-g8-m12:f=1", "pr-g12:f=1"] {
        let lu = solve(name, &system, &f, "steps=40");
        let gs = solve(&format!("{name}:inner=gs"), &system, &f, "steps=40");
        for (a, b) in lu.state.radiosity.iter().zip(&gs.state.radiosity) {
            assert!((a - b).abs() <= 1e-11 * a.abs().max(1.0), "{name}: {a} against {b}");
        }
    }
}

// Guard rails: the condition of group systems, their fallback, and divergence.

use radiosity_core::dense_lu::{lu_solve, lu_solve_columns};

#[test]
fn lu_solves_several_right_hand_sides_with_one_factorisation() {
    let a = [[4.0, 1.0, 0.5], [1.0, 3.0, -1.0], [0.0, 2.0, 5.0]];
    let rhs = vec![vec![1.0, 2.0, 3.0], vec![1.0; 3], vec![-2.0, 0.0, 7.5]];
    let solved = lu_solve_columns(3, false, |i, j| a[i][j], &rhs).unwrap();
    assert_eq!(solved.len(), 3);
    for (b, x) in rhs.iter().zip(&solved) {
        for i in 0..3 {
            let ax: Real = (0..3).map(|j| a[i][j] * x[j]).sum();
            assert!((ax - b[i]).abs() < 1e-14, "{ax} against {}", b[i]);
        }
        // The one-column wrapper gives the same solution.
        assert_eq!(&lu_solve(3, false, |i, j| a[i][j], |i| b[i]).unwrap(), x);
    }
    assert!(lu_solve_columns(3, false, |i, j| a[i][j], &[]).unwrap().is_empty());
    let singular =
        lu_solve_columns(2, false, |_, _| 1.0, &rhs[..1].iter().map(|b| b[..2].to_vec()).collect::<Vec<_>>());
    assert_eq!(singular.unwrap_err().value, 0.0);
}

/// A closed grey furnace of `n` patches whose form factors come from `f` (rows summing to 1),
/// uniform reflectivity `rho`, every patch emitting 1.
fn furnace(area: Vec<Real>, rho: Real, f: impl FnMut(usize, usize) -> Real) -> (LinearSystem, DenseColumns) {
    let n = area.len();
    let system = LinearSystem::new(Channels::Grey, area, vec![rho; n], vec![1.0; n]).unwrap();
    (system, DenseColumns::from_fn(n, f))
}

#[test]
fn the_condition_estimate_is_exact_on_a_closed_furnace() {
    for rho in [0.5, 0.999] {
        // Planar patches, F_ij = 1/(n − 1) off the diagonal: ‖Φ‖_∞ = 1 + ρ and
        // Φ⁻¹ 1 = 1/(1 − ρ), so κ_∞ = (1 + ρ)/(1 − ρ).
        let (system, f) = furnace(vec![1.0; 6], rho, |i, j| if i == j { 0.0 } else { 0.2 });
        let run = solve("group-pr-g6", &system, &f, "steps=1");
        let exact = (1.0 + rho) / (1.0 - rho);
        let got = run.record.real("group_condition").unwrap();
        assert!((got / exact - 1.0).abs() < 1e-9, "ρ = {rho}: κ_∞ {got} against {exact}");
        assert_eq!(run.record.count("group_fallbacks"), Some(0));
        // The one group is the whole system: one step solves it, B = E/(1 − ρ).
        for b in &run.state.radiosity {
            assert!((b * (1.0 - rho) - 1.0).abs() < 1e-10, "ρ = {rho}: {b}");
        }
        // F_ij = A_j / ΣA (rows sum to 1, with F_ii = A_i/ΣA ≠ 0): Φ = I − ρ 1 wᵀ with
        // w = A/ΣA, so ‖Φ‖_∞ = 1 + ρ − 2ρ min w and ‖Φ⁻¹‖_∞ = 1/(1 − ρ) (Sherman–Morrison).
        let area: Vec<Real> = (0..6).map(|i| 1.0 + i as Real).collect();
        let total: Real = area.iter().sum();
        let weights: Vec<Real> = area.iter().map(|a| a / total).collect();
        let (system, f) = furnace(area.clone(), rho, |_, j| weights[j]);
        let run = solve("group-pr-g6", &system, &f, "steps=1");
        let exact = (1.0 + rho - 2.0 * rho * weights[0]) / (1.0 - rho);
        let got = run.record.real("group_condition").unwrap();
        assert!((got / exact - 1.0).abs() < 1e-9, "ρ = {rho}, F_ij = A_j/ΣA: κ_∞ {got} against {exact}");
        for b in &run.state.radiosity {
            assert!((b * (1.0 - rho) - 1.0).abs() < 1e-10, "ρ = {rho}: {b}");
        }
    }
    // The inner Gauss–Seidel's bound (1 + q)/(1 − q), q = ‖ρ F_rr‖_∞ = ρ, is exact here too.
    let (system, f) = furnace(vec![1.0; 6], 0.5, |i, j| if i == j { 0.0 } else { 0.2 });
    let problem = Problem::new(&system, &f).unwrap();
    let group: Vec<usize> = (0..6).collect();
    let columns: Vec<&[Real]> = group.iter().map(|&g| f.column(g)).collect();
    for inner in [InnerSolve::Lu, InnerSolve::GaussSeidel] {
        let mut state = State::from_emission(system.emissions(), 1);
        let shot = group_shot(&problem, &mut state, &group, &columns, &[0.0; 6], inner).unwrap();
        assert!((shot.condition / 3.0 - 1.0).abs() < 1e-12, "{inner:?}: {}", shot.condition);
    }
    // No group step: no estimate, 0 for a group solver before its first group step (the
    // emitters shoot first) and nothing at all for a point solver.
    let run = solve("pr-g2:f=1", &system, &f, "steps=1");
    assert_eq!((run.record.real("group_condition"), run.record.count("group_steps")), (Some(0.0), Some(0)));
    assert!(solve("pr", &system, &f, "steps=3").record.is_empty());
    assert_eq!(CONDITION_LIMIT, 1e10);
}

/// Checks that `ΔB` is the residual of `x = B − ΔB`, to 1e-12 relative to the largest `|x|`
/// (at least 1).
fn assert_unshot_is_the_residual(name: &str, system: &LinearSystem, f: &DenseColumns, state: &State) {
    let scale = state.radiosity.iter().zip(&state.unshot).map(|(b, u)| (b - u).abs()).fold(1.0, Real::max);
    let r = residual_of_shot(system, f, state);
    for (idx, (r, u)) in r.iter().zip(&state.unshot).enumerate() {
        assert!((r - u).abs() <= 1e-12 * scale, "{name}, entry {idx}: residual {r}, unshot {u}");
    }
}

/// Six RGB patches; patches 0, 1 and 2 see each other with F = `inside` (so `ρ F_rr` has
/// spectral radius `2 ρ inside`), every other pair with F = 0.05, ρ = 0.9; patches 0, 1 and 2
/// emit (`emitting_group`) or patch 5 alone does, seen by the group with F = 0.3.
fn bad_group(inside: Real, emitting_group: bool) -> (LinearSystem, DenseColumns) {
    let n = 6;
    let e: Vec<Real> = (0..3 * n).map(|idx| if (idx / 3 < 3) == emitting_group { 1.0 } else { 0.0 }).collect();
    let f = DenseColumns::from_fn(n, |i, j| match (i, j) {
        _ if i == j => 0.0,
        (0..3, 0..3) => inside,
        (0..3, 5) if !emitting_group => 0.3,
        _ => 0.05,
    });
    (LinearSystem::new(Channels::Rgb, vec![1.0; n], vec![0.9; 3 * n], e).unwrap(), f)
}

#[test]
fn a_group_that_is_singular_or_not_an_m_matrix_falls_back_to_point_shots() {
    // inside = 1/(2ρ): ρ F_rr has spectral radius exactly 1 and Φ_rr is singular, its
    // pivot an exact zero (ρ F = 1/2 is exact in binary); inside = 1.2: spectral radius 2.16,
    // Φ_rr is regular but not an M-matrix.
    for inside in [1.0 / 1.8, 1.2] {
        let (system, f) = bad_group(inside, true);
        let problem = Problem::new(&system, &f).unwrap();
        let group = [0, 1, 2];
        let columns: Vec<&[Real]> = group.iter().map(|&g| f.column(g)).collect();
        for inner in [InnerSolve::Lu, InnerSolve::GaussSeidel] {
            let mut state = State::from_emission(system.emissions(), 3);
            let shot = group_shot(&problem, &mut state, &group, &columns, &[0.0; 9], inner).unwrap();
            assert!(shot.fell_back, "{inside}, {inner:?}");
            assert_eq!(shot.condition, Real::INFINITY, "{inside}, {inner:?}");
            // The fallback shot each member in turn: the last one holds nothing.
            assert!(state.unshot[6..9].iter().all(|&u| u == 0.0), "{:?}", state.unshot);
            assert_unshot_is_the_residual(&format!("{inside}, {inner:?}"), &system, &f, &state);
        }
        // Through the solvers: the group steps fall back, nothing fails, and ΔB stays the
        // residual of the shot radiosity. Group acceleration's groups come after the emitter
        // (patch 5) and leave out the last shooter: pairs, which are not M-matrices only for
        // inside = 1.2 (spectral radius ρ · inside).
        let (late, late_f) = bad_group(inside, false);
        let mut cases = vec![("group-pr-g3", &system, &f), ("group-xu-g3", &system, &f)];
        if inside > 1.0 {
            cases.extend([("pr-g2-m3:f=1", &late, &late_f), ("pr-g2-m3:f=1:inner=gs", &late, &late_f)]);
        }
        for (name, system, f) in cases {
            let run = solve(name, system, f, "steps=8");
            assert!(run.record.count("group_fallbacks").unwrap() > 0, "{name}, {inside}: {}", run.record);
            assert_eq!(run.record.real("group_condition"), Some(Real::INFINITY), "{name}, {inside}");
            assert_unshot_is_the_residual(&format!("{name}, {inside}"), system, f, &run.state);
        }
    }
}

#[test]
fn a_well_posed_group_does_not_fall_back() {
    let (system, f) = twelve();
    for name in SHOOTING.iter().filter(|s| s.contains("-g")) {
        let run = solve(name, &system, &f, "steps=17");
        assert_eq!(run.record.count("group_fallbacks"), Some(0), "{name}");
        let kappa = run.record.real("group_condition").unwrap();
        assert!((1.0..1e3).contains(&kappa), "{name}: κ_∞ {kappa}");
    }
}

#[test]
fn inner_gauss_seidel_stops_on_the_residual_of_the_group_system() {
    // One group step with the inner Gauss–Seidel: the group keeps s − Φ_rr y as unshot, and
    // that residual, not the last change of y, is below 1e-13 Σ |y|.
    let (system, f) = twelve();
    let problem = Problem::new(&system, &f).unwrap();
    let k = 3;
    let group: Vec<usize> = (0..12).collect();
    let columns: Vec<&[Real]> = group.iter().map(|&g| f.column(g)).collect();
    let mut state = State::from_emission(system.emissions(), k);
    let shot = group_shot(&problem, &mut state, &group, &columns, &[0.0; 36], InnerSolve::GaussSeidel).unwrap();
    assert!(!shot.fell_back);
    for c in 0..k {
        // The shot radiosity started at 0, so y = x = B − ΔB.
        let y: Vec<Real> = (0..12).map(|i| state.radiosity[i * k + c] - state.unshot[i * k + c]).collect();
        let mut residual = 0.0;
        for i in 0..12 {
            let phi_y = y[i] - system.rho(i, c) * (0..12).map(|j| f.get(i, j) * y[j]).sum::<Real>();
            let r = system.e(i, c) - phi_y;
            assert!((r - state.unshot[i * k + c]).abs() < 1e-15, "channel {c}, patch {i}");
            residual += r.abs();
        }
        let norm: Real = y.iter().map(|v| v.abs()).sum();
        assert!(residual <= 1e-13 * norm, "channel {c}: residual {residual:e} of Σ|y| {norm:e}");
    }
    // As LU does, to that tolerance.
    let mut lu = State::from_emission(system.emissions(), k);
    group_shot(&problem, &mut lu, &group, &columns, &[0.0; 36], InnerSolve::Lu).unwrap();
    for (a, b) in lu.radiosity.iter().zip(&state.radiosity) {
        assert!((a - b).abs() <= 1e-12 * a.abs(), "{a} against {b}");
    }
}

/// Six patches seeing each other with F = 0.9 and ρ = 0.9: ρ F has row sums 4.05, far above 1,
/// so every method must blow up.
fn non_physical() -> (LinearSystem, DenseColumns) {
    let mut e = vec![0.0; 6];
    e[0] = 1.0;
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.9; 6], e).unwrap();
    (system, DenseColumns::from_fn(6, |i, j| if i == j { 0.0 } else { 0.9 }))
}

#[test]
fn a_non_physical_system_ends_as_diverged_within_the_step_cap() {
    let (system, f) = non_physical();
    let cap = StopRules::default().step_cap;
    let names = ["pr", "southwell", "xu", "relax-1.5", "jacobi", "gauss-seidel", "sor-1.2"];
    let groups = ["group-pr-g3", "group-southwell-g3", "pr-g3:f=1", "xu-g3-m6:f=2", "group-gs-g3", "group-jacobi-g3"];
    for name in names.into_iter().chain(groups) {
        let run = solve_capped(name, &system, &f, "", cap);
        let TerminationReason::Diverged { step, residual, minimum } = run.termination else {
            panic!("{name}: {}", run.termination)
        };
        assert_eq!(step, run.state.step, "{name}");
        assert!(step < 20 * 6, "{name}: {step} steps");
        assert!(residual > DIVERGENCE_FACTOR * minimum.max(DIVERGENCE_FLOOR), "{name}: {residual} from {minimum}");
        assert!(run.state.radiosity.iter().all(|b| b.is_finite()), "{name}");
        let text = run.termination.to_string();
        assert!(
            text.starts_with("diverged: the residual power rose from ") && text.ends_with(&format!("by step {step}"))
        );
        // A residual rule cannot hide it.
        let run = solve_capped(name, &system, &f, "residual=1e-3,steps=100", cap);
        assert!(matches!(run.termination, TerminationReason::Diverged { .. }), "{name}: {}", run.termination);
    }
    let shown = TerminationReason::Diverged { step: 812, residual: 45.0, minimum: 1.2e-3 }.to_string();
    assert_eq!(shown, "diverged: the residual power rose from 1.2e-3 to 4.5e1 by step 812");
}

#[test]
fn a_physical_system_never_diverges() {
    // Residuals that are not monotone (over-relaxation, overshooting, gathering estimates)
    // rise for a while but never ten thousandfold above their best.
    let (twelve_system, twelve_f) = twelve();
    let twelve_f = twelve_f.with_measured_reciprocity(twelve_system.areas()).unwrap();
    let mut e = vec![0.0; 6];
    e[1] = 1.0;
    let cube_systems: Vec<LinearSystem> = [0.5, 0.9, 0.999]
        .map(|rho| LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![rho; 6], e.clone()).unwrap())
        .into();
    let f = cube();
    let names = solvers().into_iter().chain(["relax-1.9", "sor-1.9", "xu", "relax-1.9-g3-m6:f=2"].map(String::from));
    for name in names.collect::<Vec<_>>() {
        let mut cases: Vec<(&LinearSystem, &DenseColumns)> = cube_systems.iter().map(|s| (s, &f)).collect();
        cases.push((&twelve_system, &twelve_f));
        for (system, f) in cases {
            let run = solve(&name, system, f, "residual=1e-15");
            assert!(
                !matches!(run.termination, TerminationReason::Diverged { .. }),
                "{name} on {} patches: {}",
                system.len(),
                run.termination
            );
        }
    }
}

/// A column source whose column 3 is NaN from the `after`-th column fetched on.
struct Poisoned<'a> {
    inner: &'a DenseColumns,
    after: u64,
    fetched: std::sync::atomic::AtomicU64,
}

impl radiosity_core::ColumnSource for Poisoned<'_> {
    fn patch_count(&self) -> usize {
        radiosity_core::ColumnSource::patch_count(self.inner)
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        radiosity_core::ColumnSource::fill_column(self.inner, j, column);
        let count = self.fetched.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        if count >= self.after {
            column[3] = Real::NAN;
        }
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        radiosity_core::ColumnSource::reciprocity_bound(self.inner)
    }
}

#[test]
fn a_value_that_is_not_finite_stops_the_run_with_an_error_naming_the_patch() {
    // Every solver, a NaN form factor met late in the run: an error naming the step and a
    // patch, never a divergence or a panic.
    let (system, f) = twelve();
    let f = f.with_measured_reciprocity(system.areas()).unwrap();
    for name in solvers().iter().map(String::as_str) {
        let poisoned = Poisoned { inner: &f, after: 20, fetched: Default::default() };
        let problem = Problem::new(&system, &poisoned).unwrap();
        let err = solve_problem(name, &problem, "residual=1e-15").unwrap_err();
        let SolverError::NonFinite { step, patch, value } = err else { panic!("{name}: {err:?}") };
        assert!(!value.is_finite() && patch < 12 && step > 0, "{name}: {err}");
    }
}

/// A solver that does nothing but write `value` into patch 4's radiosity and unshot radiosity
/// (`both`), its unshot radiosity (`unshot`) or every unshot radiosity (`all`) at its step
/// `at`, unchecked, and reports the residual power `script[step]`, then the unshot power once
/// the script ends.
struct Rogue {
    script: Vec<Real>,
    at: u64,
    target: &'static str,
    value: Real,
}

impl Solver for Rogue {
    fn name(&self) -> String {
        "rogue".into()
    }

    fn next_step(&mut self, _problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        if state.step == self.at {
            match self.target {
                "both" => (state.radiosity[4], state.unshot[4]) = (self.value, self.value),
                "unshot" => state.unshot[4] = self.value,
                _ => state.unshot.fill(self.value),
            }
        }
        Ok(Record::new())
    }

    fn residual_power(&self, problem: &Problem<'_>, state: &State) -> Option<Real> {
        Some(self.script.get(state.step as usize).copied().unwrap_or_else(|| unshot_power(problem, state)))
    }
}

fn run_rogue(rogue: &mut Rogue, rules: &str) -> Result<Run, SolverError> {
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let f = cube();
    let problem = Problem::new(&system, &f).unwrap();
    Executor::new(rogue, StopRules::parse(rules).unwrap()).run(&problem)
}

#[test]
fn the_executor_stops_a_residual_that_is_not_finite_with_an_error() {
    // A radiosity that is NaN, or an unshot radiosity that is infinite (the shot radiosity
    // B − ΔB is then −∞): an error naming the step that produced it and the patch.
    for (target, value, shown) in [("both", Real::NAN, Real::NAN), ("unshot", Real::INFINITY, Real::NEG_INFINITY)] {
        let mut rogue = Rogue { script: Vec::new(), at: 2, target, value };
        let err = run_rogue(&mut rogue, "steps=10").unwrap_err();
        let SolverError::NonFinite { step, patch, value } = err else { panic!("{target}: {err:?}") };
        assert_eq!((step, patch), (3, 4), "{target}");
        assert!(value.is_nan() == shown.is_nan() && (value.is_nan() || value == shown), "{target}: {value}");
    }
    // Every value finite, only their sum overflows: a divergence with an infinite residual.
    let mut rogue = Rogue { script: Vec::new(), at: 2, target: "all", value: 1e308 };
    let run = run_rogue(&mut rogue, "steps=10").unwrap();
    assert_eq!(run.termination, TerminationReason::Diverged { step: 3, residual: Real::INFINITY, minimum: 1.0 });
}

#[test]
fn the_divergence_rule_measures_rises_from_a_floor_under_the_minimum() {
    let rogue = |script: Vec<Real>| Rogue { script, at: u64::MAX, target: "none", value: 0.0 };
    // From 1e-12 (round-off below the floor of 1e-6 of the first residual) to 5e-3: within
    // 1e4 × 1e-6; to 2e-2: beyond it.
    let run = run_rogue(&mut rogue(vec![1.0, 1e-12, 5e-3, 5e-3, 5e-3]), "steps=4").unwrap();
    assert_eq!(run.termination, TerminationReason::Steps(4));
    let run = run_rogue(&mut rogue(vec![1.0, 1e-12, 5e-3, 2e-2]), "steps=4").unwrap();
    assert_eq!(run.termination, TerminationReason::Diverged { step: 3, residual: 2e-2, minimum: 1e-12 });
    // Above the floor the minimum counts: from 0.1 to 999 is within 1e4, to 1001 beyond it.
    let run = run_rogue(&mut rogue(vec![1.0, 0.1, 999.0, 999.0, 999.0]), "steps=4").unwrap();
    assert_eq!(run.termination, TerminationReason::Steps(4));
    let run = run_rogue(&mut rogue(vec![1.0, 0.1, 1001.0]), "steps=4").unwrap();
    assert_eq!(run.termination, TerminationReason::Diverged { step: 2, residual: 1001.0, minimum: 0.1 });
}

// The registry: families of names, typed parameters, a user's own solver, suggestions.

use std::str::FromStr;

#[test]
fn every_listed_name_builds_and_keeps_its_name() {
    let registry = SolverRegistry::builtin();
    for name in POINT_SOLVERS.iter().chain(&GROUP_SOLVERS).chain(&BEYOND_PAPER_SOLVERS).chain(&KRYLOV_SOLVERS) {
        assert_eq!(solver_by_name(name).unwrap().name(), *name);
        assert_eq!(registry.build(name).unwrap().name(), *name);
    }
    // And every family's examples.
    for entry in registry.entries() {
        for example in entry.examples() {
            assert!(registry.build(example).is_ok(), "{}: {example}", entry.syntax());
        }
    }
}

#[test]
fn typed_parameters_parse_their_family_and_no_other() {
    assert_eq!("sor-1.2".parse::<GaussSeidelParams>(), Ok(GaussSeidelParams { omega: 1.2 }));
    assert_eq!("gauss-seidel".parse::<GaussSeidelParams>(), Ok(GaussSeidelParams::default()));
    assert_eq!("pr".parse::<GaussSeidelParams>(), Err(ParseSolverError::OtherFamily));
    assert_eq!("sor-abc".parse::<GaussSeidelParams>(), Err(ParseSolverError::OtherFamily));
    let Err(ParseSolverError::Refused(e)) = "sor-2.5".parse::<GaussSeidelParams>() else { panic!("sor-2.5") };
    assert_eq!(e.to_string(), "solver 'sor-2.5': SOR needs 0 < ω < 2, not 2.5");
    assert_eq!("jacobi".parse::<JacobiParams>(), Ok(JacobiParams::default()));
    assert_eq!("jacobi:sweep=product".parse::<JacobiParams>(), Ok(JacobiParams { by_products: true }));
    assert_eq!(
        "relax-1.5".parse::<PointShootingParams>(),
        Ok(PointShootingParams { method: ShootingMethod::Relax(1.5) })
    );
    assert_eq!("group-gs-g30".parse::<PointShootingParams>(), Err(ParseSolverError::OtherFamily));
    assert_eq!(
        "group-xu-g4".parse::<GroupShootingParams>(),
        Ok(GroupShootingParams { method: ShootingMethod::Xu(XuParts::BOTH), group: 4 })
    );
    assert_eq!("group-gs-g4".parse::<GroupShootingParams>(), Err(ParseSolverError::OtherFamily));
    let gathering = "group-gs-g8:groups=spatial".parse::<GroupGatheringParams>().unwrap();
    assert_eq!((gathering.group, gathering.partition), (8, Partition::Spatial));
    // Group acceleration: the parameters, the name as written and the canonical one.
    let p = GroupAcceleratedParams::from_str("xu-g30-m480:f=10:groups=interaction").unwrap();
    assert_eq!(p.method, ShootingMethod::Xu(XuParts::BOTH));
    assert_eq!((p.group, p.memory, p.frequency), (30, 480, Frequency::Fixed(10)));
    assert_eq!(p.building, GroupBuilding::Interaction);
    assert_eq!(p.canonical_name(), "xu-g30-m480:f=10:groups=interaction");
    let p = GroupAcceleratedParams::from_str("pr-g30:f=auto:target=0.1").unwrap();
    assert_eq!(p.frequency, Frequency::Auto { target: 0.1 });
    assert_eq!((p.solver_name(), p.canonical_name()), ("pr-g30:f=auto:target=0.1".into(), "pr-g30:target=0.1".into()));
    let p = GroupAcceleratedParams::from_str("pr-g30:target=0.2:f=timed").unwrap();
    assert_eq!(p.frequency, Frequency::Timed { target: 0.2 });
    assert_eq!(p.canonical_name(), "pr-g30:f=timed:target=0.2");
    assert_eq!(
        GroupAcceleratedParams::from_str("pr-g30").unwrap().frequency,
        Frequency::Auto { target: DEFAULT_TARGET }
    );
    assert_eq!(GroupAcceleratedParams::from_str("group-pr-g30"), Err(ParseSolverError::OtherFamily));
    // Built without a name: the canonical one.
    let typed = GroupAcceleratedParams { memory: 480, inner: InnerSolve::GaussSeidel, ..Default::default() };
    assert_eq!(typed.build().unwrap().name(), "pr-g30-m480:inner=gs");
    let southwell = GroupAcceleratedParams { method: ShootingMethod::Southwell, ..Default::default() };
    assert!(southwell.build().err().unwrap().to_string().contains("not to southwell"));
}

#[test]
fn bad_parameters_of_the_new_frequency_are_refused_like_the_others() {
    for (bad, words) in [
        ("pr-g30:f=timed:target=0", "positive number"),
        ("pr-g30:f=sometimes", "needs f=auto, f=timed or f ≥ 1"),
        ("pr-g30:f=timed:speed=2", "f=timed"),
        ("xu-g30:f=timed:inner=cg", "inner=lu or inner=gs"),
    ] {
        let e = solver_by_name(bad).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.starts_with(&format!("solver '{bad}': ")) && e.contains(words), "{bad}: {e}");
    }
    assert_eq!(solver_by_name("xu-g30-m480:f=timed").unwrap().name(), "xu-g30-m480:f=timed");
}

/// A user's solver: shoots nothing, for `lazy-N` steps at most (checked by its stop rule).
struct Lazy(u64);

impl Solver for Lazy {
    fn name(&self) -> String {
        format!("lazy-{}", self.0)
    }

    fn next_step(&mut self, _problem: &Problem<'_>, _state: &mut State) -> Result<Record, SolverError> {
        Ok(Record::new())
    }

    fn residual_power(&self, _problem: &Problem<'_>, _state: &State) -> Option<Real> {
        None
    }

    fn record(&self) -> Record {
        Record::new().with("laziness", self.0)
    }
}

/// The typed family of [`Lazy`]: `lazy-N`, `N ≥ 1`.
#[derive(Debug, PartialEq)]
struct LazyParams(u64);

impl FromStr for LazyParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<LazyParams, ParseSolverError> {
        let n = name.strip_prefix("lazy-").ok_or(ParseSolverError::OtherFamily)?;
        match n.parse::<u64>() {
            Ok(n) if n > 0 => Ok(LazyParams(n)),
            _ => Err(SolverError::BadParams(format!("solver '{name}': needs lazy-N with N ≥ 1")).into()),
        }
    }
}

impl SolverParams for LazyParams {
    const SYNTAX: &'static str = "lazy-N";
    const HELP: &'static str = "does nothing for N steps";
    const EXAMPLES: &'static [&'static str] = &["lazy-3"];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        Ok(Box::new(Lazy(self.0)))
    }
}

#[test]
fn a_users_solver_builds_through_the_registry() {
    let mut registry = SolverRegistry::builtin();
    registry.register::<LazyParams>().register_fn("idle", "does nothing at all", ["idle"], |name| {
        Ok((name == "idle").then(|| Box::new(Lazy(0)) as Box<dyn Solver>))
    });
    let mut lazy = registry.build("lazy-3").unwrap();
    assert_eq!(lazy.name(), "lazy-3");
    assert_eq!(registry.build("idle").unwrap().name(), "lazy-0");
    // Its run, and its record, through the executor.
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let f = cube();
    let problem = Problem::new(&system, &f).unwrap();
    let run = Executor::new(lazy.as_mut(), StopRules::parse("steps=3").unwrap()).run(&problem).unwrap();
    assert_eq!((run.termination, run.state.cost[Unit::Columns]), (TerminationReason::Steps(3), 0));
    assert_eq!(run.record.count("laziness"), Some(3));
    // Its refusals name it; the built-in names keep their meaning; the lists show it.
    assert_eq!(registry.build("lazy-0").err().unwrap().to_string(), "solver 'lazy-0': needs lazy-N with N ≥ 1");
    assert_eq!(registry.build("pr").unwrap().name(), "pr");
    assert!(registry.names().ends_with("; lazy-N (e.g. lazy-3); idle"), "{}", registry.names());
    assert!(
        registry.help().lines().any(|l| l.starts_with("lazy-N") && l.contains("lazy-3") && l.ends_with("for N steps"))
    );
    assert_eq!(registry.suggest("lazzy-3").as_deref(), Some("lazy-3"));
    // Without the built-in families, only its own.
    let mut own = SolverRegistry::empty();
    own.register::<LazyParams>();
    assert_eq!(own.build("lazy-2").unwrap().name(), "lazy-2");
    let Err(SolverError::UnknownSolver { valid, .. }) = own.build("pr") else { panic!("pr without built-ins") };
    assert_eq!(valid, "lazy-N (e.g. lazy-3)");
}

#[test]
fn unknown_names_get_the_nearest_name_and_the_wrapped_list() {
    let registry = SolverRegistry::builtin();
    for (typo, nearest) in [
        ("gaus-seidel", Some("gauss-seidel")),
        ("xu-g30-m48O", Some("xu-g30-m480")),
        ("xu-g30-m48O:f=10", Some("xu-g30-m480:f=10")),
        ("xu-q30", Some("xu-g30")),
        ("jacobbi", Some("jacobi")),
        ("group-pr-g3O", Some("group-pr-g30")),
        ("magic", None),
        ("sor-abc", None),
    ] {
        let Err(SolverError::UnknownSolver { name, valid, suggestion }) = registry.build(typo) else {
            panic!("{typo} is not unknown")
        };
        assert_eq!((name.as_str(), suggestion.as_deref()), (typo, nearest), "{typo}");
        assert_eq!(valid, registry.names());
        assert_eq!(solver_by_name(typo).err().unwrap().to_string(), registry.build(typo).err().unwrap().to_string());
    }
    // One sentence on one line: the typo, the guess, and where every family is listed.
    let message = solver_by_name("gaus-seidel").err().unwrap().to_string();
    assert_eq!(
        message,
        "unknown solver 'gaus-seidel' (did you mean 'gauss-seidel'?); `cargo xtask solve --help` lists every solver \
         family (SolverRegistry::help)"
    );
    let no_guess = solver_by_name("magic").err().unwrap().to_string();
    assert!(no_guess.starts_with("unknown solver 'magic'; `cargo xtask solve --help`"), "{no_guess}");
    // The list names every family, with placeholders and examples.
    for words in ["sor-ω (e.g. sor-1.2)", "relax-ω (e.g. relax-1.5)", "group-S-gM", "pr-g30", "xu-g30-m480:f=10"] {
        assert!(registry.names().contains(words), "{words}: {}", registry.names());
    }
}

#[test]
fn the_help_has_one_line_per_family() {
    let registry = SolverRegistry::builtin();
    let help = registry.help();
    let lines: Vec<&str> = help.lines().collect();
    assert_eq!(lines.len(), registry.entries().len());
    for (line, entry) in lines.iter().zip(registry.entries()) {
        assert!(line.starts_with(entry.syntax()), "{line}");
        assert!(line.contains(&format!("e.g. {}", entry.examples().join(", "))), "{line}");
        assert!(line.ends_with(entry.help()), "{line}");
    }
}

// Observers: when they are called, in which mode, what steps hand them, and rules no
// monitor feeds.

/// Counts its calls, the steps it saw and the figures they handed back.
#[derive(Default)]
struct Calls {
    init: Vec<String>,
    steps: Vec<u64>,
    figures: Vec<Record>,
    last: Option<(u64, TerminationReason)>,
}

impl Observer for Calls {
    fn observe_init(&mut self, solver: &str, state: &State) {
        assert_eq!(state.step, 0);
        self.init.push(solver.to_string());
    }

    fn observe_step(&mut self, state: &State, figures: &Record) {
        self.steps.push(state.step);
        self.figures.push(figures.clone());
    }

    fn observe_final(&mut self, run: &Run) {
        self.last = Some((run.state.step, run.termination.clone()));
    }
}

#[test]
fn observers_see_the_start_the_steps_their_mode_takes_and_the_end() {
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let f = cube();
    let problem = Problem::new(&system, &f).unwrap();
    // Three observers on one run, each in its mode.
    let (mut always, mut third, mut never) = (Calls::default(), Calls::default(), Calls::default());
    let mut solver = solver_by_name("pr").unwrap();
    Executor::new(solver.as_mut(), StopRules::parse("steps=7").unwrap())
        .add_observer(&mut always, ObserverMode::Always)
        .add_observer(&mut third, ObserverMode::Every(3))
        .add_observer(&mut never, ObserverMode::Never)
        .run(&problem)
        .unwrap();
    let end = Some((7, TerminationReason::Steps(7)));
    assert_eq!((always.init, always.steps, always.last), (vec!["pr".to_string()], (1..=7).collect(), end.clone()));
    assert_eq!((third.init.len(), third.steps, third.last), (1, vec![3, 6], end.clone()));
    assert_eq!((never.init.len(), never.steps.len(), never.last), (1, 0, end));
    // Every 0 steps is every step.
    assert!((1..5).all(|k| ObserverMode::Every(0).observes(k)));
    // The rms rule holds where the monitor says: e_rms = 1/step ≤ 0.2 from step 5.
    let mut monitor = |state: &State| Some(1.0 / state.step as Real);
    let mut solver = solver_by_name("pr").unwrap();
    let done = Executor::new(solver.as_mut(), StopRules::parse("rms=0.2").unwrap())
        .monitor(&mut monitor)
        .run(&problem)
        .unwrap();
    assert_eq!((done.state.step, done.termination), (5, TerminationReason::Rms(0.2)));
}

#[test]
fn a_step_hands_its_own_figures_to_the_observers() {
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let f = cube();
    let problem = Problem::new(&system, &f).unwrap();
    let run = |name: &str, steps: &str| {
        let mut calls = Calls::default();
        let mut solver = solver_by_name(name).unwrap();
        let run = Executor::new(solver.as_mut(), StopRules::parse(steps).unwrap())
            .add_observer(&mut calls, ObserverMode::Always)
            .run(&problem)
            .unwrap();
        (calls.figures, run.record)
    };
    // Group shooting: every step is a group of 3, whose size and condition come back.
    for figures in run("group-pr-g3", "steps=4").0 {
        assert_eq!((figures.count("group_size"), figures.count("group_fell_back")), (Some(3), Some(0)));
        assert!(figures.real("group_condition").is_some_and(|k| (1.0..1e10).contains(&k)), "{figures:?}");
    }
    // A point solver hands back nothing.
    assert!(run("pr", "steps=4").0.iter().all(Record::is_empty));
    // Group-accelerated shooting on twelve patches: the steps that ran a group step hand back
    // its figures, the others nothing.
    let (twelve, f12) = twelve();
    let problem = Problem::new(&twelve, &f12).unwrap();
    let mut calls = Calls::default();
    let mut solver = solver_by_name("pr-g4-m12:f=3").unwrap();
    let record = Executor::new(solver.as_mut(), StopRules::parse("steps=30").unwrap())
        .add_observer(&mut calls, ObserverMode::Always)
        .run(&problem)
        .unwrap()
        .record;
    let figures = calls.figures;
    let group_steps: Vec<&Record> = figures.iter().filter(|f| !f.is_empty()).collect();
    assert_eq!(group_steps.len() as u64, record.count("group_steps").unwrap());
    assert!(!group_steps.is_empty() && group_steps.len() < figures.len());
    let sizes: Vec<u64> = group_steps.iter().map(|f| f.count("group_size").unwrap()).collect();
    assert!(sizes.iter().all(|m| (1..=4).contains(m)), "{sizes:?}");
    let mean = sizes.iter().sum::<u64>() as Real / sizes.len() as Real;
    assert_eq!(Some(mean), record.real("group_size_mean"));
}

#[test]
fn an_rms_rule_without_a_monitor_is_refused_before_the_run() {
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let f = cube();
    let problem = Problem::new(&system, &f).unwrap();
    let mut solver = solver_by_name("pr").unwrap();
    let rules = StopRules::parse("steps=100,rms=0.1").unwrap();
    let err = Executor::new(solver.as_mut(), rules).run(&problem).unwrap_err();
    assert_eq!(err, SolverError::ErrorNotMeasured { rule: "rms=0.1".into() });
    assert_eq!(
        err.to_string(),
        "the stop rule rms=0.1 needs e_rms against a reference solution, which this run does not measure"
    );
    // Nothing ran: an observer was not even called on the initial state.
    let mut calls = Calls::default();
    let mut solver = solver_by_name("pr").unwrap();
    let rules = StopRules::parse("rms=1e-3").unwrap();
    let err = Executor::new(solver.as_mut(), rules).add_observer(&mut calls, ObserverMode::Always).run(&problem);
    assert!(err.unwrap_err().to_string().starts_with("the stop rule rms=1e-3 needs"));
    assert!(calls.init.is_empty() && calls.steps.is_empty() && calls.last.is_none());
}

#[test]
fn a_cost_counts_each_unit_apart_and_reads_in_its_own() {
    let columns = Cost::default().with(Unit::Columns, 659).with(Unit::Reused, 12).with_seconds(1.5, 0.25);
    assert_eq!(
        (columns.seconds(), columns.principal(), columns.to_string()),
        (1.75, Unit::Columns, "659 columns".into())
    );
    let krylov = Cost::default().with(Unit::Products, 7).with(Unit::Links, 4100);
    assert_eq!((krylov.principal(), krylov.to_string()), (Unit::Links, "0 columns + 7 products (4100 links)".into()));
    let rays = Cost::default().with(Unit::Rays, 1000);
    assert!(rays.only_rays() && !krylov.only_rays());
    assert_eq!((rays.principal(), rays.to_string()), (Unit::Rays, "1000 rays".into()));
    assert_eq!(Cost::default().principal(), Unit::Columns);
    let mixed = Cost::default().with(Unit::Columns, 3).with(Unit::Rays, 10);
    assert_eq!(mixed.to_string(), "3 columns + 10 rays");
    // Every paid unit is a rule's key; columns served from memory are free and are not.
    for unit in Unit::ALL {
        assert_eq!(Unit::from_key(unit.key()), unit.paid().then_some(unit), "{unit}");
    }
    let free = StopRules::parse("columns_reused=5").unwrap_err().to_string();
    assert!(free.contains("unknown rule"), "{free}");
    let typo = StopRules::parse("product=5").unwrap_err().to_string();
    assert!(typo.contains("did you mean 'products'?"), "{typo}");
}

#[test]
fn stop_rules_show_as_written() {
    let list = "columns=2n, steps=100, rms=1e-3, residual=1e-4, time=30s, steps=n, rms=0.05, time=0.25s, products=4, \
                rays=500, links=10n, std_error=0.01";
    let rules = StopRules::parse(list).unwrap();
    let shown: Vec<String> = rules.rules.iter().map(ToString::to_string).collect();
    assert_eq!(shown.join(", "), list);
    assert_eq!(StopRules::parse(&shown.join(",")).unwrap(), rules);
}

// The solver's record.

#[test]
fn a_record_keeps_its_keys_in_order_and_typed() {
    let mut record = Record::new().with("group_steps", 3u64).with("group_condition", 12.5);
    record.set("note", "fine").set("group_steps", 4u64);
    assert_eq!(record.len(), 3);
    assert_eq!(record.iter().map(|(k, _)| k).collect::<Vec<_>>(), ["group_steps", "group_condition", "note"]);
    assert_eq!((record.count("group_steps"), record.real("group_condition")), (Some(4), Some(12.5)));
    assert_eq!((record.text("note"), record.get("note")), (Some("fine"), Some(&Value::Text("fine".into()))));
    assert_eq!((record.real("group_steps"), record.count("missing")), (None, None));
    assert_eq!(record.to_string(), "group_steps=4, group_condition=12.5, note=fine");
    assert_eq!((&record).into_iter().len(), 3);
    assert!(Record::new().is_empty());
}

#[test]
fn group_solvers_record_their_group_steps() {
    let (system, f) = twelve();
    // Group PR: every step a group step; the first group is the 3 emitters, the next ones 4.
    let run = solve("group-pr-g4", &system, &f, "steps=5");
    let r = &run.record;
    assert_eq!(
        (r.count("group_steps"), r.count("group_size_max"), r.count("group_fallbacks")),
        (Some(5), Some(4), Some(0))
    );
    assert_eq!(r.real("group_size_mean"), Some((3.0 + 4.0 * 4.0) / 5.0));
    assert!(r.real("group_condition").is_some_and(|k| (1.0..1e3).contains(&k)), "{r}");
    let keys: Vec<&str> = r.iter().map(|(k, _)| k).collect();
    assert_eq!(keys, ["group_steps", "group_size_mean", "group_size_max", "group_condition", "group_fallbacks"]);
    // Group Gauss–Seidel with groups of 5 over 12 patches: 5, 5, 2.
    let run = solve("group-gs-g5", &system, &f, "steps=3");
    let r = &run.record;
    assert_eq!(
        (r.count("group_steps"), r.count("group_size_max"), r.real("group_size_mean")),
        (Some(3), Some(5), Some(4.0))
    );
    assert_eq!(r.count("group_fallbacks"), Some(0));
    assert!(r.real("group_condition").is_some_and(|k| (1.0..1e3).contains(&k)), "{r}");
    // The whole cube in one group: κ_∞ of Φ = I − ρ F, exact as for group shooting.
    let furnace = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let uniform = DenseColumns::from_fn(6, |i, j| if i == j { 0.0 } else { 0.2 });
    let kappa = solve("group-jacobi-g6", &furnace, &uniform, "steps=1").record.real("group_condition").unwrap();
    assert!((kappa / 3.0 - 1.0).abs() < 1e-12, "{kappa}");
    // Group acceleration adds its counted operations and its period.
    let run = solve("pr-g4-m12:f=3", &system, &f, "steps=30");
    assert!(run.record.count("group_steps").unwrap() > 0);
    assert!(run.record.count("group_operations").unwrap() > 0);
    assert_eq!(run.record.count("group_period"), Some(3));
}

#[test]
fn automatic_group_frequency_is_reproducible_and_follows_the_cost_model() {
    let (system, f) = twelve();
    let (n, k, m_stored) = (12u64, 3u64, 8u64);
    // A target small enough for this tiny system's groups to cost more than its columns'
    // share at least sometimes, so that the model spaces group steps apart.
    let (name, target) = ("pr-g8-m16:target=0.01", 0.01);
    // Two runs of the same problem take the same steps.
    let first = solve(name, &system, &f, "steps=60");
    let second = solve(name, &system, &f, "steps=60");
    assert_eq!(first.state.radiosity, second.state.radiosity);
    assert_eq!(first.state.unshot, second.state.unshot);
    assert_eq!(
        (first.state.step, first.state.cost[Unit::Columns], first.state.cost[Unit::Reused]),
        (second.state.step, second.state.cost[Unit::Columns], second.state.cost[Unit::Reused])
    );
    assert_eq!(first.record, second.record);
    // The runs are deterministic, so a run of s steps is the first s steps of a longer one:
    // read off where group steps happen and what each counted.
    let at: Vec<(u64, u64, u64)> = (0..=60)
        .map(|s| {
            let r = if s == 0 { Record::new() } else { solve(name, &system, &f, &format!("steps={s}")).record };
            (
                r.count("group_steps").unwrap_or(0),
                r.count("group_operations").unwrap_or(0),
                r.count("group_period").unwrap_or(0),
            )
        })
        .collect();
    let group_steps: Vec<usize> = (1..=60).filter(|&s| at[s].0 > at[s - 1].0).collect();
    assert!(group_steps.len() >= 5, "{group_steps:?}");
    let column = target * column_operations(n as usize);
    let mut longer = false;
    for pair in group_steps.windows(2) {
        let (s, next) = (pair[0], pair[1]);
        let operations = at[s].1 - at[s - 1].1;
        let predicted = (operations as Real / column).ceil().max(1.0) as usize;
        assert_eq!(next - s, predicted, "group steps at {group_steps:?}: {operations} operations at step {s}");
        assert_eq!(at[s].2 as usize, predicted);
        longer |= predicted > 1;
    }
    assert!(longer, "the model must space some group steps apart: {group_steps:?}");
    // The first group step runs as soon as m = 8 columns are stored (K = 8), and counts, for
    // PR (no row term) and its group of size m': K k to choose, m'² k to build Φ_rr,
    // (⌊2m'³/3⌋ + 4m'²) k for the LU, n m' k to shoot, and m' k for the members' overshoots.
    let s = group_steps[0];
    let m = solve(name, &system, &f, &format!("steps={s}")).record.count("group_size_max").unwrap();
    let model = m_stored * k + m * m * k + (2 * m * m * m / 3 + 4 * m * m) * k + n * m * k + m * k;
    assert_eq!(at[s].1, model, "first group step at {s}, group of {m}");
    // A smaller target spaces them further apart.
    let sparse = solve("pr-g8-m16:target=0.002", &system, &f, "steps=60").record;
    assert!(sparse.count("group_steps").unwrap() < first.record.count("group_steps").unwrap());
}

/// Every state a run passes through after a step.
struct States(Vec<State>);

impl Observer for States {
    fn observe_step(&mut self, state: &State, _figures: &Record) {
        self.0.push(state.clone());
    }
}

/// A dense matrix that multiplies a whole vector itself, as a stored matrix or the
/// hierarchical operator does.
struct Multiplying<'a>(&'a DenseColumns);

impl radiosity_core::ColumnSource for Multiplying<'_> {
    fn patch_count(&self) -> usize {
        radiosity_core::ColumnSource::patch_count(self.0)
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        self.0.fill_column(j, column)
    }

    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        for (idx, o) in out.iter_mut().enumerate() {
            let (i, c) = (idx / channels, idx % channels);
            *o = (0..self.patch_count()).map(|j| self.0.get(i, j) * x[j * channels + c]).sum();
        }
        true
    }
}

#[test]
fn jacobi_by_products_takes_the_sweeps_of_jacobi_by_rows() {
    // `jacobi:sweep=product` takes a whole sweep a step: after k steps its radiosity is plain
    // Jacobi's after k sweeps (k n steps) to rounding, over a source that multiplies itself (k
    // products, no column) and over plain columns (n columns a product), and the change it
    // keeps is the residual of the radiosity before the step.
    let system =
        LinearSystem::new(Channels::Rgb, vec![1.0; 6], [0.9, 0.5, 0.2].repeat(6), [1.0, 2.0, 0.5].repeat(6)).unwrap();
    let f = cube();
    let by_rows = solve("jacobi", &system, &f, "steps=30");
    assert_eq!(by_rows.state.cost[Unit::Columns], 30);
    let multiplying = Multiplying(&f);
    let sources: [(&dyn radiosity_core::ColumnSource, (u64, u64)); 2] = [(&multiplying, (0, 5)), (&f, (30, 0))];
    for (source, (columns, products)) in sources {
        let problem = Problem::new(&system, source).unwrap();
        let mut solver = solver_by_name("jacobi:sweep=product").unwrap();
        let mut states = States(Vec::new());
        let run = Executor::new(solver.as_mut(), StopRules::parse("steps=5").unwrap())
            .add_observer(&mut states, ObserverMode::Always)
            .run(&problem)
            .unwrap();
        assert_eq!(solver.step_kind(), StepKind::Product);
        assert_eq!(
            (run.state.step, run.state.cost[Unit::Columns], run.state.cost[Unit::Products]),
            (5, columns, products)
        );
        for (a, b) in run.state.radiosity.iter().zip(&by_rows.state.radiosity) {
            assert!((a - b).abs() <= 1e-13 * b.abs(), "{a} against {b}");
        }
        assert!(states.0.len() >= 5, "a state after every step");
        for state in &states.0 {
            assert_unshot_is_the_residual("jacobi:sweep=product", &system, &f, state);
        }
    }
    // Every paid unit has its rule, read from the one cost: products stop this run, as columns
    // stop one over plain columns, and the reason names what was spent.
    let problem = Problem::new(&system, &multiplying).unwrap();
    let mut solver = solver_by_name("jacobi:sweep=product").unwrap();
    let run = Executor::new(solver.as_mut(), StopRules::parse("products=3").unwrap()).run(&problem).unwrap();
    assert_eq!(run.termination, TerminationReason::Spent(Unit::Products, 3));
    assert_eq!((run.state.step, run.termination.to_string()), (3, "3 products computed".to_string()));
    let Err(ParseSolverError::Refused(e)) = "jacobi:sweep=sideways".parse::<JacobiParams>() else { panic!("sideways") };
    assert_eq!(e.to_string(), "solver 'jacobi' takes sweep=rows or sweep=product, not 'sweep=sideways'");
}
