//! Scene-level tests: every point, group and Krylov solver on built-in scenes with analytic form factors,
//! measured against the exact reference of the same discrete system, and convergence
//! tables of those runs under snapshot tests.
//!
//! Each scene's form factors are assembled once into a [`FormFactors`] matrix shared by
//! every test and solver: solvers then read stored columns, which keeps runs cheap, and the
//! matrix serves exact rows to gathering methods.

use radiosity_core::{LinearSystem, Real};
use radiosity_eval::errors;
use radiosity_eval::{ConvergenceTable, Evaluator, FormFactors, ReferenceParams, ReferenceSolution, TableRow};
use radiosity_ff::{BackendSpec, FormFactorInput};
use radiosity_geom::{SceneAnalysis, Visibility, load_scene};
use radiosity_solvers::{
    BEYOND_PAPER_SOLVERS, Executor, GROUP_SOLVERS, KRYLOV_SOLVERS, Observer, ObserverMode, POINT_SOLVERS, Problem,
    Record, Run, State, StopRules, solver_by_name,
};
use radiosity_solvers::{Cost, Unit};
use std::collections::HashMap;
use std::panic::{self, AssertUnwindSafe};
use std::sync::OnceLock;

/// A closed box with a block inside (30 patches): the block makes the form factors need
/// shadow rays, and the closed box makes every row sum to 1.
const FURNACE: &str = "furnace:res=2:block=true";
/// The Cornell box at its coarsest but one (53 patches): coloured, open at the front.
const CORNELL_SMALL: &str = "cornell:res=2";
/// The Cornell box at its default resolution (560 patches).
const CORNELL: &str = "cornell";
/// The paper's scene (480 patches): heavy occlusion.
const MULTI_CUBES: &str = "multi-cubes";

/// The paper's second scene (3364 patches): high reflectivity, open to the sky.
const LABYRINTH: &str = "labyrinth";

/// The scenes whose fixtures [`fixture`] caches.
const SCENES: [&str; 5] = [FURNACE, CORNELL_SMALL, CORNELL, MULTI_CUBES, LABYRINTH];

/// Runs stop at e_rms ≤ 1e-9 and the test asserts 1e-8: a run that ends just short of the
/// target (at round-off) still passes, one that stalls does not.
const RMS_TARGET: &str = "rms=1e-9";
/// The asserted bound on e_rms at the end of a run.
const RMS_BOUND: Real = 1e-8;
/// Steps allowed, per patch, to reach [`RMS_TARGET`]: the default 20n is too short here
/// (Jacobi needs about 28n in the furnace and the small Cornell box).
const STEP_CAP: f64 = 400.0;

/// A scene's system, its stored form factors and the exact reference solution.
struct Fixture {
    system: LinearSystem,
    matrix: FormFactors,
    reference: ReferenceSolution,
}

impl Fixture {
    /// Loads `arg`, assembles its analytic form factors (default parameters) and solves it.
    fn build(arg: &str) -> Fixture {
        let scene = load_scene(arg).unwrap_or_else(|e| panic!("{arg}: {e}")).scene;
        let visibility = Visibility::new(&scene);
        let analysis = SceneAnalysis::new(&scene, &visibility);
        let spec = BackendSpec::parse("analytic").unwrap();
        let input = FormFactorInput { scene: &scene, visibility: visibility.clone(), analysis: &analysis };
        let backend = spec.build(input).unwrap();
        let params = ReferenceParams::default();
        let matrix = FormFactors::assemble(&backend, params.max_matrix_bytes).unwrap_or_else(|e| panic!("{arg}: {e}"));
        let system = LinearSystem::from_scene(&scene);
        let reference =
            ReferenceSolution::solve_matrix(&system, &matrix, params).unwrap_or_else(|e| panic!("{arg}: {e}"));
        Fixture { system, matrix, reference }
    }

    fn n(&self) -> usize {
        self.system.len()
    }

    /// Runs solver `name` on the stored form factors, watched by `observer` if any; an `rms=`
    /// rule is fed e_rms of the displayed B against the reference, after every step.
    fn run(&self, name: &str, rules: StopRules, observer: Option<&mut dyn Observer>) -> Run {
        let mut solver = solver_by_name(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let problem = Problem::new(&self.system, &self.matrix).unwrap();
        let mut monitor = |state: &State| Some(errors(&self.system, &self.reference, &state.radiosity).unwrap().e_rms);
        let mut executor = Executor::new(solver.as_mut(), rules).monitor(&mut monitor);
        if let Some(observer) = observer {
            executor = executor.add_observer(observer, ObserverMode::Always);
        }
        executor.run(&problem).unwrap_or_else(|e| panic!("{name}: {e}"))
    }
}

/// The fixture of `arg` (one of [`SCENES`]), built on first use and shared by every test.
fn fixture(arg: &str) -> &'static Fixture {
    static FIXTURES: [OnceLock<Fixture>; SCENES.len()] = [const { OnceLock::new() }; SCENES.len()];
    let slot = SCENES.iter().position(|s| *s == arg).unwrap_or_else(|| panic!("{arg} is not in SCENES"));
    FIXTURES[slot].get_or_init(|| Fixture::build(arg))
}

/// Runs every point and group solver on `scene` until e_rms ≤ 1e-9 and checks that each ends
/// within [`RMS_BOUND`]. A solver that panics does not hide the others: every failure is listed
/// before the test fails.
fn check_reaches_reference(scene: &str) {
    let fixture = fixture(scene);
    let mut failures = Vec::new();
    for &name in POINT_SOLVERS.iter().chain(&GROUP_SOLVERS).chain(&BEYOND_PAPER_SOLVERS).chain(&KRYLOV_SOLVERS) {
        let rules = StopRules { step_cap: STEP_CAP, ..StopRules::parse(RMS_TARGET).unwrap() };
        // The fixture is only read, so a panic cannot leave it half-updated.
        let attempt = panic::catch_unwind(AssertUnwindSafe(|| fixture.run(name, rules, None)));
        let Ok(run) = attempt else {
            failures.push(format!("{name} on {scene}: panicked (message above)"));
            continue;
        };
        let e_rms = errors(&fixture.system, &fixture.reference, &run.state.radiosity).unwrap().e_rms;
        // Written so that a NaN fails too.
        let reached = e_rms <= RMS_BOUND;
        if !reached {
            failures.push(format!(
                "{name} on {scene} (n = {}): e_rms {e_rms:.3e} after {} steps, {} columns; {}",
                fixture.n(),
                run.state.step,
                run.state.cost[Unit::Columns],
                run.termination
            ));
        }
    }
    assert!(failures.is_empty(), "solvers short of e_rms ≤ {RMS_BOUND:e}:\n{}", failures.join("\n"));
}

#[test]
fn every_solver_reaches_the_reference_in_the_furnace() {
    check_reaches_reference(FURNACE);
}

#[test]
fn every_solver_reaches_the_reference_in_a_small_cornell_box() {
    check_reaches_reference(CORNELL_SMALL);
}

#[test]
fn every_solver_reaches_the_reference_in_multi_cubes() {
    check_reaches_reference(MULTI_CUBES);
}

/// The state of a run when it first reached a column count.
struct Recorded {
    step: u64,
    columns: u64,
    radiosity: Vec<Real>,
}

/// Records B at each target column count; returns no error, so it feeds no rule.
struct ColumnRecorder {
    targets: Vec<u64>,
    recorded: Vec<Option<Recorded>>,
}

impl Observer for ColumnRecorder {
    fn observe_step(&mut self, state: &State, _figures: &Record) {
        for (target, slot) in self.targets.iter().zip(&mut self.recorded) {
            if slot.is_none() && state.cost[Unit::Columns] == *target {
                *slot = Some(Recorded {
                    step: state.step,
                    columns: state.cost[Unit::Columns],
                    radiosity: state.radiosity.clone(),
                });
            }
        }
    }
}

/// A table of every point solver on `scene` at n/4, n/2, n and 2n columns: e_rms, e_max and
/// the residual power of the displayed B, measured on the stored matrix whatever the solver
/// (so the residual column compares solvers on the same footing). No timings: the table is
/// deterministic.
fn convergence_table(scene: &str) -> String {
    let fixture = fixture(scene);
    let n = fixture.n() as u64;
    let targets = vec![n / 4, n / 2, n, 2 * n];
    let evaluator = Evaluator::new(&fixture.system, &fixture.matrix, &fixture.reference).unwrap();
    let mut table = ConvergenceTable::new().without_timings();
    for &name in POINT_SOLVERS.iter() {
        let mut recorder =
            ColumnRecorder { recorded: targets.iter().map(|_| None).collect(), targets: targets.clone() };
        let run = fixture.run(name, StopRules::parse("columns=2n").unwrap(), Some(&mut recorder));
        for (target, recorded) in targets.iter().zip(recorder.recorded) {
            let Some(r) = recorded else {
                panic!("{name} on {scene}: never at exactly {target} columns; {}", run.termination)
            };
            let m = evaluator.evaluate(&r.radiosity).unwrap();
            table.push(TableRow {
                solver: name.to_string(),
                step: r.step,
                cost: Cost::default().with(Unit::Columns, r.columns),
                e_rms: m.e_rms,
                e_max: m.e_max,
                residual: m.residual,
                bound: m.relative_bound,
                std_error: f64::NAN,
            });
        }
    }
    let mut out = format!("{scene}, n = {n}, analytic form factors; residual = R of the displayed B\n\n").into_bytes();
    table.write_markdown(&mut out).unwrap();
    String::from_utf8(out).unwrap()
}

#[test]
fn multi_cubes_convergence_table() {
    insta::assert_snapshot!("multi_cubes", convergence_table(MULTI_CUBES));
}

#[test]
fn cornell_convergence_table() {
    insta::assert_snapshot!("cornell", convergence_table(CORNELL));
}

/// Records the residual power of the displayed B every `every` steps.
struct ResidualRecorder<'a> {
    evaluator: Evaluator<'a>,
    every: u64,
    residuals: Vec<Real>,
}

impl Observer for ResidualRecorder<'_> {
    fn observe_step(&mut self, state: &State, _figures: &Record) {
        if state.step % self.every == 0 {
            self.residuals.push(self.evaluator.evaluate(&state.radiosity).unwrap().residual);
        }
    }
}

/// Every shooting solver's residual keeps falling: measured every n steps, it is below its
/// previous value until it reaches round-off. docs/design.md §4.4 records overshooting variants
/// that froze (a patch chosen again and again to shoot nothing) or cycled; either would show here
/// as a window without progress. (Over a shorter window, `relax-1.5` may rise for a while in
/// the furnace: over-relaxation does not make the residual norm monotone, only smaller in
/// the end.)
fn check_residual_keeps_falling(scene: &str) {
    let fixture = fixture(scene);
    let n = fixture.n() as u64;
    let mut stalls = Vec::new();
    let shooting = POINT_SOLVERS.iter().filter(|s| !["jacobi", "gauss-seidel", "sor-1.2"].contains(s));
    for &name in shooting.chain(&GROUP_SOLVERS).chain(&BEYOND_PAPER_SOLVERS) {
        let evaluator = Evaluator::new(&fixture.system, &fixture.matrix, &fixture.reference).unwrap();
        let mut recorder = ResidualRecorder { evaluator, every: n, residuals: Vec::new() };
        fixture.run(name, StopRules::parse("steps=12n").unwrap(), Some(&mut recorder));
        let r = &recorder.residuals;
        for k in 1..r.len() {
            // `r[k] >= r[k - 1]` would let a NaN through.
            let fell = r[k] < r[k - 1];
            if r[k - 1] > 1e-12 && !fell {
                stalls.push(format!(
                    "{name} on {scene}: R = {:.3e} after {:.3e}, at step {}",
                    r[k],
                    r[k - 1],
                    k as u64 * n
                ));
            }
        }
    }
    assert!(stalls.is_empty(), "residuals that did not fall:\n{}", stalls.join("\n"));
}

#[test]
fn shooting_residuals_keep_falling_in_multi_cubes() {
    check_residual_keeps_falling(MULTI_CUBES);
}

#[test]
fn shooting_residuals_keep_falling_in_the_furnace() {
    check_residual_keeps_falling(FURNACE);
}

/// Runs each of `names` on `scene` until `rule`, and returns the table of where they ended
/// (headed by `title`, no timings) and each one's e_rms.
fn end_table(scene: &str, names: &[&'static str], rule: &str, title: &str) -> (String, HashMap<&'static str, Real>) {
    let fixture = fixture(scene);
    let evaluator = Evaluator::new(&fixture.system, &fixture.matrix, &fixture.reference).unwrap();
    let mut table = ConvergenceTable::new().without_timings();
    let mut e_rms = HashMap::new();
    for &name in names {
        let run = fixture.run(name, StopRules::parse(rule).unwrap(), None);
        let m = evaluator.evaluate(&run.state.radiosity).unwrap();
        e_rms.insert(name, m.e_rms);
        table.push(TableRow {
            solver: name.to_string(),
            step: run.state.step,
            cost: Cost::default()
                .with(Unit::Columns, run.state.cost[Unit::Columns])
                .with(Unit::Products, run.state.cost[Unit::Products]),
            e_rms: m.e_rms,
            e_max: m.e_max,
            residual: m.residual,
            bound: m.relative_bound,
            std_error: f64::NAN,
        });
    }
    let mut out = format!("{title}\n\n").into_bytes();
    table.write_markdown(&mut out).unwrap();
    (String::from_utf8(out).unwrap(), e_rms)
}

/// The paper's claims on multi-cubes (its §5, Fig. 1), at n shooting steps, with group steps
/// every 10 shots: group acceleration helps PR and Xu, storing every column helps more, and
/// Xu beats PR. An independent prototype with centroid form factors gave, in this order,
/// 4.7e-3, 3.3e-3, 9e-4 (`pr-g30-m480`), 1.5e-3, 4.3e-4 and 4.2e-5.
#[test]
fn the_papers_claims_on_multi_cubes() {
    let names = ["pr", "pr-g30:f=10", "pr-g30-m480:f=10", "xu", "xu-g30:f=10", "xu-g30-m480:f=10"];
    let title = "multi-cubes, n = 480 shooting steps, analytic form factors";
    let (table, e_rms) = end_table(MULTI_CUBES, &names, "steps=n", title);
    insta::assert_snapshot!("papers_claims_multi_cubes", table);
    for (better, worse) in [
        ("pr-g30:f=10", "pr"),
        ("pr-g30-m480:f=10", "pr-g30:f=10"),
        ("xu", "pr"),
        ("xu-g30:f=10", "xu"),
        ("xu-g30-m480:f=10", "xu-g30:f=10"),
    ] {
        assert!(
            e_rms[better] < e_rms[worse],
            "{better} ({:.3e}) should beat {worse} ({:.3e})",
            e_rms[better],
            e_rms[worse]
        );
    }
}

/// The paper's claim on the labyrinth (its §5, Fig. 2): group-accelerated Xu with a memory of
/// 500 columns gives a nearly converged solution within n steps; the issue asks for e_rms at
/// most 1e-2 within n columns. PR and Xu at n columns are recorded beside it.
#[test]
fn the_papers_claim_on_the_labyrinth() {
    let title = format!("labyrinth, n = {} columns, analytic form factors", fixture(LABYRINTH).n());
    let (table, e_rms) = end_table(LABYRINTH, &["pr", "xu", "xu-g50-m500:f=10"], "columns=n", &title);
    insta::assert_snapshot!("papers_claim_labyrinth", table);
    assert!(e_rms["xu-g50-m500:f=10"] <= 1e-2, "{e_rms:?}");
    assert!(e_rms["xu-g50-m500:f=10"] < e_rms["xu"] && e_rms["xu"] < e_rms["pr"], "{e_rms:?}");
}
