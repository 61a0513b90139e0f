//! A fast operator measured against a trusted one: the figures of `operator_distance` against
//! values worked out independently, and the hierarchical operator on the furnace with its
//! occluder against the closed form `E / (1 − ρ)`; its contraction bounded by two products
//! against the one its assembled matrix gives, and a reference through its products.

use radiosity_core::dense_lu::lu_solve;
use radiosity_core::{ColumnSource, DenseColumns, LinearSystem, Real};
use radiosity_eval::{
    Contraction, FormFactors, Method, NoProgress, OperatorDistanceParams, ReferenceParams, ReferenceSolution,
    ShootingParams, errors_against, operator_distance, solve_by_shooting,
};
use radiosity_ff::{AnalyticColumns, AnalyticParams, HierarchicalColumns, HierarchicalParams};
use radiosity_geom::PreparedScene;

/// `(I − diag(ρ) F) B = E` by LU, one channel.
fn exact(system: &LinearSystem, f: &DenseColumns) -> Vec<Real> {
    let n = system.len();
    let a = |i: usize, j: usize| Real::from(u8::from(i == j)) - system.rho(i, 0) * f.get(i, j);
    lu_solve(n, false, a, |i| system.e(i, 0)).unwrap()
}

#[test]
fn the_distance_of_a_scaled_matrix_is_what_its_solutions_and_rows_say() {
    // F̃ = 0.98 F: every row 2% below, the transfer ρ (F − F̃) B̃ = 0.02 ρ F B̃ on every row,
    // and the two exact solutions by LU.
    let p = PreparedScene::load("furnace:res=3:rho=0.7:block=true").unwrap();
    let system = LinearSystem::from_scene(p.scene());
    let n = system.len();
    let analytic = AnalyticColumns::new(p.scene(), &p.visibility().unwrap(), &p.analysis, AnalyticParams::default());
    let f = DenseColumns::from_fn(n, |i, j| {
        let mut c = vec![0.0; n];
        analytic.fill_column(j, &mut c);
        c[i]
    });
    let scaled = DenseColumns::from_fn(n, |i, j| 0.98 * f.get(i, j));
    let (b, b_scaled) = (exact(&system, &f), exact(&system, &scaled));
    let params = OperatorDistanceParams { rows: n, ..OperatorDistanceParams::default() };
    let d = operator_distance(&system, &scaled, &f, Some(&b), params).unwrap();
    assert!(d.solve.converged && d.solve.residual <= 1e-10, "{:?}", d.solve);
    for (x, y) in d.operator_solution.iter().zip(&b_scaled) {
        assert!((x - y).abs() <= 1e-8 * y.abs(), "B̃ {x} against {y} by LU");
    }
    let e_rms = errors_against(&system, &b, &b_scaled).unwrap().e_rms;
    assert!(e_rms > 1e-3, "the systems differ: {e_rms}");
    assert!((d.solution_e_rms.unwrap() - e_rms).abs() <= 1e-7 * e_rms, "{:?} against {e_rms}", d.solution_e_rms);
    for r in &d.rows.rows {
        assert!((r.relative_l1 - 0.02).abs() < 1e-12 || r.reference_sum == 0.0, "{r:?}");
    }
    // The transfer over every row, worked out here.
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..n {
        let fb: Real = (0..n).map(|j| f.get(i, j) * b_scaled[j]).sum();
        num += system.areas()[i] * (0.02 * system.rho(i, 0) * fb).powi(2);
        den += system.areas()[i] * b_scaled[i] * b_scaled[i];
    }
    let transfer = (num / den).sqrt();
    assert!((d.transfer - transfer).abs() <= 1e-6 * transfer, "{} against {transfer}", d.transfer);
    // Against itself: nothing differs.
    let same = operator_distance(&system, &f, &f, Some(&b), params).unwrap();
    assert_eq!(same.transfer, 0.0);
    assert!(same.solution_e_rms.unwrap() < 1e-9, "{:?}", same.solution_e_rms);
}

#[test]
fn the_hierarchical_operator_keeps_the_furnace_identity_with_an_occluder() {
    // A closed box with a solid block inside, ρ = 0.5 and E = 1 everywhere: B = E / (1 − ρ) = 2
    // on every patch exactly when every row of F sums to 1. The hierarchical operator's own
    // exact solution stays within 1% (e_rms) at its default threshold, with shadow rays
    // deciding the links the block crosses.
    let p = PreparedScene::load("furnace:res=6:block=true").unwrap();
    let system = LinearSystem::from_scene(p.scene());
    let f = HierarchicalColumns::new(p.scene(), &p.visibility().unwrap(), &p.analysis, HierarchicalParams::default());
    assert!(f.figures().rays > 0 && f.figures().far_pairs > 0, "{:?}", f.figures());
    let truth = AnalyticColumns::new(p.scene(), &p.visibility().unwrap(), &p.analysis, AnalyticParams::default());
    let star: Vec<Real> = (0..system.len()).map(|i| system.e(i, 0) / (1.0 - system.rho(i, 0))).collect();
    let params = OperatorDistanceParams { rows: 10, ..OperatorDistanceParams::default() };
    let d = operator_distance(&system, &f, &truth, Some(&star), params).unwrap();
    assert!(d.solve.converged, "{:?}", d.solve);
    let e = d.solution_e_rms.unwrap();
    assert!(e < 1e-2, "e_rms {e} against E / (1 − ρ)");
}

#[test]
fn the_contraction_from_products_bounds_the_one_of_the_assembled_matrix() {
    // The hierarchical operator multiplies natively and is reciprocal to rounding: its two
    // products bound the contraction its assembled matrix gives, from above and within 1e-8,
    // and a `shooting` reference over it runs `gmres-30` through products, certified by that
    // contraction, and lands within its certified bound of the dense solve of the same matrix.
    let p = PreparedScene::load("cornell:res=6").unwrap();
    let system = LinearSystem::from_scene(p.scene());
    let params = HierarchicalParams { eps: 5e-2, ..HierarchicalParams::default() };
    let f = HierarchicalColumns::new(p.scene(), &p.visibility().unwrap(), &p.analysis, params);
    let m = FormFactors::assemble(&f, 1 << 30).unwrap();
    let measured = Contraction::from_matrix(&system, &m).unwrap();
    let bounded = Contraction::from_products(&system, &f).unwrap().expect("the operator multiplies natively");
    assert!(bounded.measured);
    let close = |bound: Real, exact: Real| bound >= exact && bound <= exact * (1.0 + 1e-8);
    assert!(close(bounded.max_row_sum, measured.max_row_sum), "{bounded:?} against {measured:?}");
    for c in 0..measured.kappa.len() {
        assert!(close(bounded.kappa[c], measured.kappa[c]), "channel {c}: {bounded:?} against {measured:?}");
    }
    // A source that multiplies column by column gives none: a product would cost n columns.
    let dense = DenseColumns::from_fn(system.len(), |i, j| m.get(i, j));
    assert_eq!(Contraction::from_products(&system, &dense).unwrap(), None);

    let reference = solve_by_shooting(&system, &f, &ShootingParams::default(), &NoProgress).unwrap();
    match reference.method() {
        Method::Shooting { solver, columns, .. } => assert_eq!((solver.as_str(), *columns), ("gmres-30", 0)),
        other => panic!("{other:?}"),
    }
    let certificate = reference.certificate();
    assert!(certificate.certified && certificate.contraction.measured, "{certificate}");
    let exact = ReferenceSolution::solve_matrix(&system, &m, ReferenceParams::default()).unwrap();
    let k = system.channels().count();
    let (mut error, mut total) = (0.0, 0.0);
    for (idx, (&a, &b)) in reference.values().iter().zip(exact.values()).enumerate() {
        error += system.areas()[idx / k] * (a - b).abs();
        total += system.areas()[idx / k] * b.abs();
    }
    assert!(error / total <= certificate.relative_bound, "{} > {}", error / total, certificate.relative_bound);
    assert!(certificate.relative_bound <= 1e-8, "{certificate}");
}
