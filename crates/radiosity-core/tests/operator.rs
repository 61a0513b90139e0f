//! The radiosity operator: products, residuals and their cost checked against sums written out
//! by hand, and faer's own solvers through the `LinOp` adapter against dense LU.

use approx::assert_relative_eq;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::matrix_free::IdentityPrecond;
use faer::matrix_free::bicgstab::{BicgParams, bicgstab, bicgstab_scratch};
use faer::matrix_free::conjugate_gradient::{CgParams, conjugate_gradient, conjugate_gradient_scratch};
use faer::{Mat, Par};
use radiosity_core::dense_lu::lu_solve;
use radiosity_core::*;

const N: usize = 4;
const AREA: [Real; N] = [1.0, 2.0, 0.5, 3.0];

/// Reciprocal form factors of four patches: `A_i F_ij` is a symmetric matrix `G`, and every
/// row sums to less than 1.
fn form_factors() -> DenseColumns {
    let g = |i: usize, j: usize| if i == j { 0.0 } else { 0.05 * (1 + i + j) as Real * AREA[i].min(AREA[j]) };
    DenseColumns::from_fn(N, |i, j| g(i, j) / AREA[i])
}

/// Three channels with different reflectivities, two emitters.
fn system() -> LinearSystem {
    let rho = [0.5, 0.7, 0.3, 0.9, 0.2, 0.6, 0.4, 0.8, 0.95, 0.1, 0.5, 0.65];
    let e = [1.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 1.0, 0.5];
    LinearSystem::new(Channels::Rgb, AREA.to_vec(), rho.to_vec(), e.to_vec()).unwrap()
}

/// `E + ρ F x − x`, written out entry by entry.
fn residual_by_hand(system: &LinearSystem, f: &DenseColumns, x: &[Real]) -> Vec<Real> {
    let k = 3;
    (0..N * k)
        .map(|idx| {
            let (i, c) = (idx / k, idx % k);
            let fx: Real = (0..N).map(|j| f.get(i, j) * x[j * k + c]).sum();
            system.e(i, c) + system.rho(i, c) * fx - x[idx]
        })
        .collect()
}

#[test]
fn residual_and_product_are_the_sums_written_out() {
    let (system, f) = (system(), form_factors());
    let op = RadiosityOperator::new(&system, &f).unwrap();
    assert_eq!(op.dim(), N * 3);
    let x: Vec<Real> = (0..N * 3).map(|i| 0.3 + 0.1 * i as Real).collect();
    let mut r = vec![0.0; N * 3];
    let cost = op.residual(&x, &mut r);
    for (got, want) in r.iter().zip(residual_by_hand(&system, &f, &x)) {
        assert_relative_eq!(*got, want, max_relative = 1e-14);
    }
    assert_eq!((cost.columns, cost.skipped, cost.native), (N as u64, 0, false));

    // A x = E − r.
    let mut ax = vec![0.0; N * 3];
    op.apply(&x, &mut ax);
    for ((a, r), e) in ax.iter().zip(&r).zip(system.emissions()) {
        assert_relative_eq!(*a, e - r, max_relative = 1e-14);
    }
}

#[test]
fn columns_of_patches_where_the_vector_is_zero_are_left_out() {
    let (system, f) = (system(), form_factors());
    let op = RadiosityOperator::new(&system, &f).unwrap();
    // The emission is zero at patches 1 and 2 in every channel.
    let mut fe = vec![0.0; N * 3];
    let cost = op.f_times(system.emissions(), &mut fe);
    assert_eq!((cost.columns, cost.skipped), (2, 2));
    let (x, k) = (system.emissions(), 3);
    for (idx, got) in fe.iter().enumerate() {
        let want: Real = (0..N).map(|j| f.get(idx / k, j) * x[j * k + idx % k]).sum();
        assert_relative_eq!(*got, want, max_relative = 1e-14);
    }
}

/// A source that multiplies a vector itself, through its rows: what a stored matrix does.
struct Multiplying(DenseColumns);

impl ColumnSource for Multiplying {
    fn patch_count(&self) -> usize {
        self.0.patch_count()
    }
    fn fill_column(&self, j: usize, column: &mut [Real]) {
        self.0.fill_column(j, column)
    }
    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        for (idx, o) in out.iter_mut().enumerate() {
            let (i, c) = (idx / channels, idx % channels);
            *o = (0..N).map(|j| self.0.get(i, j) * x[j * channels + c]).sum();
        }
        true
    }
}

#[test]
fn a_source_that_multiplies_itself_is_used_and_agrees_with_its_columns() {
    let system = system();
    let native = Multiplying(form_factors());
    let x: Vec<Real> = (0..N * 3).map(|i| (i as Real).sin().abs()).collect();
    let (mut by_rows, mut by_columns) = (vec![0.0; N * 3], vec![0.0; N * 3]);
    let cost = RadiosityOperator::new(&system, &native).unwrap().f_times(&x, &mut by_rows);
    assert_eq!((cost.columns, cost.native), (0, true));
    multiply(&native.0, &x, 3, &mut by_columns);
    for (a, b) in by_rows.iter().zip(&by_columns) {
        assert_relative_eq!(*a, *b, max_relative = 1e-14);
    }
}

#[test]
fn a_source_of_another_size_is_refused_in_one_sentence() {
    let system = system();
    let f = DenseColumns::from_fn(N + 1, |_, _| 0.1);
    let error = RadiosityOperator::new(&system, &f).unwrap_err().to_string();
    assert_eq!(error, "the form-factor source's patch count has length 5, expected 4");
}

/// The radiosity of every channel by dense LU.
fn lu_radiosity(system: &LinearSystem, f: &DenseColumns) -> Vec<Real> {
    let k = 3;
    let mut b = vec![0.0; N * k];
    for c in 0..k {
        let a = |i: usize, j: usize| Real::from(u8::from(i == j)) - system.rho(i, c) * f.get(i, j);
        let x = lu_solve(N, false, a, |i| system.e(i, c)).unwrap();
        for i in 0..N {
            b[i * k + c] = x[i];
        }
    }
    b
}

#[test]
fn faer_bicgstab_through_the_operator_finds_the_lu_radiosity() {
    let (system, f) = (system(), form_factors());
    let op = RadiosityOperator::new(&system, &f).unwrap();
    let dim = op.dim();
    let rhs = Mat::from_fn(dim, 1, |i, _| system.emissions()[i]);
    let mut out = Mat::<Real>::zeros(dim, 1);
    let precond = IdentityPrecond { dim };
    let params = BicgParams { max_iters: 200, ..BicgParams::default() };
    let mut buffer = MemBuffer::new(bicgstab_scratch(precond, precond, op, 1, Par::Seq));
    bicgstab(out.as_mut(), precond, precond, op, rhs.as_ref(), params, |_| {}, Par::Seq, MemStack::new(&mut buffer))
        .unwrap();
    for (idx, want) in lu_radiosity(&system, &f).iter().enumerate() {
        assert_relative_eq!(out[(idx, 0)], *want, max_relative = 1e-10);
    }
}

#[test]
fn faer_conjugate_gradients_on_the_symmetrized_operator_find_the_lu_radiosity() {
    let (system, f) = (system(), form_factors());
    let op = SymmetrizedOperator::new(RadiosityOperator::new(&system, &f).unwrap()).unwrap();
    let dim = N * 3;
    let rhs_values = op.rhs();
    let rhs = Mat::from_fn(dim, 1, |i, _| rhs_values[i]);
    let mut out = Mat::<Real>::zeros(dim, 1);
    let precond = IdentityPrecond { dim };
    let params = CgParams { max_iters: 200, ..CgParams::default() };
    let mut buffer = MemBuffer::new(conjugate_gradient_scratch(precond, &op, 1, Par::Seq));
    conjugate_gradient(out.as_mut(), precond, &op, rhs.as_ref(), params, |_| {}, Par::Seq, MemStack::new(&mut buffer))
        .unwrap();
    for (idx, want) in lu_radiosity(&system, &f).iter().enumerate() {
        assert_relative_eq!(out[(idx, 0)], *want, max_relative = 1e-10);
    }
}

#[test]
fn the_symmetrized_operator_refuses_a_patch_that_reflects_nothing() {
    let f = form_factors();
    let system = LinearSystem::new(Channels::Grey, AREA.to_vec(), vec![0.5, 0.0, 0.5, 0.5], vec![1.0; N]).unwrap();
    assert!(SymmetrizedOperator::new(RadiosityOperator::new(&system, &f).unwrap()).is_none());
}
