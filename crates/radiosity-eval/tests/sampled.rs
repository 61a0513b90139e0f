//! Solvers that sample transport in the lab: the lab gives their problem its transport
//! sampler (the stored matrix sampled exactly here), built only for them; every step is
//! recorded with its rays and the solver's standard error; a comparison that mixes them with a
//! deterministic solver gives one table and one set of plots, with a log–log rays plot of its
//! own; a plot or table names whom it leaves out, no plot is drawn against a unit nobody spent,
//! and each solver's cost is counted in its own unit, named.
//!
//! The solver is this file's own, [`DirectByRays`]: direct lighting `E + ρ F E` estimated by
//! rays from the emitters, in two replicates, each step adding rays to both.

use radiosity_core::Real;
use radiosity_eval::{
    Comparison, Lab, LabError, LabOptions, NoProgress, Progress, RecordPlan, ReferenceKind, Transport,
};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::Unit;
use radiosity_solvers::{
    Problem, Record, Sequence, Solver, SolverError, SolverRegistry, StandardError, State, StepKind, StopRules,
};
use std::sync::Mutex;

/// Direct lighting by rays: each step casts `rays` rays from every emitting patch in each of
/// two replicates (independent streams), and each replicate's estimate of `E + ρ F E` is `E`
/// plus `ρ` times the power landed on each patch over its area, averaged over the rays cast
/// so far. Unbiased for the system the sampler samples; its standard error is the spread of
/// the two replicates.
struct DirectByRays {
    rays: usize,
    seed: u64,
    /// Per replicate, the power landed on each patch and channel over its area, summed over
    /// every step (divided by the steps taken, it is the estimate of `F E`).
    landed: [Vec<Real>; 2],
    error: Option<StandardError>,
}

impl DirectByRays {
    fn new(rays: usize, seed: u64) -> DirectByRays {
        DirectByRays { rays, seed, landed: [Vec::new(), Vec::new()], error: None }
    }
}

impl Solver for DirectByRays {
    fn name(&self) -> String {
        "direct-rays".into()
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let system = problem.system();
        let (n, k) = (problem.n(), problem.channels());
        let (areas, emission) = (system.areas(), system.emissions());
        let step = state.step;
        let (rays, seed, name) = (self.rays, self.seed, self.name());
        let emitters: Vec<usize> = (0..n).filter(|&j| emission[j * k..(j + 1) * k].iter().any(|&e| e > 0.0)).collect();
        for (r, landed) in self.landed.iter_mut().enumerate() {
            landed.resize(n * k, 0.0);
            problem.cast(&name, |cast| {
                for &j in &emitters {
                    let mut stream = Sequence::Random.stream(seed, [r as u64, step, j as u64]);
                    let share = areas[j] * cast.ray_weight(j) / rays as Real;
                    for _ in 0..rays {
                        if let Some(i) = cast.cast(j, stream.next_point()) {
                            for c in 0..k {
                                landed[i * k + c] += share * emission[j * k + c] / areas[i];
                            }
                        }
                    }
                }
            })?;
        }
        let steps = (step + 1) as Real;
        let estimate = |landed: &[Real]| -> Vec<Real> {
            (0..n * k).map(|idx| emission[idx] + system.reflectivities()[idx] * landed[idx] / steps).collect()
        };
        let replicates = [estimate(&self.landed[0]), estimate(&self.landed[1])];
        let views: Vec<&[Real]> = replicates.iter().map(Vec::as_slice).collect();
        self.error = Some(StandardError::of_replicates(&views, &mut state.radiosity));
        state.unshot.fill(0.0);
        Ok(Record::new())
    }

    fn residual_power(&self, _problem: &Problem<'_>, _state: &State) -> Option<Real> {
        None
    }

    fn standard_error(&self, _problem: &Problem<'_>, _state: &State) -> Option<StandardError> {
        self.error.clone()
    }

    fn step_kind(&self) -> StepKind {
        StepKind::Sampled
    }
}

/// A lab on `scene` over the analytic backend with a `matrix` reference and `transport`.
fn lab(scene: &PreparedScene, reference: ReferenceKind, transport: Transport) -> Result<Lab<'_>, LabError> {
    let options = LabOptions::default().with_reference(reference).with_transport(transport);
    Lab::new(scene, &BackendSpec::parse("analytic").unwrap(), options, &NoProgress)
}

/// `E + ρ F E` over the lab's stored matrix: what [`DirectByRays`] estimates without bias.
fn direct_lighting(lab: &Lab<'_>) -> Vec<Real> {
    let (system, matrix) = (lab.system(), lab.matrix().unwrap());
    let (n, k) = (lab.n(), system.channels().count());
    let (e, rho) = (system.emissions(), system.reflectivities());
    (0..n * k)
        .map(|idx| {
            let (i, c) = (idx / k, idx % k);
            e[idx] + rho[idx] * (0..n).map(|j| matrix.get(i, j) * e[j * k + c]).sum::<Real>()
        })
        .collect()
}

/// The units the progress bars were given.
#[derive(Default)]
struct Units(Mutex<Vec<String>>);

impl Progress for Units {
    fn begin(&self, _task: &str, _total: u64, unit: &str) {
        self.0.lock().unwrap().push(unit.to_string());
    }
}

#[test]
fn a_sampled_run_records_every_step_with_its_rays_and_standard_error() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let lab = lab(&scene, ReferenceKind::Matrix, Transport::Matrix).unwrap();
    let units = Units::default();
    let rules = StopRules::parse("rays=1e5").unwrap();
    let o = lab.run(&mut DirectByRays::new(2000, 1), &rules, &RecordPlan::default(), &units).unwrap();
    assert_eq!(*units.0.lock().unwrap(), ["rays"], "a rays= rule counts the progress in rays");
    // Every step recorded, each with the rays so far; the first point is the initial state.
    let steps = o.state.step;
    assert!(o.termination.to_string().contains("rays"), "{}", o.termination);
    assert_eq!(o.points.len() as u64, steps + 1);
    assert_eq!(o.rows.len() as u64, steps + 1);
    assert!(o.points.windows(2).all(|w| w[1].cost[Unit::Rays] > w[0].cost[Unit::Rays]), "rays grow at every step");
    assert_eq!(o.points.last().unwrap().cost[Unit::Rays], o.state.cost[Unit::Rays]);
    assert!(
        o.state.cost[Unit::Rays] >= 100_000 && o.state.cost[Unit::Columns] == 0,
        "{} rays, {} columns",
        o.state.cost[Unit::Rays],
        o.state.cost[Unit::Columns]
    );
    // The initial state has no standard error; every step's has its two replicates'.
    assert!(o.points[0].std_error.is_nan());
    assert!(o.points[1..].iter().all(|p| p.std_error.is_finite() && p.std_error > 0.0));
    assert_eq!(o.last.replicates, Some(2));
    let last = o.last.standard_error.unwrap();
    assert_eq!(last, o.points.last().unwrap().std_error);
    assert_eq!(last, o.rows.last().unwrap().std_error);
    let spread = o.standard_error.as_ref().unwrap();
    assert_eq!(last, spread.relative_rms(lab.system(), &o.state.radiosity));
    // No certified bound of the solver's own at any step (the final one is F's, the matrix being kept).
    assert!(o.points.iter().all(|p| p.bound.is_nan()));
    // The rays sampled the lab's stored matrix: the estimate is within 3 of its standard
    // errors of `E + ρ F E` over that matrix. The squared summaries of the error and of the
    // standard error have the same expectation, each a sum over the lit patches, so their
    // ratio is near 1; 3 leaves room for the two-replicate spread, with a fixed seed.
    let exact = direct_lighting(&lab);
    let error = radiosity_eval::errors_against(lab.system(), &exact, &o.state.radiosity).unwrap().e_rms;
    assert!(error <= 3.0 * last, "e_rms against E + ρ F E {error:e}, standard error {last:e}");
    // A steps= rule counts the progress in steps.
    let rules = StopRules::parse("steps=2").unwrap();
    let units = Units::default();
    lab.run(&mut DirectByRays::new(100, 1), &rules, &RecordPlan::default(), &units).unwrap();
    assert_eq!(*units.0.lock().unwrap(), ["steps"]);
}

#[test]
fn the_standard_error_falls_as_one_over_the_root_of_the_rays() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let lab = lab(&scene, ReferenceKind::Matrix, Transport::Matrix).unwrap();
    let rules = StopRules::parse("steps=16").unwrap();
    let o = lab.run(&mut DirectByRays::new(1000, 3), &rules, &RecordPlan::default(), &NoProgress).unwrap();
    // 16 times the rays of step 1: a standard error 4 times smaller. The two-replicate
    // summaries, each over the lit patches, spread by some tens of percent; the ratio is
    // asked within a factor 1.6 of 4.
    let (first, last) = (o.points[1].std_error, o.points[16].std_error);
    let ratio = first / last;
    assert!((2.5..6.4).contains(&ratio), "standard error {first:e} after 1 step, {last:e} after 16: ratio {ratio}");
}

#[test]
fn the_sampler_is_built_only_for_runs_that_sample_transport() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    // No reference, so no stored matrix to sample.
    let lab = lab(&scene, ReferenceKind::None, Transport::Matrix).unwrap();
    let registry = SolverRegistry::builtin();
    let rules = StopRules::parse("columns=n,steps=2n").unwrap();
    lab.run(registry.build("pr").unwrap().as_mut(), &rules, &RecordPlan::default(), &NoProgress).unwrap();
    let sampled = lab.run(&mut DirectByRays::new(10, 1), &rules, &RecordPlan::default(), &NoProgress);
    let message = sampled.expect_err("no matrix to sample").to_string();
    assert!(message.contains("--transport matrix") && message.contains("keeps none"), "{message}");
    assert!(!message.contains('\n'), "one sentence: {message}");
    // A comparison without a solver that casts rays builds no sampler; one with refuses
    // before anything runs.
    let comparison = lab.compare(vec![registry.build("pr").unwrap()], &rules, &NoProgress).unwrap();
    assert!(comparison.transport.is_none());
    let solvers: Vec<Box<dyn Solver>> = vec![registry.build("pr").unwrap(), Box::new(DirectByRays::new(10, 1))];
    assert!(lab.compare(solvers, &rules, &NoProgress).is_err());
    // With a matrix reference the lab keeps the matrix for the rays, even without residuals.
    let options = LabOptions::default()
        .with_reference(ReferenceKind::Matrix)
        .with_transport(Transport::Matrix)
        .with_residuals(false);
    let kept = Lab::new(&scene, &BackendSpec::parse("analytic").unwrap(), options, &NoProgress).unwrap();
    assert!(kept.matrix().is_some());
    let built = kept.transport_sampler().unwrap();
    assert_eq!(built.sampler.patch_count(), kept.n());
    assert!(built.cost().constant, "a stored matrix's ray is an alias draw");
}

#[test]
fn a_comparison_mixing_deterministic_and_sampled_solvers_gives_one_table_and_one_set_of_plots() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let lab = lab(&scene, ReferenceKind::Matrix, Transport::Matrix).unwrap();
    let solvers: Vec<Box<dyn Solver>> =
        vec![SolverRegistry::builtin().build("pr").unwrap(), Box::new(DirectByRays::new(500, 2))];
    // Each solver stops on the rule that counts what it spends.
    let rules = StopRules::parse("columns=n,rays=2e4").unwrap();
    let comparison: Comparison = lab.compare(solvers, &rules, &NoProgress).unwrap();
    let (pr, rays) = (&comparison.outcomes[0], &comparison.outcomes[1]);
    assert!(pr.termination.to_string().contains("columns") && pr.state.cost[Unit::Rays] == 0, "{}", pr.termination);
    assert!(
        rays.termination.to_string().contains("rays") && rays.state.cost[Unit::Columns] == 0,
        "{}",
        rays.termination
    );
    assert!(comparison.transport.as_deref().is_some_and(|t| t.starts_with("`matrix`")), "{:?}", comparison.transport);
    let dir = std::env::temp_dir().join(format!("radiosity-eval-sampled-{}", std::process::id()));
    let written = comparison.write(&dir).unwrap();
    let names: Vec<String> =
        written.files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
    for stem in ["e_rms-steps", "e_rms-columns", "e_rms-rays", "e_rms-seconds"] {
        assert!(names.contains(&format!("{stem}.svg")) && names.contains(&format!("{stem}.png")), "{names:?}");
    }
    // One table: both solvers' rows, with the rays and standard errors.
    let csv = std::fs::read_to_string(dir.join("convergence.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert!(header.contains(&"rays") && header.contains(&"std_error"), "{header:?}");
    let solver_rows = |name: &str| csv.lines().filter(|l| l.starts_with(&format!("{name},"))).count();
    assert!(solver_rows("pr") > 1 && solver_rows("direct-rays") > 1, "{csv}");
    // The seconds plot holds both; the rays plot the solver that cast rays; the columns plot
    // the one that computed columns.
    let svg = |stem: &str| std::fs::read_to_string(dir.join(format!("{stem}.svg"))).unwrap();
    // plotters writes each text on a line of its own.
    let holds = |text: &str, label: &str| text.contains(&format!(">\n{label}\n</text>"));
    assert!(holds(&svg("e_rms-seconds"), "pr") && holds(&svg("e_rms-seconds"), "direct-rays"));
    assert!(holds(&svg("e_rms-rays"), "direct-rays") && !holds(&svg("e_rms-rays"), "pr"));
    assert!(holds(&svg("e_rms-columns"), "pr") && !holds(&svg("e_rms-columns"), "direct-rays"));
    assert!(holds(&svg("e_rms-rays"), radiosity_eval::BAND_LABEL), "the band is named in the legend");
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("## Error bars: certified bounds and standard errors"), "{report}");
    let row = report.lines().find(|l| l.starts_with("| `direct-rays` |") && l.contains("(2)")).unwrap();
    assert!(row.contains(&rays.state.cost[Unit::Rays].to_string()), "{row}");
    // The terminal summary gives the rays and the standard error beside the bound.
    let summary = comparison.summary();
    assert!(summary.lines().next().unwrap().contains("std error"), "{summary}");
    // The rays plot is log–log, with the slope a Monte Carlo error falls at drawn and named.
    assert!(holds(&svg("e_rms-rays"), "rays cast (log scale)") && holds(&svg("e_rms-rays"), "slope −½"));
    assert!(holds(&svg("e_rms-columns"), "columns computed") && !holds(&svg("e_rms-columns"), "slope −½"));
    // Whoever a plot or the table at n columns leaves out is named, with why and what it
    // spent instead, in its own unit; under the plot and in the report.
    let (pr_cost, rays_cost) = (pr.state.cost[Unit::Columns], rays.state.cost[Unit::Rays]);
    let no_columns = format!("`direct-rays` (no columns computed; its cost: {} rays cast)", grouped(rays_cost));
    let no_rays = format!("`pr` (no rays cast; its cost: {pr_cost} columns computed)");
    let under = |stem: &str| svg_text(&svg(stem));
    assert!(under("e_rms-columns").contains(&format!("Left out: {}.", no_columns.replace('`', ""))), "{no_columns}");
    assert!(
        under("e_rms-rays").contains(&format!("Left out: {}.", no_rays.replace('`', ""))),
        "{}",
        under("e_rms-rays")
    );
    assert!(!under("e_rms-steps").contains("Left out") && !under("e_rms-seconds").contains("Left out"));
    let section = |head: &str| report.split(head).nth(1).unwrap().split("\n## ").next().unwrap().to_string();
    let at_n = section("## e_rms at n/4, n/2, n and 2n columns");
    assert!(at_n.contains("| `pr` |") && !at_n.contains("| `direct-rays` |"), "{at_n}");
    assert!(at_n.contains(&format!("Left out: {no_columns}.")), "{at_n}");
    let plots = section("## Plots");
    for (stem, left) in [("e_rms-columns", &no_columns), ("e_rms-rays", &no_rays)] {
        let after = plots.split(&format!("({stem}.png)")).nth(1).unwrap();
        assert!(after.trim_start().starts_with(&format!("Left out: {left}.")), "{stem}: {plots}");
    }
    // The summary says at n columns what a solver without columns has there.
    let row = summary.lines().find(|l| l.starts_with("direct-rays ")).unwrap();
    assert!(row.contains(" no columns "), "{summary}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `k` with thousands separators, as reports write counts.
fn grouped(k: u64) -> String {
    let digits = k.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// The texts of an SVG, trimmed, joined by spaces (a wrapped note reads as one).
fn svg_text(svg: &str) -> String {
    let texts: Vec<&str> =
        svg.split("<text").skip(1).filter_map(|t| Some(t.split_once('>')?.1.split_once("</text>")?.0.trim())).collect();
    texts.join(" ")
}

#[test]
fn a_comparison_where_no_solver_computes_columns_draws_no_columns_plot_and_says_so() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let lab = lab(&scene, ReferenceKind::Matrix, Transport::Matrix).unwrap();
    let rules = StopRules::parse("rays=2e4").unwrap();
    let comparison = lab.compare(vec![Box::new(DirectByRays::new(500, 3))], &rules, &NoProgress).unwrap();
    let dir = std::env::temp_dir().join(format!("radiosity-eval-no-columns-{}", std::process::id()));
    let written = comparison.write(&dir).unwrap();
    let names: Vec<String> =
        written.files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
    // Steps, rays and seconds; no plot against a unit nobody spent.
    for stem in ["e_rms-steps", "e_rms-rays", "e_rms-seconds"] {
        assert!(names.contains(&format!("{stem}.png")), "{names:?}");
    }
    assert!(!names.iter().any(|n| n.starts_with("e_rms-columns")), "{names:?}");
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("No plot against columns computed: no solver computed one."), "{report}");
    assert!(!report.contains("e_rms-columns"), "{report}");
    // The table at n columns has no row, and says whom it leaves out.
    let at_n = report.split("## e_rms at n/4, n/2, n and 2n columns").nth(1).unwrap().split("\n## ").next().unwrap();
    assert!(at_n.starts_with("\n\nLeft out: `direct-rays` (no columns computed"), "{at_n:?}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn each_solvers_cost_is_counted_in_its_own_unit_and_named() {
    // A deterministic and a stochastic solver both reach e_rms 1e-3: the summary gives the
    // columns of one and the rays of the other, each named, never a bare count.
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let lab = lab(&scene, ReferenceKind::Matrix, Transport::Matrix).unwrap();
    let registry = SolverRegistry::builtin();
    let solvers = vec![registry.build("pr").unwrap(), registry.build("stochastic-jacobi").unwrap()];
    let rules = StopRules::parse("columns=4n,rays=1.5e6").unwrap();
    let comparison = lab.compare(solvers, &rules, &NoProgress).unwrap();
    let summary = comparison.summary();
    assert!(summary.lines().next().unwrap().contains("1e-3 at seconds"), "{summary}");
    for (solver, unit) in [("pr", Unit::Columns), ("stochastic-jacobi", Unit::Rays)] {
        let o = comparison.outcome(solver).unwrap();
        let reached = comparison.reached(o, 1e-3).unwrap_or_else(|| panic!("{solver} reaches 1e-3: {summary}"));
        let row = summary.lines().find(|l| l.starts_with(&format!("{solver} "))).unwrap();
        // The two words before the seconds, the row's last.
        let words: Vec<&str> = row.split_whitespace().collect();
        let field = words[words.len() - 3..words.len() - 1].join(" ");
        assert_eq!(field, format!("{} {}", grouped(reached.cost[unit]), unit.name()), "{summary}");
    }
}

#[test]
fn stochastic_jacobi_casts_its_rays_in_the_scene_by_default() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let lab = Lab::new(&scene, &BackendSpec::parse("analytic").unwrap(), LabOptions::default(), &NoProgress).unwrap();
    assert_eq!(lab.transport(), Transport::Scene);
    let registry = SolverRegistry::builtin();
    let solvers = || vec![registry.build("pr").unwrap(), registry.build("stochastic-jacobi:seed=2").unwrap()];
    // Rules that only count columns would never stop it: refused before anything runs.
    let only_columns = StopRules::parse("columns=n").unwrap();
    let message = lab.compare(solvers(), &only_columns, &NoProgress).unwrap_err().to_string();
    assert!(message.starts_with("stochastic-jacobi") && message.contains("rays="), "{message}");
    let rules = StopRules::parse("columns=n,rays=2e4").unwrap();
    let comparison = lab.compare(solvers(), &rules, &NoProgress).unwrap();
    let transport = comparison.transport.as_deref().unwrap();
    assert!(transport.starts_with("`scene`, one ray through"), "{transport}");
    // The report says that their e_rms holds the backend's own distance from the kernel.
    assert!(transport.contains("includes that backend's own distance from the exact kernel"), "{transport}");
    assert!(comparison.report_markdown(&[]).contains("backend's own distance"));
    let o = &comparison.outcomes[1];
    assert!(
        o.state.cost[Unit::Rays] >= 20_000 && o.state.cost[Unit::Columns] == 0,
        "{} rays, {} columns",
        o.state.cost[Unit::Rays],
        o.state.cost[Unit::Columns]
    );
    assert_eq!(o.last.replicates, Some(4));
    let (e_rms, spread) = (o.last.e_rms.unwrap(), o.last.standard_error.unwrap());
    // The rays see the exact geometry, the reference the analytic backend's F: e_rms holds
    // both the noise and their difference, which on 53 patches is far below 1.
    assert!(e_rms < 0.5 && spread > 0.0 && spread < 0.5, "e_rms {e_rms}, standard error {spread}");
}

/// The mean over `seeds` runs of `name:seed=s` in `lab` under `rules`, the standard error of
/// that mean (the spread over seeds), and the runs' mean e_rms² over their mean standard
/// error² against `exact` with the fraction of runs whose e_rms lies within 2 standard errors.
fn over_seeds(
    lab: &Lab<'_>,
    name: &str,
    rules: &str,
    seeds: u64,
    exact: &[Real],
) -> (Vec<Real>, Vec<Real>, Real, Real) {
    let registry = SolverRegistry::builtin();
    let rules = StopRules::parse(rules).unwrap();
    let (mut runs, mut e2, mut s2, mut within) = (Vec::new(), 0.0, 0.0, 0);
    for seed in 1..=seeds {
        let mut solver = registry.build(&format!("{name}:seed={seed}")).unwrap();
        let o = lab.run(solver.as_mut(), &rules, &RecordPlan::errors_only(), &NoProgress).unwrap();
        let e_rms = radiosity_eval::errors_against(lab.system(), exact, &o.state.radiosity).unwrap().e_rms;
        let spread = o.last.standard_error.unwrap();
        (e2, s2) = (e2 + e_rms * e_rms, s2 + spread * spread);
        within += usize::from(e_rms <= 2.0 * spread);
        runs.push(o.state.radiosity);
    }
    let slices: Vec<&[Real]> = runs.iter().map(Vec::as_slice).collect();
    let mut mean = vec![0.0; exact.len()];
    let se = StandardError::of_replicates(&slices, &mut mean);
    (mean, se.values, e2 / s2, within as Real / seeds as Real)
}

#[test]
fn at_a_small_budget_stochastic_jacobi_is_unbiased_in_a_scene_and_its_bar_covers() {
    // A closed box of one material, rays in the scene: B = E / (1 − ρ) = 2 on every patch
    // whatever the form factors. At ρ = 0.5 the incremental series takes about 2 batches of
    // rays; a budget of 1.5 batches once cut it after its second iteration, a bias of 1/8 of
    // B shared by every replicate, with a standard error of a few percent.
    let scene = PreparedScene::load("furnace:res=3:rho=0.5").unwrap();
    let lab = lab(&scene, ReferenceKind::None, Transport::Scene).unwrap();
    let exact = vec![2.0; lab.n()];
    let (mean, se, ratio, within) = over_seeds(&lab, "stochastic-jacobi:batch=2000", "rays=3000", 24, &exact);
    for (idx, (m, s)) in mean.iter().zip(&se).enumerate() {
        assert!((m - 2.0).abs() <= 4.0 * s, "patch {idx}: mean {m} against 2, standard error {s}");
    }
    // The bar: mean e_rms² over mean standard error² near 1 (each a mean over 24 seeds of
    // sums over 54 patches), and about t_coverage_of_two(4) = 0.86 of the runs within 2.
    assert!((0.6..1.6).contains(&ratio), "mean e_rms² over mean standard error² {ratio}");
    assert!(within >= 0.6, "{within} of the runs within 2 standard errors");
}

#[test]
fn global_lines_through_the_scene_are_unbiased_in_a_closed_furnace() {
    // lines=global over SceneTransport, rays in a closed box: B = E / (1 − ρ) = 2. Per patch
    // the mean over seeds lies within 4 of its standard errors; the area-weighted mean over
    // patches, whose standard error is a fraction of any patch's, within 4 of its own, which
    // catches a bias of 1% of B in the lines' weight (its standard error is below 0.25%).
    let scene = PreparedScene::load("furnace:res=3:rho=0.5").unwrap();
    let lab = lab(&scene, ReferenceKind::None, Transport::Scene).unwrap();
    let exact = vec![2.0; lab.n()];
    let seeds = 24;
    let registry = SolverRegistry::builtin();
    let rules = StopRules::parse("steps=12").unwrap();
    let areas = lab.system().areas();
    let total: Real = areas.iter().sum();
    let mut levels = Vec::new();
    let mut runs = Vec::new();
    for seed in 1..=seeds {
        let mut solver = registry.build(&format!("stochastic-jacobi:lines=global:seed={seed}")).unwrap();
        let o = lab.run(solver.as_mut(), &rules, &RecordPlan::errors_only(), &NoProgress).unwrap();
        levels.push(o.state.radiosity.iter().zip(areas).map(|(b, a)| a * b).sum::<Real>() / total);
        runs.push(o.state.radiosity);
    }
    let slices: Vec<&[Real]> = runs.iter().map(Vec::as_slice).collect();
    let mut mean = vec![0.0; exact.len()];
    let se = StandardError::of_replicates(&slices, &mut mean);
    for (idx, (m, s)) in mean.iter().zip(&se.values).enumerate() {
        assert!((m - 2.0).abs() <= 4.0 * s, "patch {idx}: mean {m} against 2, standard error {s}");
    }
    let level: Vec<&[Real]> = levels.chunks(1).collect();
    let mut mean_level = [0.0];
    let level_se = StandardError::of_replicates(&level, &mut mean_level).values[0];
    assert!(level_se < 2.5e-3 * 2.0, "no power: the level's standard error is {level_se}");
    assert!((mean_level[0] - 2.0).abs() <= 4.0 * level_se, "level {} ± {level_se} against 2", mean_level[0]);
}

#[test]
fn a_stochastic_run_shows_no_bound_from_f_and_no_band_on_a_bound_axis() {
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let registry = SolverRegistry::builtin();
    let rules = StopRules::parse("columns=n,rays=2e4").unwrap();
    let solvers = || vec![registry.build("pr").unwrap(), registry.build("stochastic-jacobi:seed=2").unwrap()];
    // F is kept: the deterministic run shows F's bound, the stochastic one none, and the
    // report's row gives its standard error and its unshot power instead.
    let kept = lab(&scene, ReferenceKind::Matrix, Transport::Matrix).unwrap();
    let comparison = kept.compare(solvers(), &rules, &NoProgress).unwrap();
    let (pr, sj) = (&comparison.outcomes[0], &comparison.outcomes[1]);
    assert!(pr.last.bound.is_some() && sj.last.bound.is_none(), "{:?} {:?}", pr.last.bound, sj.last.bound);
    assert!(!sj.rows.is_empty() && sj.rows.iter().all(|r| r.bound.is_nan()), "a bound in the stochastic run's rows");
    assert!(pr.rows.iter().all(|r| r.bound.is_finite()));
    assert!(sj.last.standard_error.is_some());
    let unshot = sj.record.real("unshot_power").unwrap();
    assert!((0.0..=1e-4).contains(&unshot), "unshot power {unshot} after the incremental series");
    let dir = std::env::temp_dir().join(format!("radiosity-eval-bars-{}", std::process::id()));
    comparison.write(&dir).unwrap();
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("| standard error (replicates) | unshot power | rays |"), "{report}");
    let row = report.lines().find(|l| l.starts_with("| `stochastic-jacobi:seed=2` |")).unwrap();
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    assert_eq!(cells[3], "—", "no certified bound: {row}");
    std::fs::remove_dir_all(&dir).ok();
    // Without a reference the plots show certified bounds: no standard-error band on them.
    let blind = lab(&scene, ReferenceKind::None, Transport::Scene).unwrap();
    let comparison = blind.compare(solvers(), &rules, &NoProgress).unwrap();
    let written = comparison.write(&dir).unwrap();
    let svgs: Vec<_> = written.files.iter().filter(|f| f.extension().is_some_and(|e| e == "svg")).collect();
    assert!(!svgs.is_empty(), "{:?}", written.files);
    for svg in svgs {
        let text = std::fs::read_to_string(svg).unwrap();
        assert!(!text.contains(radiosity_eval::BAND_LABEL), "a band on {}", svg.display());
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn without_a_reference_a_stochastic_run_is_named_as_left_out_of_every_plot_of_bounds() {
    // A run that samples transport has no certified bound: with `--reference none` every plot
    // shows bounds, so it has nothing on any of them, and each says so.
    let scene = PreparedScene::load("cornell:res=2").unwrap();
    let lab = lab(&scene, ReferenceKind::None, Transport::Scene).unwrap();
    let registry = SolverRegistry::builtin();
    let solvers = vec![registry.build("pr").unwrap(), registry.build("stochastic-jacobi").unwrap()];
    let comparison = lab.compare(solvers, &StopRules::parse("columns=n,rays=2e4").unwrap(), &NoProgress).unwrap();
    let dir = std::env::temp_dir().join(format!("radiosity-eval-sampled-none-{}", std::process::id()));
    let written = comparison.write(&dir).unwrap();
    let names: Vec<String> =
        written.files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
    // Nothing to draw against rays: no plot.
    assert!(!names.iter().any(|n| n.starts_with("bound-rays")), "{names:?}");
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for stem in ["bound-steps", "bound-seconds"] {
        let svg = std::fs::read_to_string(dir.join(format!("{stem}.svg"))).unwrap();
        assert!(svg_text(&svg).contains("Left out: stochastic-jacobi (no certified bound to show)."), "{stem}");
        let after = report.split(&format!("({stem}.png)")).nth(1).unwrap();
        assert!(after.trim_start().starts_with("Left out: `stochastic-jacobi` (no certified bound to show)."));
    }
    std::fs::remove_dir_all(&dir).ok();
}
