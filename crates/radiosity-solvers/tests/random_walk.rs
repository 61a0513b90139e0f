//! `random-walk` over stored systems sampled exactly ([`radiosity_core::ColumnTransport`]),
//! against their dense LU solutions: unbiased in every form and scoring, exact where the
//! theory says so (the closed furnace), an error bar that covers at the rate it claims, the
//! same numbers for the same seed whatever the thread count, and its refusals.

use super::krylov::exact;
use super::{cube, furnace, twelve};
use radiosity_core::{Channels, ColumnTransport, DenseColumns, LinearSystem, Real};
use radiosity_solvers::*;

/// Every form and scoring, as name parameters.
const FORMS: [&str; 4] = [
    "form=shooting:score=collision",
    "form=shooting:score=absorption",
    "form=gathering:score=collision",
    "form=gathering:score=absorption",
];

/// What one run leaves: the run, and the solver's standard error at its end.
struct Walked {
    run: Run,
    error: Option<StandardError>,
}

/// Runs `name` on `system` with `f` sampled exactly, under `rules`.
fn walk(name: &str, system: &LinearSystem, f: &DenseColumns, rules: &str) -> Result<Walked, SolverError> {
    let transport = ColumnTransport::new(f, system.areas()).unwrap();
    let problem = Problem::new(system, f)?.with_transport(&transport)?;
    let mut solver = solver_by_name(name)?;
    let run = Executor::new(solver.as_mut(), StopRules::parse(rules)?).run(&problem)?;
    assert_eq!(run.state.cost[Unit::Rays], problem.spent(Unit::Rays));
    let error = solver.standard_error(&problem, &run.state);
    Ok(Walked { run, error })
}

/// The mean over `seeds` runs of `name:seed=s` and the standard error of that mean (the
/// spread over seeds, each run independent), patch-major.
fn over_seeds(name: &str, system: &LinearSystem, f: &DenseColumns, rules: &str, seeds: u64) -> (Vec<Real>, Vec<Real>) {
    let runs: Vec<Vec<Real>> =
        (0..seeds).map(|s| walk(&format!("{name}:seed={s}"), system, f, rules).unwrap().run.state.radiosity).collect();
    let len = runs[0].len();
    let s = seeds as Real;
    let mean: Vec<Real> = (0..len).map(|idx| runs.iter().map(|b| b[idx]).sum::<Real>() / s).collect();
    let se = (0..len)
        .map(|idx| (runs.iter().map(|b| (b[idx] - mean[idx]).powi(2)).sum::<Real>() / (s - 1.0) / s).sqrt())
        .collect();
    (mean, se)
}

/// Asserts that the mean over seeds lies within 4 of its standard errors of `star` at every
/// patch and channel (and 1e-12 of `B*` for round-off, where the spread is zero), and that the
/// test has power: each standard error at most `power` of `B*`.
///
/// Tolerance: for an unbiased estimator, `(mean − B*) / se` over 64 seeds follows Student's
/// `t` with 63 degrees of freedom closely where each seed's estimate is near normal, which
/// is why every run takes 16 to 40 steps (with 10, the rare large scores of gathering by
/// absorption left the seeds' means skewed); beyond 4 with probability 1.6e-4, so over the
/// 36 patch channels of the 7 cases on `twelve` about a 4% chance of one false alarm, which
/// the fixed seeds make a fixed outcome either way. A bias is caught where it exceeds 4
/// standard errors: at most `4 · power` of `B*` at the worst-sampled entry, a few percent at
/// most entries; a bias anywhere also shifts the coverage of the error bar, tested apart.
fn assert_unbiased(label: &str, mean: &[Real], se: &[Real], star: &[Real], power: Real) {
    for (idx, ((m, s), b)) in mean.iter().zip(se).zip(star).enumerate() {
        assert!((m - b).abs() <= 4.0 * s + 1e-12 * b, "{label}: entry {idx}: mean {m} against {b}, standard error {s}");
        assert!(power.is_infinite() || *s <= power * b, "{label}: entry {idx}: standard error {s} of {b} has no power");
    }
}

#[test]
fn every_form_and_scoring_is_unbiased_on_a_stored_system() {
    // Twelve patches, RGB, reciprocal (gathering's hypothesis), rows summing to 0.95 at most
    // (rays escape), ρ from 0.3 to 0.9, a third of the patches emitting.
    // Power: 48 walks a patch or emitter, replicate and step (walks=48n), so that every
    // standard error of the mean over seeds is at most 0.8% of B*: a bias of 5% at the
    // worst-sampled entry lies 6 standard errors out, and fails.
    let (system, f) = twelve();
    let star = exact(&system, &f);
    for form in FORMS {
        let (mean, se) = over_seeds(&format!("random-walk:{form}:walks=48n"), &system, &f, "steps=40", 64);
        let worst = (0..se.len()).max_by(|&a, &b| (se[a] / star[a]).total_cmp(&(se[b] / star[b]))).unwrap();
        eprintln!("{form}: worst entry {worst}, standard error {:.4} of B*", se[worst] / star[worst]);
        assert_unbiased(form, &mean, &se, &star, 0.008);
    }
    // Quasi-random points, one stream per depth: every point uniform, so unbiased too.
    for name in ["random-walk:seq=sobol", "random-walk:seq=halton", "random-walk:form=gathering:seq=sobol"] {
        let (mean, se) = over_seeds(name, &system, &f, "steps=40", 64);
        assert_unbiased(name, &mean, &se, &star, 0.05);
    }
}

#[test]
fn the_closed_furnace_gives_e_over_one_minus_rho() {
    // Rows F_ij = A_j / ΣA sum to 1 (patches see themselves), ρ = 0.9, E = 1: B = 10 at every
    // patch. Its columns sum to 1 up to round-off, so rays escape only with the probability
    // that round-off leaves.
    let area: Vec<Real> = (0..6).map(|i| 1.0 + i as Real).collect();
    let total: Real = area.iter().sum();
    let (system, f) = furnace(area.clone(), 0.9, |_, j| area[j] / total);
    let star = vec![10.0; 6];
    for form in FORMS {
        let (mean, se) = over_seeds(&format!("random-walk:{form}"), &system, &f, "steps=40", 64);
        assert_unbiased(form, &mean, &se, &star, 0.05);
    }
    // Gathering by absorption: every walk is absorbed once and scores ρ E / (1 − ρ): exact,
    // without variance (to round-off over the ray weights, 1 within 1e-15).
    let gathered = walk("random-walk:form=gathering:score=absorption", &system, &f, "steps=3").unwrap();
    for b in &gathered.run.state.radiosity {
        assert!((b / 10.0 - 1.0).abs() < 1e-12, "{b}");
    }
    assert!(gathered.error.unwrap().values.iter().all(|&s| s < 1e-12));
    // Shooting by absorption: every walk scores the whole reflected power, Φ ρ / (1 − ρ), so
    // Σ A (B − E) is exact in every replicate however the walks spread it.
    let shot = walk("random-walk:score=absorption", &system, &f, "steps=3").unwrap();
    let reflected: Real = shot.run.state.radiosity.iter().zip(&area).map(|(b, a)| a * (b - 1.0)).sum();
    assert!((reflected / (total * 9.0) - 1.0).abs() < 1e-12, "{reflected}");
    assert!(shot.error.unwrap().values.iter().any(|&s| s > 1e-3), "the spread over patches is not zero");
    // A walk casts L rays, L geometric with mean 1/(1 − ρ) = 10 and standard deviation
    // √ρ/(1 − ρ): the mean over the walks within 4 of its standard errors.
    let record = &gathered.run.record;
    let walks = record.count("walks").unwrap();
    assert_eq!(walks, 3 * 4 * 6, "3 steps, 4 replicates, one walk from each of 6 patches");
    let long = walk("random-walk:form=gathering:walks=600", &system, &f, "steps=2").unwrap();
    let (walks, length) = (long.run.record.count("walks").unwrap(), long.run.record.real("mean_walk_length").unwrap());
    assert_eq!((walks, long.run.state.cost[Unit::Rays]), (2 * 4 * 600, (length * walks as Real).round() as u64));
    let se = 0.9f64.sqrt() / 0.1 / (walks as Real).sqrt();
    assert!((length - 10.0).abs() < 4.0 * se, "mean walk length {length}, standard error {se}");
}

#[test]
fn reflectivity_099_stays_unbiased() {
    // The cube lit from its top, ρ = 0.99 on every face: walks of a hundred rays.
    let mut e = vec![0.0; 6];
    e[1] = 1.0;
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.99; 6], e).unwrap();
    let f = cube();
    let star = exact(&system, &f);
    for form in FORMS {
        let (mean, se) = over_seeds(&format!("random-walk:{form}"), &system, &f, "steps=16", 64);
        assert_unbiased(form, &mean, &se, &star, 0.05);
    }
}

#[test]
fn channels_far_apart_keep_a_finite_variance() {
    // ρ = 0.99, 0.5 and 0 on every face of the cube lit from its top: a walk survives with the
    // largest ρ, so no channel's weight grows from landing to landing (with the mean ρ, the
    // first channel's second moment would grow by 0.99² / 0.497 ≈ 1.97 a landing: infinite
    // variance). The mean over 64 seeds is unbiased within 4 standard errors, and the
    // replicates' error bar estimates the spread between seeds: the mean squared standard
    // error within a factor 2 of the squared spread of the seeds' estimates (a mean of 64
    // chi-square-like terms against a sample variance of 64 runs).
    let mut e = vec![0.0; 18];
    e[3..6].copy_from_slice(&[1.0, 1.0, 1.0]);
    let rho: Vec<Real> = (0..18).map(|idx| [0.99, 0.5, 0.0][idx % 3]).collect();
    let system = LinearSystem::new(Channels::Rgb, vec![1.0; 6], rho, e).unwrap();
    let f = cube();
    let star = exact(&system, &f);
    for form in FORMS {
        let name = format!("random-walk:{form}");
        let (mean, se) = over_seeds(&name, &system, &f, "steps=40", 64);
        // The third channel reflects nothing: B = E exactly there, with no spread. Power: each
        // standard error at most a tenth of B* for collision; absorption, which scores only
        // where a walk ends, ends rarely here (survival 0.99) and is only checked unbiased.
        let power = if form.contains("collision") { 0.1 } else { Real::INFINITY };
        assert_unbiased(&name, &mean, &se, &star, power);
        let bars: Real = (0..64)
            .map(|s| {
                let walked = walk(&format!("{name}:seed={s}"), &system, &f, "steps=40").unwrap();
                walked.error.unwrap().values.iter().map(|v| v * v).sum::<Real>()
            })
            .sum::<Real>()
            / 64.0;
        // The seeds' spread: se over seeds times sqrt(64) is one run's standard deviation.
        let spread: Real = se.iter().map(|v| v * v * 64.0).sum();
        assert!((0.5..2.0).contains(&(bars / spread)), "{name}: mean squared bar {bars} against spread {spread}");
    }
}

#[test]
fn the_standard_error_covers_at_the_rate_it_claims() {
    // Per patch and channel, (B̄ − B*) / s follows Student's t with R − 1 degrees of freedom
    // where each replicate's estimate is near normal: within 2 s with probability
    // t_coverage_of_two(R), 0.861 for R = 4 and 0.936 for R = 16.
    //
    // Tolerance: the 36 patch channels of one seed share its walks, so the fraction covered is
    // taken per seed, and its mean over independent seeds has a standard error from their
    // spread (a binomial spread where the 36 were independent, wider where they are not);
    // the mean lies within 3 of those standard errors, plus 0.02 for non-normality. Each
    // replicate's estimate is a mean over m ≥ 480 walks (40 steps of 12 walks, from the
    // emitters or from every patch; of 36 with R = 16), so its skewness falls as 1/√m and its excess kurtosis as 1/m; a symmetric
    // interval covers as often whichever way the estimate is skewed, so its coverage moves
    // only by terms in the skewness squared and the excess kurtosis, both O(1/m): with a
    // walk's score 0 most of the time (skewness about 3, excess kurtosis about 10 where a
    // patch is hit one walk in ten), about 0.02.
    let (system, f) = twelve();
    let star = exact(&system, &f);
    let cases: Vec<(String, u64)> = FORMS
        .iter()
        .map(|form| {
            let per_patch = if form.contains("gathering") { ":walks=12n" } else { "" };
            (format!("random-walk:{form}{per_patch}"), 100)
        })
        .chain([("random-walk:replicates=16:walks=3n".to_string(), 60)])
        .collect();
    for (name, seeds) in cases {
        let replicates = if name.contains("replicates=16") { 16 } else { 4 };
        let claimed = t_coverage_of_two(replicates);
        let fractions: Vec<Real> = (0..seeds)
            .map(|seed| {
                let walked = walk(&format!("{name}:seed={seed}"), &system, &f, "steps=40").unwrap();
                let error = walked.error.unwrap();
                assert_eq!(error.replicates, replicates);
                let b = &walked.run.state.radiosity;
                let covered = (0..b.len()).filter(|&idx| (b[idx] - star[idx]).abs() <= 2.0 * error.values[idx]).count();
                covered as Real / b.len() as Real
            })
            .collect();
        let s = seeds as Real;
        let mean = fractions.iter().sum::<Real>() / s;
        let se = (fractions.iter().map(|x| (x - mean).powi(2)).sum::<Real>() / (s - 1.0) / s).sqrt();
        eprintln!("{name}: {mean:.3} ± {se:.3} within 2 standard errors, {claimed:.3} claimed");
        assert!(
            (mean - claimed).abs() <= 3.0 * se + 0.02,
            "{name}: covered {mean:.3} ± {se:.3} of patch channels within 2 s, against {claimed:.3}"
        );
    }
}

#[test]
fn the_same_seed_gives_the_same_numbers_whatever_the_thread_count() {
    let (system, f) = twelve();
    // 600 walks a step: three batches of shooting walks in each of four replicates.
    assert_eq!(RandomWalk::WALKS_PER_BATCH, 256);
    for name in [
        "random-walk:walks=600",
        "random-walk:walks=600:seq=sobol:score=absorption",
        "random-walk:walks=600:seq=halton",
        "random-walk:form=gathering:walks=5n",
        "random-walk:form=gathering:walks=5n:seq=sobol",
    ] {
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| walk(name, &system, &f, "steps=3").unwrap())
        };
        let one = on(1);
        for threads in [2, 4] {
            let other = on(threads);
            assert_eq!(one.run.state.radiosity, other.run.state.radiosity, "{name} on {threads} threads");
            assert_eq!(one.error, other.error, "{name} on {threads} threads");
            assert_eq!(
                (one.run.state.cost[Unit::Rays], &one.run.record),
                (other.run.state.cost[Unit::Rays], &other.run.record),
                "{name}"
            );
        }
        let reseeded = walk(&format!("{name}:seed=2"), &system, &f, "steps=3").unwrap();
        assert_ne!(one.run.state.radiosity, reseeded.run.state.radiosity, "{name}");
    }
}

#[test]
fn names_parse_to_typed_parameters_and_keep_their_canonical_form() {
    let p: RandomWalkParams =
        "random-walk:seq=sobol:form=gathering:walks=2n:replicates=8:seed=7:score=absorption".parse().unwrap();
    assert_eq!(
        p,
        RandomWalkParams {
            form: WalkForm::Gathering,
            score: WalkScore::Absorption,
            walks: Count::PerPatch(2.0),
            replicates: 8,
            seed: 7,
            seq: Sequence::Sobol,
        }
    );
    assert_eq!(
        p.build().unwrap().name(),
        "random-walk:form=gathering:score=absorption:walks=2n:replicates=8:seed=7:seq=sobol"
    );
    assert_eq!("random-walk".parse::<RandomWalkParams>(), Ok(RandomWalkParams::default()));
    assert_eq!("random-walk:walks=1e4".parse::<RandomWalkParams>().unwrap().walks, Count::Absolute(10_000));
    assert_eq!("random".parse::<RandomWalkParams>(), Err(ParseSolverError::OtherFamily));
    assert_eq!("pr".parse::<RandomWalkParams>(), Err(ParseSolverError::OtherFamily));
    let registry = SolverRegistry::builtin();
    for example in RandomWalkParams::EXAMPLES {
        assert_eq!(registry.build(example).unwrap().name(), *example);
        assert_eq!(registry.build(example).unwrap().step_kind(), StepKind::Sampled);
    }
    assert_eq!(registry.suggest("random-wlak"), Some("random-walk".into()));
    // Parameters built by hand are checked as names are, in one sentence.
    let one = RandomWalkParams { replicates: 1, ..RandomWalkParams::default() };
    assert_eq!(
        one.build().err().unwrap().to_string(),
        "random-walk needs 2 to 1024 replicates, not 1, since the error bar is the spread between replicates"
    );
    let none = RandomWalkParams { walks: Count::Absolute(0), ..RandomWalkParams::default() };
    assert_eq!(
        none.build().err().unwrap().to_string(),
        "random-walk needs a positive number of walks a step, not walks=0"
    );
}

#[test]
fn bad_parameters_are_refused_in_one_sentence() {
    for (name, message) in [
        ("random-walk:form=sideways", "'form=sideways' needs form=shooting or form=gathering"),
        ("random-walk:score=track", "'score=track' needs score=collision or score=absorption"),
        ("random-walk:walks=0", "'walks=0' needs a positive number of walks, such as walks=1000 or walks=2n"),
        ("random-walk:walks=-2n", "'walks=-2n' needs a positive number of walks, such as walks=1000 or walks=2n"),
        (
            "random-walk:replicates=1",
            "'replicates=1' needs a whole number from 2 to 1024, since the error bar is the spread between replicates",
        ),
        (
            "random-walk:replicates=5000",
            "'replicates=5000' needs a whole number from 2 to 1024, since the error bar is the spread between replicates",
        ),
        ("random-walk:seed=-1", "'seed=-1' needs a whole number from 0 to 2^64 − 1"),
        ("random-walk:seq=lattice", "'seq=lattice' needs seq=random, seq=sobol or seq=halton"),
        (
            "random-walk:lines=global",
            "'lines=global' is not a parameter; random-walk takes form=, score=, walks=, replicates=, seed= and seq=",
        ),
        (
            "random-walk:form=gathering:",
            "'' is not a parameter; random-walk takes form=, score=, walks=, replicates=, seed= and seq=",
        ),
    ] {
        let e = solver_by_name(name).err().unwrap().to_string();
        assert_eq!(e, format!("solver '{name}': {message}"));
        assert!(!e.contains(". ") && !e.ends_with('.'), "one sentence: {e}");
    }
}

#[test]
fn a_problem_without_a_transport_sampler_is_refused_before_any_work() {
    let (system, f) = twelve();
    let problem = Problem::new(&system, &f).unwrap();
    for form in FORMS {
        let name = format!("random-walk:{form}");
        let mut solver = solver_by_name(&name).unwrap();
        let err = Executor::new(solver.as_mut(), StopRules::parse("steps=5").unwrap()).run(&problem).unwrap_err();
        let SolverError::NotApplicable { solver: who, .. } = &err else { panic!("{name}: {err}") };
        assert_eq!(who, &solver.name());
        assert!(err.to_string().contains("has no transport sampler"), "{err}");
        assert_eq!((problem.spent(Unit::Rays), problem.spent(Unit::Columns)), (0, 0));
    }
}

#[test]
fn a_dark_system_is_solved_at_once_and_rays_are_counted_as_the_rule_asks() {
    // Nothing emitted: B = 0 exactly, known without a ray.
    let dark = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.5; 6], vec![0.0; 6]).unwrap();
    let walked = walk("random-walk", &dark, &cube(), "steps=10").unwrap();
    assert_eq!(walked.run.termination, TerminationReason::RoundOff);
    assert_eq!((walked.run.state.step, walked.run.state.cost[Unit::Rays]), (0, 0));
    assert!(walked.run.state.radiosity.iter().all(|&b| b == 0.0));
    assert!(walked.error.unwrap().values.iter().all(|&s| s == 0.0));
    // A rays= budget stops the first step that reaches it; no residual, the spread as error.
    let (system, f) = twelve();
    let walked = walk("random-walk", &system, &f, "rays=5000").unwrap();
    let TerminationReason::Spent(Unit::Rays, rays) = walked.run.termination else {
        panic!("{}", walked.run.termination)
    };
    assert!(rays >= 5000 && walked.run.state.cost[Unit::Columns] == 0, "{rays} rays");
    let error = walked.error.unwrap();
    assert!(error.relative_rms(&system, &walked.run.state.radiosity) > 0.0);
}
