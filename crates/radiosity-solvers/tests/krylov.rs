//! The Krylov solvers (`cg`, `gmres-K`, `bicgstab`): their answers against dense LU, their
//! finite termination, what a step costs, the hypothesis `cg` checks, and the step cap.

use super::{non_physical, solve_capped, twelve};
use radiosity_core::dense_lu::lu_solve;
use radiosity_core::{
    Channels, ColumnSource, DenseColumns, LinearSystem, RadiosityOperator, Real, SymmetrizedOperator,
};
use radiosity_solvers::*;

/// `B*` of every channel by dense LU.
pub(super) fn exact(system: &LinearSystem, f: &DenseColumns) -> Vec<Real> {
    let (n, k) = (system.len(), system.channels().count());
    let mut b = vec![0.0; n * k];
    for c in 0..k {
        let a = |i: usize, j: usize| Real::from(u8::from(i == j)) - system.rho(i, c) * f.get(i, j);
        let x = lu_solve(n, false, a, |i| system.e(i, c)).unwrap();
        for (i, v) in x.into_iter().enumerate() {
            b[i * k + c] = v;
        }
    }
    b
}

/// `twelve()`, stating its reciprocity (it is exact by construction).
fn twelve_reciprocal() -> (LinearSystem, DenseColumns) {
    let (system, f) = twelve();
    let f = f.with_measured_reciprocity(system.areas()).unwrap();
    assert!(f.reciprocity_bound().unwrap() < 1e-14);
    (system, f)
}

fn run(name: &str, system: &LinearSystem, f: &DenseColumns, rules: &str) -> Result<Run, SolverError> {
    let mut solver = solver_by_name(name)?;
    let problem = Problem::new(system, f)?;
    let rules = StopRules { step_cap: 2000.0, ..StopRules::parse(rules)? };
    Executor::new(solver.as_mut(), rules).run(&problem)
}

#[test]
fn krylov_solvers_reach_the_lu_solution_within_their_finite_termination() {
    // In exact arithmetic CG and GMRES with K ≥ n end within n products after the first
    // (which computes r_0), BiCGSTAB within 2n; with unequal areas, reflectivities and three
    // channels, a few more in floating point.
    let (system, f) = twelve_reciprocal();
    let n = system.len() as u64;
    let star = exact(&system, &f);
    for (name, products) in [("cg", n + 1), ("gmres-30", n + 1), ("gmres-12", n + 1), ("bicgstab", 2 * n + 1)] {
        let run = run(name, &system, &f, "residual=1e-14").unwrap();
        assert!(
            matches!(run.termination, TerminationReason::Residual(_) | TerminationReason::RoundOff),
            "{name}: {}",
            run.termination
        );
        assert!(run.state.step <= products + 3, "{name}: {} products for n = {n}", run.state.step);
        for (idx, (b, s)) in run.state.radiosity.iter().zip(&star).enumerate() {
            assert!((b - s).abs() <= 1e-12 * s.abs().max(1.0), "{name}: entry {idx}: {b} against {s}");
        }
        assert_eq!(run.record.count("matvecs"), Some(run.state.step), "{name}: one product a step");
    }
}

#[test]
fn restarting_gmres_early_costs_products_but_still_converges() {
    let (system, f) = twelve_reciprocal();
    let star = exact(&system, &f);
    let full = run("gmres-30", &system, &f, "residual=1e-13").unwrap();
    let short = run("gmres-2", &system, &f, "residual=1e-13").unwrap();
    assert!(short.state.step > full.state.step, "gmres-2: {} against {}", short.state.step, full.state.step);
    // Every cycle of gmres-2 takes three products: r_0, then two Arnoldi steps.
    let cycles = short.record.count("cycles").unwrap();
    assert!(short.state.step <= 3 * cycles && short.state.step > 3 * (cycles - 1), "{}", short.record);
    let worst = short.state.radiosity.iter().zip(&star).map(|(b, s)| (b - s).abs() / s.abs().max(1.0));
    assert!(worst.fold(0.0, Real::max) < 1e-11);
}

#[test]
fn a_step_costs_the_columns_of_the_patches_it_multiplies() {
    // The first product multiplies the emission: only the emitters' columns. Every later one
    // multiplies a dense vector: n columns, as a gathering sweep.
    let (system, f) = twelve_reciprocal();
    let n = system.len() as u64;
    let emitters = (0..system.len()).filter(|&i| (0..3).any(|c| system.e(i, c) != 0.0)).count() as u64;
    assert!(emitters < n);
    for name in KRYLOV_SOLVERS {
        let one = run(name, &system, &f, "steps=1").unwrap();
        assert_eq!((one.state.step, one.state.cost[Unit::Columns]), (1, emitters), "{name}");
        assert_eq!(one.state.radiosity, system.emissions(), "{name}: the first step only measures r_0");
        let four = run(name, &system, &f, "steps=4").unwrap();
        assert_eq!(four.state.cost[Unit::Columns], emitters + 3 * n, "{name}");
        assert_eq!(four.record.count("columns_skipped"), Some(n - emitters), "{name}: {}", four.record);
    }
}

#[test]
fn the_step_cap_counts_a_product_as_n_steps() {
    // A cap of 3n steps allows a gathering solver three sweeps and a Krylov solver three
    // products, unless an explicit rule asks for more.
    let (system, f) = twelve_reciprocal();
    for name in KRYLOV_SOLVERS {
        let capped = solve_capped(name, &system, &f, "residual=1e-300", 3.0);
        assert_eq!(capped.termination, TerminationReason::StepCap(3), "{name}");
        let more = solve_capped(name, &system, &f, "steps=5", 3.0);
        assert_eq!(more.termination, TerminationReason::Steps(5), "{name}");
    }
    let gs = solve_capped("gauss-seidel", &system, &f, "residual=1e-300", 3.0);
    assert_eq!(gs.termination, TerminationReason::StepCap(36));
}

#[test]
fn cg_refuses_form_factors_that_state_no_reciprocity_in_one_sentence() {
    let (system, f) = twelve();
    let e = run("cg", &system, &f, "residual=1e-10").unwrap_err();
    assert!(matches!(e, SolverError::NotApplicable { .. }));
    let text = e.to_string();
    assert!(text.starts_with("cg cannot solve this system: cg solves the symmetrized system"), "{text}");
    assert!(text.contains("state no reciprocity bound") && text.ends_with("gmres-30 and bicgstab need no symmetry"));
    assert_eq!(text.matches(". ").count(), 0, "one sentence: {text}");
    // GMRES and BiCGSTAB need none.
    let star = exact(&system, &f);
    for name in ["gmres-30", "bicgstab"] {
        let b = run(name, &system, &f, "residual=1e-13").unwrap().state.radiosity;
        assert!(b.iter().zip(&star).all(|(b, s)| (b - s).abs() < 1e-10 * s.abs().max(1.0)), "{name}");
    }
}

#[test]
fn cg_refuses_a_stated_reciprocity_error_above_its_limit() {
    // F_12 = 0.4 but F_21 = 0.3 with equal areas: a relative error of 1/4.
    let system = LinearSystem::new(Channels::Grey, vec![1.0, 1.0], vec![0.5, 0.5], vec![1.0, 0.0]).unwrap();
    let f = DenseColumns::from_rows(2, &[0.0, 0.4, 0.3, 0.0]).unwrap().with_measured_reciprocity(&[1.0, 1.0]).unwrap();
    let text = run("cg", &system, &f, "residual=1e-10").unwrap_err().to_string();
    assert!(text.contains("reciprocal only to a relative 2.50e-1, above the 1e-6 cg accepts"), "{text}");
    assert!((f.reciprocity_bound().unwrap() - 0.25).abs() < 1e-15);
}

#[test]
fn cg_stops_where_the_symmetrized_system_is_not_positive_definite() {
    // ρ F with rows of 4.05: reciprocal, but A = 1.81 I − 0.81 J has the eigenvalue −3.05.
    let (system, f) = non_physical();
    let f = f.with_measured_reciprocity(system.areas()).unwrap();
    // The run ends with its state kept, as it stood after the first product, and says why.
    let stopped = run("cg", &system, &f, "residual=1e-10").unwrap();
    let TerminationReason::Breakdown { step, reason } = &stopped.termination else { panic!("{}", stopped.termination) };
    assert_eq!(*step, 2);
    assert!(reason.contains("the symmetrized system of channel 0 is not positive definite"), "{reason}");
    assert!(stopped.termination.to_string().starts_with("broke down at step 2: "), "{}", stopped.termination);
    assert_eq!(stopped.state.step, 1);
    assert_eq!(stopped.state.radiosity, system.emissions(), "B = E until the breakdown");
    // GMRES needs no definiteness: it finds the non-physical system's solution (negative
    // radiosities), which no contraction-based method reaches.
    let star = exact(&system, &f);
    assert!(star.iter().any(|b| *b < 0.0));
    let b = run("gmres-30", &system, &f, "residual=1e-12").unwrap().state.radiosity;
    assert!(b.iter().zip(&star).all(|(b, s)| (b - s).abs() < 1e-9 * s.abs().max(1.0)), "{b:?} against {star:?}");
}

#[test]
fn a_stiff_furnace_takes_one_product_after_the_first() {
    // Uniform ρ = 0.999 and E in a closed cube: r_0 = ρ F E is a multiple of the all-ones
    // eigenvector of F, so each method ends after one more product, where point methods need
    // thousands of sweeps.
    let (opposite, adjacent) = (0.1998248525509989, 0.2000437868622503);
    let f = DenseColumns::from_fn(6, |i, j| {
        if i == j {
            0.0
        } else if j == (i ^ 1) {
            opposite
        } else {
            adjacent
        }
    })
    .with_measured_reciprocity(&[1.0; 6])
    .unwrap();
    let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.999; 6], vec![1.0; 6]).unwrap();
    let row = opposite + 4.0 * adjacent;
    let exact = 1.0 / (1.0 - 0.999 * row);
    for name in KRYLOV_SOLVERS {
        let run = run(name, &system, &f, "residual=1e-13").unwrap();
        assert!(run.state.step <= 3, "{name}: {} products", run.state.step);
        assert!(
            run.state.radiosity.iter().all(|b| (b / exact - 1.0).abs() < 1e-12),
            "{name}: {:?}",
            run.state.radiosity
        );
    }
}

#[test]
fn krylov_names_parse_and_bad_ones_are_refused() {
    assert_eq!("gmres-30".parse::<GmresParams>(), Ok(GmresParams { restart: 30 }));
    assert_eq!("gmres".parse::<GmresParams>(), Err(ParseSolverError::OtherFamily));
    assert_eq!("cg".parse::<CgParams>(), Ok(CgParams));
    assert_eq!("bicgstab".parse::<BicgstabParams>(), Ok(BicgstabParams));
    let zero = solver_by_name("gmres-0").err().unwrap().to_string();
    assert_eq!(zero, "solver 'gmres-0': GMRES needs a restart length K ≥ 1, not 0");
    let params = solver_by_name("cg:tol=1").err().unwrap().to_string();
    assert_eq!(params, "solver 'cg' takes no parameters, not 'tol=1'");
    let typo = solver_by_name("bicgstb").err().unwrap().to_string();
    assert!(typo.contains("did you mean 'bicgstab'?"), "{typo}");
    for name in KRYLOV_SOLVERS {
        assert_eq!(solver_by_name(name).unwrap().name(), name);
        assert_eq!(solver_by_name(name).unwrap().step_kind(), StepKind::Product);
    }
}

/// `x` with `A x = b` by faer's own matrix-free solver, `cg` or `bicgstab`, through the public
/// operator ([`RadiosityOperator`] as faer's `LinOp`).
fn faer_solve(op: impl faer::matrix_free::LinOp<Real> + Copy, b: &[Real], cg: bool) -> Vec<Real> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::matrix_free::{IdentityPrecond, bicgstab, conjugate_gradient};
    let dim = b.len();
    let rhs = faer::Mat::from_fn(dim, 1, |i, _| b[i]);
    let mut out = faer::Mat::<Real>::zeros(dim, 1);
    let precond = IdentityPrecond { dim };
    let par = faer::Par::Seq;
    if cg {
        let params = conjugate_gradient::CgParams { max_iters: 500, ..Default::default() };
        let mut buffer = MemBuffer::new(conjugate_gradient::conjugate_gradient_scratch(precond, op, 1, par));
        let stack = MemStack::new(&mut buffer);
        conjugate_gradient::conjugate_gradient(out.as_mut(), precond, op, rhs.as_ref(), params, |_| {}, par, stack)
            .unwrap();
    } else {
        let params = bicgstab::BicgParams { max_iters: 500, ..Default::default() };
        let mut buffer = MemBuffer::new(bicgstab::bicgstab_scratch(precond, precond, op, 1, par));
        let stack = MemStack::new(&mut buffer);
        bicgstab::bicgstab(out.as_mut(), precond, precond, op, rhs.as_ref(), params, |_| {}, par, stack).unwrap();
    }
    (0..dim).map(|i| out[(i, 0)]).collect()
}

#[test]
fn faers_own_cg_and_bicgstab_agree_with_ours_on_a_stored_system() {
    // Twelve patches, three channels, reciprocal form factors stored in memory.
    let (system, f) = twelve();
    let f = f.with_measured_reciprocity(system.areas()).unwrap();
    let op = RadiosityOperator::new(&system, &f).unwrap();
    let symmetric = SymmetrizedOperator::new(op).unwrap();
    let theirs_cg = faer_solve(&symmetric, &symmetric.rhs(), true);
    let theirs_bicgstab = faer_solve(op, system.emissions(), false);
    for (name, theirs) in [("cg", theirs_cg), ("bicgstab", theirs_bicgstab)] {
        let ours = run(name, &system, &f, "residual=1e-14").unwrap().state.radiosity;
        for (a, b) in ours.iter().zip(&theirs) {
            assert!((a - b).abs() <= 1e-10 * b.abs().max(1.0), "{name}: ours {a}, faer's {b}");
        }
    }
}
