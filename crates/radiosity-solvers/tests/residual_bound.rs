//! The solvers' bounds on the residual of their displayed radiosity
//! ([`radiosity_solvers::ResidualBound`]), checked against the exact residual after every step.

use super::{assert_unshot_is_the_residual, bad_group};
use radiosity_core::{Channels, DenseColumns, LinearSystem, Real};
use radiosity_solvers::*;

/// A deterministic value in `[0, 1)` from `seed` (a 64-bit mix).
fn unit(seed: u64) -> Real {
    let mut z = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 31)) as Real / 2f64.powi(64)
}

/// An RGB system of `n` patches with exact reciprocity, `F_ij = G_ij / A_i` for a symmetric
/// random `G ≥ 0` (diagonal `diagonal` times a random weight), scaled so that the largest row
/// sums to `row`; reflectivities from `rho(idx)`, patches `i % 3 == 1` emitting.
fn reciprocal(
    n: usize,
    seed: u64,
    diagonal: Real,
    row: Real,
    rho: impl Fn(usize) -> Real,
) -> (LinearSystem, DenseColumns) {
    let area: Vec<Real> = (0..n).map(|i| 0.5 + 2.0 * unit(seed + i as u64)).collect();
    let g = |i: usize, j: usize| {
        let (a, b) = (i.min(j) as u64, i.max(j) as u64);
        let w = unit(seed * 1000 + a * 37 + b * 101);
        if i == j { diagonal * w } else { w * w }
    };
    let max_row = (0..n).map(|i| (0..n).map(|j| g(i, j)).sum::<Real>() / area[i]).fold(0.0, Real::max);
    let f =
        DenseColumns::from_fn(n, |i, j| row * g(i, j) / area[i] / max_row).with_measured_reciprocity(&area).unwrap();
    let rho: Vec<Real> = (0..3 * n).map(rho).collect();
    let e: Vec<Real> = (0..3 * n).map(|idx| if (idx / 3) % 3 == 1 { 1.0 + (idx % 3) as Real } else { 0.0 }).collect();
    (LinearSystem::new(Channels::Rgb, area, rho, e).unwrap(), f)
}

/// A closed reciprocal enclosure of 10 planar patches (rows sum to at most 1, the largest to
/// 1), reflectivities spread over `[0, 0.95]`.
fn enclosure() -> (LinearSystem, DenseColumns) {
    reciprocal(10, 7, 0.0, 1.0, |idx| 0.95 * unit(500 + idx as u64))
}

/// The enclosure with patch 0 alone emitting: gathering's first steps then change nothing
/// but what the emitter sent, which a bound must still count.
fn lamp() -> (LinearSystem, DenseColumns) {
    let (system, f) = enclosure();
    let e: Vec<Real> = (0..30).map(|idx| if idx < 3 { 1.0 + idx as Real } else { 0.0 }).collect();
    (LinearSystem::new(Channels::Rgb, system.areas().to_vec(), system.reflectivities().to_vec(), e).unwrap(), f)
}

/// 9 patches that see themselves (`F_ii > 0`), rows summing to at most 1, reflectivities 0.99
/// (red), 0.999 (green) and spread over `[0.5, 0.95]` (blue).
fn concave() -> (LinearSystem, DenseColumns) {
    reciprocal(9, 11, 3.0, 1.0, |idx| match idx % 3 {
        0 => 0.99,
        1 => 0.999,
        _ => 0.5 + 0.45 * unit(900 + idx as u64),
    })
}

/// `κ_c = max_j Σ_i A_i ρ_ic F_ij / A_j` per channel.
fn kappa(system: &LinearSystem, f: &DenseColumns) -> Vec<Real> {
    let (n, k, area) = (system.len(), system.channels().count(), system.areas());
    (0..k)
        .map(|c| {
            (0..n)
                .map(|j| (0..n).map(|i| area[i] * system.rho(i, c) * f.get(i, j)).sum::<Real>() / area[j])
                .fold(0.0, Real::max)
        })
        .collect()
}

/// Every `(r_ic, s_ic)` of `r = E + ρ F B − B`, patch-major, with the scale of its round-off
/// `s_ic = |E_ic| + ρ_ic Σ_j F_ij |B_jc| + |B_ic|`.
fn residual_entries(system: &LinearSystem, f: &DenseColumns, b: &[Real]) -> Vec<(Real, Real)> {
    let (n, k) = (system.len(), system.channels().count());
    (0..n * k)
        .map(|idx| {
            let (i, c) = (idx / k, idx % k);
            let (fb, fb_abs) = (0..n).fold((0.0, 0.0), |(s, t), j| {
                let v = f.get(i, j) * b[j * k + c];
                (s + v, t + v.abs())
            });
            let r = system.e(i, c) + system.rho(i, c) * fb - b[idx];
            (r, system.e(i, c).abs() + system.rho(i, c) * fb_abs + b[idx].abs())
        })
        .collect()
}

/// Per channel, `‖r_c‖_A` of `r = E + ρ F B − B`, and the scale of its round-off,
/// `Σ_i A_i s_ic` ([`residual_entries`]).
fn residual_norms(system: &LinearSystem, f: &DenseColumns, b: &[Real]) -> Vec<(Real, Real)> {
    let (k, area) = (system.channels().count(), system.areas());
    let mut norms = vec![(0.0, 0.0); k];
    for (idx, (r, scale)) in residual_entries(system, f, b).into_iter().enumerate() {
        norms[idx % k].0 += area[idx / k] * r.abs();
        norms[idx % k].1 += area[idx / k] * scale;
    }
    norms
}

/// The most negative `r_ic / s_ic` ([`residual_entries`]; 0 when no entry is negative).
fn most_negative_residual(system: &LinearSystem, f: &DenseColumns, b: &[Real]) -> Real {
    residual_entries(system, f, b)
        .into_iter()
        .filter(|(_, scale)| *scale > 0.0)
        .map(|(r, scale)| r / scale)
        .fold(0.0, Real::min)
}

/// Checks every bound the executor passes against the exact residual, and keeps the ratios
/// bound / residual.
pub(super) struct Checker<'a> {
    name: String,
    system: &'a LinearSystem,
    f: &'a DenseColumns,
    kappa: Vec<Real>,
    /// Bounds checked, how many of them the solver did not know, and how many stated a
    /// non-negative residual (each checked).
    checked: u64,
    pub(super) missing: u64,
    nonnegative: u64,
    /// `(step, channel, bound / ‖r_c‖_A)` for every check with `‖r_c‖_A > 0`.
    ratios: Vec<(u64, usize, Real)>,
}

impl<'a> Checker<'a> {
    fn new(name: &str, system: &'a LinearSystem, f: &'a DenseColumns) -> Checker<'a> {
        Checker {
            name: name.to_string(),
            system,
            f,
            kappa: kappa(system, f),
            checked: 0,
            missing: 0,
            nonnegative: 0,
            ratios: Vec::new(),
        }
    }
}

impl Observer for Checker<'_> {
    fn observe_step(&mut self, _state: &State, _figures: &Record) {}

    fn wants_residual_bound(&self) -> bool {
        true
    }

    fn observe_residual_bound(&mut self, state: &State, bound: Option<&ResidualBound>) {
        self.checked += 1;
        let Some(bound) = bound else {
            self.missing += 1;
            return;
        };
        assert_eq!(bound.channels(), state.channels, "{}", self.name);
        if bound.nonnegative {
            self.nonnegative += 1;
            let worst = most_negative_residual(self.system, self.f, &state.radiosity);
            assert!(
                worst >= -1e-12,
                "{}: step {}: a residual stated non-negative reaches {worst:e}",
                self.name,
                state.step
            );
        }
        for (c, (norm, scale)) in residual_norms(self.system, self.f, &state.radiosity).into_iter().enumerate() {
            let (through_f, direct) = (bound.through_f[c], bound.direct[c]);
            assert!(through_f >= 0.0 && direct >= 0.0, "{}: step {}, channel {c}: {bound:?}", self.name, state.step);
            let limit = bound.residual_norm(c, self.kappa[c]);
            assert!(
                norm <= limit + 1e-12 * scale,
                "{}: step {}, channel {c}: ‖r‖_A = {norm:e} above the bound {limit:e} (κ {}, {bound:?})",
                self.name,
                state.step,
                self.kappa[c]
            );
            if norm > 0.0 {
                self.ratios.push((state.step, c, limit / norm));
            }
        }
    }
}

/// Runs `name` for `steps` on `system`, its problem carrying a patch order (for
/// `:groups=spatial`), with a [`Checker`]; returns the checker.
pub(super) fn check<'a>(name: &str, system: &'a LinearSystem, f: &'a DenseColumns, steps: &str) -> Checker<'a> {
    let order: Vec<usize> = (0..system.len()).rev().collect();
    let problem = Problem::new(system, f).unwrap().with_patch_order(&order).unwrap();
    let mut solver = solver_by_name(name).unwrap();
    let mut checker = Checker::new(name, system, f);
    let run = Executor::new(solver.as_mut(), StopRules::parse(steps).unwrap())
        .add_observer(&mut checker, ObserverMode::Always)
        .run(&problem)
        .unwrap();
    assert_eq!(checker.checked, run.state.step + 1, "{name}: a bound at init and after every step");
    checker
}

/// Every built-in name that works through `F`: the lists as they are and with groups and
/// memories scaled to these systems, every registry example but those that sample transport
/// or need a hierarchy,
/// and variants that reach other paths (under-relaxation,
/// inner Gauss–Seidel, adaptive and interaction groups, timed frequencies, spatial groups,
/// one group holding every patch).
fn every_name() -> Vec<String> {
    let listed: Vec<&str> = POINT_SOLVERS
        .iter()
        .chain(&GROUP_SOLVERS)
        .chain(&BEYOND_PAPER_SOLVERS)
        .chain(&KRYLOV_SOLVERS)
        .copied()
        .collect();
    let scaled = listed.iter().map(|s| s.replace("g30", "g4").replace("m480", "m8"));
    // The solvers that sample transport by rays run on problems with a sampler and bound no
    // residual: their error bar is a standard error (tests/random_walk.rs).
    let examples = SolverRegistry::builtin()
        .entries()
        .iter()
        .flat_map(|e| e.examples().to_vec())
        .filter(|name| solver_by_name(name).unwrap().step_kind() != StepKind::Sampled)
        // Groups of the tree's clusters need a hierarchy (radiosity-eval's node_shooting tests
        // run them on one).
        .filter(|name| !name.contains("groups=clusters"))
        .collect::<Vec<_>>();
    let extra = [
        "sor-0.8",
        "sor-1.9",
        "relax-0.8",
        "group-relax-1.5-g4",
        "group-shao-g3",
        "group-xu-direct-g4",
        "group-xu-ambient-g4",
        "pr-g2:f=1",
        "xu-g4-m8:f=2:inner=gs",
        "shao-g3-m6:f=1",
        "feda-g4:f=auto",
        "relax-1.5-g3:f=timed",
        "pr-g4-m10:f=1:adaptive=0.2",
        "xu-direct-g3:f=1:groups=interaction",
        "group-jacobi-g1",
        "group-gs-g1",
        "group-gs-g4:groups=spatial",
        "group-jacobi-g3:groups=spatial",
        "group-gs-g12",
        "group-jacobi-g12",
        "gmres-1",
        "gmres-4",
    ];
    let mut names: Vec<String> = listed.iter().map(|s| s.to_string()).chain(scaled).chain(examples).collect();
    names.extend(extra.map(String::from));
    let mut seen = std::collections::HashSet::new();
    names.retain(|name| seen.insert(name.clone()));
    names
}

#[test]
fn every_solver_bounds_the_residual_of_its_displayed_radiosity_after_every_step() {
    for (label, (system, f)) in [("enclosure", enclosure()), ("lamp", lamp()), ("concave", concave())] {
        for name in every_name() {
            let checker = check(&name, &system, &f, "steps=6n");
            assert_eq!(checker.missing, 0, "{name} on the {label}: no bound");
            // Southwell and PR from non-negative emissions never make ΔB negative, so they
            // state the sign at every step; gathering solvers never do.
            if ["southwell", "pr"].contains(&name.as_str()) {
                assert_eq!(checker.nonnegative, checker.checked, "{name} on the {label}");
            }
            if ["jacobi", "gauss-seidel"].contains(&name.as_str()) {
                assert_eq!(checker.nonnegative, 0, "{name} on the {label}");
            }
            assert!(!checker.ratios.is_empty(), "{name} on the {label}");
        }
    }
}

#[test]
fn group_steps_that_fall_back_keep_the_bound() {
    // Groups whose systems are not M-matrices fall back to point shots (non-physical systems,
    // which diverge, but every step is still bounded); the inner Gauss–Seidel refuses them too.
    for (emitting_group, names) in [
        (true, ["group-pr-g3", "group-xu-g3", "group-relax-1.5-g3"]),
        (false, ["pr-g2-m3:f=1", "pr-g2-m3:f=1:inner=gs", "relax-1.5-g2-m3:f=1"]),
    ] {
        let (system, f) = bad_group(1.2, emitting_group);
        for name in names {
            let checker = check(name, &system, &f, "steps=8");
            assert_eq!(checker.missing, 0, "{name}");
            let mut solver = solver_by_name(name).unwrap();
            let problem = Problem::new(&system, &f).unwrap();
            let run = Executor::new(solver.as_mut(), StopRules::parse("steps=8").unwrap()).run(&problem).unwrap();
            assert!(run.record.count("group_fallbacks").unwrap() > 0, "{name}: {}", run.record);
        }
    }
}

#[test]
fn the_shooting_bound_is_not_vacuous() {
    // PR's d = ΔB: with through_f replaced by zeros the bound would be 0 < ‖r‖_A. It stays
    // within a small factor of the true residual: r = ρ F ΔB exactly, and κ ‖ΔB‖_A overestimates
    // ‖ρ F ΔB‖_A only as far as the columns' weights Σ_i A_i ρ_i F_ij / A_j differ.
    let (system, f) = enclosure();
    let checker = check("pr", &system, &f, "steps=3n");
    for &(step, c, ratio) in &checker.ratios {
        assert!((1.0 - 1e-12..=10.0).contains(&ratio), "pr step {step}, channel {c}: bound / residual {ratio}");
    }
    // So is Gauss–Seidel's, mid-sweep included.
    let checker = check("gauss-seidel", &system, &f, "steps=3n");
    let worst = checker.ratios.iter().map(|r| r.2).fold(0.0, Real::max);
    assert!(worst <= 50.0, "gauss-seidel: bound / residual up to {worst}");
}

#[test]
fn shooting_keeps_the_unshot_radiosity_the_residual_when_patches_see_themselves() {
    // With F_jj > 0 the shooter receives its own share ρ_j F_jj s of its shot, which it keeps
    // unshot: ΔB stays exactly the residual of x = B − ΔB.
    let (system, f) = concave();
    for name in ["pr", "southwell", "feda", "shao", "xu", "relax-1.5", "group-pr-g3", "pr-g3:f=1", "xu-g3-m6:f=2"] {
        let mut solver = solver_by_name(name).unwrap();
        let problem = Problem::new(&system, &f).unwrap();
        let run = Executor::new(solver.as_mut(), StopRules::parse("steps=40").unwrap()).run(&problem).unwrap();
        assert_unshot_is_the_residual(name, &system, &f, &run.state);
    }
}

#[test]
fn the_bound_follows_its_formula_and_reaches_observers_as_asked() {
    let bound = ResidualBound::new(vec![2.0, 0.5], vec![0.25, 0.0]);
    assert_eq!((bound.residual_norm(0, 0.5), bound.residual_norm(1, 0.9), bound.channels()), (1.25, 0.45, 2));
    assert_eq!(area_norms(&[1.0, 2.0], &[1.0, -2.0, -3.0, 4.0], 2), [7.0, 10.0]);
    // A solver of one's own knows none unless it says so.
    struct Idle;
    impl Solver for Idle {
        fn name(&self) -> String {
            "idle".into()
        }
        fn next_step(&mut self, _: &Problem<'_>, _: &mut State) -> Result<Record, SolverError> {
            Ok(Record::new())
        }
        fn residual_power(&self, _: &Problem<'_>, _: &State) -> Option<Real> {
            None
        }
    }
    let (system, f) = enclosure();
    let problem = Problem::new(&system, &f).unwrap();
    let mut checker = Checker::new("idle", &system, &f);
    Executor::new(&mut Idle, StopRules::parse("steps=3").unwrap())
        .add_observer(&mut checker, ObserverMode::Always)
        .run(&problem)
        .unwrap();
    assert_eq!((checker.checked, checker.missing), (4, 4));
    // Every n-th step only, and always at init; none at all to an observer that does not ask.
    let mut every = Checker::new("pr", &system, &f);
    let mut pr = solver_by_name("pr").unwrap();
    Executor::new(pr.as_mut(), StopRules::parse("steps=7").unwrap())
        .add_observer(&mut every, ObserverMode::Every(3))
        .run(&problem)
        .unwrap();
    assert_eq!(every.checked, 3);
    let mut sor = solver_by_name("sor-1.2").unwrap();
    let run = Executor::new(sor.as_mut(), StopRules::parse("steps=4").unwrap()).run(&problem).unwrap();
    let direct = sor.residual_bound(&problem, &run.state).unwrap().direct;
    let unshot = area_norms(system.areas(), &run.state.unshot, 3);
    for (d, u) in direct.iter().zip(&unshot) {
        assert!((d - (1.0 / 1.2 - 1.0 as Real).abs() * u).abs() <= 1e-15 * u, "SOR's e = |1/ω − 1| u: {d} against {u}");
    }
}

#[test]
fn jacobi_by_products_bounds_its_residual() {
    // `jacobi:sweep=product` over a source that multiplies itself: a step is a sweep by one
    // product and its bound that of a shooting method over the sweep's change, checked against the exact
    // residual after every step, and stated non-negative from a non-negative start.
    let (system, f) = reciprocal(12, 7, 0.0, 0.98, |idx| 0.3 + 0.6 * unit(idx as u64));
    let multiplying = super::Multiplying(&f);
    let problem = Problem::new(&system, &multiplying).unwrap();
    let mut solver = solver_by_name("jacobi:sweep=product").unwrap();
    let mut checker = Checker::new("jacobi:sweep=product", &system, &f);
    let run = Executor::new(solver.as_mut(), StopRules::parse("steps=20").unwrap())
        .add_observer(&mut checker, ObserverMode::Always)
        .run(&problem)
        .unwrap();
    assert_eq!((run.state.step, run.state.cost[Unit::Columns], run.state.cost[Unit::Products]), (20, 0, 20));
    assert_eq!((checker.checked, checker.missing), (21, 0));
    assert_eq!(checker.nonnegative, 21, "E ≥ 0 and F ≥ 0: every residual is non-negative");
}
