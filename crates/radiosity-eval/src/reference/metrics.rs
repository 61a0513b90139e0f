//! Error metrics of a radiosity vector against the reference, and its certified error bound.
//!
//! Every metric is about the vector it is given, `b`, patch-major like
//! [`LinearSystem`] (`b[i * channels + c]`), against the exact solution `B*` of the same
//! discrete system ([`ReferenceSolution`]):
//!
//! - `e_rms = sqrt( Σ_c Σ_i A_i (B_ic − B*_ic)² / Σ_c Σ_i A_i B*_ic² )`, area-weighted and
//!   relative: the main convergence curve;
//! - `e_max = max_{i,c} |B_ic − B*_ic| / max_{i,c} B*_ic`;
//! - the residual power `R = Σ_c Σ_i A_i |r_ic| / Σ_c Σ_i A_i E_ic`, with
//!   `r = E + ρ F B − B`;
//! - the certified bound `Σ_c Σ_i A_i |B_ic − B*_ic| ≤ Σ_c ‖r_c‖_A / (1 − q_c)`, with
//!   `‖x‖_A = Σ_i A_i |x_i|`, set beside the true area-weighted L1 error.
//!
//! `e_rms` and `e_max` need only the reference ([`errors`]). The residual needs `F B`, a
//! pass over all `n` columns: [`Residual::from_columns`] streams them from any
//! [`ColumnSource`] (as costly as one Jacobi sweep with a geometric backend: `n` column
//! computations), and [`Evaluator`] reads them from a stored [`FormFactors`] (`2 n²` flops).
//! Either way metric evaluation happens **outside** a solver's timed region: a run records
//! its vectors, and they are measured afterwards.
//!
//! **Which vector.** In shooting methods the residual of the shot radiosity `x` is exactly the
//! unshot `ΔB`, while the residual of the displayed `B = x + ΔB` is `ρ F ΔB` (docs/design.md §6.1).
//! These functions know nothing of that: they measure whatever vector they are handed, so a
//! caller says which vector a figure is about and bounds the error of the vector it reports.
//!
//! The certified bound these metrics carry is [`crate::reference::certificate`]'s.

use crate::error::EvalError;
use crate::reference::certificate::{Contraction, ErrorBound, Residual, from_columns_dyn};
use crate::reference::matrix::{FormFactors, check_sizes, check_vector};
use crate::reference::solution::ReferenceSolution;
use radiosity_core::{ColumnSource, LinearSystem, Real};

/// The errors of a vector against the reference, which need no form factors.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Errors {
    /// `sqrt( Σ_c Σ_i A_i (B_ic − B*_ic)² / Σ_c Σ_i A_i B*_ic² )`.
    pub e_rms: Real,
    /// `max_{i,c} |B_ic − B*_ic| / max_{i,c} B*_ic`.
    pub e_max: Real,
    /// The true area-weighted L1 error `Σ_c Σ_i A_i |B_ic − B*_ic|`.
    pub l1: Real,
    /// The area-weighted L1 norm of the exact answer, `Σ_c Σ_i A_i |B*_ic|`.
    pub reference_l1: Real,
}

/// `e_rms`, `e_max` and the area-weighted L1 error of `b` against `reference`.
///
/// Fails if sizes differ or if the reference is zero everywhere (nothing emits).
pub fn errors(system: &LinearSystem, reference: &ReferenceSolution, b: &[Real]) -> Result<Errors, EvalError> {
    check_reference(system, reference)?;
    errors_against(system, reference.values(), b)
}

/// `e_rms`, `e_max` and the area-weighted L1 error of `b` against any exact answer `star`,
/// patch-major like `b`: a closed form such as the furnace identity, where the reference is
/// itself what is under test.
///
/// Fails if sizes differ or if `star` is zero everywhere.
pub fn errors_against(system: &LinearSystem, star: &[Real], b: &[Real]) -> Result<Errors, EvalError> {
    check_vector(system, Some(b))?;
    check_vector(system, Some(star))?;
    let k = system.channels().count();
    let area = system.areas();
    let (mut num, mut den, mut l1, mut norm, mut max_diff, mut max_ref) = (0.0, 0.0, 0.0, 0.0, 0.0_f64, 0.0_f64);
    for (idx, (&x, &s)) in b.iter().zip(star).enumerate() {
        let a = area[idx / k];
        let d = x - s;
        num += a * d * d;
        den += a * s * s;
        l1 += a * d.abs();
        norm += a * s.abs();
        max_diff = max_diff.max(d.abs());
        max_ref = max_ref.max(s);
    }
    if den == 0.0 || max_ref <= 0.0 {
        return Err(EvalError::ZeroReference);
    }
    Ok(Errors { e_rms: (num / den).sqrt(), e_max: max_diff / max_ref, l1, reference_l1: norm })
}

fn check_reference(system: &LinearSystem, reference: &ReferenceSolution) -> Result<(), EvalError> {
    let expected = system.len() * system.channels().count();
    let found = reference.values().len();
    if found != expected {
        return Err(EvalError::SizeMismatch { what: "the reference solution", expected, found });
    }
    Ok(())
}

/// Every metric of one vector.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Metrics {
    /// Area-weighted relative RMS error.
    pub e_rms: Real,
    /// Largest error relative to the largest reference value.
    pub e_max: Real,
    /// Residual power `R`.
    pub residual: Real,
    /// The true area-weighted L1 error `Σ_c Σ_i A_i |B_ic − B*_ic|`.
    pub l1_error: Real,
    /// The certified bound on `l1_error`.
    pub bound: ErrorBound,
    /// The certified bound relative to the reference's L1 norm, `bound / Σ A |B*|`
    /// (infinite where the bound is not certified).
    pub relative_bound: Real,
}

impl Metrics {
    fn new(errors: Errors, residual: &Residual) -> Metrics {
        Metrics {
            e_rms: errors.e_rms,
            e_max: errors.e_max,
            residual: residual.power(),
            l1_error: errors.l1,
            bound: residual.bound(),
            relative_bound: {
                let b = residual.bound();
                if !b.certified {
                    Real::INFINITY
                } else if b.bound == 0.0 {
                    0.0
                } else {
                    b.bound / errors.reference_l1
                }
            },
        }
    }
}

/// Every metric of `b`, streaming the columns of `f` (`n` column computations).
pub fn evaluate(
    system: &LinearSystem,
    f: &(impl ColumnSource + ?Sized),
    reference: &ReferenceSolution,
    b: &[Real],
) -> Result<Metrics, EvalError> {
    let errors = errors(system, reference, b)?;
    let residual = from_columns_dyn(system, &f, b)?;
    Ok(Metrics::new(errors, &residual))
}

/// Measures many vectors against one reference with a stored matrix: the [`Contraction`] is
/// measured once, and each vector then costs one product `F b` (`2 n²` flops, rows in
/// parallel).
#[derive(Clone, Debug)]
pub struct Evaluator<'a> {
    system: &'a LinearSystem,
    matrix: &'a FormFactors,
    reference: &'a ReferenceSolution,
    contraction: Contraction,
}

impl<'a> Evaluator<'a> {
    /// Prepares to measure vectors of `system` against `reference`, with `F` stored in `matrix`.
    pub fn new(
        system: &'a LinearSystem,
        matrix: &'a FormFactors,
        reference: &'a ReferenceSolution,
    ) -> Result<Evaluator<'a>, EvalError> {
        let contraction = Contraction::from_matrix(system, matrix)?;
        Evaluator::with_contraction(system, matrix, reference, contraction)
    }

    /// As [`Evaluator::new`], with the contraction of `matrix` already measured (the
    /// reference's certificate carries it), so that no `n²` pass is repeated.
    pub fn with_contraction(
        system: &'a LinearSystem,
        matrix: &'a FormFactors,
        reference: &'a ReferenceSolution,
        contraction: Contraction,
    ) -> Result<Evaluator<'a>, EvalError> {
        check_reference(system, reference)?;
        check_sizes(system, matrix.patch_count(), None)?;
        Ok(Evaluator { system, matrix, reference, contraction })
    }

    /// The contraction measured once for every vector.
    pub fn contraction(&self) -> &Contraction {
        &self.contraction
    }

    /// The residual of `b`.
    pub fn residual(&self, b: &[Real]) -> Result<Residual, EvalError> {
        Residual::with_contraction(self.system, self.matrix, self.contraction.clone(), b)
    }

    /// Every metric of `b`.
    pub fn evaluate(&self, b: &[Real]) -> Result<Metrics, EvalError> {
        let errors = errors(self.system, self.reference, b)?;
        Ok(Metrics::new(errors, &self.residual(b)?))
    }
}
