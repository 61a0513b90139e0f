//! The laboratory's references and bounds: the certified bound of every step holds against
//! the reference, `--reference none` runs without matrix or reference, `auto` weighs the
//! matrix against the memory budget, the shooting and stored-matrix references agree with
//! dense LU within their certificates, the cache tells reference kinds apart and keeps the
//! hierarchical operator; charged columns give the computed runs' numbers, and the clock a
//! `time=` rule and `:f=timed` read is the one the report prints; plot titles name the scene
//! by its short name; a run that casts no ray frees the scene's BVH.

use radiosity_core::{Clock, ColumnSource};
use radiosity_eval::ShootingParams;
use radiosity_eval::{
    Cache, ColumnCharge, ColumnCost, Lab, LabOptions, Method, NoProgress, RecordPlan, ReferenceOrigin, ReferenceParams,
};
use radiosity_eval::{MemoryBudget, ReferenceKind, parse_bytes};
use radiosity_eval::{SolverBound, errors, errors_against};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::Unit;
use radiosity_solvers::{
    Executor, Observer, ObserverMode, POINT_SOLVERS, Problem, Record, ResidualBound, SolverRegistry, State, StopRules,
};

fn analytic() -> BackendSpec {
    BackendSpec::parse("analytic").unwrap()
}

fn lab<'p>(scene: &'p PreparedScene, options: LabOptions) -> Lab<'p> {
    Lab::new(scene, &analytic(), options, &NoProgress).unwrap()
}

/// Checks, at init and after every step, that the true relative L1 error of the displayed
/// radiosity is at most the certified bound, and counts the checks.
struct BoundCheck<'a> {
    lab: &'a Lab<'a>,
    known: Option<ResidualBound>,
    checked: usize,
    solver: String,
    largest_ratio: f64,
}

impl Observer for BoundCheck<'_> {
    fn observe_step(&mut self, state: &State, _figures: &Record) {
        let system = self.lab.system();
        let reference = self.lab.reference().unwrap();
        let known =
            self.known.take().unwrap_or_else(|| panic!("{} knows no bound at step {}", self.solver, state.step));
        let bound = SolverBound::new(system, self.lab.contraction(), &known, &state.radiosity);
        let e = errors(system, reference, &state.radiosity).unwrap();
        let relative = e.l1 / e.reference_l1;
        // Round-off only: the reference itself is certified to 1e-10.
        assert!(
            relative <= bound.relative * (1.0 + 1e-9) + 1e-10,
            "{} at step {}: relative L1 error {relative:e} above its bound {:e}",
            self.solver,
            state.step,
            bound.relative
        );
        assert!(bound.relative.is_finite(), "{} at step {}", self.solver, state.step);
        if relative > 1e-8 {
            self.largest_ratio = self.largest_ratio.max(bound.relative / relative);
        }
        self.checked += 1;
    }

    fn wants_residual_bound(&self) -> bool {
        true
    }

    fn observe_residual_bound(&mut self, _state: &State, bound: Option<&ResidualBound>) {
        self.known = bound.cloned();
    }
}

#[test]
fn the_certified_bound_of_every_step_holds_against_the_reference() {
    let scene = PreparedScene::load("cornell:res=4").unwrap();
    let lab = lab(&scene, LabOptions::default());
    assert!(lab.contraction().measured, "a matrix reference measures the contraction");
    let registry = SolverRegistry::builtin();
    let n = lab.n();
    let groups = ["group-jacobi-g16", "group-gs-g16", "group-pr-g8", "pr-g8", "xu-g16-m80"];
    for name in POINT_SOLVERS.into_iter().chain(["relax-1.5"]).chain(groups) {
        let mut solver = registry.build(name).unwrap();
        // The lab's stored matrix holds exactly the columns its source gives (rounded to
        // f32 both ways), and serves them without computing them again.
        let problem = Problem::new(lab.system(), lab.matrix().unwrap()).unwrap();
        let mut check = BoundCheck { lab: &lab, known: None, checked: 0, solver: name.into(), largest_ratio: 0.0 };
        let rules = StopRules::parse("columns=2n").unwrap();
        Executor::new(solver.as_mut(), rules).add_observer(&mut check, ObserverMode::Always).run(&problem).unwrap();
        // A step is a patch or a group of up to 16: every one of 2n columns' steps is checked.
        assert!(check.checked > 2 * n / 16, "{name}: {} steps checked", check.checked);
        // Not vacuous: within a modest factor of the true error for the shooting methods.
        if ["pr", "southwell", "xu"].contains(&name) {
            assert!(check.largest_ratio < 50.0, "{name}: the bound was {}× the error", check.largest_ratio);
        }
    }
}

#[test]
fn a_run_records_the_bound_beside_e_rms_and_ends_on_it() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let lab = lab(&scene, LabOptions::default());
    let mut solver = SolverRegistry::builtin().build("xu").unwrap();
    let rules = StopRules::parse("columns=2n").unwrap();
    let o = lab.run(solver.as_mut(), &rules, &RecordPlan::default(), &NoProgress).unwrap();
    assert!(o.points.iter().all(|p| p.bound.is_finite() && p.e_rms.is_finite()));
    let (first, last) = (o.points.first().unwrap(), o.points.last().unwrap());
    // The first point is the initial state, B = E, with its error against the reference.
    let at_start = errors_against(lab.system(), lab.reference().unwrap().values(), lab.system().emissions()).unwrap();
    assert_eq!((first.step, first.cost[Unit::Columns], first.e_rms), (0, 0, at_start.e_rms));
    assert!(last.bound < 1e-2 * first.bound, "{first:?} {last:?}");
    assert_eq!(o.last.bound, Some(last.bound));
    // The rows of the table carry the same bound as the point of their step.
    for row in &o.rows {
        let p = o.points.iter().find(|p| p.step == row.step).unwrap();
        assert_eq!(row.bound, p.bound, "step {}", row.step);
    }
}

#[test]
fn a_watch_sees_every_point_with_its_state_and_can_end_the_run() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let lab = lab(&scene, LabOptions::default());
    let mut solver = SolverRegistry::builtin().build("xu").unwrap();
    let rules = StopRules::parse("columns=2n").unwrap();
    let mut seen = Vec::new();
    let mut watch = |p: &radiosity_eval::Point, state: &State| {
        // The point is the state's: its step, and its e_rms against the reference.
        let e = errors_against(lab.system(), lab.reference().unwrap().values(), &state.radiosity).unwrap();
        assert_eq!((p.step, p.e_rms), (state.step, e.e_rms));
        seen.push(p.step);
        if p.step == 7 { std::ops::ControlFlow::Break(()) } else { std::ops::ControlFlow::Continue(()) }
    };
    let o = lab.run_watched(solver.as_mut(), &rules, &RecordPlan::default(), &NoProgress, &mut watch).unwrap();
    assert_eq!(seen, (0..=7).collect::<Vec<u64>>());
    assert_eq!(o.state.step, 7);
    assert_eq!(o.termination.to_string(), "stopped by its observer after 7 steps");
    assert_eq!(o.points.last().unwrap().step, 7);
    // A run that is not stopped goes on to its rule.
    let o = lab.run(solver.as_mut(), &rules, &RecordPlan::default(), &NoProgress).unwrap();
    assert!(o.state.step > 7, "{}", o.termination);
}

#[test]
fn reference_none_measures_the_bound_alone_without_any_matrix() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let options = LabOptions::default().with_reference(ReferenceKind::None);
    let lab = lab(&scene, options);
    assert!(lab.reference().is_none() && lab.matrix().is_none());
    assert_eq!(lab.origin(), &ReferenceOrigin::NotComputed);
    assert_eq!(lab.chosen().kind, ReferenceKind::None);
    assert!(!lab.contraction().measured);
    // The same run against a matrix reference: the same bounds, step for step, but for the
    // contraction (measured there, assumed here).
    let with_reference = self::lab(&scene, LabOptions::default());
    let registry = SolverRegistry::builtin();
    let rules = StopRules::parse("columns=n").unwrap();
    let none = lab.run(registry.build("pr").unwrap().as_mut(), &rules, &RecordPlan::default(), &NoProgress).unwrap();
    let measured = with_reference
        .run(registry.build("pr").unwrap().as_mut(), &rules, &RecordPlan::default(), &NoProgress)
        .unwrap();
    assert_eq!(none.last.e_rms, None);
    assert!(none.points.iter().all(|p| p.e_rms.is_nan() && p.bound.is_finite()));
    assert_eq!(none.state.radiosity, measured.state.radiosity, "the reference does not change the run");
    for (a, b) in none.points.iter().zip(&measured.points) {
        let (rho_max, kappa) = (lab.contraction().factor(0), with_reference.contraction().kappa[0]);
        // The assumed κ = ρ_max against the measured one; both bounds of the same vector.
        if kappa <= rho_max {
            assert!(a.bound >= b.bound * (1.0 - 1e-12), "step {}: {} against {}", a.step, a.bound, b.bound);
        }
    }
    // An rms= rule cannot be measured.
    let e = lab
        .run(
            registry.build("pr").unwrap().as_mut(),
            &StopRules::parse("rms=1e-3").unwrap(),
            &RecordPlan::default(),
            &NoProgress,
        )
        .unwrap_err();
    assert!(e.to_string().contains("e_rms"), "{e}");
    assert!(lab.reference_state().is_err());
    // The comparison plots and tabulates the bound.
    let dir = std::env::temp_dir().join(format!("radiosity-lab-none-{}", std::process::id()));
    let comparison = lab.compare(vec![registry.build("pr").unwrap()], &rules, &NoProgress).unwrap();
    comparison.write(&dir).unwrap();
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("Reference `none`") && report.contains("## bound at n/4"), "{report}");
    assert!(std::fs::read(dir.join("bound-columns.png")).unwrap().starts_with(b"\x89PNG"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn auto_weighs_the_matrix_against_the_memory_budget() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let fits = lab(&scene, LabOptions::default().with_memory(MemoryBudget::fixed(1 << 30)));
    assert_eq!(fits.chosen().kind, ReferenceKind::Matrix, "{:?}", fits.chosen());
    assert!(fits.matrix().is_some());
    let tiny = || LabOptions::default().with_memory(MemoryBudget::fixed(1024));
    let shooting = lab(&scene, tiny());
    assert_eq!(shooting.chosen().kind, ReferenceKind::Shooting, "{:?}", shooting.chosen());
    assert!(shooting.chosen().why.contains("needs about"), "{:?}", shooting.chosen());
    assert!(shooting.matrix().is_none());
    // Asked for explicitly, a matrix over the budget is refused before anything is assembled.
    let e = Lab::new(&scene, &analytic(), tiny().with_reference(ReferenceKind::Matrix), &NoProgress).err().unwrap();
    assert!(e.to_string().contains("RADIOSITY_MEMORY"), "{e}");
    // The shooting reference is the matrix's within its certificate.
    let (a, b) = (fits.reference().unwrap(), shooting.reference().unwrap());
    assert!(matches!(b.method(), Method::Shooting { .. }), "{}", b.method());
    assert!(b.certificate().certified && b.certificate().relative_bound <= 1e-8, "{}", b.certificate());
    assert!(!b.certificate().contraction.measured);
    let e = errors(fits.system(), a, b.values()).unwrap();
    assert!(e.l1 / e.reference_l1 <= b.certificate().relative_bound + a.certificate().relative_bound + 1e-12, "{e:?}");
}

#[test]
fn the_stored_matrix_reference_agrees_with_dense_lu() {
    let scene = PreparedScene::load("cornell:res=4").unwrap();
    let lu = lab(&scene, LabOptions::default());
    assert_eq!(lu.reference().unwrap().method(), &Method::DenseLu);
    let mut options = LabOptions::default();
    options.reference = ReferenceParams::default().with_dense_limit(10);
    let gs = lab(&scene, options);
    let r = gs.reference().unwrap();
    assert!(matches!(r.method(), Method::GaussSeidel { .. }), "{}", r.method());
    assert!(r.certificate().certified && r.certificate().relative_bound <= 1e-10, "{}", r.certificate());
    let e = errors(gs.system(), lu.reference().unwrap(), r.values()).unwrap();
    assert!(e.l1 / e.reference_l1 <= 1e-10, "{e:?}");
    assert!(gs.matrix().unwrap().stored().is_some(), "no dense f64 copy");
    // Assembled by reciprocity, each pair once, the matrix holds the very columns solvers
    // read: the reference solves their system.
    let n = gs.n();
    let (mut stored, mut computed) = (vec![0.0; n], vec![0.0; n]);
    let mut differ = 0;
    for j in 0..n {
        gs.matrix().unwrap().fill_column(j, &mut stored);
        gs.source().fill_column(j, &mut computed);
        for (a, b) in stored.iter().zip(&computed) {
            assert!((a - b).abs() <= 1e-7 * b.abs(), "column {j}: {a} against {b}");
            differ += usize::from(a != b);
        }
    }
    assert!(differ <= n * n / 10_000, "{differ} entries differ in their last bit");
}

#[test]
fn the_cache_tells_reference_kinds_apart() {
    let dir = std::env::temp_dir().join(format!("radiosity-lab-cache-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let with = |kind| {
        let options =
            LabOptions::default().with_cache(Some(Cache::at(&dir))).with_reference(kind).with_residuals(false);
        let lab = lab(&scene, options);
        (lab.origin().clone(), lab.reference().unwrap().values().to_vec(), lab.matrix().is_some())
    };
    let (first, matrix_values, kept) = with(ReferenceKind::Matrix);
    assert!(matches!(first, ReferenceOrigin::Solved { .. }) && kept, "{first:?}");
    let (shooting, shooting_values, kept) = with(ReferenceKind::Shooting);
    assert!(matches!(shooting, ReferenceOrigin::Solved { .. }), "a shooting reference read the matrix's: {shooting:?}");
    assert!(!kept);
    assert_ne!(matrix_values, shooting_values);
    let (again, values, kept) = with(ReferenceKind::Matrix);
    assert!(matches!(again, ReferenceOrigin::Cached { .. }) && !kept, "{again:?}");
    assert_eq!(values, matrix_values);
    let (again, values, _) = with(ReferenceKind::Shooting);
    assert!(matches!(again, ReferenceOrigin::Cached { .. }), "{again:?}");
    assert_eq!(values, shooting_values);
    // A different shooting target is another entry.
    let options = LabOptions::default()
        .with_cache(Some(Cache::at(&dir)))
        .with_reference(ReferenceKind::Shooting)
        .with_shooting(ShootingParams::default().with_certified(1e-6));
    assert!(matches!(lab(&scene, options).origin(), ReferenceOrigin::Solved { .. }));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_cache_keeps_the_hierarchical_operator() {
    // A second lab over the same scene and parameters reads the operator's links instead of
    // building them, and a run over it gives the same radiosity to the bit; other parameters
    // are another entry.
    let dir = std::env::temp_dir().join(format!("radiosity-lab-hierarchy-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scene = PreparedScene::load("cornell:res=4").unwrap();
    let run = |spec: &str| {
        let options = LabOptions::default().with_cache(Some(Cache::at(&dir))).with_reference(ReferenceKind::None);
        let lab = Lab::new(&scene, &BackendSpec::parse(spec).unwrap(), options, &NoProgress).unwrap();
        let mut solver = SolverRegistry::builtin().build("gmres-30").unwrap();
        let rules = StopRules::parse("residual=1e-8").unwrap();
        let outcome = lab.run(solver.as_mut(), &rules, &RecordPlan::errors_only(), &NoProgress).unwrap();
        (lab.backend_figures().unwrap().loaded, outcome.state.radiosity.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
    };
    let (loaded, first) = run("hierarchical:eps=5e-2");
    assert!(!loaded, "built the first time");
    let (loaded, again) = run("hierarchical:eps=5e-2");
    assert!(loaded, "read the second time");
    assert_eq!(first, again);
    assert!(!run("hierarchical:eps=1e-2").0, "other parameters are another entry");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Keeps the warnings it is given.
#[derive(Default)]
struct Warnings(std::sync::Mutex<Vec<String>>);

impl radiosity_eval::Progress for Warnings {
    fn warn(&self, message: &str) {
        self.0.lock().unwrap().push(message.to_string());
    }
}

#[test]
fn a_cache_whose_directory_cannot_be_made_is_said_once_and_the_operator_still_built() {
    // A file where the cache's directory would be: nothing can be written under it, and the
    // lab says so in one warning, before turning the operator into bytes.
    let file = std::env::temp_dir().join(format!("radiosity-lab-not-a-dir-{}", std::process::id()));
    std::fs::write(&file, b"a file").unwrap();
    let scene = PreparedScene::load("cornell:res=4").unwrap();
    let options =
        LabOptions::default().with_cache(Some(Cache::at(file.join("cache")))).with_reference(ReferenceKind::None);
    let warnings = Warnings::default();
    let lab = Lab::new(&scene, &BackendSpec::parse("hierarchical:eps=5e-2").unwrap(), options, &warnings).unwrap();
    assert!(!lab.backend_figures().unwrap().loaded);
    let warnings = warnings.0.into_inner().unwrap();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].starts_with("the hierarchical backend was not cached: cannot create"), "{}", warnings[0]);
    std::fs::remove_file(&file).unwrap();
}

#[test]
fn memory_budgets_and_kinds_parse_or_say_why_not() {
    assert_eq!(parse_bytes("6G").unwrap(), 6 << 30);
    assert_eq!(parse_bytes("512MiB").unwrap(), 512 << 20);
    assert_eq!(parse_bytes(" 1.5 g ").unwrap(), 3 << 29);
    assert_eq!(parse_bytes("4096").unwrap(), 4096);
    for bad in ["", "six", "6X", "-1G", "0"] {
        let e = parse_bytes(bad).unwrap_err().to_string();
        assert!(e.contains("RADIOSITY_MEMORY"), "{bad}: {e}");
    }
    for kind in ReferenceKind::NAMES {
        assert_eq!(kind.parse::<ReferenceKind>().unwrap().to_string(), kind);
    }
    let e = "matrx".parse::<ReferenceKind>().unwrap_err().to_string();
    assert!(e.contains("auto, matrix, shooting or none"), "{e}");
}

/// A source that counts how often it is asked to forget what it keeps.
struct Forgetting<S> {
    inner: S,
    resets: std::sync::Arc<std::sync::atomic::AtomicUsize>,
}

impl<S: ColumnSource> ColumnSource for Forgetting<S> {
    fn patch_count(&self) -> usize {
        self.inner.patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [f64]) {
        self.inner.fill_column(j, column)
    }

    fn reset_memory(&self) {
        self.resets.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }
}

/// A lab over the analytic columns of `scene`, wrapped in a [`Forgetting`] (which states no
/// reciprocity bound), and its count of resets.
fn forgetting_lab(scene: &PreparedScene) -> (Lab<'_>, std::sync::Arc<std::sync::atomic::AtomicUsize>) {
    let inner = radiosity_eval::fresh_backend(scene, &analytic(), &NoProgress).unwrap();
    let resets = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let source = Box::new(Forgetting { inner, resets: resets.clone() });
    // Columns computed through the source: charged ones come from the stored matrix.
    let options = LabOptions::default().with_columns(ColumnCost::Computed);
    (Lab::with_source(scene, "forgetting", source, true, options, &NoProgress).unwrap(), resets)
}

#[test]
fn every_run_of_a_lab_starts_from_a_source_that_forgot_earlier_runs() {
    // Otherwise the analytic backend's record of visible fractions, filled by one solver,
    // would make the next one's columns cheaper and its seconds flattering.
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let (lab, resets) = forgetting_lab(&scene);
    let rules = StopRules::parse("columns=n").unwrap();
    for (k, name) in ["xu", "gmres-30", "gauss-seidel"].into_iter().enumerate() {
        let mut solver = SolverRegistry::builtin().build(name).unwrap();
        lab.run(solver.as_mut(), &rules, &RecordPlan::default(), &NoProgress).unwrap();
        assert_eq!(resets.load(std::sync::atomic::Ordering::Relaxed), k + 1, "{name}");
    }
}

#[test]
fn a_comparison_refuses_a_solver_these_form_factors_do_not_suit_before_running_any() {
    // The wrapper states no reciprocity bound, so `cg` cannot run: nothing runs, not even
    // `xu` before it (a run would have asked the source to forget).
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let (lab, resets) = forgetting_lab(&scene);
    let registry = SolverRegistry::builtin();
    let solvers = vec![registry.build("xu").unwrap(), registry.build("cg").unwrap()];
    let e = lab.compare(solvers, &StopRules::parse("columns=n").unwrap(), &NoProgress).err().unwrap();
    assert!(e.to_string().contains("cg cannot solve this system"), "{e}");
    assert_eq!(resets.load(std::sync::atomic::Ordering::Relaxed), 0);
}

#[test]
fn charged_columns_give_the_computed_runs_numbers_at_the_measured_price() {
    // Occluded, so the analytic columns trace shadow rays; a gathering solver (rows), a
    // shooting one, a group-accelerated one and a Krylov one.
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let registry = SolverRegistry::builtin();
    let names = ["gauss-seidel", "xu", "xu-g8-m16:f=4", "gmres-30"];
    let rules = StopRules::parse("columns=2n").unwrap();
    let compare = |columns| {
        let lab = lab(&scene, LabOptions::default().with_columns(columns));
        let solvers = names.iter().map(|name| registry.build(name).unwrap()).collect();
        let comparison = lab.compare(solvers, &rules, &NoProgress).unwrap();
        (comparison, lab.charge().copied())
    };
    let (computed, none) = compare(ColumnCost::Computed);
    let (charged, charge) = compare(ColumnCost::Charged);
    assert!(none.is_none() && computed.charge.is_none());
    let charge = charge.expect("a matrix reference is kept, so columns are charged");
    assert!(charge.fresh > 0.0 && charge.recorded <= charge.fresh);
    assert_eq!(charge.sampled, ColumnCharge::SAMPLE.min(computed.n as usize));
    assert_eq!(charged.charge, Some(charge));
    for (a, b) in computed.outcomes.iter().zip(&charged.outcomes) {
        assert_eq!(
            (a.state.step, a.state.cost[Unit::Columns]),
            (b.state.step, b.state.cost[Unit::Columns]),
            "{}",
            a.solver
        );
        assert_eq!(a.state.radiosity, b.state.radiosity, "{}", a.solver);
        let e = |o: &radiosity_eval::Outcome| {
            o.points.iter().map(|p| (p.step, p.cost[Unit::Columns], p.e_rms)).collect::<Vec<_>>()
        };
        assert_eq!(e(a), e(b), "{}", a.solver);
        // Between every column recorded and every column fresh; the last point is the run's.
        let (columns, ff) = (b.state.cost[Unit::Columns] as f64, b.state.cost.ff_seconds);
        let slack = 1e-9 * ff.max(1e-9);
        assert!(ff >= charge.recorded * columns - slack && ff <= charge.fresh * columns + slack, "{}", a.solver);
        assert_eq!(b.points.last().unwrap().cost.seconds(), b.seconds(), "{}", a.solver);
    }
    // Jacobi's first sweep gathers each row once, in order: the k-th has k of its pairs
    // recorded, so n rows cost n·fresh − (fresh − recorded)(n − 1)/2.
    let lab = lab(&scene, LabOptions::default().with_columns(ColumnCost::Charged));
    let mut jacobi = registry.build("jacobi").unwrap();
    let run = lab.run(jacobi.as_mut(), &StopRules::parse("steps=n").unwrap(), &RecordPlan::default(), &NoProgress);
    let charge = lab.charge().unwrap();
    let n = lab.n() as f64;
    let expected = n * charge.fresh - (charge.fresh - charge.recorded) * (n - 1.0) / 2.0;
    let ff = run.unwrap().state.cost.ff_seconds;
    assert!((ff - expected).abs() <= 1e-9 * expected, "{ff} against {expected}");
    assert!(charged.seconds_phrase().contains("charged"), "{}", charged.seconds_phrase());
}

#[test]
fn the_clock_rules_and_the_report_read_the_same_seconds() {
    // Charged at given prices, a run's form-factor seconds are known in advance: at 1 s a
    // column, fresh or not, `pr` (one column a step) passes 10.5 s at its 11th column, its
    // solving taking microseconds. The report prints the same seconds, named `charged`.
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let registry = SolverRegistry::builtin();
    let time = |limit: &str| StopRules::parse(&format!("time={limit}")).unwrap();
    let charged =
        lab(&scene, LabOptions::default().with_columns(ColumnCost::Charged)).with_charge(ColumnCharge::new(1.0, 1.0));
    assert_eq!(charged.clock(), Clock::Charged);
    let comparison = charged.compare(vec![registry.build("pr").unwrap()], &time("10.5s"), &NoProgress).unwrap();
    assert_eq!(comparison.clock, Clock::Charged);
    let run = &comparison.outcomes[0];
    assert_eq!(run.clock, Clock::Charged);
    assert_eq!((run.state.cost[Unit::Columns], run.state.cost.ff_seconds), (11, 11.0));
    assert!(run.state.cost.solve_seconds < 0.5, "{}", run.state.cost.solve_seconds);
    stopped_where_the_seconds_pass(run, 10.5);
    let summary = comparison.summary();
    let header = summary.lines().next().unwrap();
    assert!(header.ends_with("seconds (charged)"), "{summary}");
    let printed: f64 = summary.lines().nth(1).unwrap().split_whitespace().last().unwrap().parse().unwrap();
    assert_eq!(printed, (run.seconds() * 1e3).round() / 1e3, "{summary}");
    let mut csv = Vec::new();
    comparison.table().write_csv(&mut csv).unwrap();
    let csv = String::from_utf8(csv).unwrap();
    assert!(csv.lines().skip(1).all(|l| l.split(',').nth(5) == Some("charged")), "{csv}");

    // Computed, the same rule stops on measured seconds, as the report prints them.
    let computed = lab(&scene, LabOptions::default().with_columns(ColumnCost::Computed));
    assert_eq!(computed.clock(), Clock::Measured);
    let comparison = computed.compare(vec![registry.build("pr").unwrap()], &time("5ms"), &NoProgress).unwrap();
    assert_eq!((comparison.clock, comparison.outcomes[0].clock), (Clock::Measured, Clock::Measured));
    stopped_where_the_seconds_pass(&comparison.outcomes[0], 5e-3);
    assert!(comparison.summary().lines().next().unwrap().ends_with("seconds (measured)"));

    // `:f=timed` takes a column's cost from the same clock: at 1000 s a column a group step of
    // milliseconds is due after every step (as with f=1); at 1e-15 s, never after the first
    // (as with an f beyond the run).
    let steps = StopRules::parse("steps=n").unwrap();
    let groups = |lab: &Lab<'_>, name: &str| {
        let mut solver = registry.build(name).unwrap();
        let run = lab.run(solver.as_mut(), &steps, &RecordPlan::default(), &NoProgress).unwrap();
        (run.record.count("group_steps").unwrap(), run.state.radiosity)
    };
    let dear =
        lab(&scene, LabOptions::default().with_columns(ColumnCost::Charged)).with_charge(ColumnCharge::new(1e3, 1e3));
    let (timed, every) = (groups(&dear, "xu-g4:f=timed"), groups(&dear, "xu-g4:f=1"));
    assert!(every.0 > 10 && timed == every, "{} and {} group steps", timed.0, every.0);
    let cheap = lab(&scene, LabOptions::default().with_columns(ColumnCost::Charged))
        .with_charge(ColumnCharge::new(1e-15, 1e-15));
    let (timed, once) = (groups(&cheap, "xu-g4:f=timed"), groups(&cheap, "xu-g4:f=1000000"));
    assert!(once.0 == 1 && timed == once, "{} and {} group steps", timed.0, once.0);
}

/// `run` ended on its `time=` rule at its first point whose seconds reached `limit`.
fn stopped_where_the_seconds_pass(run: &radiosity_eval::Outcome, limit: f64) {
    assert!(run.termination.to_string().starts_with("time limit"), "{}", run.termination);
    let [.., before, last] = &run.points[..] else { panic!("{:?}", run.points) };
    assert!(
        before.cost.seconds() < limit && last.cost.seconds() >= limit,
        "{} then {}",
        before.cost.seconds(),
        last.cost.seconds()
    );
    assert_eq!(last.cost.seconds(), run.seconds());
}

/// Analytic columns standing in for an operator split over ranks: they say they are.
struct Split<'a> {
    inner: Box<dyn radiosity_ff::FormFactorBackend + 'a>,
    ranks: std::sync::Arc<radiosity_core::InProcessRanks>,
}

impl ColumnSource for Split<'_> {
    fn patch_count(&self) -> usize {
        self.inner.patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [radiosity_core::Real]) {
        self.inner.fill_column(j, column);
    }

    fn collective(&self) -> Option<&dyn radiosity_core::Collective> {
        Some(self.ranks.as_ref())
    }
}

#[test]
fn node_shooters_over_a_split_operator_are_warned_that_they_run_one_level() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let registry = SolverRegistry::builtin();
    let warnings = radiosity_core::InProcessRanks::run(1, |ranks| {
        let inner = radiosity_eval::fresh_backend(&scene, &analytic(), &NoProgress).unwrap();
        let options = LabOptions::default().with_columns(ColumnCost::Computed);
        let lab = Lab::with_source(&scene, "split", Box::new(Split { inner, ranks }), true, options, &NoProgress);
        let lab = lab.unwrap();
        let warn = |name: &str| lab.link_warning(registry.build(name).unwrap().as_ref());
        (warn("h-xu"), warn("xu"))
    });
    let (node, point) = &warnings[0];
    assert!(node.as_deref().is_some_and(|w| w.contains("h-xu") && w.contains("one level")), "{node:?}");
    assert_eq!(point, &None);
    // Over the whole hierarchical operator, which shows its links, no warning.
    let spec = BackendSpec::parse("hierarchical:eps=0.05").unwrap();
    let lab = Lab::new(&scene, &spec, LabOptions::default().with_reference(ReferenceKind::None), &NoProgress).unwrap();
    assert_eq!(lab.link_warning(registry.build("h-xu").unwrap().as_ref()), None);
}

#[test]
fn a_budget_a_last_step_overshoots_is_said_and_a_capped_run_is_not_converged() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let lab = Lab::new(&scene, &analytic(), LabOptions::default(), &NoProgress).unwrap();
    let registry = SolverRegistry::builtin();
    // A step of gmres-30 is a product, the columns of every lit patch at once: it goes past
    // n/2 columns in its first step.
    let comparison =
        lab.compare(vec![registry.build("gmres-30").unwrap()], &StopRules::parse("columns=0.5n").unwrap(), &NoProgress);
    let comparison = comparison.unwrap();
    let spent = comparison.outcomes[0].state.cost[Unit::Columns];
    assert!(spent > lab.n() as u64 / 2, "{spent}");
    assert_eq!(comparison.notes.len(), 1, "{:?}", comparison.notes);
    assert!(comparison.notes[0].starts_with(&format!("gmres-30 spent {spent} columns, past columns=0.5n")));
    assert!(comparison.report_markdown(&[]).contains("**Not as asked.** gmres-30 spent"));
    // PR stops exactly at its budget: nothing to say.
    let comparison =
        lab.compare(vec![registry.build("pr").unwrap()], &StopRules::parse("columns=0.5n").unwrap(), &NoProgress);
    assert!(comparison.unwrap().notes.is_empty());
}

#[test]
fn plot_titles_name_the_scene_by_its_short_name() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let lab = lab(&scene, LabOptions::default());
    let registry = SolverRegistry::builtin();
    let rules = StopRules::parse("columns=n").unwrap();
    let mut comparison = lab.compare(vec![registry.build("pr").unwrap()], &rules, &NoProgress).unwrap();
    let dir = std::env::temp_dir().join(format!("radiosity-lab-titles-{}", std::process::id()));
    // The title of a plot, its first text.
    let title = |stem: &str| {
        let svg = std::fs::read_to_string(dir.join(format!("{stem}.svg"))).unwrap();
        let text = svg.split("<text").nth(1).unwrap().split_once('>').unwrap().1;
        text.split_once("</text>").unwrap().0.trim().to_string()
    };
    // A built-in scene as written, with its parameters.
    comparison.write(&dir).unwrap();
    assert_eq!(title("e_rms-steps"), "cornell:res=2: e_rms against shooting steps");
    // A file by its name alone, without its folders, on every plot.
    comparison.scene.scene = "/home/someone/scenes/mgf/salon/classroom.mgf:size=0.1".into();
    comparison.write(&dir).unwrap();
    for (stem, axis) in [("e_rms-steps", "shooting steps"), ("e_rms-columns", "columns computed")] {
        assert_eq!(title(stem), format!("classroom.mgf:size=0.1: e_rms against {axis}"));
    }
    assert!(title("e_rms-seconds").starts_with("classroom.mgf:size=0.1: e_rms against measured seconds"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_run_that_casts_no_ray_frees_the_bvh_and_a_later_request_for_rays_is_refused() {
    let registry = SolverRegistry::builtin();
    let rules = StopRules::parse("residual=1e-6").unwrap();
    let hierarchical = BackendSpec::parse("hierarchical:eps=5e-2").unwrap();
    let options = || LabOptions::default().with_reference(ReferenceKind::None);
    let scene = PreparedScene::load("cornell:res=4").unwrap();
    let mut gmres = registry.build("gmres-30").unwrap();
    let kept = Lab::new(&scene, &hierarchical, options(), &NoProgress).unwrap();
    let before = kept.run(gmres.as_mut(), &rules, &RecordPlan::errors_only(), &NoProgress).unwrap();

    // A solver that samples transport through the scene keeps it.
    let stochastic = registry.build("stochastic-jacobi").unwrap();
    assert_eq!(kept.release_rays(Some(stochastic.as_ref())), 0);
    assert!(scene.has_visibility());
    // The operator holds no handle on the tree once built: it is freed, all of it.
    let bvh = scene.memory().bvh;
    assert!(bvh > 0);
    assert_eq!(kept.release_rays(Some(gmres.as_ref())), bvh);
    assert!(!scene.has_visibility());
    assert_eq!(scene.memory().bvh, 0);
    assert_eq!(kept.release_rays(None), 0, "freed once");
    // The run needs no ray: the same bits without the tree.
    let after = kept.run(gmres.as_mut(), &rules, &RecordPlan::errors_only(), &NoProgress).unwrap();
    let bits = |s: &State| s.radiosity.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&before.state), bits(&after.state));
    // Whatever asks for rays now is refused in one sentence, not given a tree that misses.
    let e = kept.transport_sampler().err().unwrap().to_string();
    assert!(e.contains("the scene's BVH was released") && e.contains("sampling transport by rays"), "{e}");
    let e = Lab::new(&scene, &analytic(), options(), &NoProgress).err().unwrap().to_string();
    assert!(e.contains("the scene's BVH was released") && e.contains("building a form-factor backend"), "{e}");

    // A backend that computes its entries by rays shares the tree, which is then kept.
    let scene = PreparedScene::load("cornell:res=4").unwrap();
    let analytic_lab = Lab::new(&scene, &analytic(), options(), &NoProgress).unwrap();
    assert_eq!(analytic_lab.release_rays(Some(gmres.as_ref())), 0);
    assert!(scene.has_visibility());
    assert!(analytic_lab.transport_sampler().is_ok());
}
