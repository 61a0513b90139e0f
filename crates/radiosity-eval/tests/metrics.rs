//! Metrics on hand-made vectors, and the certified bound against true errors.

use crate::{cube_form_factors, random_system};
use approx::assert_relative_eq;
use radiosity_core::{Channels, ColumnSource, DenseColumns, LinearSystem};
use radiosity_eval::{
    EvalError, Evaluator, FormFactors, ReferenceParams, ReferenceSolution, Residual, SolverBound, errors, evaluate,
};
use radiosity_solvers::ResidualBound;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Areas 1 and 3, F12 = 1/2, F21 = 1/6 (A1 F12 = A2 F21), ρ = 1/2, E = (1, 0):
/// B* = (48/47, 4/47).
fn pair() -> (LinearSystem, DenseColumns, ReferenceSolution) {
    let f = DenseColumns::from_rows(2, &[0.0, 0.5, 1.0 / 6.0, 0.0]).unwrap();
    let system = LinearSystem::new(Channels::Grey, vec![1.0, 3.0], vec![0.5, 0.5], vec![1.0, 0.0]).unwrap();
    let reference = ReferenceSolution::solve(&system, &f, ReferenceParams::default()).unwrap();
    assert_relative_eq!(reference.get(0, 0), 48.0 / 47.0, max_relative = 1e-15);
    assert_relative_eq!(reference.get(1, 0), 4.0 / 47.0, max_relative = 1e-15);
    (system, f, reference)
}

#[test]
fn metrics_of_emission_alone_by_hand() {
    let (system, f, reference) = pair();
    let b = [1.0, 0.0];
    let m = evaluate(&system, &f, &reference, &b).unwrap();
    // Errors (−1/47, −4/47): Σ A d² = 49/47², Σ A B*² = (48² + 3·4²)/47² = 2352/47².
    assert_relative_eq!(m.e_rms, (49.0_f64 / 2352.0).sqrt(), max_relative = 1e-13);
    // max |d| = 4/47 over max B* = 48/47.
    assert_relative_eq!(m.e_max, 1.0 / 12.0, max_relative = 1e-13);
    assert_relative_eq!(m.l1_error, 13.0 / 47.0, max_relative = 1e-13);
    // r = E + ρ F b − b = (0, ρ F21) = (0, 1/12); R = 3 · 1/12 over A1 E1 = 1.
    assert_relative_eq!(m.residual, 0.25, max_relative = 1e-15);
    // κ = max(A2 ρ F21 / A1, A1 ρ F12 / A2) = max(1/4, 1/12); q = max(ρ_max, κ) = 1/2.
    let r = Residual::from_columns(&system, &f, &b).unwrap();
    assert_eq!(r.values(), &[0.0, 1.0 / 12.0]);
    assert_eq!(r.contraction().kappa, vec![0.25]);
    assert_eq!(r.contraction().factor(0), 0.5);
    assert!(m.bound.certified);
    assert_relative_eq!(m.bound.bound, 0.5, max_relative = 1e-15);
    assert!(m.bound.bound >= m.l1_error);
}

#[test]
fn the_solvers_bound_by_hand_and_what_the_sign_of_the_residual_buys() {
    // PR on the pair after shooting patch 0: B = (1, 1/12), ΔB = (0, 1/12) ≥ 0, so the
    // residual ρ F ΔB ≥ 0 and B ≤ B*. ‖ΔB‖_A = 3/12; with the measured κ = 1/4 the absolute
    // bound is κ ‖ΔB‖_A / (1 − κ) = 1/12 (true: 1/47 + 3/564 = 15/564).
    let (system, f, reference) = pair();
    let b = [1.0, 1.0 / 12.0];
    let contraction = Residual::from_columns(&system, &f, &b).unwrap().contraction().clone();
    let known = ResidualBound::new(vec![0.25], vec![0.0]);
    let unsigned = SolverBound::new(&system, &contraction, &known, &b);
    assert_relative_eq!(unsigned.absolute, 1.0 / 12.0, max_relative = 1e-15);
    // Relative to max(‖B‖_A − 1/12, Σ A E) = 7/6 without the sign, to Σ A B = 5/4 with it.
    assert_relative_eq!(unsigned.relative, 1.0 / 14.0, max_relative = 1e-15);
    let signed = SolverBound::new(&system, &contraction, &known.with_nonnegative_residual(true), &b);
    assert_relative_eq!(signed.relative, 1.0 / 15.0, max_relative = 1e-15);
    // Both hold: the true relative L1 error is (15/564) / (60/47) = 1/48.
    let e = errors(&system, &reference, &b).unwrap();
    assert_relative_eq!(e.l1 / e.reference_l1, 1.0 / 48.0, max_relative = 1e-12);
    assert!(e.l1 <= signed.absolute && e.l1 / e.reference_l1 <= signed.relative);
}

#[test]
fn metrics_of_a_hand_made_rgb_vector() {
    // No interaction (F = 0): B* = E. Areas 1 and 3.
    let f = DenseColumns::from_fn(2, |_, _| 0.0);
    let e = vec![1.0, 2.0, 0.0, 2.0, 4.0, 1.0];
    let system = LinearSystem::new(Channels::Rgb, vec![1.0, 3.0], vec![0.5; 6], e.clone()).unwrap();
    let reference = ReferenceSolution::solve(&system, &f, ReferenceParams::default()).unwrap();
    assert_eq!(reference.values(), &e[..]);
    let b = [1.5, 2.0, 0.0, 2.0, 3.0, 1.5];
    // d = (0.5, 0, 0, 0, −1, 0.5): Σ A d² = 0.25 + 3 (1 + 0.25) = 4;
    // Σ A B*² = (1 + 4) + 3 (4 + 16 + 1) = 68.
    let errors = errors(&system, &reference, &b).unwrap();
    assert_relative_eq!(errors.e_rms, (4.0_f64 / 68.0).sqrt(), max_relative = 1e-15);
    assert_relative_eq!(errors.e_max, 1.0 / 4.0, max_relative = 1e-15);
    assert_relative_eq!(errors.l1, 0.5 + 3.0 * 1.5, max_relative = 1e-15);
    // r = E − b (F = 0): Σ A |r| = 5; Σ A E = 3 + 3 · 7 = 24.
    let m = evaluate(&system, &f, &reference, &b).unwrap();
    assert_relative_eq!(m.residual, 5.0 / 24.0, max_relative = 1e-15);
    // κ = 0 and ρ_max = 0.5 per channel: the bound is 2 ‖r‖_A = 10.
    assert_relative_eq!(m.bound.bound, 10.0, max_relative = 1e-15);
}

#[test]
fn streamed_and_stored_residuals_are_identical() {
    let (system, f) = random_system(300, 11, 0.98, 0.9);
    let m = FormFactors::assemble(&f, usize::MAX).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let b: Vec<f64> = (0..system.len() * 3).map(|_| rng.random::<f64>()).collect();
    let streamed = Residual::from_columns(&system, &f, &b).unwrap();
    let stored = Residual::from_matrix(&system, &m, &b).unwrap();
    assert_eq!(streamed, stored);
    // The stored matrix serves columns too.
    let again = Residual::from_columns(&system, &m, &b).unwrap();
    assert_eq!(streamed, again);

    let reference = ReferenceSolution::solve_matrix(&system, &m, ReferenceParams::default()).unwrap();
    let evaluator = Evaluator::new(&system, &m, &reference).unwrap();
    assert_eq!(evaluator.evaluate(&b).unwrap(), evaluate(&system, &f, &reference, &b).unwrap());
}

#[test]
fn the_certified_bound_bounds_the_true_error() {
    let mut ratios = Vec::new();
    let mut sharp = Vec::new();
    let cube = cube_form_factors();
    let e = (0..6).map(|i| if i == 0 { 1.0 } else { 0.0 }).collect();
    let cube_system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![0.9; 6], e).unwrap();
    let (low, f_low) = random_system(200, 21, 0.999, 0.5);
    let (high, f_high) = random_system(200, 22, 0.999, 0.95);
    let cases = [("cube ρ=0.9", cube_system, cube), ("random ρ≤0.5", low, f_low), ("random ρ≤0.95", high, f_high)];
    for (name, system, f) in &cases {
        let reference = ReferenceSolution::solve(system, f, ReferenceParams::default()).unwrap();
        let star = reference.values();
        for seed in 0..4 {
            for magnitude in [1e-1, 1e-4, 1e-8] {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                // Relative noise; with seed 0 one-signed (a solver's error usually is).
                let b: Vec<f64> = star
                    .iter()
                    .map(|s| {
                        let u = rng.random::<f64>();
                        let u = if seed == 0 { u } else { 2.0 * u - 1.0 };
                        s + magnitude * (s.abs() + 0.01) * u
                    })
                    .collect();
                let m = evaluate(system, f, &reference, &b).unwrap();
                let r = Residual::from_columns(system, f, &b).unwrap();
                let q = r.contraction().max_factor();
                assert!(m.bound.certified);
                assert!(m.bound.bound >= m.l1_error, "{name} seed {seed} {magnitude:e}: {m:?}");
                // ‖r‖ = ‖Φ e‖ ≤ (1 + κ) ‖e‖, so the bound is at most (1 + q)/(1 − q) times
                // the true error (up to the reference's own error).
                let ratio = m.bound.bound / m.l1_error;
                assert!(ratio <= (1.0 + q) / (1.0 - q) * (1.0 + 1e-6), "{name}: ratio {ratio}, q {q}");
                assert!(m.bound.sharp >= m.l1_error && m.bound.sharp <= m.bound.bound);
                ratios.push((name.to_string(), format!("noise {magnitude:.0e}, seed {seed}"), ratio));
                sharp.push(m.bound.sharp / m.l1_error);
            }
        }
        // Jacobi iterates from B = E: a solver's error, smooth and one-signed.
        let n = system.len();
        let k = system.channels().count();
        let mut b = system.emissions().to_vec();
        let mut column = vec![0.0; n];
        for sweep in 1..=40 {
            let mut next = system.emissions().to_vec();
            for j in 0..n {
                f.fill_column(j, &mut column);
                for i in 0..n {
                    for c in 0..k {
                        next[i * k + c] += system.rho(i, c) * column[i] * b[j * k + c];
                    }
                }
            }
            b = next;
            if [1, 5, 40].contains(&sweep) {
                let m = evaluate(system, f, &reference, &b).unwrap();
                // In the closed cube with uniform ρ the bound is attained (all the error is
                // lost at the rate ρ), so it is checked to round-off.
                assert!(m.bound.bound >= m.l1_error * (1.0 - 1e-12), "{name} Jacobi {sweep}: {m:?}");
                assert!(m.bound.sharp >= m.l1_error * (1.0 - 1e-12) && m.bound.sharp <= m.bound.bound);
                ratios.push((name.to_string(), format!("Jacobi, {sweep} sweeps"), m.bound.bound / m.l1_error));
                sharp.push(m.bound.sharp / m.l1_error);
            }
        }
    }
    for ((name, what, ratio), sharp) in ratios.iter().zip(&sharp) {
        println!("{name:>14}, {what:<22}: bound / true L1 error = {ratio:.3}, sharp bound / error = {sharp:.3}");
    }
}

#[test]
fn sizes_and_dark_scenes_are_errors() {
    let (system, f, reference) = pair();
    assert!(matches!(
        evaluate(&system, &f, &reference, &[1.0]),
        Err(EvalError::SizeMismatch { expected: 2, found: 1, .. })
    ));
    let dark = LinearSystem::new(Channels::Grey, vec![1.0, 3.0], vec![0.5, 0.5], vec![0.0, 0.0]).unwrap();
    let reference = ReferenceSolution::solve(&dark, &f, ReferenceParams::default()).unwrap();
    assert_eq!(reference.values(), &[0.0, 0.0]);
    assert_eq!(errors(&dark, &reference, &[0.0, 0.0]), Err(EvalError::ZeroReference));
}
