//! The group shooting step shared by group shooting and group-accelerated shooting: solve the
//! group's own interactions exactly, then shoot the result to every patch; or, when the group
//! system cannot be trusted, shoot the group's patches one after another.
//!
//! ## Rule (docs/design.md §4.6)
//!
//! For a group `r` of `m` patches with their columns, and per channel:
//!
//! 1. solve `Φ_rr y = s_r` with `s_r = ΔB_r + ΔB⁺_r` and `Φ_rr = I − N`, `N = diag(ρ_r) F_rr`
//!    (`m × m`, LU with partial pivoting, [`radiosity_core::dense_lu`]);
//! 2. for **every** patch `i`, `δ_i = ρ_i Σ_{k∈r} F_ik y_k` and `B_i += δ_i`; for `i` outside
//!    `r` also `ΔB_i += δ_i`;
//! 3. for `k` in `r`, `ΔB_k = −ΔB⁺_k` (zero without overshoot).
//!
//! The shot radiosity of the group grows by `y`, and the residual of the group becomes exactly
//! `s_r − ΔB⁺_r − Φ_rr y = −ΔB⁺_r`: every interaction inside the group is resolved. The paper's
//! printed update `−Φ_{s,r} Φ_rr⁻¹ ΔB_r` holds for the patches outside the group; inside it,
//! this is the consistent one (it gives `B_r = x_r + y_r` and zero unshot).
//!
//! Cost: one `m × m` LU per channel (`O(m³)`), and `O(n m)` per channel for the update. The
//! columns must already be in hand: this step computes none. The step counts its operations
//! ([`GroupShot::operations`]), for a frequency rule that must not depend on the clock
//! ([`crate::group::group_accelerated`]): per channel `m²` to build `Φ_rr`, `⌊2m³/3⌋ + 4m²` for the
//! LU with its two right-hand sides (as [`radiosity_core::dense_lu::solve_m_matrix`] does
//! it), or for the inner Gauss–Seidel `m²` for the bound and `m²` per sweep and per residual
//! check, and `n m` to shoot `y` to every patch (the fallback's point shots cost the same).
//!
//! ## What the solvers record
//!
//! Every solver that runs group steps (group shooting, group-accelerated shooting, group
//! gathering) keeps a [`GroupStats`] and records it ([`crate::Record`]): `group_steps`,
//! `group_size_mean`, `group_size_max`, `group_condition` and `group_fallbacks`.
//!
//! ## When the group system is trusted
//!
//! A group system is solved, and its solution amplified through the shot to every patch, only
//! when it is well posed; otherwise the step falls back (below). The test per channel, and the
//! estimate it reports ([`GroupShot::condition`], the largest over channels; the solvers
//! record the largest over their steps as `group_condition`, [`GroupStats`]):
//!
//! - **LU.** Form factors and reflectivities are non-negative, so `N ≥ 0` entrywise and
//!   `Φ_rr = I − N` is a Z-matrix. A Z-matrix is a nonsingular M-matrix exactly when the
//!   spectral radius of `N` is below 1, exactly when some `z > 0` has `Φ_rr z > 0`, and its
//!   inverse is then `Σ_k N^k ≥ 0` entrywise (Berman & Plemmons, ch. 6, Theorem 2.3:
//!   semipositive and inverse-positive Z-matrices). The factorisation that solves
//!   `Φ_rr y = s` also solves `Φ_rr z = 1` ([`radiosity_core::dense_lu::lu_solve_columns`]).
//!   If every `z_a` is finite and positive, `Φ_rr` is a nonsingular M-matrix, and since
//!   `Φ_rr⁻¹ ≥ 0`, `‖Φ_rr⁻¹‖_∞ = ‖Φ_rr⁻¹ 1‖_∞ = max_a z_a` exactly, so
//!   `κ_∞ = ‖Φ_rr‖_∞ · max_a z_a` with `‖Φ_rr‖_∞ = max_a Σ_b |δ_ab − ρ_a F_ab|`: the condition
//!   number itself, not a bound (Higham, ch. 7 for `κ_∞`, ch. 15 on estimating it). A zero or
//!   non-finite pivot, a `z_a` that is not finite and positive, or a negative or non-finite
//!   entry of `N` mean that `Φ_rr` is not a nonsingular M-matrix: the form factors inside the
//!   group exceed what light can do (some `ρ_a Σ_b F_ab ≥ 1`, since row sums of `N` below 1
//!   bound its spectral radius below 1). The step then falls back and records `κ_∞ = ∞`. It
//!   also falls back when `κ_∞ >` [`CONDITION_LIMIT`], recording `κ_∞`.
//! - **Inner Gauss–Seidel.** With `q = max_a Σ_b |ρ_a F_ab|` over the group (the largest row
//!   sum of `N`, `‖N‖_∞`) below 1, the Neumann series gives `‖Φ_rr⁻¹‖_∞ ≤ 1/(1 − q)` and
//!   `‖Φ_rr‖_∞ ≤ 1 + q`, so `κ_∞ ≤ (1 + q)/(1 − q)`, recorded as the estimate; `Φ_rr` is then
//!   strictly diagonally dominant and the sweeps converge (Saad, §4.2). The step falls back
//!   when `q ≥ 1` or an entry of `N` is not finite (no bound: recorded as `∞`), when the bound
//!   exceeds [`CONDITION_LIMIT`] (recorded as the bound), and when the sweeps fail (a value
//!   that is not finite, or [`MAX_INNER_SWEEPS`] sweeps without meeting the stopping rule
//!   below; recorded as the bound).
//!
//! ## Fallback
//!
//! The step does not solve the group. It shoots the group's patches one after another, in
//! group order, as plain progressive-refinement point shots from the columns already in hand:
//! for each member `k`, `s_k = ΔB_k` (as it is now, so later shots see earlier ones),
//! `δ_i = ρ_i F_ik s_k` for every `i`, `B_i += δ_i`, `ΔB_i += δ_i`, then `ΔB_k −= s_k` (zero
//! for planar patches, `F_kk = 0`; the subtraction keeps the invariant when `F_kk ≠ 0`). The
//! overshoots are not used. This costs no column, keeps `ΔB` exactly the residual of
//! `x = B − ΔB`, and cannot amplify anything that a point method would not. The step reports
//! it ([`GroupShot::fell_back`]), and the solvers count it as `group_fallbacks` in their record
//! ([`GroupStats`]). A system whose groups are not M-matrices is not physical as
//! a whole either (the spectral radius of `ρ F` is at least that of any principal block): its
//! runs end as diverged ([`crate::run::executor`]).
//!
//! ## Inner Gauss–Seidel
//!
//! [`InnerSolve::GaussSeidel`], beyond the paper, which names larger groups solved iteratively
//! as future work: `y_a ← (s_a + Σ_{b≠a} N_ab y_b) / (1 − N_aa)`, patch by patch, `O(m²)` a
//! sweep. It stops on the true residual of the group system: after a sweep that changed `y` by
//! at most 1e-13 of `Σ_a |y_a|`, it computes `Σ_a |s_a − (Φ_rr y)_a|` and stops once that is
//! at most 1e-13 `Σ_a |y_a|` (a small change between iterates is only the signal to check; it
//! proves nothing). Its `y` is not exact, so the group keeps that residual `s − Φ_rr y − ΔB⁺`
//! as unshot (round-off small), and the unshot radiosity stays exactly the residual of the
//! shot radiosity. Convergence slows as `q → 1`, and a group whose sweeps reach
//! [`MAX_INNER_SWEEPS`] falls back (docs/solvers.md gives the sweeps a closed furnace took).
//!
//! LU is the default: the `group_solve` bench (`cargo bench -p radiosity-solvers --bench
//! group_solve`, figures in `docs/solvers.md`) found no size up to m = 400 where the inner
//! Gauss–Seidel is faster, since the `O(n m)` shot to every patch costs as much as either
//! solve. The second right-hand side adds `O(m²)` to the LU's `O(m³)`.
//!
//! ## References
//!
//! - Rousselle & Renaud, "Group accelerated shooting methods for radiosity", §3.2–3.3.
//! - Berman & Plemmons 1994, *Nonnegative Matrices in the Mathematical Sciences*, SIAM,
//!   ch. 6 (nonsingular M-matrices and their nonnegative inverses).
//! - Higham 2002, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., SIAM, ch. 7
//!   (condition numbers of linear systems) and ch. 15 (condition number estimation).
//! - Saad 2003, *Iterative Methods for Sparse Linear Systems*, 2nd ed., SIAM, §4.2
//!   (convergence of Gauss–Seidel for diagonally dominant matrices).

use crate::error::SolverError;
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::state::State;
use crate::shooting::rule::{receive, set_unshot, shoot_column};
use radiosity_core::Real;
use radiosity_core::dense_lu::solve_m_matrix;

/// How a group system `Φ_rr y = s` is solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum InnerSolve {
    /// Dense LU with partial pivoting: exact, `O(m³)`.
    #[default]
    Lu,
    /// Gauss–Seidel sweeps until the group system's residual is 1e-13 of the solution:
    /// `O(m²)` a sweep.
    GaussSeidel,
}

/// The largest condition number `κ_∞(Φ_rr)` (or, for the inner Gauss–Seidel, its bound) with
/// which a group system is solved; a worse group falls back to point shots. LU is backward
/// stable, so the group's residual `s − Φ_rr y`, which the step takes as zero, is round-off
/// relative to `‖Φ_rr‖ ‖y‖`, that is up to about `κ_∞ ε` relative to `s` (Higham, ch. 7): at
/// the limit about 1e-6, the most the step lets into the invariant "ΔB is the residual of
/// `x`". Physical groups stay far below it: a closed furnace of reflectivity `ρ` has
/// `κ_∞ = (1 + ρ)/(1 − ρ)`, 2·10⁴ at `ρ = 0.9999`.
pub const CONDITION_LIMIT: Real = 1e10;

/// Sweeps allowed to the inner Gauss–Seidel before it gives up (and the step falls back).
pub const MAX_INNER_SWEEPS: usize = 10_000;

/// The inner Gauss–Seidel's tolerance: the residual `Σ |s − Φ_rr y|` relative to `Σ |y|`.
const INNER_TOLERANCE: Real = 1e-13;

/// What one group step did ([`group_shot`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroupShot {
    /// Patches in the group (0: there was no group, and nothing happened).
    pub size: usize,
    /// The condition estimate `κ_∞(Φ_rr)` (or, for the inner Gauss–Seidel, its bound), the
    /// largest over channels: infinite when a channel's system is singular, not an M-matrix,
    /// or without a bound (module doc).
    pub condition: Real,
    /// Whether the step fell back to point shots (module doc).
    pub fell_back: bool,
    /// The operations the step counted: building, solving and shooting (module doc).
    pub operations: u64,
}

impl GroupShot {
    /// What the step hands back to observers ([`crate::Solver::next_step`]): `group_size`,
    /// `group_condition` and `group_fell_back` (0 or 1).
    pub fn figures(&self) -> Record {
        let mut record = Record::new();
        record
            .set("group_size", self.size)
            .set("group_condition", self.condition)
            .set("group_fell_back", u64::from(self.fell_back));
        record
    }
}

/// What a solver's group steps did so far, recorded as `group_steps` (count),
/// `group_size_mean` and `group_size_max`, `group_condition` (the largest condition estimate
/// met: 0 before any group step, infinite once a group system was singular or not an
/// M-matrix) and `group_fallbacks` (count), module doc.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GroupStats {
    /// Group steps run.
    pub steps: u64,
    /// Patches over all of them.
    pub patches: u64,
    /// The largest group.
    pub largest: usize,
    /// The largest condition estimate (0 before any step).
    pub condition: Real,
    /// Steps that fell back to point shots.
    pub fallbacks: u64,
}

impl GroupStats {
    /// Counts one group step (one with an empty group is no step).
    pub fn add(&mut self, shot: &GroupShot) {
        if shot.size == 0 {
            return;
        }
        self.steps += 1;
        self.patches += shot.size as u64;
        self.largest = self.largest.max(shot.size);
        self.condition = self.condition.max(shot.condition);
        self.fallbacks += u64::from(shot.fell_back);
    }

    /// The mean group size (0 before any step).
    pub fn mean_size(&self) -> Real {
        if self.steps == 0 { 0.0 } else { self.patches as Real / self.steps as Real }
    }

    /// Writes the figures into `record`, under the keys of the type's doc.
    pub fn record(&self, record: &mut Record) {
        record
            .set("group_steps", self.steps)
            .set("group_size_mean", self.mean_size())
            .set("group_size_max", self.largest)
            .set("group_condition", self.condition)
            .set("group_fallbacks", self.fallbacks);
    }
}

/// What a group system gave in one channel.
enum ChannelSolve {
    /// Trusted: the solution, the residual the group keeps (zero for LU) and `κ_∞` (or its
    /// bound).
    Solved { y: Vec<Real>, left: Vec<Real>, condition: Real },
    /// Not trusted: the condition estimate that refused it (infinite when the system is
    /// singular, not an M-matrix, or without a bound).
    Refused { condition: Real },
}

/// The operations of an `m × m` LU with two right-hand sides (module doc).
fn lu_operations(m: u64) -> u64 {
    2 * m * m * m / 3 + 4 * m * m
}

/// `N = diag(ρ_r) F_rr` for channel `c`, row-major.
fn group_matrix(problem: &Problem<'_>, group: &[usize], columns: &[&[Real]], c: usize) -> Vec<Real> {
    let m = group.len();
    let system = problem.system();
    let mut n_rr = vec![0.0; m * m];
    for (a, &g) in group.iter().enumerate() {
        let rho = system.rho(g, c);
        for (b, column) in columns.iter().enumerate() {
            n_rr[a * m + b] = rho * column[g];
        }
    }
    n_rr
}

/// Solves `(I − N) y = s` by LU, with the M-matrix test and `κ_∞` of the module doc.
fn solve_lu(m: usize, n_rr: &[Real], s: Vec<Real>) -> ChannelSolve {
    let Some((y, condition)) = solve_m_matrix(m, n_rr, s) else {
        return ChannelSolve::Refused { condition: Real::INFINITY };
    };
    if condition > CONDITION_LIMIT {
        return ChannelSolve::Refused { condition };
    }
    ChannelSolve::Solved { y, left: vec![0.0; m], condition }
}

/// Solves `(I − N) y = s` by Gauss–Seidel, with the bound and the residual stopping rule of
/// the module doc; adds its operations to `operations` (`m²` for the bound, `m²` a sweep and a
/// residual check).
fn solve_gauss_seidel(m: usize, n_rr: &[Real], s: Vec<Real>, operations: &mut u64) -> ChannelSolve {
    let square = (m * m) as u64;
    *operations += square;
    if n_rr.iter().any(|v| !v.is_finite()) {
        return ChannelSolve::Refused { condition: Real::INFINITY };
    }
    let q = (0..m).map(|a| n_rr[a * m..(a + 1) * m].iter().map(|v| v.abs()).sum::<Real>()).fold(0.0, Real::max);
    if q >= 1.0 {
        return ChannelSolve::Refused { condition: Real::INFINITY };
    }
    let condition = (1.0 + q) / (1.0 - q);
    if condition > CONDITION_LIMIT {
        return ChannelSolve::Refused { condition };
    }
    // q < 1, so every diagonal entry 1 − N_aa ≥ 1 − q is positive.
    let diagonal: Vec<Real> = (0..m).map(|a| 1.0 - n_rr[a * m + a]).collect();
    let mut y = s.clone();
    let mut left = vec![0.0; m];
    for _ in 0..MAX_INNER_SWEEPS {
        *operations += square;
        let (mut change, mut norm) = (0.0, 0.0);
        for a in 0..m {
            let row = &n_rr[a * m..(a + 1) * m];
            let others: Real = (0..m).filter(|&b| b != a).map(|b| row[b] * y[b]).sum();
            let next = (s[a] + others) / diagonal[a];
            change += (next - y[a]).abs();
            norm += next.abs();
            y[a] = next;
        }
        if !(change.is_finite() && norm.is_finite()) {
            break;
        }
        if change <= INNER_TOLERANCE * norm {
            // The true residual of the group system, s − (I − N) y, decides.
            *operations += square;
            let mut residual = 0.0;
            for a in 0..m {
                let row = &n_rr[a * m..(a + 1) * m];
                left[a] = s[a] - y[a] + row.iter().zip(&y).map(|(n, v)| n * v).sum::<Real>();
                residual += left[a].abs();
            }
            if residual <= INNER_TOLERANCE * norm {
                return ChannelSolve::Solved { y, left, condition };
            }
        }
    }
    ChannelSolve::Refused { condition }
}

/// Runs one group step on `group` (patch indices) with `columns[a][i] = F_{i, group[a]}` and
/// overshoots `plus[a * k + c]` (all zero for group PR and Southwell): the group solve and
/// shot, or the point-shot fallback when the group system is not trusted (module doc). Either
/// way it reports the condition estimate, whether it fell back, and its operations.
pub fn group_shot(
    problem: &Problem<'_>,
    state: &mut State,
    group: &[usize],
    columns: &[&[Real]],
    plus: &[Real],
    inner: InnerSolve,
) -> Result<GroupShot, SolverError> {
    let (m, k, n) = (group.len(), state.channels, problem.n());
    if m == 0 {
        return Ok(GroupShot { size: 0, condition: 0.0, fell_back: false, operations: 0 });
    }
    let (m64, k64) = (m as u64, k as u64);
    // Building Φ_rr and shooting y (or the fallback's point shots) to every patch.
    let mut operations = k64 * (m64 * m64 + n as u64 * m64);
    let system = problem.system();
    // y[a * k + c], and what the group keeps unshot beyond −ΔB⁺ (zero for LU).
    let mut y = vec![0.0; m * k];
    let mut left = vec![0.0; m * k];
    let (mut condition, mut trusted) = (0.0, true);
    for c in 0..k {
        let n_rr = group_matrix(problem, group, columns, c);
        let s: Vec<Real> = (0..m).map(|a| state.unshot[group[a] * k + c] + plus[a * k + c]).collect();
        let solved = match inner {
            InnerSolve::Lu => {
                operations += lu_operations(m64);
                solve_lu(m, &n_rr, s)
            }
            InnerSolve::GaussSeidel => solve_gauss_seidel(m, &n_rr, s, &mut operations),
        };
        match solved {
            ChannelSolve::Solved { y: yc, left: lc, condition: kc } => {
                condition = Real::max(condition, kc);
                for a in 0..m {
                    y[a * k + c] = yc[a];
                    left[a * k + c] = lc[a];
                }
            }
            ChannelSolve::Refused { condition: kc } => {
                condition = Real::max(condition, kc);
                trusted = false;
            }
        }
    }
    let shot = GroupShot { size: m, condition, fell_back: !trusted, operations };
    if !trusted {
        point_shots(problem, state, group, columns)?;
        return Ok(shot);
    }
    let mut delta = vec![0.0; k];
    for i in 0..n {
        delta.fill(0.0);
        for (a, column) in columns.iter().enumerate() {
            let f = column[i];
            if f != 0.0 {
                for c in 0..k {
                    delta[c] += f * y[a * k + c];
                }
            }
        }
        for (c, &d) in delta.iter().enumerate() {
            receive(state, i * k + c, system.rho(i, c) * d)?;
        }
    }
    for (a, &g) in group.iter().enumerate() {
        for c in 0..k {
            set_unshot(state, g * k + c, left[a * k + c] - plus[a * k + c])?;
        }
    }
    Ok(shot)
}

/// The fallback: the group's members shot one after another, in group order, as plain
/// progressive-refinement shots from their columns, each shooting its unshot radiosity as it
/// is when its turn comes.
fn point_shots(
    problem: &Problem<'_>,
    state: &mut State,
    group: &[usize],
    columns: &[&[Real]],
) -> Result<(), SolverError> {
    let k = state.channels;
    let mut amount = vec![0.0; k];
    for (&g, column) in group.iter().zip(columns) {
        amount.copy_from_slice(&state.unshot[g * k..(g + 1) * k]);
        shoot_column(problem, state, &amount, column)?;
        for (c, &s) in amount.iter().enumerate() {
            let rest = state.unshot[g * k + c] - s;
            set_unshot(state, g * k + c, rest)?;
        }
    }
    Ok(())
}
