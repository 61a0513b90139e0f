//! The linear operator of the radiosity system: `F·x`, `A·x = (I − diag(ρ) F)·x` and the
//! residual `E − A·x`, over any [`ColumnSource`].
//!
//! ## Rule
//!
//! Vectors are patch-major with the system's channels (`x[i * k + c]`), the layout of
//! [`LinearSystem`]. Per channel the system is `A B = E` with `A = I − diag(ρ) F`
//! (docs/design.md §3.1); over all channels `A` is block diagonal, so one operator of dimension
//! `n·k` serves every channel at once, and one column of `F` serves every channel of a product.
//!
//! `F·x` is what a source multiplies itself when it can do so cheaper than `n` columns
//! ([`ColumnSource::multiply`]: one pass over a stored matrix's entries); otherwise it is the
//! sum of the columns `F_{·j} x_j` in index order, leaving out the columns of patches where
//! `x` is zero in every channel (their terms are zero, so no value changes). What a product
//! cost comes back as a [`Product`]. Each row is summed in a fixed order, whatever the thread
//! count, so products are deterministic.
//!
//! This is the seam every solver, metric and reference multiplies through: the Krylov
//! solvers apply `A`, the metrics take the residual, and a backend that multiplies faster
//! than it gives columns (a stored matrix, a hierarchical operator) serves them all by
//! implementing [`ColumnSource::multiply`]. A researcher reaches it as they would scipy's
//! `LinearOperator`; [`crate::faer_operator`] hands it to faer's matrix-free solvers.
//!
//! ## References
//!
//! - Saad 2003, *Iterative Methods for Sparse Linear Systems*, 2nd ed., SIAM, ch. 6–7
//!   (operators used only through their products).

use crate::column::ColumnSource;
use crate::error::CoreError;
use crate::math::Real;
use crate::system::LinearSystem;

/// What one product by `F` cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct Product {
    /// Columns fetched from the source (0 when it multiplied itself).
    pub columns: u64,
    /// Columns left out because `x` was zero at their patch in every channel.
    pub skipped: u64,
    /// Whether the source multiplied the vector itself ([`ColumnSource::multiply`]).
    pub native: bool,
}

impl Product {
    /// A product the source computed itself: no column fetched.
    pub fn native() -> Product {
        Product { native: true, ..Product::default() }
    }
}

/// `A = I − diag(ρ) F` of a [`LinearSystem`] over a [`ColumnSource`], applied through
/// products by `F` (module doc).
#[derive(Clone, Copy)]
pub struct RadiosityOperator<'a> {
    system: &'a LinearSystem,
    f: &'a dyn ColumnSource,
}

impl std::fmt::Debug for RadiosityOperator<'_> {
    fn fmt(&self, out: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        out.debug_struct("RadiosityOperator")
            .field("patches", &self.system.len())
            .field("channels", &self.channels())
            .finish()
    }
}

impl<'a> RadiosityOperator<'a> {
    /// The operator of `system` with the form factors of `f`; refuses a source whose patch
    /// count is not the system's.
    pub fn new(system: &'a LinearSystem, f: &'a dyn ColumnSource) -> Result<RadiosityOperator<'a>, CoreError> {
        if f.patch_count() != system.len() {
            return Err(CoreError::SizeMismatch {
                what: "the form-factor source's patch count",
                expected: system.len(),
                found: f.patch_count(),
            });
        }
        Ok(RadiosityOperator { system, f })
    }

    /// The system it belongs to.
    pub fn system(&self) -> &'a LinearSystem {
        self.system
    }

    /// The form factors it multiplies by.
    pub fn source(&self) -> &'a dyn ColumnSource {
        self.f
    }

    /// The channels `k` of every vector.
    pub fn channels(&self) -> usize {
        self.system.channels().count()
    }

    /// The length `n·k` of every vector.
    pub fn dim(&self) -> usize {
        self.system.len() * self.channels()
    }

    /// `out = F x` (module doc).
    ///
    /// # Panics
    ///
    /// When `x` or `out` is not of length [`RadiosityOperator::dim`].
    pub fn f_times(&self, x: &[Real], out: &mut [Real]) -> Product {
        multiply(self.f, x, self.channels(), out)
    }

    /// `out = A x = x − ρ F x`.
    ///
    /// # Panics
    ///
    /// When `x` or `out` is not of length [`RadiosityOperator::dim`].
    pub fn apply(&self, x: &[Real], out: &mut [Real]) -> Product {
        let product = self.f_times(x, out);
        apply_from_product(self.system, x, out);
        product
    }

    /// `out = E − A x = E + ρ F x − x`, the residual of `x`.
    ///
    /// # Panics
    ///
    /// When `x` or `out` is not of length [`RadiosityOperator::dim`].
    pub fn residual(&self, x: &[Real], out: &mut [Real]) -> Product {
        let product = self.f_times(x, out);
        residual_from_product(self.system, x, out);
        product
    }
}

/// Turns `fx = F x` into `A x = x − ρ F x`, in place: for callers that computed the product
/// themselves ([`multiply_by_columns`]).
///
/// # Panics
///
/// When `x` or `fx` is not of length `n·k`.
pub fn apply_from_product(system: &LinearSystem, x: &[Real], fx: &mut [Real]) {
    let rho = system.reflectivities();
    assert!(x.len() == rho.len() && fx.len() == rho.len(), "vectors of length n·k");
    for ((o, &xv), &r) in fx.iter_mut().zip(x).zip(rho) {
        *o = xv - r * *o;
    }
}

/// Turns `fx = F x` into the residual `E + ρ F x − x` of `x`, in place: for callers that
/// computed the product in a pass of their own (a metric that measures more on the way).
///
/// # Panics
///
/// When `x` or `fx` is not of length `n·k`.
pub fn residual_from_product(system: &LinearSystem, x: &[Real], fx: &mut [Real]) {
    let (e, rho) = (system.emissions(), system.reflectivities());
    assert!(x.len() == e.len() && fx.len() == e.len(), "vectors of length n·k");
    for (((r, &xv), &ev), &rv) in fx.iter_mut().zip(x).zip(e).zip(rho) {
        *r = ev + rv * *r - xv;
    }
}

/// `out = F x` through `f` (module doc), `x` and `out` patch-major with `channels` channels.
///
/// # Panics
///
/// When `x` or `out` is not of length `f.patch_count() · channels`.
pub fn multiply(f: &(impl ColumnSource + ?Sized), x: &[Real], channels: usize, out: &mut [Real]) -> Product {
    multiply_dyn(&f, x, channels, out)
}

fn multiply_dyn(f: &dyn ColumnSource, x: &[Real], k: usize, out: &mut [Real]) -> Product {
    let n = f.patch_count();
    assert!(x.len() == n * k && out.len() == n * k, "vectors of length n·k");
    if f.multiply(x, k, out) {
        return Product::native();
    }
    let mut column = vec![0.0; n];
    multiply_by_columns(x, k, out, &mut column, |j, column| f.fill_column(j, column))
}

/// `out = F x` as the sum of the columns `F_{·j} x_j` in index order, each fetched by
/// `fetch(j, column)` into `column` (of length `n`), leaving out the columns of patches where
/// `x` is zero in every channel (module doc): the product by columns, for a caller that
/// fetches columns its own way (a solver's counted problem).
///
/// # Panics
///
/// When `x` or `out` is not of length `column.len() · channels`.
pub fn multiply_by_columns(
    x: &[Real],
    channels: usize,
    out: &mut [Real],
    column: &mut [Real],
    mut fetch: impl FnMut(usize, &mut [Real]),
) -> Product {
    let k = channels;
    assert!(x.len() == column.len() * k && out.len() == x.len(), "vectors of length n·k");
    out.fill(0.0);
    let mut product = Product::default();
    for (j, xj) in x.chunks_exact(k).enumerate() {
        if xj.iter().all(|v| *v == 0.0) {
            product.skipped += 1;
            continue;
        }
        fetch(j, column);
        product.columns += 1;
        for (&fij, o) in column.iter().zip(out.chunks_exact_mut(k)) {
            if fij != 0.0 {
                for (o, v) in o.iter_mut().zip(xj) {
                    *o += fij * v;
                }
            }
        }
    }
    product
}
