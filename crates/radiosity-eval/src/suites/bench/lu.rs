//! Group solves: one group system solved by LU, nalgebra against faer, as the group grows.
//!
//! The systems are those of the `group_solve` criterion bench of radiosity-solvers: a
//! 3400-patch (labyrinth-sized) enclosure with `F_ij = G_ij / A_i`, `G` symmetric and rows of
//! `ρ F` well below 1, reflectivity 0.6; the group is `m` patches spread over it, and the
//! system `Φ_rr = I − diag(ρ_r) F_rr` is solved for the group's unshot radiosity and for the
//! ones of the condition estimate, two right-hand sides on one factorisation, sequentially,
//! as `group_step` solves one channel. [`measure`] times both for every group size (after
//! checking that they agree), [`report`] writes the section from the medians.

use crate::error::LabError;
use crate::lab::timing::median;
use crate::progress::Progress;
use crate::reports::report_text::duration;
use radiosity_core::Real;
use radiosity_core::dense_lu::lu_solve_columns;
use std::fmt::Write as _;
use std::hint::black_box;
use std::time::Instant;

/// Patches of the synthetic system the groups are taken from.
pub const N: usize = 3400;
/// Its reflectivity.
const RHO: Real = 0.6;

/// A deterministic value in `[0, 1)` for an unordered pair (as the `group_solve` bench).
fn hash01(i: usize, j: usize) -> Real {
    let (a, b) = (i.min(j) as u64, i.max(j) as u64);
    let x = a.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ b.wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    (x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as Real / (1u64 << 53) as Real
}

/// The synthetic enclosure: areas and the scale that keeps its rows of F at most 0.9.
struct Enclosure {
    area: Vec<Real>,
    scale: Real,
}

impl Enclosure {
    fn new() -> Enclosure {
        let area: Vec<Real> = (0..N).map(|i| 1.0 + (i % 7) as Real * 0.2).collect();
        let worst = (0..N)
            .map(|i| (0..N).filter(|&j| j != i).map(|j| hash01(i, j)).sum::<Real>() / area[i])
            .fold(0.0, Real::max);
        Enclosure { area, scale: 0.9 / worst }
    }

    fn f(&self, i: usize, j: usize) -> Real {
        if i == j { 0.0 } else { self.scale * hash01(i, j) / self.area[i] }
    }

    /// `Φ_rr` (row-major) and the group's unshot radiosity for a group of `m` patches.
    fn group(&self, m: usize) -> (Vec<Real>, Vec<Real>) {
        let group: Vec<usize> = (0..m).map(|a| a * (N / m)).collect();
        let mut phi = vec![0.0; m * m];
        for (a, &ga) in group.iter().enumerate() {
            for (b, &gb) in group.iter().enumerate() {
                phi[a * m + b] = Real::from(a == b) - RHO * self.f(ga, gb);
            }
        }
        let s = group.iter().map(|&g| if g % 50 == 0 { 1.0 } else { 0.1 }).collect();
        (phi, s)
    }
}

fn faer_solve(m: usize, phi: &[Real], s: &[Real]) -> Vec<Vec<Real>> {
    lu_solve_columns(m, false, |a, b| phi[a * m + b], &[s.to_vec(), vec![1.0; m]]).unwrap_or_default()
}

fn nalgebra_solve(m: usize, phi: &[Real], s: &[Real]) -> Vec<Vec<Real>> {
    let matrix = nalgebra::DMatrix::from_fn(m, m, |a, b| phi[a * m + b]);
    let rhs = nalgebra::DMatrix::from_fn(m, 2, |a, r| if r == 0 { s[a] } else { 1.0 });
    match matrix.lu().solve(&rhs) {
        Some(x) => (0..2).map(|r| x.column(r).iter().copied().collect()).collect(),
        None => Vec::new(),
    }
}

/// Seconds per call of `solve`, from as many calls as fill `budget` seconds.
fn time_per_call(budget: f64, mut solve: impl FnMut() -> Vec<Vec<Real>>) -> f64 {
    let start = Instant::now();
    let mut calls = 0u32;
    while calls == 0 || start.elapsed().as_secs_f64() < budget {
        black_box(solve());
        calls += 1;
    }
    start.elapsed().as_secs_f64() / f64::from(calls)
}

/// What the group-solve section measures.
#[derive(Clone, Debug, PartialEq)]
pub struct LuParams {
    /// The group sizes `m`, each 1 to [`N`].
    pub group_sizes: Vec<usize>,
    /// Runs of every measurement; the figures are their medians.
    pub runs: usize,
    /// Seconds each timing fills with repeated solves (one solve at least).
    pub budget: f64,
}

/// One group size's median seconds per solve, building the matrix included.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LuTiming {
    /// Patches in the group.
    pub m: usize,
    /// nalgebra's LU.
    pub nalgebra: f64,
    /// faer's LU ([`radiosity_core::dense_lu`], what the solvers use).
    pub faer: f64,
}

/// Times nalgebra's and faer's LU on the group system of every size in `params`, `params.runs`
/// times each, and gives their medians; `progress` counts the runs. Refuses a group larger
/// than the synthetic system, a singular group system, and solvers that disagree.
pub fn measure(params: &LuParams, progress: &dyn Progress) -> Result<Vec<LuTiming>, LabError> {
    let enclosure = Enclosure::new();
    progress.begin("group LU", (params.group_sizes.len() * params.runs) as u64, "runs");
    let timings = time_groups(&enclosure, params, progress);
    progress.end();
    timings
}

fn time_groups(enclosure: &Enclosure, params: &LuParams, progress: &dyn Progress) -> Result<Vec<LuTiming>, LabError> {
    let mut rows = Vec::new();
    let mut done = 0;
    for &m in &params.group_sizes {
        if m == 0 || m > N {
            return Err(LabError::Invalid(format!("a group of {m} patches does not fit the {N}-patch system")));
        }
        let (phi, s) = enclosure.group(m);
        // The two agree before they are timed.
        let (x, y) = (faer_solve(m, &phi, &s), nalgebra_solve(m, &phi, &s));
        if x.len() != 2 || y.len() != 2 {
            return Err(LabError::Invalid(format!("the group system of {m} patches is singular")));
        }
        let scale = x[0].iter().fold(0.0, |a: Real, v| a.max(v.abs()));
        let gap = x.iter().flatten().zip(y.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, Real::max);
        if gap > 1e-10 * scale.max(1.0) {
            return Err(LabError::Invalid(format!(
                "nalgebra and faer disagree by {gap:.1e} on the group system of {m} patches"
            )));
        }
        let (mut nalgebra, mut faer) = (Vec::new(), Vec::new());
        for r in 0..params.runs {
            progress.advance(done, &format!("m = {m}, run {}/{}", r + 1, params.runs));
            nalgebra.push(time_per_call(params.budget, || nalgebra_solve(m, &phi, &s)));
            faer.push(time_per_call(params.budget, || faer_solve(m, &phi, &s)));
            done += 1;
            progress.advance(done, "");
        }
        rows.push(LuTiming { m, nalgebra: median(&nalgebra), faer: median(&faer) });
    }
    Ok(rows)
}

/// The section, headed `## 3. Group solve: nalgebra against faer`, from [`measure`]'s
/// medians.
pub fn report(timings: &[LuTiming]) -> String {
    let mut out = String::from("## 3. Group solve: nalgebra against faer\n\n");
    let _ = writeln!(
        out,
        "One group system `Φ_rr y = s` with the second right-hand side of the condition estimate (one channel, \
         one thread, as a group step solves it; an RGB step solves three), groups of m patches spread over the \
         synthetic {N}-patch enclosure of the `group_solve` criterion bench. faer is `radiosity_core::dense_lu`, \
         what the solvers use. Time per solve, building the matrix included.\n"
    );
    out += "| m | nalgebra | faer | nalgebra ÷ faer |\n|--:|--:|--:|--:|\n";
    for t in timings {
        let _ =
            writeln!(out, "| {} | {} | {} | {:.2} |", t.m, duration(t.nalgebra), duration(t.faer), t.nalgebra / t.faer);
    }
    out.push('\n');
    out
}
