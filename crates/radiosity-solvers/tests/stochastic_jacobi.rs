//! `stochastic-jacobi` on stored systems sampled exactly (`ColumnTransport`): unbiased against
//! the exact answer, its standard error honest, its variance as the first-order formula says,
//! the same numbers for the same seed whatever the thread count.
//!
//! Statistical tolerances: a mean over `S` seeds is compared with the exact answer within 4 of
//! its standard errors, measured from the same seeds' spread (a false alarm in about 1 of
//! 16,000 values compared, so a few in a thousand for a test comparing 36 values).

use super::{cube_form_factors, solve, twelve};
use radiosity_core::{Channels, ColumnTransport, DenseColumns, LinearSystem, Real};
use radiosity_solvers::*;

/// Runs `name` on `system` with transport sampled from `f`, under `rules`.
fn run_sampled(name: &str, system: &LinearSystem, f: &DenseColumns, rules: &str) -> (Run, Option<StandardError>) {
    let transport = ColumnTransport::new(f, system.areas()).unwrap();
    let problem = Problem::new(system, f).unwrap().with_transport(&transport).unwrap();
    let mut solver = solver_by_name(name).unwrap();
    let rules = StopRules { step_cap: 1e6, ..StopRules::parse(rules).unwrap() };
    let run = Executor::new(solver.as_mut(), rules).run(&problem).unwrap();
    let se = solver.standard_error(&problem, &run.state);
    (run, se)
}

/// The exact solution, by Gauss–Seidel to round-off.
fn exact(system: &LinearSystem, f: &DenseColumns) -> Vec<Real> {
    solve("gauss-seidel", system, f, "residual=1e-15").state.radiosity
}

/// Checks that the mean over `seeds` runs of `name` (its seed appended) is within 4 standard
/// errors of `star` everywhere.
fn assert_unbiased(name: &str, system: &LinearSystem, f: &DenseColumns, rules: &str, seeds: u64, star: &[Real]) {
    let runs: Vec<Vec<Real>> =
        (1..=seeds).map(|s| run_sampled(&format!("{name}:seed={s}"), system, f, rules).0.state.radiosity).collect();
    let slices: Vec<&[Real]> = runs.iter().map(Vec::as_slice).collect();
    let mut mean = vec![0.0; star.len()];
    let se = StandardError::of_replicates(&slices, &mut mean);
    for (idx, ((m, s), t)) in mean.iter().zip(&se.values).zip(star).enumerate() {
        assert!(
            (m - t).abs() <= 4.0 * s + 1e-12 * t.abs(),
            "{name}: value {idx}: mean {m} against {t}, standard error {s}"
        );
    }
}

#[test]
fn every_form_is_unbiased_on_a_stored_system() {
    let (system, f) = twelve();
    let star = exact(&system, &f);
    for name in [
        "stochastic-jacobi:batch=400",
        "stochastic-jacobi:batch=400:form=gathering",
        "stochastic-jacobi:batch=400:form=gathering:cv=true",
        "stochastic-jacobi:batch=400:lines=global",
        "stochastic-jacobi:batch=400:seq=sobol",
        "stochastic-jacobi:batch=400:seq=halton",
    ] {
        assert_unbiased(name, &system, &f, "steps=40", 200, &star);
    }
}

/// Howell's closed cube, every face emitting 1 and reflecting `rho`: `B = 1 / (1 − ρ)`.
fn furnace(rho: Real) -> (LinearSystem, DenseColumns) {
    let (opposite, adjacent) = cube_form_factors();
    let f = DenseColumns::from_fn(6, |i, j| {
        if i == j {
            0.0
        } else if j == i ^ 1 {
            opposite
        } else {
            adjacent
        }
    });
    (LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![rho; 6], vec![1.0; 6]).unwrap(), f)
}

#[test]
fn a_closed_furnace_at_rho_099_gives_e_over_one_minus_rho() {
    // Howell's cube, every face emitting 1, ρ = 0.99: B = 1 / (1 − ρ) = 100 on every face.
    let (system, f) = furnace(0.99);
    assert_unbiased("stochastic-jacobi:batch=600", &system, &f, "steps=1200", 40, &[100.0; 6]);
}

#[test]
fn the_standard_error_covers_the_true_error_at_the_rate_it_claims() {
    // Per value, (B̄ − B*) / s follows Student's t with R − 1 degrees of freedom where the
    // estimates are close to normal: over 36 values × 200 seeds, the share within 2 standard
    // errors is t_coverage_of_two(R) up to 3 binomial standard deviations (0.006 at R = 16)
    // plus 0.02 for what is not normal (few landings on the smallest patches).
    let (system, f) = twelve();
    let star = exact(&system, &f);
    let replicates = 16;
    let (mut within, mut total) = (0usize, 0usize);
    let (mut e2, mut s2) = (0.0, 0.0);
    for seed in 1..=200 {
        let name = format!("stochastic-jacobi:batch=1600:replicates={replicates}:seed={seed}");
        let (run, se) = run_sampled(&name, &system, &f, "steps=30");
        let se = se.unwrap();
        assert_eq!(se.replicates, replicates);
        for ((b, t), s) in run.state.radiosity.iter().zip(&star).zip(&se.values) {
            within += usize::from((b - t).abs() <= 2.0 * s);
            total += 1;
        }
        let (num, den): (Real, Real) = run
            .state
            .radiosity
            .iter()
            .zip(&star)
            .enumerate()
            .map(|(idx, (b, t))| (system.areas()[idx / 3] * (b - t).powi(2), system.areas()[idx / 3] * t * t))
            .fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
        e2 += num / den;
        s2 += se.relative_rms(&system, &run.state.radiosity).powi(2);
    }
    let share = within as Real / total as Real;
    let claimed = t_coverage_of_two(replicates);
    eprintln!(
        "coverage: {share:.3} within 2 standard errors, {claimed:.3} claimed; mean e_rms² / mean SE² {:.3}",
        e2 / s2
    );
    assert!((share - claimed).abs() < 0.04, "{share} of the values within 2 standard errors, {claimed} claimed");
    // The summary squared estimates the mean e_rms squared: their means over 200 seeds agree
    // within 15% (each a mean of 200 chi-square-like terms).
    assert!((e2 / s2 - 1.0).abs() < 0.15, "mean e_rms² {e2} against mean standard error² {s2}");
}

#[test]
fn the_same_seed_gives_the_same_numbers_whatever_the_thread_count() {
    let (system, f) = twelve();
    let run_on = |threads: usize, name: &str| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| run_sampled(name, &system, &f, "steps=12").0.state.radiosity)
    };
    for name in
        ["stochastic-jacobi:seed=3", "stochastic-jacobi:form=gathering:seq=sobol", "stochastic-jacobi:lines=global"]
    {
        let one = run_on(1, name);
        assert_eq!(one, run_on(2, name), "{name}");
        assert_eq!(one, run_on(3, name), "{name}");
    }
    assert_ne!(run_on(2, "stochastic-jacobi:seed=3"), run_on(2, "stochastic-jacobi:seed=4"));
}

#[test]
fn a_patch_s_many_rays_cast_in_parts_land_once_each_and_give_the_same_numbers_on_any_threads() {
    // Howell's cube, ρ = 0.5, every face emitting 1: B = 2 on every face. 20,000 rays a step
    // and replicate, over 6 faces, so that every face casts its rays in parts of 2,048.
    let (system, f) = furnace(0.5);
    let name = "stochastic-jacobi:batch=80000:seq=sobol";
    let run_on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| run_sampled(name, &system, &f, "steps=6").0)
    };
    let one = run_on(1);
    assert_eq!(one.state.radiosity, run_on(2).state.radiosity, "the parts depend on the threads");
    assert_eq!(one.state.radiosity, run_on(3).state.radiosity, "the parts depend on the threads");
    // Each ray lands once: a part cast twice, or lost, would move every face by a share of
    // its light, far beyond the 1% the rays' noise leaves here.
    for (i, b) in one.state.radiosity.iter().enumerate() {
        assert!((b - 2.0).abs() < 0.02, "face {i}: {b} against 2");
    }
}

#[test]
fn rays_are_the_cost_and_the_rays_rule_stops_the_run() {
    let (system, f) = twelve();
    let (run, _) = run_sampled("stochastic-jacobi:batch=1000", &system, &f, "rays=20000");
    assert!(matches!(run.termination, TerminationReason::Spent(Unit::Rays, r) if r >= 20_000));
    // A step casts at most a batch and a rounding per patch and replicate beyond the rule.
    assert!(run.state.cost[Unit::Rays] < 20_000 + 1000 + 4 * 12, "{}", run.state.cost[Unit::Rays]);
    assert_eq!(run.state.cost[Unit::Columns], 0, "a stochastic solver computes no column");
}

#[test]
fn the_std_error_rule_stops_at_the_first_step_whose_standard_error_meets_it() {
    // With a spread observer: every step's standard error, so the stop is seen to be the first
    // step at or below the target, and the reason carries the value it read.
    struct Spreads<'a>(&'a LinearSystem, Vec<Real>);
    impl Observer for Spreads<'_> {
        fn observe_step(&mut self, _: &State, _: &Record) {}
        fn wants_standard_error(&self) -> bool {
            true
        }
        fn observe_standard_error(&mut self, state: &State, error: Option<&StandardError>) {
            self.1.push(error.map_or(Real::NAN, |e| e.relative_rms(self.0, &state.radiosity)));
        }
    }
    let (system, f) = twelve();
    let transport = ColumnTransport::new(&f, system.areas()).unwrap();
    let problem = Problem::new(&system, &f).unwrap().with_transport(&transport).unwrap();
    let mut solver = solver_by_name("stochastic-jacobi:batch=200").unwrap();
    let mut spreads = Spreads(&system, Vec::new());
    let rules = StopRules { step_cap: 1e6, ..StopRules::parse("std_error=2e-2").unwrap() };
    let run =
        Executor::new(solver.as_mut(), rules).add_observer(&mut spreads, ObserverMode::Always).run(&problem).unwrap();
    let TerminationReason::StdError(s) = run.termination else { panic!("{}", run.termination) };
    let seen = &spreads.1;
    assert_eq!(s, *seen.last().unwrap(), "the reason holds the standard error of the final state");
    assert!(s <= 2e-2 && seen.len() > 2, "{seen:?}");
    assert!(
        seen[..seen.len() - 1].iter().all(|e| e.is_nan() || *e > 2e-2),
        "it stops at the first step that meets it: {seen:?}"
    );
    // A solver without a standard error never meets the rule: the step cap ends it.
    let mut pr = solver_by_name("pr").unwrap();
    let rules = StopRules { step_cap: 3.0, ..StopRules::parse("std_error=1").unwrap() };
    let run = Executor::new(pr.as_mut(), rules).run(&problem).unwrap();
    assert!(matches!(run.termination, TerminationReason::StepCap(_)), "{}", run.termination);
}

#[test]
fn a_problem_without_transport_and_bad_parameters_are_refused_in_one_sentence() {
    let (system, f) = twelve();
    let problem = Problem::new(&system, &f).unwrap();
    let mut solver = solver_by_name("stochastic-jacobi").unwrap();
    let e = Executor::new(solver.as_mut(), StopRules::parse("steps=3").unwrap()).run(&problem).unwrap_err();
    assert!(matches!(e, SolverError::NotApplicable { .. }), "{e}");
    assert!(e.to_string().contains("transport sampler"), "{e}");
    for (name, says) in [
        ("stochastic-jacobi:seq=niederreiter", "seq is random, sobol or halton"),
        ("stochastic-jacobi:replicates=1", "replicates is a whole number from 2"),
        ("stochastic-jacobi:cv=true", "applies to the gathering form"),
        ("stochastic-jacobi:batch=-3", "batch is a number of rays"),
        ("stochastic-jacobi:colour=red", "unknown parameter 'colour'"),
    ] {
        let e = solver_by_name(name).err().unwrap().to_string();
        assert!(e.starts_with("solver 'stochastic-jacobi"), "{e}");
        assert!(e.contains(says), "{name}: {e}");
        assert!(!e.trim_end_matches('.').contains(". "), "one sentence: {e}");
    }
    assert_eq!(
        solver_by_name("stochastic-jacobi:seq=sobol:replicates=8").unwrap().name(),
        "stochastic-jacobi:seq=sobol:replicates=8"
    );
}

/// A grey enclosure-like system of `n` patches with exact reciprocity, unequal areas, rows
/// summing to `row`, reflectivities from 0.3 to 0.8 and two emitters.
fn enclosure(n: usize, row: Real) -> (LinearSystem, DenseColumns) {
    let area: Vec<Real> = (0..n).map(|i| 1.0 + (i % 7) as Real * 0.25).collect();
    let g = |i: usize, j: usize| if i == j { 0.0 } else { 1.0 + ((i * 13 + j * 13 + i * j) % 17) as Real };
    let max_row = (0..n).map(|i| (0..n).map(|j| g(i, j)).sum::<Real>() / area[i]).fold(0.0, Real::max);
    let f = DenseColumns::from_fn(n, |i, j| row * g(i, j) / area[i] / max_row);
    let rho: Vec<Real> = (0..n).map(|i| 0.3 + 0.5 * ((i * 5) % 9) as Real / 8.0).collect();
    let e: Vec<Real> = (0..n).map(|i| if i % 20 == 3 { 5.0 } else { 0.0 }).collect();
    (LinearSystem::new(Channels::Grey, area, rho, e).unwrap(), f)
}

#[test]
fn the_error_against_rays_follows_the_first_order_variance_formula() {
    // Bekaert's first-order variance of stochastic Jacobi (module doc of
    // stochastic_jacobi.rs): V[P_i] ≈ ρ_i P_T (P_i − Φ_i) / N for N rays in all, P_T the total
    // power, so the expected e_rms² is Σ_i V_i / A_i / Σ_i A_i B_i². Over 60 seeds at each of
    // three budgets, the measured root mean e_rms² is within 30% of it (the target;
    // the formula leaves out the noise carried from one iteration to the next and the
    // rounding of ray counts).
    let (system, f) = enclosure(60, 0.9);
    let star = exact(&system, &f);
    let areas = system.areas();
    let power: Vec<Real> = star.iter().zip(areas).map(|(b, a)| a * b).collect();
    let total: Real = power.iter().sum();
    let norm: Real = star.iter().zip(areas).map(|(b, a)| a * b * b).sum();
    for budget in [20_000u64, 80_000, 320_000] {
        let (mut e2, mut rays) = (0.0, 0.0);
        let seeds = 60;
        for seed in 1..=seeds {
            let (run, _) = run_sampled(
                &format!("stochastic-jacobi:batch=2000:seed={seed}"),
                &system,
                &f,
                &format!("rays={budget}"),
            );
            let num: Real =
                run.state.radiosity.iter().zip(&star).zip(areas).map(|((b, t), a)| a * (b - t).powi(2)).sum();
            e2 += num / norm;
            rays += run.state.cost[Unit::Rays] as Real;
        }
        let (e2, rays) = (e2 / seeds as Real, rays / seeds as Real);
        let predicted: Real = (0..system.len())
            .map(|i| system.rho(i, 0) * total * (power[i] - areas[i] * system.e(i, 0)) / rays / areas[i])
            .sum::<Real>()
            / norm;
        let ratio = (e2 / predicted).sqrt();
        eprintln!("variance formula: {budget} rays, measured e_rms over predicted {ratio:.3}");
        assert!((ratio - 1.0).abs() < 0.3, "{budget} rays: e_rms {} against {} predicted", e2.sqrt(), predicted.sqrt());
    }
}

#[test]
fn a_problem_without_form_factors_runs_only_the_solvers_that_sample() {
    let (system, f) = twelve();
    let transport = ColumnTransport::new(&f, system.areas()).unwrap();
    let problem = Problem::sampled(&system, &transport).unwrap();
    let mut sampled = solver_by_name("stochastic-jacobi").unwrap();
    let run = Executor::new(sampled.as_mut(), StopRules::parse("steps=5").unwrap()).run(&problem).unwrap();
    assert!(run.state.cost[Unit::Rays] > 0 && run.state.radiosity.iter().all(|b| b.is_finite()));
    let mut formed = solver_by_name("gauss-seidel").unwrap();
    let e = Executor::new(formed.as_mut(), StopRules::parse("steps=5").unwrap()).run(&problem).unwrap_err();
    assert!(e.to_string().contains("only samples transport"), "{e}");
}

/// A sampler that lands rays as `ColumnTransport` does but knows no row sum (as rays in a
/// scene that is not closed).
struct WithoutRowSums(ColumnTransport);

impl radiosity_core::TransportSampler for WithoutRowSums {
    fn patch_count(&self) -> usize {
        self.0.patch_count()
    }

    fn cast(&self, from: usize, u: [Real; 4]) -> Option<usize> {
        self.0.cast(from, u)
    }

    fn cost(&self) -> radiosity_core::SampleCost {
        self.0.cost()
    }
}

#[test]
fn the_control_variate_is_refused_before_any_ray_where_row_sums_are_unknown() {
    let (system, f) = twelve();
    let transport = WithoutRowSums(ColumnTransport::new(&f, system.areas()).unwrap());
    let problem = Problem::sampled(&system, &transport).unwrap();
    let mut solver = solver_by_name("stochastic-jacobi:form=gathering:cv=true").unwrap();
    let e = Executor::new(solver.as_mut(), StopRules::parse("steps=5").unwrap()).run(&problem).unwrap_err();
    assert!(matches!(e, SolverError::NotApplicable { .. }) && e.to_string().contains("row sums"), "{e}");
    assert_eq!(problem.spent(Unit::Rays), 0);
    // Without the control variate, the same sampler serves the gathering form.
    let mut plain = solver_by_name("stochastic-jacobi:form=gathering").unwrap();
    assert!(Executor::new(plain.as_mut(), StopRules::parse("steps=5").unwrap()).run(&problem).is_ok());
}

#[test]
fn a_written_batch_is_cast_as_written() {
    // batch=400 over 4 replicates: 100 rays a replicate and regular iteration, each patch's
    // share rounded (at most one ray off a patch, 12 patches), never raised to a floor.
    let (system, f) = twelve();
    let rays_after = |steps: u64| {
        run_sampled("stochastic-jacobi:batch=400", &system, &f, &format!("steps={steps}")).0.state.cost[Unit::Rays]
    };
    let (first, second, third) = (rays_after(1), rays_after(2), rays_after(3));
    for regular in [second - first, third - second] {
        assert!(regular.abs_diff(400) <= 4 * 12, "a regular iteration cast {regular} rays for batch=400");
    }
    // The first step is the whole incremental series: 400 rays for the emitted power, then
    // fewer for each reflection of it, so more than a batch in all.
    assert!(first > 400, "the incremental series cast {first} rays");
    // Fewer rays than replicates is refused, not raised.
    let message = solver_by_name("stochastic-jacobi:batch=3").err().unwrap().to_string();
    assert!(message.contains("fewer than one ray"), "{message}");
}

#[test]
fn the_standard_error_is_the_textbook_formula() {
    // Four replicates of two values, worked by hand: the first (1, 2, 3, 6) has mean 3 and
    // squared deviations summing to 14, so s² = 14 / (R (R − 1)) = 14 / 12; the second is the
    // same in every replicate, s = 0. Dividing by R² instead (an R for R − 1) gives 14 / 16.
    let replicates: [&[Real]; 4] = [&[1.0, 2.0], &[2.0, 2.0], &[3.0, 2.0], &[6.0, 2.0]];
    let mut mean = [0.0; 2];
    let se = StandardError::of_replicates(&replicates, &mut mean);
    assert_eq!(mean, [3.0, 2.0]);
    assert!((se.values[0] - (14.0f64 / 12.0).sqrt()).abs() < 1e-15, "{:?}", se.values);
    assert_eq!((se.values[1], se.replicates), (0.0, 4));
    // The summary: sqrt(Σ A s² / Σ A B̄²) with areas 1 and 3: sqrt((14/12) / (9 + 12)).
    let system = LinearSystem::new(Channels::Grey, vec![1.0, 3.0], vec![0.5, 0.5], vec![1.0, 0.0]).unwrap();
    let summary = se.relative_rms(&system, &mean);
    assert!((summary - (14.0f64 / 12.0 / 21.0).sqrt()).abs() < 1e-15, "{summary}");
}

#[test]
fn a_replicate_holds_its_estimate_and_streams_alone_between_steps() {
    // Each replicate keeps its estimate (n k reals) and its streams' positions (n counts); the
    // unshot radiosity of its incremental series lives only while the series is shot, within
    // the first step. At ten million patches an unshot vector a replicate held to the end was
    // 1 GB of four replicates' 2.4. On one thread, so that whatever is allocated is freed by
    // the thread the count follows.
    let (replicates, n) = (4, 2000);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let held = pool.install(|| {
        let (system, f) = enclosure(n, 0.9);
        let transport = ColumnTransport::new(&f, system.areas()).unwrap();
        let problem = Problem::new(&system, &f).unwrap().with_transport(&transport).unwrap();
        let mut solver = solver_by_name(&format!("stochastic-jacobi:batch=4000:replicates={replicates}")).unwrap();
        let mut state = State::from_emission(system.emissions(), 1);
        let info = allocation_counter::measure(|| {
            solver.init(&problem, &mut state).unwrap();
            for _ in 0..3 {
                solver.next_step(&problem, &mut state).unwrap();
            }
        });
        info.bytes_current
    });
    let chains = (replicates * (n * size_of::<Real>() + n * size_of::<u64>())) as i64;
    assert!(held >= chains && held <= chains + chains / 10, "{held} bytes held after three steps, {chains} asked");
}
