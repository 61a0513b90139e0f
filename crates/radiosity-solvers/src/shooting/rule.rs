//! The shooting update shared by the point shooting methods (Southwell, progressive
//! refinement): shoot an amount `s` from patch `j` to every patch.
//!
//! For every patch `i` and channel `c`: `δ_ic = ρ_ic F_ij s_c`, `B_ic += δ_ic`,
//! `ΔB_ic += δ_ic` (Cohen, Chen, Wallace & Greenberg 1988, "A progressive refinement
//! approach to fast radiosity image generation"). The caller then sets the shooter's own
//! unshot radiosity: what it keeps back (zero, or `−ΔB⁺_j` when overshooting) plus its own
//! share of the shot, `ρ_j F_jj s` ([`own_share`]; zero for planar patches, `F_jj = 0`). With
//! that share, `ΔB` stays exactly the residual of the shot radiosity `x = B − ΔB`: `x_j` grows
//! by `s`, which changes `r_j(x)` by `ρ_j F_jj s − s`.

use crate::error::SolverError;
use crate::run::problem::Problem;
use crate::run::state::State;
use radiosity_core::Real;

/// Shoots `amount` (one value per channel) from patch `j`, using `column` as scratch space.
pub fn shoot(
    problem: &Problem<'_>,
    state: &mut State,
    j: usize,
    amount: &[Real],
    column: &mut [Real],
) -> Result<(), SolverError> {
    problem.column(j, column);
    shoot_column(problem, state, amount, column)
}

/// Shoots `amount` through a column already fetched (`column[i] = F_ij`).
pub fn shoot_column(
    problem: &Problem<'_>,
    state: &mut State,
    amount: &[Real],
    column: &[Real],
) -> Result<(), SolverError> {
    let k = state.channels;
    let rho = problem.system().reflectivities();
    for (i, &f) in column.iter().enumerate() {
        if f == 0.0 {
            continue;
        }
        for (c, &a) in amount.iter().enumerate() {
            receive(state, i * k + c, rho[i * k + c] * f * a)?;
        }
    }
    Ok(())
}

/// The share of a shot of `amount` (one channel, `c`) from patch `j` through `column`
/// (`column[i] = F_ij`) that `j` receives itself: `ρ_jc F_jj amount`, exactly zero when
/// `F_jj = 0`. The shooter keeps it unshot (module doc).
pub fn own_share(problem: &Problem<'_>, j: usize, c: usize, amount: Real, column: &[Real]) -> Real {
    let f = column[j];
    if f == 0.0 { 0.0 } else { problem.system().rho(j, c) * f * amount }
}

/// Adds `delta` to the radiosity and the unshot radiosity at `idx` (`i * channels + c`),
/// stopping the run if the radiosity stops being finite.
pub fn receive(state: &mut State, idx: usize, delta: Real) -> Result<(), SolverError> {
    state.radiosity[idx] += delta;
    state.unshot[idx] += delta;
    if !state.radiosity[idx].is_finite() {
        let k = state.channels;
        return Err(SolverError::NonFinite { step: state.step + 1, patch: idx / k, value: state.radiosity[idx] });
    }
    Ok(())
}

/// Sets the unshot radiosity at `idx` (`i * channels + c`) to `value`, stopping the run if it
/// is not finite: the shot radiosity `x = B − ΔB` would not be either.
pub fn set_unshot(state: &mut State, idx: usize, value: Real) -> Result<(), SolverError> {
    state.unshot[idx] = value;
    if !value.is_finite() {
        let k = state.channels;
        return Err(SolverError::NonFinite { step: state.step + 1, patch: idx / k, value });
    }
    Ok(())
}

/// The residual power of the shot radiosity: `Σ_c Σ_i A_i |ΔB_ic| / Σ_c Σ_i A_i E_ic`.
pub fn unshot_power(problem: &Problem<'_>, state: &State) -> Real {
    let (area, emission, k) = (problem.system().areas(), problem.system().emissions(), state.channels);
    let mut unshot = 0.0;
    let mut emitted = 0.0;
    for i in 0..area.len() {
        for c in 0..k {
            unshot += area[i] * state.unshot[i * k + c].abs();
            emitted += area[i] * emission[i * k + c].abs();
        }
    }
    if emitted > 0.0 { unshot / emitted } else { 0.0 }
}
