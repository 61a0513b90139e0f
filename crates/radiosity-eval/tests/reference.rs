//! Reference solutions against closed forms, dense LU against Gauss–Seidel, and the errors
//! refused inputs give.

use crate::{cube_form_factors, random_system};
use approx::assert_relative_eq;
use radiosity_core::{Channels, DenseColumns, LinearSystem};
use radiosity_eval::{EvalError, FormFactors, Method, ReferenceParams, ReferenceSolution};

fn dense() -> ReferenceParams {
    ReferenceParams::default()
}

fn gauss_seidel() -> ReferenceParams {
    ReferenceParams::default().with_dense_limit(0)
}

/// Gauss–Seidel pushed to round-off, to be checked against closed forms at 1e-12.
fn exact_gauss_seidel() -> ReferenceParams {
    gauss_seidel().with_certified(1e-14)
}

/// A furnace: areas 1, 2, 3, 4, 6 and `F_ij = A_j / ΣA` (rows sum to exactly 1, reciprocity
/// exact, `F_ii ≠ 0`); ρ = 0.9 / 0.5 / 0.0 and E = 1 / 2 / 3 in the three channels.
fn furnace() -> (LinearSystem, DenseColumns) {
    let area = vec![1.0, 2.0, 3.0, 4.0, 6.0];
    let total: f64 = area.iter().sum();
    let n = area.len();
    let f = DenseColumns::from_fn(n, |_, j| area[j] / total);
    let rho = [0.9, 0.5, 0.0].repeat(n);
    let e = [1.0, 2.0, 3.0].repeat(n);
    (LinearSystem::new(Channels::Rgb, area, rho, e).unwrap(), f)
}

#[test]
fn furnace_is_emission_over_one_minus_rho() {
    let (system, f) = furnace();
    for params in [dense(), exact_gauss_seidel()] {
        let reference = ReferenceSolution::solve(&system, &f, params).unwrap();
        for i in 0..system.len() {
            for (c, expected) in [10.0, 4.0, 3.0].into_iter().enumerate() {
                assert_relative_eq!(reference.get(i, c), expected, max_relative = 1e-12);
            }
        }
        let cert = reference.certificate();
        assert!(cert.certified, "{cert}");
        assert!(cert.contraction.rows_at_most_one());
        assert_relative_eq!(cert.contraction.max_row_sum, 1.0, max_relative = 1e-15);
        assert!(cert.relative_bound <= 1e-10, "{cert}");
    }
}

#[test]
fn two_facing_patches_match_the_closed_form() {
    // A1 F12 = A2 F21: 2 · 0.3 = 1 · 0.6.
    let (a, b) = (0.3, 0.6);
    let f = DenseColumns::from_rows(2, &[0.0, a, b, 0.0]).unwrap();
    let rho = [0.8, 0.5, 0.2, 0.6, 0.4, 0.9];
    let e = [1.0, 0.5, 0.0, 0.25, 2.0, 1.0];
    let system = LinearSystem::new(Channels::Rgb, vec![2.0, 1.0], rho.to_vec(), e.to_vec()).unwrap();
    for params in [dense(), exact_gauss_seidel()] {
        let reference = ReferenceSolution::solve(&system, &f, params).unwrap();
        for c in 0..3 {
            let (r1, r2, e1, e2) = (rho[c], rho[3 + c], e[c], e[3 + c]);
            let d = 1.0 - r1 * r2 * a * b;
            assert_relative_eq!(reference.get(0, c), (e1 + r1 * a * e2) / d, max_relative = 1e-12);
            assert_relative_eq!(reference.get(1, c), (e2 + r2 * b * e1) / d, max_relative = 1e-12);
        }
    }
}

#[test]
fn howell_form_factors_of_the_unit_cube() {
    let f = cube_form_factors();
    assert_relative_eq!(f.get(0, 1), 0.19982489569838, epsilon = 1e-13);
    assert_relative_eq!(f.get(0, 2), 0.20004377607540, epsilon = 1e-13);
    let row: f64 = (0..6).map(|j| f.get(0, j)).sum();
    assert_relative_eq!(row, 1.0, epsilon = 1e-12);
}

#[test]
fn unit_cube_with_a_glowing_top() {
    let f = cube_form_factors();
    for (rho, [top, bottom, side]) in [(0.5, [1.090909, 0.181746, 0.181836]), (0.9, [2.372881, 1.525311, 1.525452])] {
        let e = (0..6).map(|i| if i == 0 { 1.0 } else { 0.0 }).collect();
        let system = LinearSystem::new(Channels::Grey, vec![1.0; 6], vec![rho; 6], e).unwrap();
        for params in [dense(), exact_gauss_seidel()] {
            let reference = ReferenceSolution::solve(&system, &f, params).unwrap();
            let b = reference.values();
            let round6 = |x: f64| (x * 1e6).round() / 1e6;
            assert_eq!(round6(b[0]), top, "ρ = {rho}");
            assert_eq!(round6(b[1]), bottom, "ρ = {rho}");
            for &s in &b[2..] {
                assert_eq!(round6(s), side, "ρ = {rho}");
            }
            assert!(reference.certificate().certified);
        }
    }
}

#[test]
fn dense_lu_and_certified_gauss_seidel_agree() {
    for (seed, rho_max) in [(1, 0.5), (2, 0.9), (3, 0.99)] {
        let (system, f) = random_system(120, seed, 0.999, rho_max);
        let lu = ReferenceSolution::solve(&system, &f, dense()).unwrap();
        let gs = ReferenceSolution::solve(&system, &f, gauss_seidel()).unwrap();
        assert_eq!(lu.method(), &Method::DenseLu);
        let Method::GaussSeidel { sweeps } = *gs.method() else { panic!("expected Gauss-Seidel, got {}", gs.method()) };
        assert!(sweeps > 1 && sweeps < 2000, "{sweeps} sweeps");
        let scale = lu.values().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (x, y) in lu.values().iter().zip(gs.values()) {
            assert!((x - y).abs() <= 1e-10 * scale, "{x} against {y}");
        }
        for r in [&lu, &gs] {
            let cert = r.certificate();
            assert!(cert.certified && cert.relative_bound <= 1e-10, "{}: {cert}", r.method());
        }
        // LU is exact to round-off; its certificate says so.
        assert!(lu.certificate().relative_bound < 1e-13, "{}", lu.certificate());
    }
}

#[test]
fn solving_a_stored_matrix_gives_the_same_answer() {
    let (system, f) = random_system(50, 4, 0.99, 0.8);
    let m = FormFactors::assemble(&f, usize::MAX).unwrap();
    let direct = ReferenceSolution::solve(&system, &f, dense()).unwrap();
    let stored = ReferenceSolution::solve_matrix(&system, &m, dense()).unwrap();
    assert_eq!(direct, stored);
}

#[test]
fn rows_above_one_are_reported() {
    // Rows sum to 1.1 and ρ = 0.5: κ = 0.55 < 1, so the bound is still proven.
    let f = DenseColumns::from_rows(2, &[0.1, 1.0, 1.0, 0.1]).unwrap();
    let system = LinearSystem::new(Channels::Grey, vec![1.0, 1.0], vec![0.5, 0.5], vec![1.0, 0.0]).unwrap();
    let cert = ReferenceSolution::solve(&system, &f, dense()).unwrap().certificate().clone();
    assert!(cert.certified && !cert.contraction.rows_at_most_one());
    assert_relative_eq!(cert.contraction.kappa[0], 0.55, max_relative = 1e-15);
    assert!(cert.to_string().contains("sums to 1.100000 > 1"), "{cert}");

    // Rows sum to 1.6 and ρ = 0.8: κ = 1.28, no bound.
    let f = DenseColumns::from_rows(2, &[0.0, 1.6, 1.6, 0.0]).unwrap();
    let system = LinearSystem::new(Channels::Grey, vec![1.0, 1.0], vec![0.8, 0.8], vec![1.0, 0.0]).unwrap();
    let cert = ReferenceSolution::solve(&system, &f, dense()).unwrap().certificate().clone();
    assert!(!cert.certified && cert.bound.is_infinite());
    assert!(cert.to_string().starts_with("not certified"), "{cert}");
}

#[test]
fn refused_inputs_are_errors() {
    let (system, f) = furnace();
    let small = DenseColumns::from_fn(4, |_, _| 0.25);
    assert!(matches!(
        ReferenceSolution::solve(&system, &small, dense()),
        Err(EvalError::SizeMismatch { expected: 5, found: 4, .. })
    ));
    let negative = DenseColumns::from_fn(5, |i, j| if (i, j) == (3, 1) { -0.1 } else { 0.1 });
    assert!(matches!(
        ReferenceSolution::solve(&system, &negative, dense()),
        Err(EvalError::InvalidFormFactor { i: 3, j: 1, .. })
    ));
    assert!(matches!(
        ReferenceSolution::solve(&system, &f, dense().with_max_matrix_bytes(100)),
        Err(EvalError::MatrixTooLarge { n: 5, bytes: 200, limit: 100 })
    ));
    assert!(matches!(
        ReferenceSolution::solve(&system, &f, dense().with_certified(0.0)),
        Err(EvalError::InvalidParameter { name: "certified", .. })
    ));
    let (system, f) = random_system(30, 5, 0.999, 0.95);
    let err = ReferenceSolution::solve(&system, &f, gauss_seidel().with_max_sweeps(2)).unwrap_err();
    assert!(matches!(err, EvalError::NotConverged { sweeps: 2, .. }), "{err}");
    assert!(err.to_string().starts_with("Gauss-Seidel reached a relative bound of"), "{err}");
}

#[test]
fn a_stored_reference_reads_back_whole_and_refuses_anything_else() {
    let (system, f) = furnace();
    for params in [dense(), exact_gauss_seidel()] {
        let reference = ReferenceSolution::solve(&system, &f, params).unwrap();
        let bytes = reference.to_bytes("the key");
        assert_eq!(ReferenceSolution::from_bytes(&bytes, "the key", &system).unwrap(), reference);
        let refused =
            |bytes: &[u8], key: &str, system: &LinearSystem| match ReferenceSolution::from_bytes(bytes, key, system) {
                Err(EvalError::StoredReference(why)) => why,
                other => panic!("{other:?}"),
            };
        assert!(refused(&bytes, "another key", &system).contains("computed for 'the key'"));
        // Every truncation and every flipped byte is caught (by the magic, the length or the
        // checksum), never read as a reference.
        for len in 0..bytes.len() {
            refused(&bytes[..len], "the key", &system);
        }
        for at in [0, 20, 30, bytes.len() / 2, bytes.len() - 1] {
            let mut damaged = bytes.clone();
            damaged[at] ^= 0x40;
            refused(&damaged, "the key", &system);
        }
        let grey = LinearSystem::new(Channels::Grey, vec![1.0; 5], vec![0.5; 5], vec![1.0; 5]).unwrap();
        assert!(refused(&bytes, "the key", &grey).contains("size"));
    }
}
