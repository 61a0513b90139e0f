//! The overshooting step shared by `feda`, `shao`, `xu` and `relax-ω`: shoot more than the
//! unshot radiosity, anticipating the light that will come back.
//!
//! ## Rule
//!
//! Pick `j = argmax_j A_j Σ_c |ΔB_jc + ΔB⁺_jc|` (lowest index on ties), shoot
//! `s = ΔB_j + ΔB⁺_j` ([`crate::shooting::shoot_column`]), then set `ΔB_j = −ΔB⁺_j`. The shot
//! radiosity `x = B − ΔB` grows by `s` at `j`, and `ΔB` stays exactly the residual of `x`
//! whatever `ΔB⁺` is: the overshoot changes the speed, never the fixed point. One column a
//! step.
//!
//! Every variant's overshoot is a sum of three terms, per channel `c`:
//!
//! `ΔB⁺_jc = ρ_jc · (row term + a_c ΔB̄_c) + (ω − 1) ΔB_jc`,
//!
//! with `ΔB̄_c = Σ_k A_k ΔB_kc / Σ_k A_k` the ambient unshot radiosity, `a_c` a weight fixed by
//! the variant (built from `ρ̄_c`, the area-weighted mean reflectivity, and `R̄_c = 1/(1 − ρ̄_c)`),
//! and the row term a sum along the patch's own row, `Σ_k F_jk ΔB_kc` (signed) or
//! `Σ_k F_jk max(ΔB_kc, 0)` (positive). [`Overshoot`] says which terms a variant uses.
//!
//! ## Selection, and why it uses the overshoot
//!
//! Once a patch has shot, its unshot radiosity is `−ΔB⁺`, possibly large. Choosing by
//! `A_j |ΔB_j|` would pick it again and again, and each time it would shoot `≈ 0` (DESIGN §4
//! records a prototype of `xu` freezing at e_rms 1.6e-2 that way). So selection uses
//! `|ΔB_j + ΔB⁺_j|`, with the overshoot the shot will use. The ambient and relaxation terms
//! are known for every patch. The row term is known only for the shooter, whose column is
//! fetched for the shot (its row follows by reciprocity, `F_jk = F_kj A_k / A_j`); for the
//! others it is estimated:
//!
//! - a patch that has shot before: the row term of its last shot, scaled by how much the
//!   unshot power `Σ A |ΔB|` changed since. Right after a shot this is exact, so the shooter's
//!   selection value is zero and it cannot be chosen to shoot nothing; as the solution
//!   converges the estimate fades and the patch's own `|ΔB|` decides;
//! - a patch that has never shot: the ambient value (`ΔB̄_c`, or the area-weighted mean of
//!   `max(ΔB, 0)` for the positive term), which the row term equals when the patch sees the
//!   whole scene evenly.
//!
//! An estimate steers only the choice: the shot itself always uses the exact row term.
//!
//! ## References
//!
//! - Feda & Purgathofer 1992, "Accelerating radiosity by overshooting", Third Eurographics
//!   Workshop on Rendering, 21–32.
//! - Shao & Badler 1993, "Analysis and acceleration of progressive refinement radiosity
//!   method", Fourth Eurographics Workshop on Rendering, 247–258.
//! - Xu & Fussell 1994, "A fast solver of radiosity equation systems", Pacific Graphics.
//! - Gortler, Cohen & Slusallek 1993, "Radiosity and relaxation methods: progressive
//!   refinement is Southwell relaxation", Princeton CS-TR-408-93.
//! - Rousselle & Renaud, "Group accelerated shooting methods for radiosity", §2.

use crate::error::SolverError;
use crate::executor::Solver;
use crate::problem::Problem;
use crate::shooting::{shoot_column, unshot_power};
use crate::state::State;
use radiosity_core::Real;

/// A sum along the shooter's own row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowTerm {
    /// `Σ_k F_jk ΔB_k`.
    Signed,
    /// `Σ_k F_jk max(ΔB_k, 0)`.
    Positive,
}

/// The ambient term's weight `a_c` on `ΔB̄_c`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AmbientTerm {
    /// No ambient term.
    Off,
    /// `a = R̄ = 1/(1 − ρ̄)`: all future bounces of the ambient light (Feda).
    AllBounces,
    /// `a = ρ̄ R̄`: the bounces after the first (Xu's second part).
    LaterBounces,
}

/// Which terms an overshooting variant uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overshoot {
    /// The row term, if any.
    pub row: Option<RowTerm>,
    /// The ambient term.
    pub ambient: AmbientTerm,
    /// `ω`: the relaxation term is `(ω − 1) ΔB_j` (1 for none).
    pub omega: Real,
}

/// Point shooting with an overshoot: the solver behind `feda`, `shao`, `xu` and `relax-ω`.
#[derive(Debug)]
pub struct Overshooting {
    name: String,
    rule: Overshoot,
    /// `a_c` per channel.
    ambient_weight: Vec<Real>,
    /// The row term of each patch's last shot, patch-major.
    last_row: Vec<Real>,
    /// The unshot power just after each patch's last shot (`NaN`: never shot).
    power_then: Vec<Real>,
    column: Vec<Real>,
}

/// The state-wide quantities an overshoot needs, measured before each step.
struct Ambient {
    /// `ΔB̄_c`.
    mean: Vec<Real>,
    /// The area-weighted mean of `max(ΔB_c, 0)`.
    positive: Vec<Real>,
    /// `Σ_c Σ_i A_i |ΔB_ic|`.
    power: Real,
}

impl Ambient {
    fn measure(problem: &Problem<'_>, state: &State) -> Ambient {
        let (area, k) = (problem.system().areas(), state.channels);
        let (mut mean, mut positive, mut power, mut total) = (vec![0.0; k], vec![0.0; k], 0.0, 0.0);
        for (i, unshot) in state.unshot.chunks_exact(k).enumerate() {
            total += area[i];
            for (c, &u) in unshot.iter().enumerate() {
                mean[c] += area[i] * u;
                positive[c] += area[i] * u.max(0.0);
                power += area[i] * u.abs();
            }
        }
        for c in 0..k {
            mean[c] /= total;
            positive[c] /= total;
        }
        Ambient { mean, positive, power }
    }
}

impl Overshooting {
    /// An overshooting solver named `name` (as on the command line) using `rule`.
    pub fn new(name: impl Into<String>, rule: Overshoot) -> Result<Overshooting, SolverError> {
        if !(rule.omega > 0.0 && rule.omega < 2.0) {
            return Err(SolverError::BadParams(format!("relaxation needs 0 < ω < 2, not {}", rule.omega)));
        }
        Ok(Overshooting::unchecked(name, rule))
    }

    /// The solver for a rule without relaxation (`ω = 1`, always valid).
    pub(crate) fn without_relaxation(name: impl Into<String>, rule: Overshoot) -> Overshooting {
        Overshooting::unchecked(name, Overshoot { omega: 1.0, ..rule })
    }

    fn unchecked(name: impl Into<String>, rule: Overshoot) -> Overshooting {
        Overshooting {
            name: name.into(),
            rule,
            ambient_weight: Vec::new(),
            last_row: Vec::new(),
            power_then: Vec::new(),
            column: Vec::new(),
        }
    }

    /// The overshoot of patch `j` into `plus`, from its row term `row` (exact or estimated).
    fn overshoot(
        &self,
        problem: &Problem<'_>,
        state: &State,
        ambient: &Ambient,
        j: usize,
        row: &[Real],
        plus: &mut [Real],
    ) {
        let k = state.channels;
        for c in 0..k {
            let rho = problem.system().rho(j, c);
            let unshot = state.unshot[j * k + c];
            plus[c] = rho * (row[c] + self.ambient_weight[c] * ambient.mean[c]) + (self.rule.omega - 1.0) * unshot;
        }
    }

    /// The row term of patch `j` as estimated without its row, into `row`.
    fn estimated_row(&self, ambient: &Ambient, k: usize, j: usize, row: &mut [Real]) {
        let Some(term) = self.rule.row else {
            row.fill(0.0);
            return;
        };
        let then = self.power_then[j];
        if then.is_nan() {
            row.copy_from_slice(match term {
                RowTerm::Signed => &ambient.mean,
                RowTerm::Positive => &ambient.positive,
            });
        } else {
            let scale = if then > 0.0 { ambient.power / then } else { 0.0 };
            for (r, &last) in row.iter_mut().zip(&self.last_row[j * k..(j + 1) * k]) {
                *r = last * scale;
            }
        }
    }

    /// The patch maximising `A_j Σ_c |ΔB_jc + ΔB⁺_jc|`, lowest index on ties.
    fn select(&self, problem: &Problem<'_>, state: &State, ambient: &Ambient) -> usize {
        let (area, k) = (problem.system().areas(), state.channels);
        let (mut row, mut plus) = (vec![0.0; k], vec![0.0; k]);
        let mut best = (0, Real::NEG_INFINITY);
        for (j, (unshot, a)) in state.unshot.chunks_exact(k).zip(area).enumerate() {
            self.estimated_row(ambient, k, j, &mut row);
            self.overshoot(problem, state, ambient, j, &row, &mut plus);
            let value = a * unshot.iter().zip(&plus).map(|(u, p)| (u + p).abs()).sum::<Real>();
            if value > best.1 {
                best = (j, value);
            }
        }
        best.0
    }

    /// The exact row term of `j` from its column: `Σ_i F_ji f(ΔB_i)` with
    /// `F_ji = F_ij A_i / A_j`.
    fn exact_row(&self, problem: &Problem<'_>, state: &State, j: usize, row: &mut [Real]) {
        row.fill(0.0);
        let Some(term) = self.rule.row else { return };
        let (area, k) = (problem.system().areas(), state.channels);
        for (i, &f) in self.column.iter().enumerate() {
            if f == 0.0 {
                continue;
            }
            let f_ji = f * area[i] / area[j];
            for (c, r) in row.iter_mut().enumerate() {
                let u = state.unshot[i * k + c];
                *r += f_ji * if term == RowTerm::Positive { u.max(0.0) } else { u };
            }
        }
    }
}

impl Solver for Overshooting {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn init(&mut self, problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        let (system, k, n) = (problem.system(), problem.channels(), problem.n());
        let total: Real = system.areas().iter().sum();
        self.ambient_weight = (0..k)
            .map(|c| {
                let mean_rho = (0..n).map(|i| system.areas()[i] * system.rho(i, c)).sum::<Real>() / total;
                let all = 1.0 / (1.0 - mean_rho);
                match self.rule.ambient {
                    AmbientTerm::Off => 0.0,
                    AmbientTerm::AllBounces => all,
                    AmbientTerm::LaterBounces => mean_rho * all,
                }
            })
            .collect();
        self.last_row = vec![0.0; n * k];
        self.power_then = vec![Real::NAN; n];
        self.column = vec![0.0; n];
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        let k = state.channels;
        let ambient = Ambient::measure(problem, state);
        let j = self.select(problem, state, &ambient);
        problem.column(j, &mut self.column);
        let (mut row, mut plus) = (vec![0.0; k], vec![0.0; k]);
        self.exact_row(problem, state, j, &mut row);
        self.overshoot(problem, state, &ambient, j, &row, &mut plus);
        let unshot = &state.unshot[j * k..(j + 1) * k];
        let amount: Vec<Real> = unshot.iter().zip(&plus).map(|(u, p)| u + p).collect();
        shoot_column(problem, state, &amount, &self.column)?;
        for (u, p) in state.unshot[j * k..(j + 1) * k].iter_mut().zip(&plus) {
            *u = -p;
        }
        self.last_row[j * k..(j + 1) * k].copy_from_slice(&row);
        self.power_then[j] = Ambient::measure(problem, state).power;
        Ok(())
    }

    fn residual_power(&self, problem: &Problem<'_>, state: &State) -> Option<Real> {
        Some(unshot_power(problem, state))
    }
}
