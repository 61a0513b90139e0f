//! Tests of radiosity-solvers on small in-memory systems with exact answers: the furnace
//! identity, the two-patch closed form, the unit cube, and the accounting and stop rules.

use radiosity_core::{Channels, DenseColumns, LinearSystem, Real};
use radiosity_solvers::*;

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

/// The unit cube, one patch per face; faces 0/1 are bottom/top, 2..6 the sides.
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
}

/// Every point solver, and under-relaxed SOR and relaxation.
fn solvers() -> impl Iterator<Item = &'static str> {
    POINT_SOLVERS.into_iter().chain(["sor-0.8", "relax-0.8"])
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
    Executor::new(solver.as_mut(), rules).run(&problem, &mut NoObserver).unwrap()
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
    for name in solvers() {
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
    let f = DenseColumns::from_rows(2, &[0.0, a, b, 0.0]).unwrap();
    let d = 1.0 - r1 * r2 * a * b;
    let exact = [(e1 + r1 * a * e2) / d, (e2 + r2 * b * e1) / d];
    for name in solvers() {
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
        for name in solvers() {
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
    for name in solvers() {
        let run = solve(name, &system, &f, "steps=2n");
        assert_eq!(run.termination, TerminationReason::Steps(12), "{name}");
        assert_eq!(run.state.columns, 12, "{name}");
        let run = solve(name, &system, &f, "columns=7,steps=100");
        assert_eq!(run.termination, TerminationReason::Columns(7), "{name}");
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
}

#[test]
fn column_time_is_form_factor_time() {
    // 12 columns of at least 1 ms each: at least 12 ms of form factors, and none of it
    // counted as solving (a 6-patch step takes microseconds).
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let f = cube();
    let slow = Sleepy(&f);
    for name in solvers() {
        let mut solver = solver_by_name(name).unwrap();
        let problem = Problem::new(&system, &slow).unwrap();
        let run = Executor::new(solver.as_mut(), StopRules::parse("steps=12").unwrap())
            .run(&problem, &mut NoObserver)
            .unwrap();
        assert!(run.state.ff_seconds >= 0.012, "{name}: {}", run.state.ff_seconds);
        assert!(run.state.solve_seconds < run.state.ff_seconds, "{name}: {} s solving", run.state.solve_seconds);
    }
}

#[test]
fn runs_end_at_round_off_or_at_the_step_cap() {
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

struct Rms(Vec<Real>);

impl Observer for Rms {
    fn observe(&mut self, state: &State) -> Option<Real> {
        let num: Real = state.radiosity.iter().zip(&self.0).map(|(b, x)| (b - x).powi(2)).sum();
        let den: Real = self.0.iter().map(|x| x * x).sum();
        Some((num / den).sqrt())
    }
}

#[test]
fn the_rms_rule_uses_the_observer() {
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![1.0; 6]).unwrap();
    let f = cube();
    let mut solver = solver_by_name("gauss-seidel").unwrap();
    let problem = Problem::new(&system, &f).unwrap();
    let mut observer = Rms(vec![2.0; 6]);
    let run =
        Executor::new(solver.as_mut(), StopRules::parse("rms=1e-6").unwrap()).run(&problem, &mut observer).unwrap();
    let TerminationReason::Rms(e) = run.termination else { panic!("{}", run.termination) };
    assert!(e <= 1e-6);
}

#[test]
fn stop_rules_parse_and_refuse_clearly() {
    let rules = StopRules::parse("columns=2n, steps=100, rms=1e-3, residual=1e-4, time=30s").unwrap();
    assert_eq!(rules.rules.len(), 5);
    assert_eq!(rules.rules[0], StopRule::Columns(Count::PerPatch(2.0)));
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
        ("colums=5", "unknown rule"),
    ] {
        let e = StopRules::parse(bad).unwrap_err().to_string();
        assert!(e.contains(bad) && e.contains(words) && e.contains("columns=2n"), "{bad}: {e}");
    }
}

#[test]
fn errors_are_reported_not_panicked() {
    let names = solver_by_name("xu-g30").err().unwrap().to_string();
    assert!(names.contains("unknown solver 'xu-g30'") && names.contains("pr"), "{names}");
    assert!(solver_by_name("sor-2.5").err().unwrap().to_string().contains("0 < ω < 2"));
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 2], vec![0.5; 2], vec![1.0; 2]).unwrap();
    let f = cube();
    assert!(matches!(Problem::new(&system, &f), Err(SolverError::SizeMismatch { columns: 6, system: 2 })));
    // A form factor that is not finite stops the run at the first step that uses it (within
    // the first sweep or the first two shots), naming a patch.
    let broken = DenseColumns::from_rows(2, &[0.0, 0.5, f64::INFINITY, 0.0]).unwrap();
    for name in solvers() {
        let mut solver = solver_by_name(name).unwrap();
        let problem = Problem::new(&system, &broken).unwrap();
        let err = Executor::new(solver.as_mut(), StopRules::default()).run(&problem, &mut NoObserver).unwrap_err();
        assert!(matches!(err, SolverError::NonFinite { step: 1 | 2, .. }), "{name}: {err:?}");
        assert!(err.to_string().contains(": the radiosity of patch"), "{err}");
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
    assert_eq!((problem.columns_fetched(), problem.columns_reused()), (2, 1));
    // Full: 2 is stored in place of the least recently used, 1; 0 stays.
    assert_eq!(memory.column(&problem, 2, &mut scratch), f.column(2));
    assert!(memory.contains(0) && memory.contains(2) && !memory.contains(1));
    assert_eq!(memory.peek(2), Some(f.column(2)));
    assert_eq!(memory.peek(1), None);
    assert_eq!(memory.column(&problem, 1, &mut scratch), f.column(1));
    assert_eq!((problem.columns_fetched(), problem.columns_reused()), (4, 1));
    assert_eq!(memory.len(), 2);
    // No capacity: every column is computed.
    let mut none = ColumnMemory::new(6, 0);
    assert_eq!(none.column(&problem, 3, &mut scratch), f.column(3));
    assert_eq!(none.column(&problem, 3, &mut scratch), f.column(3));
    assert_eq!((problem.columns_fetched(), problem.columns_reused()), (6, 1));
    assert!(none.is_empty());
}
