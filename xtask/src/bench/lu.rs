//! Section 3: one group system solved by LU, nalgebra against faer, as the group grows.
//!
//! The systems are those of the `group_solve` criterion bench of radiosity-solvers: a
//! 3400-patch (labyrinth-sized) enclosure with `F_ij = G_ij / A_i`, `G` symmetric and rows of
//! `ρ F` well below 1, reflectivity 0.6; the group is `m` patches spread over it, and the
//! system `Φ_rr = I − diag(ρ_r) F_rr` is solved for the group's unshot radiosity and for the
//! ones of the condition estimate, two right-hand sides on one factorisation, sequentially,
//! as `group_step` solves one channel.

use super::{Config, progress};
use anyhow::{Result, bail};
use radiosity_core::Real;
use radiosity_core::dense_lu::lu_solve_columns;
use radiosity_eval::bench::median;
use radiosity_eval::bench::report_text::duration;
use std::fmt::Write as _;
use std::hint::black_box;
use std::time::Instant;

/// Patches of the synthetic system the groups are taken from.
const N: usize = 3400;
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

/// Runs section 3.
pub(crate) fn run(config: &Config) -> Result<String> {
    let enclosure = Enclosure::new();
    let budget = if config.quick { 0.002 } else { 0.05 };
    let bar = progress((config.group_sizes.len() * config.runs_cheap) as u64, "group LU");
    let mut rows = Vec::new();
    for &m in &config.group_sizes {
        if m == 0 || m > N {
            bail!("a group of {m} patches does not fit the {N}-patch system");
        }
        let (phi, s) = enclosure.group(m);
        // The two agree before they are timed.
        let (x, y) = (faer_solve(m, &phi, &s), nalgebra_solve(m, &phi, &s));
        if x.len() != 2 || y.len() != 2 {
            bail!("the group system of {m} patches is singular");
        }
        let scale = x[0].iter().fold(0.0, |a: Real, v| a.max(v.abs()));
        let gap = x.iter().flatten().zip(y.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, Real::max);
        if gap > 1e-10 * scale.max(1.0) {
            bail!("nalgebra and faer disagree by {gap:.1e} on the group system of {m} patches");
        }
        let (mut nalgebra, mut faer) = (Vec::new(), Vec::new());
        for r in 0..config.runs_cheap {
            bar.set_message(format!("m = {m}, run {}/{}", r + 1, config.runs_cheap));
            nalgebra.push(time_per_call(budget, || nalgebra_solve(m, &phi, &s)));
            faer.push(time_per_call(budget, || faer_solve(m, &phi, &s)));
            bar.inc(1);
        }
        rows.push((m, median(&nalgebra), median(&faer)));
    }
    bar.finish_and_clear();
    let mut out = String::from("## 3. Group solve: nalgebra against faer\n\n");
    let _ = writeln!(
        out,
        "One group system `Φ_rr y = s` with the second right-hand side of the condition estimate (one channel, \
         one thread, as a group step solves it; an RGB step solves three), groups of m patches spread over the \
         synthetic {N}-patch enclosure of the `group_solve` criterion bench. faer is `radiosity_core::dense_lu`, \
         what the solvers use. Time per solve, building the matrix included.\n"
    );
    out += "| m | nalgebra | faer | nalgebra ÷ faer |\n|--:|--:|--:|--:|\n";
    for (m, nalgebra, faer) in rows {
        let _ = writeln!(out, "| {m} | {} | {} | {:.2} |", duration(nalgebra), duration(faer), nalgebra / faer);
    }
    out.push('\n');
    Ok(out)
}
