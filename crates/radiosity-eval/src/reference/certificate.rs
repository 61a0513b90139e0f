//! The certified error bound of a radiosity vector, with no reference needed: the
//! contraction of `diag(ρ) F` it rests on, the residual it is built from, and the bound a
//! solver's own residual knowledge gives ([`SolverBound`]).
//!
//!
//! ## Rule
//!
//! Per channel, `r = E + ρFB − B = −Φ (B − B*)` with `Φ = I − diag(ρ) F`, so
//! `B − B* = −Φ⁻¹ r`. In the area-weighted L1 norm, for `F ≥ 0`,
//! `‖diag(ρ) F x‖_A ≤ κ_c ‖x‖_A` with `κ_c = max_j Σ_i A_i ρ_ic F_ij / A_j`, and when
//! `κ_c < 1` the Neumann series gives `‖B − B*‖_A ≤ ‖r‖_A / (1 − κ_c)`.
//!
//! The bound is often stated as `Σ A_i |r_i| / (1 − ρ_max)` "when rows sum to at most 1".
//! That hypothesis alone is not quite enough: the step `κ_c ≤ ρ_max` also uses reciprocity
//! (`Σ_i A_i F_ij = A_j Σ_i F_ji ≤ A_j`), which numerical backends satisfy only
//! approximately. So this module measures `κ_c` from the columns themselves and uses
//! `q_c = max(ρ_max,c, κ_c)`:
//!
//! - when rows sum to at most 1 and reciprocity holds, `κ_c ≤ ρ_max,c` and the bound is that
//!   familiar one, taken per channel (never larger than with one `ρ_max` for all channels);
//! - when they do not, the bound is still proven as long as `q_c < 1`;
//! - when some `q_c ≥ 1` there is no bound: [`ErrorBound::certified`] is false and
//!   [`ErrorBound::bound`] is infinite.
//!
//! `κ_c` alone gives the sharper, equally proven [`ErrorBound::sharp`]. The familiar form is
//! kept as the headline figure because it is the one usually stated and computed elsewhere
//! (docs/design.md §6.3 gives both); on a random enclosure with `ρ` spread over `[0, 0.95]`
//! it overestimated a Jacobi iterate's error 14 times where the sharp bound did 1.4–1.5 times
//! (see the test `the_certified_bound_bounds_the_true_error`). In a closed scene with uniform
//! `ρ` both are attained: all the error decays at the rate `ρ`. The maximum row sum is
//! reported in any case ([`Contraction::max_row_sum`]), since the usual hypothesis is stated on
//! it.

use crate::error::EvalError;
use crate::reference::matrix::{FormFactors, Pass, check_sizes, kappa_matrix, pass_columns};
use radiosity_core::{ColumnSource, LinearSystem, RadiosityOperator, Real, residual_from_product};
use radiosity_solvers::ResidualBound;

/// How strongly `diag(ρ) F` can amplify a vector in the area-weighted L1 norm, per channel,
/// and whether the certified bound holds.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Contraction {
    /// `max_i Σ_j F_ij`: at most 1 in a scene that loses no energy (up to round-off).
    pub max_row_sum: Real,
    /// Per channel, `max_i ρ_ic`.
    pub rho_max: Vec<Real>,
    /// Per channel, `κ_c = max_j Σ_i A_i ρ_ic F_ij / A_j`, the norm of `diag(ρ_c) F` in the
    /// area-weighted L1 norm.
    pub kappa: Vec<Real>,
    /// Whether `max_row_sum` and `kappa` were measured on the matrix; when not
    /// ([`Contraction::assumed`]), they are the hypothesis of
    /// docs/design.md §6.3, and every bound built on them holds under it.
    pub measured: bool,
}

impl Contraction {
    fn new(system: &LinearSystem, max_row_sum: Real, kappa: Vec<Real>) -> Contraction {
        Contraction { max_row_sum, rho_max: rho_max(system), kappa, measured: true }
    }

    /// The contraction the hypothesis of docs/design.md §6.3 gives without looking at `F`:
    /// rows sum to at most 1 and `F` is reciprocal (`A_i F_ij = A_j F_ji`), so that
    /// `κ_c = max_j Σ_i ρ_ic F_ji ≤ ρ_max,c`. What runs without a stored matrix bound their
    /// error with; the analytic backend is exactly reciprocal and its rows sum to 1 within its
    /// stated accuracy (`cargo xtask ff` measures both).
    pub fn assumed(system: &LinearSystem) -> Contraction {
        let rho_max = rho_max(system);
        Contraction { max_row_sum: 1.0, kappa: rho_max.clone(), rho_max, measured: false }
    }

    /// Measures the contraction of `system` with the stored matrix `m` (`n²` reads).
    pub fn from_matrix(system: &LinearSystem, m: &FormFactors) -> Result<Contraction, EvalError> {
        check_sizes(system, m.patch_count(), None)?;
        Ok(Contraction::new(system, m.max_row_sum(), kappa_matrix(system, m)))
    }

    /// Measures the contraction of `system` from two products by a source that multiplies a
    /// whole vector itself ([`ColumnSource::multiply`], the hierarchical operator's
    /// `O(links + n)`) and states a reciprocity bound `δ`. Reciprocity within `δ` gives
    /// `A_i F_ij ≤ A_j F_ji / (1 − δ)`, so `κ_c = max_j Σ_i A_i ρ_ic F_ij / A_j ≤
    /// max_j (F ρ_c)_j / (1 − δ)`: one product by the reflectivities, and one by ones for
    /// `max_row_sum`. Both are raised by a relative [`PRODUCT_SLACK`] for the rounding of the
    /// products' sums, so the contraction is an upper bound and the certificate stays proven.
    /// `None` when the source multiplies column by column (`n` columns a product: a stored
    /// matrix is measured with [`Contraction::from_matrix`]) or states no reciprocity bound.
    pub fn from_products(system: &LinearSystem, f: &dyn ColumnSource) -> Result<Option<Contraction>, EvalError> {
        check_sizes(system, f.patch_count(), None)?;
        let Some(delta) = f.reciprocity_bound().filter(|&d| d < 1.0) else { return Ok(None) };
        let n = system.len();
        let mut sums = vec![0.0; n];
        if !f.multiply(&vec![1.0; n], 1, &mut sums) {
            return Ok(None);
        }
        let k = system.channels().count();
        let mut gathered = vec![0.0; n * k];
        if !f.multiply(system.reflectivities(), k, &mut gathered) {
            return Ok(None);
        }
        let up = 1.0 + PRODUCT_SLACK;
        let max_row_sum = up * sums.iter().copied().fold(0.0, Real::max);
        let mut kappa = vec![0.0_f64; k];
        for (idx, &v) in gathered.iter().enumerate() {
            kappa[idx % k] = kappa[idx % k].max(up * v / (1.0 - delta));
        }
        Ok(Some(Contraction::new(system, max_row_sum, kappa)))
    }

    /// `q_c = max(ρ_max,c, κ_c)`, the factor of channel `c`: the bound is
    /// `‖r_c‖_A / (1 − q_c)`.
    pub fn factor(&self, c: usize) -> Real {
        self.rho_max[c].max(self.kappa[c])
    }

    /// The largest factor over the channels.
    pub fn max_factor(&self) -> Real {
        (0..self.kappa.len()).map(|c| self.factor(c)).fold(0.0, Real::max)
    }

    /// True when every factor is below 1, so that [`Residual::bound`] is a proven bound.
    pub fn certified(&self) -> bool {
        self.max_factor() < 1.0
    }

    /// True when every row of `F` sums to at most 1, the hypothesis stated in
    /// docs/design.md §6.3 (with reciprocity it implies `κ_c ≤ ρ_max,c`).
    pub fn rows_at_most_one(&self) -> bool {
        self.max_row_sum <= 1.0
    }
}

/// The relative slack [`Contraction::from_products`] adds to what its products measured: a
/// product's sums are rounded, and a native product (the hierarchical operator's moments)
/// sums in another order than the entries, some `1e-13` of the value apart; `1e-9` is ample.
pub const PRODUCT_SLACK: Real = 1e-9;

/// Per channel, `max_i ρ_ic`.
fn rho_max(system: &LinearSystem) -> Vec<Real> {
    let k = system.channels().count();
    let mut rho_max = vec![0.0_f64; k];
    for (idx, &r) in system.reflectivities().iter().enumerate() {
        rho_max[idx % k] = rho_max[idx % k].max(r);
    }
    rho_max
}

/// A certified bound on the area-weighted L1 error of a vector.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ErrorBound {
    /// `Σ_c ‖r_c‖_A / (1 − q_c)` with `q_c = max(ρ_max,c, κ_c)`: the design's bound, per
    /// channel; infinite when not certified.
    pub bound: Real,
    /// `Σ_c ‖r_c‖_A / (1 − κ_c)`: never larger than `bound`, and as rigorous. It is much
    /// tighter when reflectivities vary (the design's bound pays `1/(1 − ρ_max)` for the
    /// most reflective patch everywhere). Infinite when some `κ_c ≥ 1`.
    pub sharp: Real,
    /// Whether `bound` (and so `sharp`) is proven: every `q_c < 1`, see [`Contraction`].
    pub certified: bool,
}

/// The residual `r = E + ρ F b − b` of a vector `b`, per channel, patch-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Residual {
    values: Vec<Real>,
    norms: Vec<Real>,
    emitted: Real,
    contraction: Contraction,
}

impl Residual {
    /// The residual of `b`, streaming the `n` columns of `f` (in parallel blocks, `O(n)`
    /// memory). With a geometric backend this costs `n` column computations.
    pub fn from_columns(
        system: &LinearSystem,
        f: &(impl ColumnSource + ?Sized),
        b: &[Real],
    ) -> Result<Residual, EvalError> {
        from_columns_dyn(system, &f, b)
    }

    /// The residual of `b` from a stored matrix. Measures the [`Contraction`] too (`n²`
    /// reads); an [`Evaluator`](crate::Evaluator) measures it once for many vectors.
    pub fn from_matrix(system: &LinearSystem, m: &FormFactors, b: &[Real]) -> Result<Residual, EvalError> {
        let contraction = Contraction::from_matrix(system, m)?;
        Residual::with_contraction(system, m, contraction, b)
    }

    pub(crate) fn with_contraction(
        system: &LinearSystem,
        m: &FormFactors,
        contraction: Contraction,
        b: &[Real],
    ) -> Result<Residual, EvalError> {
        check_sizes(system, m.patch_count(), Some(b))?;
        let operator = RadiosityOperator::new(system, m).map_err(|_| EvalError::SizeMismatch {
            what: "the form-factor matrix",
            expected: system.len(),
            found: m.patch_count(),
        })?;
        let mut values = vec![0.0; b.len()];
        // The stored matrix multiplies itself: one pass over its entries.
        operator.residual(b, &mut values);
        Ok(Residual::finish(system, values, contraction))
    }

    /// The residual whose values `E + ρ F b − b` are given, with their norms.
    fn finish(system: &LinearSystem, values: Vec<Real>, contraction: Contraction) -> Residual {
        let k = system.channels().count();
        let (e, area) = (system.emissions(), system.areas());
        let mut norms = vec![0.0; k];
        let mut emitted = 0.0;
        for (idx, r) in values.iter().enumerate() {
            norms[idx % k] += area[idx / k] * r.abs();
            emitted += area[idx / k] * e[idx];
        }
        Residual { values, norms, emitted, contraction }
    }

    /// `r_ic` at `i * channels + c`.
    pub fn values(&self) -> &[Real] {
        &self.values
    }

    /// `Σ_c Σ_i A_i |r_ic|`.
    pub fn norm(&self) -> Real {
        self.norms.iter().sum()
    }

    /// Per channel, `‖r_c‖_A = Σ_i A_i |r_ic|`.
    pub fn channel_norms(&self) -> &[Real] {
        &self.norms
    }

    /// The residual power `R = Σ_c Σ_i A_i |r_ic| / Σ_c Σ_i A_i E_ic` (infinite or NaN when
    /// nothing emits).
    pub fn power(&self) -> Real {
        self.norm() / self.emitted
    }

    /// The contraction the bound is built on.
    pub fn contraction(&self) -> &Contraction {
        &self.contraction
    }

    /// The certified bound on `Σ_c Σ_i A_i |b_ic − B*_ic|`.
    pub fn bound(&self) -> ErrorBound {
        let sum = |q: &dyn Fn(usize) -> Real| -> Real {
            let q_max = (0..self.norms.len()).map(q).fold(0.0, Real::max);
            if q_max >= 1.0 {
                return Real::INFINITY;
            }
            self.norms.iter().enumerate().map(|(c, r)| r / (1.0 - q(c))).sum()
        };
        let sharp = sum(&|c| self.contraction.kappa[c]);
        ErrorBound { bound: sum(&|c| self.contraction.factor(c)), sharp, certified: self.contraction.certified() }
    }
}

pub(crate) fn from_columns_dyn(system: &LinearSystem, f: &dyn ColumnSource, b: &[Real]) -> Result<Residual, EvalError> {
    check_sizes(system, f.patch_count(), Some(b))?;
    // One streaming pass gives F b and, on the way, what the contraction needs.
    let Pass { mut fb, max_row_sum, kappa } = pass_columns(system, f, b)?;
    let contraction = Contraction::new(system, max_row_sum, kappa);
    residual_from_product(system, b, &mut fb);
    Ok(Residual::finish(system, fb, contraction))
}

/// The certified bound on the error of a displayed radiosity from what its solver knows
/// without extra columns ([`ResidualBound`]), and a contraction: measured on a stored matrix,
/// or the hypothesis of docs/design.md §6.3 ([`Contraction::assumed`]).
///
/// Per channel `‖r_c‖_A ≤ κ_c ‖d_c‖_A + ‖e_c‖_A` ([`ResidualBound::residual_norm`]), and
/// `Σ_c ‖B_c − B*_c‖_A ≤ Σ_c ‖r_c‖_A / (1 − κ_c)`, since `‖(I − ρ_c F)⁻¹‖_A ≤ 1 / (1 − κ_c)`
/// when `κ_c = ‖ρ_c F‖_A < 1` (the `sharp` form of [`Residual::bound`]; with
/// [`Contraction::assumed`], `κ_c = ρ_max,c` and this is the certificate of
/// docs/design.md §6.3). The relative figure needs no reference:
/// `‖B*‖_A ≥ ‖B‖_A − ‖B − B*‖_A` and `B* ≥ E` elementwise, and when the solver knows its
/// residual is non-negative ([`ResidualBound::nonnegative`]) `B* ≥ B`, so `‖B*‖_A ≥ Σ A B`;
/// the bound is divided by the largest of the three. It is therefore the same number with or
/// without a reference, and a run with `--reference none` reports what one with a reference does
/// (but for the contraction, measured on a stored matrix).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct SolverBound {
    /// The bound on `Σ_c Σ_i A_i |B_ic − B*_ic|` (infinite when some `q_c ≥ 1`).
    pub absolute: Real,
    /// The bound on that error relative to `Σ_c Σ_i A_i |B*_ic|`.
    pub relative: Real,
}

impl SolverBound {
    /// The bound on the displayed radiosity `b` (patch-major, like `system`'s vectors).
    pub fn new(system: &LinearSystem, contraction: &Contraction, known: &ResidualBound, b: &[Real]) -> SolverBound {
        let k = system.channels().count();
        let mut absolute = 0.0;
        for c in 0..k.min(known.channels()) {
            let q = contraction.kappa[c];
            if q >= 1.0 {
                absolute = Real::INFINITY;
                break;
            }
            absolute += known.residual_norm(c, q) / (1.0 - q);
        }
        let relative = relative_without_reference(system, absolute, b, known.nonnegative);
        SolverBound { absolute, relative }
    }
}

/// `absolute`, a bound on `Σ A |b − B*|`, relative to a lower bound on `Σ A |B*|` that needs no
/// reference: the largest of `Σ A |b| − absolute` (the triangle inequality), `Σ A E`
/// (`B* = Σ_k (ρ F)^k E ≥ E`, every term non-negative) and, when `below` (`b ≤ B*`
/// elementwise, [`ResidualBound::nonnegative`]), `Σ A b`. 0 when `absolute` is; infinite
/// when the lower bound is not positive.
pub(crate) fn relative_without_reference(system: &LinearSystem, absolute: Real, b: &[Real], below: bool) -> Real {
    if absolute == 0.0 {
        return 0.0;
    }
    let k = system.channels().count();
    let area = system.areas();
    let norm: Real = b.iter().enumerate().map(|(idx, v)| area[idx / k] * v.abs()).sum();
    let emitted: Real = system.emissions().iter().enumerate().map(|(idx, e)| area[idx / k] * e.abs()).sum();
    let signed: Real = if below { b.iter().enumerate().map(|(idx, v)| area[idx / k] * v).sum() } else { 0.0 };
    let lower = (norm - absolute).max(emitted).max(signed);
    if lower > 0.0 { absolute / lower } else { Real::INFINITY }
}
