//! The reference solution `B*`: the exact solution of the same discrete system, with a
//! certificate of how exact it is.
//!
//! Convergence curves measure a solver, not the form factors, so `B*` solves the **same**
//! system the solvers see, `(I − diag(ρ_c) F) B_c = E_c` for each channel `c`, with the same
//! columns of `F` ([`ColumnSource`]). `F` is fetched once into a [`FormFactors`] (every
//! column, in parallel, in a fixed order) and then solved one of two ways:
//!
//! - **Dense LU** for `n ≤ dense_limit` (default 4000): per channel, `I − diag(ρ_c) F` is
//!   factored by LU with partial pivoting and solved for `E_c`; channels run in parallel,
//!   each factorisation sequentially, so the answer does not depend on the thread count.
//! - **Gauss–Seidel** above it, on all channels at once, from `B = E`, until the certified
//!   relative bound `Σ_c ‖r_c‖_A / (1 − q_c) / Σ_c ‖B_c‖_A` falls below
//!   `certified` (default `1e-10`; see [`crate::reference::metrics`] for the bound). The stop
//!   test uses the rigorous estimate `‖r_c‖_A ≤ κ_c ‖ΔB_c‖_A` of the last sweep's change and is
//!   confirmed by the exact residual. The dense `f64` matrix needs `8 n²` bytes, refused
//!   above `max_matrix_bytes` (default 8 GiB, n ≈ 32 000); a later stored-matrix backend
//!   can serve rows instead.
//!
//! Either way [`ReferenceSolution::certificate`] reports the bound evaluated for `B*` itself,
//! from its own residual, and says whether it is certified.
//!
//! # Why faer
//!
//! Dense LU with partial pivoting (faer) rather than nalgebra: faer is several times faster at
//! n = 480 and over ten times at n = 3400 (`cargo bench -p radiosity-eval --bench lu`, figures
//! in `docs/references.md`). Each factorisation runs sequentially and the channels run in
//! parallel instead: results then cannot depend on the thread count, and an RGB system keeps
//! both cores busy.
//!
//! [`ColumnSource`]: radiosity_core::ColumnSource

use crate::error::EvalError;
use crate::reference::certificate::{Contraction, Residual};
use crate::reference::matrix::{FormFactors, check_sizes};
use radiosity_core::dense_lu::{SingularPivot, lu_solve};
use radiosity_core::{Channels, ColumnSource, LinearSystem, Real};
use rayon::prelude::*;
use std::fmt;

/// How a reference is computed.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct ReferenceParams {
    /// Largest `n` solved by dense LU; larger systems use Gauss–Seidel. Default 4000.
    pub dense_limit: usize,
    /// The certified relative bound Gauss–Seidel must reach. Default `1e-10`.
    pub certified: Real,
    /// Gauss–Seidel sweeps allowed before giving up. Default 20 000.
    pub max_sweeps: usize,
    /// Largest dense form-factor matrix held in memory, in bytes. Default 8 GiB.
    pub max_matrix_bytes: usize,
}

impl Default for ReferenceParams {
    fn default() -> Self {
        ReferenceParams { dense_limit: 4000, certified: 1e-10, max_sweeps: 20_000, max_matrix_bytes: 8 << 30 }
    }
}

impl ReferenceParams {
    /// Sets [`ReferenceParams::dense_limit`].
    pub fn with_dense_limit(mut self, dense_limit: usize) -> Self {
        self.dense_limit = dense_limit;
        self
    }

    /// Sets [`ReferenceParams::certified`].
    pub fn with_certified(mut self, certified: Real) -> Self {
        self.certified = certified;
        self
    }

    /// Sets [`ReferenceParams::max_sweeps`].
    pub fn with_max_sweeps(mut self, max_sweeps: usize) -> Self {
        self.max_sweeps = max_sweeps;
        self
    }

    /// Sets [`ReferenceParams::max_matrix_bytes`].
    pub fn with_max_matrix_bytes(mut self, max_matrix_bytes: usize) -> Self {
        self.max_matrix_bytes = max_matrix_bytes;
        self
    }

    fn validate(&self) -> Result<(), EvalError> {
        if !(self.certified.is_finite() && self.certified > 0.0) {
            let value = self.certified.to_string();
            return Err(EvalError::InvalidParameter {
                name: "certified",
                value,
                reason: "it must be finite and positive",
            });
        }
        if self.max_sweeps == 0 {
            let value = "0".to_string();
            return Err(EvalError::InvalidParameter { name: "max_sweeps", value, reason: "it must be at least 1" });
        }
        Ok(())
    }
}

/// How a reference was computed.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Method {
    /// Dense LU with partial pivoting (faer), one factorisation per channel.
    DenseLu,
    /// Gauss–Seidel on the full system.
    GaussSeidel {
        /// Sweeps done (each reads all of `F` once).
        sweeps: usize,
    },
    /// A long run of a shooting solver over the backend's columns, without a matrix
    /// ([`crate::solve_by_shooting`]).
    Shooting {
        /// The solver, as on the command line.
        solver: String,
        /// Steps taken.
        steps: u64,
        /// Columns computed.
        columns: u64,
    },
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Method::DenseLu => write!(f, "dense LU with partial pivoting (faer)"),
            Method::GaussSeidel { sweeps } => write!(f, "Gauss-Seidel, {sweeps} sweeps"),
            Method::Shooting { solver, steps, columns } => {
                write!(f, "{solver} without a matrix, {steps} steps, {columns} columns")
            }
        }
    }
}

/// The bound on `B*`'s own error, from its own residual.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Certificate {
    /// `Σ_c Σ_i A_i |r_ic|` for `r = E + ρ F B* − B*`.
    pub residual_norm: Real,
    /// The bound on `Σ_c Σ_i A_i |B*_ic − B_ic|` against the exact solution (infinite when
    /// not certified).
    pub bound: Real,
    /// `bound / Σ_c Σ_i A_i |B*_ic|` (0 when both are 0).
    pub relative_bound: Real,
    /// Whether the bound is proven; see [`Contraction`].
    pub certified: bool,
    /// The contraction the bound rests on, with the maximum row sum.
    pub contraction: Contraction,
}

impl fmt::Display for Certificate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.certified {
            write!(f, "certified relative L1 error ≤ {:.3e}", self.relative_bound)?;
        } else {
            write!(f, "not certified (contraction {:.6} ≥ 1)", self.contraction.max_factor())?;
        }
        if !self.contraction.measured {
            return write!(f, ", if rows of F sum to at most 1 and F is reciprocal (assumed, not measured)");
        }
        let rows = self.contraction.max_row_sum;
        if self.contraction.rows_at_most_one() {
            write!(f, "; rows of F sum to at most {rows:.6}")
        } else {
            write!(f, "; some row of F sums to {rows:.6} > 1")
        }
    }
}

/// The exact solution `B*` of the discrete system, patch-major like [`LinearSystem`].
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceSolution {
    channels: Channels,
    n: usize,
    values: Vec<Real>,
    method: Method,
    certificate: Certificate,
}

impl ReferenceSolution {
    /// Fetches every column of `f` once and solves `system` exactly (dense LU or certified
    /// Gauss–Seidel, by `params.dense_limit`).
    pub fn solve(
        system: &LinearSystem,
        f: &(impl ColumnSource + ?Sized),
        params: ReferenceParams,
    ) -> Result<ReferenceSolution, EvalError> {
        solve_dyn(system, &f, &params)
    }

    /// Solves `system` with a matrix already stored (which can then serve an
    /// [`Evaluator`](crate::Evaluator) too).
    pub fn solve_matrix(
        system: &LinearSystem,
        m: &FormFactors,
        params: ReferenceParams,
    ) -> Result<ReferenceSolution, EvalError> {
        params.validate()?;
        check_sizes(system, m.patch_count(), None)?;
        let contraction = Contraction::from_matrix(system, m)?;
        let (values, method) = if system.len() <= params.dense_limit {
            (dense_lu(system, m)?, Method::DenseLu)
        } else {
            let (values, sweeps) = gauss_seidel(system, m, &contraction, &params)?;
            (values, Method::GaussSeidel { sweeps })
        };
        let residual = Residual::with_contraction(system, m, contraction, &values)?;
        let bound = residual.bound();
        let norm: Real = values.iter().enumerate().map(|(idx, v)| system.areas()[idx / k(system)] * v.abs()).sum();
        let relative_bound = if bound.bound == 0.0 { 0.0 } else { bound.bound / norm };
        let certificate = Certificate {
            residual_norm: residual.norm(),
            bound: bound.bound,
            relative_bound,
            certified: bound.certified,
            contraction: residual.contraction().clone(),
        };
        Ok(ReferenceSolution { channels: system.channels(), n: system.len(), values, method, certificate })
    }

    /// A reference from its values (patch-major), how they were computed and their
    /// certificate.
    pub(crate) fn from_parts(
        system: &LinearSystem,
        values: Vec<Real>,
        method: Method,
        certificate: Certificate,
    ) -> ReferenceSolution {
        ReferenceSolution { channels: system.channels(), n: system.len(), values, method, certificate }
    }

    /// `B*_ic` at `i * channels + c`.
    pub fn values(&self) -> &[Real] {
        &self.values
    }

    /// `B*_ic`.
    pub fn get(&self, i: usize, c: usize) -> Real {
        self.values[i * self.channels.count() + c]
    }

    /// The number of patches.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false: a system has at least one patch.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The solved channels.
    pub fn channels(&self) -> Channels {
        self.channels
    }

    /// How `B*` was computed.
    pub fn method(&self) -> &Method {
        &self.method
    }

    /// The bound on `B*`'s own error.
    pub fn certificate(&self) -> &Certificate {
        &self.certificate
    }
}

fn k(system: &LinearSystem) -> usize {
    system.channels().count()
}

fn solve_dyn(
    system: &LinearSystem,
    f: &dyn ColumnSource,
    params: &ReferenceParams,
) -> Result<ReferenceSolution, EvalError> {
    params.validate()?;
    check_sizes(system, f.patch_count(), None)?;
    let m = FormFactors::assemble(f, params.max_matrix_bytes)?;
    ReferenceSolution::solve_matrix(system, &m, params.clone())
}

/// Per channel, LU of `I − diag(ρ_c) F` and one solve; channels in parallel.
fn dense_lu(system: &LinearSystem, m: &FormFactors) -> Result<Vec<Real>, EvalError> {
    let (n, k) = (system.len(), k(system));
    let per_channel: Vec<Vec<Real>> =
        (0..k).into_par_iter().map(|c| lu_channel(system, m, c)).collect::<Result<_, _>>()?;
    let mut values = vec![0.0; n * k];
    for (c, x) in per_channel.iter().enumerate() {
        for (i, v) in x.iter().enumerate() {
            values[i * k + c] = *v;
        }
    }
    Ok(values)
}

fn lu_channel(system: &LinearSystem, m: &FormFactors, c: usize) -> Result<Vec<Real>, EvalError> {
    lu_solve(system.len(), false, |i, j| Real::from(i == j) - system.rho(i, c) * m.get(i, j), |i| system.e(i, c))
        .map_err(|SingularPivot { pivot, value }| EvalError::Singular { channel: c, pivot, value })
}

/// Gauss–Seidel on all channels at once, rows in order, until the certified relative bound
/// is below `params.certified`. Returns the solution and the sweeps done.
fn gauss_seidel(
    system: &LinearSystem,
    m: &FormFactors,
    contraction: &Contraction,
    params: &ReferenceParams,
) -> Result<(Vec<Real>, usize), EvalError> {
    if m.stored().is_some() {
        return column_gauss_seidel(system, m, contraction, params);
    }
    let (n, k) = (system.len(), k(system));
    let (area, rho, e) = (system.areas(), system.reflectivities(), system.emissions());
    let weight = stop_weights(contraction, k);
    let measure = |norms: &[Real]| -> Real { norms.iter().zip(&weight).map(|(r, w)| r * w).sum() };
    let mut b = e.to_vec();
    let mut sums = vec![0.0; k];
    let mut delta = vec![0.0; k];
    let mut reached = Real::INFINITY;
    for sweep in 1..=params.max_sweeps {
        delta.fill(0.0);
        for i in 0..n {
            let row = m.dense_row(i).expect("a dense matrix has rows");
            sums.fill(0.0);
            for (j, fij) in row.iter().enumerate() {
                for c in 0..k {
                    sums[c] += fij * b[j * k + c];
                }
            }
            let fii = row[i];
            for c in 0..k {
                let idx = i * k + c;
                let old = b[idx];
                let new = (e[idx] + rho[idx] * (sums[c] - fii * old)) / (1.0 - rho[idx] * fii);
                delta[c] += area[i] * (new - old).abs();
                b[idx] = new;
            }
        }
        if !b.iter().all(|v| v.is_finite()) {
            return Err(EvalError::Diverged { sweeps: sweep });
        }
        let norm_b: Real = b.iter().enumerate().map(|(idx, v)| area[idx / k] * v.abs()).sum();
        // After a sweep r_i = ρ_i Σ_{j>i} F_ij ΔB_j, so ‖r_c‖_A ≤ κ_c ‖ΔB_c‖_A (F ≥ 0).
        let estimate: Vec<Real> = delta.iter().zip(&contraction.kappa).map(|(d, kc)| d * kc).collect();
        let relative = |x: Real| if x == 0.0 { 0.0 } else { x / norm_b };
        reached = relative(measure(&estimate));
        if reached <= params.certified {
            let residual = Residual::with_contraction(system, m, contraction.clone(), &b)?;
            reached = relative(measure(residual.channel_norms()));
            if reached <= params.certified {
                return Ok((b, sweep));
            }
        }
    }
    Err(EvalError::NotConverged { sweeps: params.max_sweeps, reached, target: params.certified })
}

/// Per channel, the weight of the residual norm in the stop measure: the bound's factor
/// `1 / (1 − q_c)` when the contraction is certified, 1 (the plain residual) when it is not.
fn stop_weights(contraction: &Contraction, k: usize) -> Vec<Real> {
    let certified = contraction.certified();
    (0..k).map(|c| if certified { 1.0 / (1.0 - contraction.factor(c)) } else { 1.0 }).collect()
}

/// Gauss–Seidel over a stored matrix's columns: shooting every patch's unshot radiosity in
/// index order, which is Gauss–Seidel on the shot radiosity `x` (the residual of `x` is the
/// unshot `u`, updated as each column is shot), read column by column as the matrix is
/// stored. A patch's own entry is solved for exactly (`s = u_j / (1 − ρ_j F_jj)` leaves
/// `u_j = 0`). After a sweep the stop measure is taken from `u` itself, then confirmed by the
/// exact residual; the answer is `x + u = E + ρ F x`. Sequential, so the sums do not depend
/// on the thread count.
fn column_gauss_seidel(
    system: &LinearSystem,
    m: &FormFactors,
    contraction: &Contraction,
    params: &ReferenceParams,
) -> Result<(Vec<Real>, usize), EvalError> {
    let stored = m.stored().expect("called for stored matrices");
    let (n, k) = (system.len(), k(system));
    let (area, rho, e) = (system.areas(), system.reflectivities(), system.emissions());
    let weight = stop_weights(contraction, k);
    let measure = |v: &[Real]| -> Real {
        let mut norms = vec![0.0; k];
        for (idx, x) in v.iter().enumerate() {
            norms[idx % k] += area[idx / k] * x.abs();
        }
        norms.iter().zip(&weight).map(|(r, w)| r * w).sum()
    };
    let diagonal: Vec<Real> = (0..n).map(|j| stored.get(j, j)).collect();
    let mut x = vec![0.0; n * k];
    let mut u = e.to_vec();
    let mut shot = vec![0.0; k];
    let mut reached = Real::INFINITY;
    for sweep in 1..=params.max_sweeps {
        for j in 0..n {
            let mut any = false;
            for (c, s) in shot.iter_mut().enumerate() {
                let idx = j * k + c;
                *s = u[idx] / (1.0 - rho[idx] * diagonal[j]);
                any |= *s != 0.0;
            }
            if !any {
                continue;
            }
            stored.for_each_in_column(j, |i, v| {
                if i != j {
                    let v = Real::from(v);
                    for c in 0..k {
                        u[i * k + c] += rho[i * k + c] * v * shot[c];
                    }
                }
            });
            for c in 0..k {
                x[j * k + c] += shot[c];
                u[j * k + c] = 0.0;
            }
        }
        let b: Vec<Real> = x.iter().zip(&u).map(|(x, u)| x + u).collect();
        if !b.iter().all(|v| v.is_finite()) {
            return Err(EvalError::Diverged { sweeps: sweep });
        }
        let norm_b: Real = b.iter().enumerate().map(|(idx, v)| area[idx / k] * v.abs()).sum();
        let relative = |r: Real| if r == 0.0 { 0.0 } else { r / norm_b };
        // The residual of x is u; that of x + u = E + ρ F x is ρ F u, at most κ ‖u‖.
        reached = relative(measure(&u) * contraction.kappa.iter().fold(0.0, |a: Real, b| a.max(*b)));
        if reached <= params.certified {
            let residual = Residual::with_contraction(system, m, contraction.clone(), &b)?;
            reached = relative(residual.channel_norms().iter().zip(&weight).map(|(r, w)| r * w).sum());
            if reached <= params.certified {
                return Ok((b, sweep));
            }
        }
    }
    Err(EvalError::NotConverged { sweeps: params.max_sweeps, reached, target: params.certified })
}

/// The magic string at the start of a stored reference.
const STORED_MAGIC: &[u8; 20] = b"radiosity-reference\0";
/// The format of a stored reference; a file of another version is refused.
pub const STORED_FORMAT_VERSION: u32 = 2;

impl ReferenceSolution {
    /// The reference as bytes for the on-disk cache, with `key` (what it was computed from)
    /// inside, and a checksum: magic, version, key, channels, patches, method, certificate
    /// and contraction, the values, all little-endian, then the xxh3 of everything before.
    pub fn to_bytes(&self, key: &str) -> Vec<u8> {
        let mut out = Vec::with_capacity(8 * self.values.len() + key.len() + 128);
        out.extend_from_slice(STORED_MAGIC);
        out.extend_from_slice(&STORED_FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(key.len() as u64).to_le_bytes());
        out.extend_from_slice(key.as_bytes());
        out.extend_from_slice(&(self.channels.count() as u64).to_le_bytes());
        out.extend_from_slice(&(self.n as u64).to_le_bytes());
        let (tag, count, columns, solver) = match &self.method {
            Method::DenseLu => (0u64, 0u64, 0u64, ""),
            Method::GaussSeidel { sweeps } => (1, *sweeps as u64, 0, ""),
            Method::Shooting { solver, steps, columns } => (2, *steps, *columns, solver.as_str()),
        };
        for word in [tag, count, columns, solver.len() as u64] {
            out.extend_from_slice(&word.to_le_bytes());
        }
        out.extend_from_slice(solver.as_bytes());
        let c = &self.certificate;
        for v in [c.residual_norm, c.bound, c.relative_bound, Real::from(u8::from(c.certified))] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&c.contraction.max_row_sum.to_le_bytes());
        out.extend_from_slice(&u64::from(c.contraction.measured).to_le_bytes());
        for v in c.contraction.rho_max.iter().chain(&c.contraction.kappa).chain(&self.values) {
            out.extend_from_slice(&v.to_le_bytes());
        }
        let sum = xxhash_rust::xxh3::xxh3_64(&out);
        out.extend_from_slice(&sum.to_le_bytes());
        out
    }

    /// Decodes a reference written by [`ReferenceSolution::to_bytes`] with the same `key`, for
    /// `system`; refuses anything else with the reason.
    pub fn from_bytes(bytes: &[u8], key: &str, system: &LinearSystem) -> Result<ReferenceSolution, EvalError> {
        let refuse = |why: &str| EvalError::StoredReference(why.to_string());
        if bytes.len() < STORED_MAGIC.len() + 12 || &bytes[..STORED_MAGIC.len()] != STORED_MAGIC {
            return Err(refuse("not a stored reference solution"));
        }
        let (body, sum) = bytes.split_at(bytes.len() - 8);
        if xxhash_rust::xxh3::xxh3_64(body).to_le_bytes() != sum {
            return Err(refuse("its checksum does not match (truncated or damaged file)"));
        }
        let mut r = StoredReader { body, at: STORED_MAGIC.len() };
        let version = u32::from_le_bytes(r.take(4)?.try_into().expect("4 bytes"));
        if version != STORED_FORMAT_VERSION {
            return Err(refuse(&format!(
                "written in format version {version}, this build reads version {STORED_FORMAT_VERSION}"
            )));
        }
        let key_len = r.word()?;
        let stored_key = r.take(usize::try_from(key_len).unwrap_or(usize::MAX))?;
        if stored_key != key.as_bytes() {
            return Err(refuse(&format!(
                "it was computed for '{}', not for '{key}'",
                String::from_utf8_lossy(stored_key)
            )));
        }
        let (k, n) = (r.word()?, r.word()?);
        if k != system.channels().count() as u64 || n != system.len() as u64 {
            return Err(refuse("its size is not this system's"));
        }
        let (k, n) = (k as usize, n as usize);
        let (tag, count, columns, solver_len) = (r.word()?, r.word()?, r.word()?, r.word()?);
        let solver = String::from_utf8(r.take(usize::try_from(solver_len).unwrap_or(usize::MAX))?.to_vec())
            .map_err(|_| refuse("the solver's name is not UTF-8"))?;
        let method = match tag {
            0 => Method::DenseLu,
            1 => Method::GaussSeidel { sweeps: count as usize },
            2 => Method::Shooting { solver, steps: count, columns },
            _ => return Err(refuse("unknown method")),
        };
        let (residual_norm, bound, relative_bound, certified) = (r.real()?, r.real()?, r.real()?, r.real()? != 0.0);
        let max_row_sum = r.real()?;
        let measured = r.word()? != 0;
        let rho_max = (0..k).map(|_| r.real()).collect::<Result<Vec<_>, _>>()?;
        let kappa = (0..k).map(|_| r.real()).collect::<Result<Vec<_>, _>>()?;
        let values = (0..n * k).map(|_| r.real()).collect::<Result<Vec<_>, _>>()?;
        if r.at != body.len() {
            return Err(refuse("trailing bytes after the values"));
        }
        let contraction = Contraction { max_row_sum, rho_max, kappa, measured };
        let certificate = Certificate { residual_norm, bound, relative_bound, certified, contraction };
        Ok(ReferenceSolution { channels: system.channels(), n, values, method, certificate })
    }
}

/// Reads a stored reference's body front to back ([`ReferenceSolution::from_bytes`]).
struct StoredReader<'b> {
    body: &'b [u8],
    at: usize,
}

impl<'b> StoredReader<'b> {
    /// The next `len` bytes.
    fn take(&mut self, len: usize) -> Result<&'b [u8], EvalError> {
        let end = self.at.checked_add(len).filter(|&end| end <= self.body.len());
        let end = end.ok_or_else(|| EvalError::StoredReference("truncated file".into()))?;
        let piece = &self.body[self.at..end];
        self.at = end;
        Ok(piece)
    }

    /// The next little-endian `u64`.
    fn word(&mut self) -> Result<u64, EvalError> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }

    /// The next little-endian `f64`.
    fn real(&mut self) -> Result<Real, EvalError> {
        Ok(Real::from_bits(self.word()?))
    }
}
