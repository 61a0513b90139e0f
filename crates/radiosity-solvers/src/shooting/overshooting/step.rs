//! The overshooting step shared by `feda`, `shao`, `xu` and `relax-ω`: shoot more than the
//! unshot radiosity, anticipating the light that will come back.
//!
//! ## Rule
//!
//! Pick `j = argmax_j A_j Σ_c |ΔB_jc + ΔB⁺_jc|` (lowest index on ties), shoot `s = ΔB_j + ΔB⁺_j`
//! ([`crate::shooting::rule::shoot_column`]), then set `ΔB_j = −ΔB⁺_j` (plus the shooter's own
//! share `ρ_j F_jj s`, zero for planar patches, [`crate::shooting::rule::own_share`]). The shot
//! radiosity `x = B − ΔB` grows by `s` at `j`, and `ΔB` stays exactly the residual of `x` whatever
//! `ΔB⁺` is: the overshoot changes the speed, never the fixed point. One column a step.
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
//! `A_j |ΔB_j|` would pick it again and again, and each time it would shoot `≈ 0`: the run
//! freezes (docs/design.md §4.4). So selection uses
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
use crate::naming::{ParseSolverError, SolverParams, named, no_params, split_params, validated};
use crate::run::executor::Solver;
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::{self, ResidualBound};
use crate::run::state::State;
use crate::shooting::overshooting::overshoot::{AmbientTerm, Overshoot, RowTerm};
use crate::shooting::overshooting::xu::XuParts;
use crate::shooting::overshooting::{feda, relax, shao, xu};
use crate::shooting::progressive::ProgressiveRefinement;
use crate::shooting::rule::{own_share, set_unshot, shoot_column, unshot_power};
use crate::shooting::southwell::Southwell;
use radiosity_core::Real;
use std::str::FromStr;

/// A point shooting method by its command-line name (`southwell`, `pr`, `feda`, `shao`, `xu`,
/// `xu-direct`, `xu-ambient`, `relax-ω`): what a point, group or group-accelerated shooting
/// name builds on.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum ShootingMethod {
    /// Southwell: the largest `|ΔB|`, no overshoot ([`crate::Southwell`]).
    Southwell,
    /// Progressive refinement: the largest `A |ΔB|`, no overshoot
    /// ([`crate::ProgressiveRefinement`]).
    Pr,
    /// Feda's ambient overshoot, `ΔB⁺_j = ρ_j R̄ ΔB̄` (Feda & Purgathofer 1992).
    Feda,
    /// Shao's positive gather, `ΔB⁺_j = ρ_j Σ_k F_jk max(ΔB_k, 0)` (Shao & Badler 1993).
    Shao,
    /// Xu's overshoot with the parts chosen ([`XuParts`]; after Xu & Fussell 1994).
    Xu(XuParts),
    /// Over-relaxation by `ω` in `(0, 2)`, `ΔB⁺_j = (ω − 1) ΔB_j` (Gortler, Cohen & Slusallek
    /// 1993).
    Relax(Real),
}

impl ShootingMethod {
    /// The method a name designates: `None` when it names none, an error for `relax-ω` with
    /// `ω` outside `(0, 2)`.
    pub fn parse(name: &str) -> Option<Result<ShootingMethod, SolverError>> {
        let method = match name {
            "southwell" => ShootingMethod::Southwell,
            "pr" => ShootingMethod::Pr,
            "feda" => ShootingMethod::Feda,
            "shao" => ShootingMethod::Shao,
            "xu" => ShootingMethod::Xu(XuParts::BOTH),
            "xu-direct" => ShootingMethod::Xu(XuParts { direct: true, ambient: false }),
            "xu-ambient" => ShootingMethod::Xu(XuParts { direct: false, ambient: true }),
            _ => {
                let omega = name.strip_prefix("relax-")?.parse::<Real>().ok()?;
                if !(omega > 0.0 && omega < 2.0) {
                    return Some(Err(SolverError::BadParams(format!("relaxation needs 0 < ω < 2, not {omega}"))));
                }
                ShootingMethod::Relax(omega)
            }
        };
        Some(Ok(method))
    }

    /// The command-line name (`relax-1.5`).
    pub fn name(self) -> String {
        match self {
            ShootingMethod::Southwell => "southwell".into(),
            ShootingMethod::Pr => "pr".into(),
            ShootingMethod::Feda => "feda".into(),
            ShootingMethod::Shao => "shao".into(),
            ShootingMethod::Xu(parts) => parts.name().into(),
            ShootingMethod::Relax(omega) => format!("relax-{omega}"),
        }
    }

    /// The overshoot it shoots with (none for Southwell and PR).
    pub fn overshoot(self) -> Overshoot {
        match self {
            ShootingMethod::Southwell | ShootingMethod::Pr => Overshoot::NONE,
            ShootingMethod::Feda => feda::RULE,
            ShootingMethod::Shao => shao::RULE,
            ShootingMethod::Xu(parts) => xu::rule(parts),
            ShootingMethod::Relax(omega) => relax::rule(omega),
        }
    }

    /// Whether selection weighs by area (every method but Southwell).
    pub fn by_area(self) -> bool {
        self != ShootingMethod::Southwell
    }
}

/// The point shooting names: `southwell`, `pr`, and the overshooting variants; none takes
/// parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointShootingParams {
    /// The method.
    pub method: ShootingMethod,
}

impl FromStr for PointShootingParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<PointShootingParams, ParseSolverError> {
        let (head, params) = split_params(name);
        let method = ShootingMethod::parse(head).ok_or(ParseSolverError::OtherFamily)?;
        no_params(head, params)?;
        let method = method.map_err(|e| named(name, e))?;
        validated(name, PointShootingParams { method })
    }
}

impl SolverParams for PointShootingParams {
    const SYNTAX: &'static str = "southwell, pr, feda, shao, xu, xu-direct, xu-ambient, relax-ω";
    const HELP: &'static str = "point shooting: southwell by |ΔB|, pr by A|ΔB|, the others overshoot (0 < ω < 2)";
    const EXAMPLES: &'static [&'static str] = &["pr", "xu", "xu-direct", "relax-1.5"];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        Ok(match self.method {
            ShootingMethod::Southwell => Box::new(Southwell::default()),
            ShootingMethod::Pr => Box::new(ProgressiveRefinement::default()),
            method => Box::new(Overshooting::new(method.name(), method.overshoot())?),
        })
    }
}

/// The overshoot of a shooting method, and what it remembers to estimate it for selection:
/// shared by point, group and group-accelerated shooting.
#[derive(Clone, Debug)]
pub struct OvershootTracker {
    rule: Overshoot,
    /// Whether selection weighs by area (PR and overshooting) or not (Southwell).
    by_area: bool,
    /// `ρ̄_c` per channel.
    mean_rho: Vec<Real>,
    /// The row term of each patch's last shot, patch-major.
    last_row: Vec<Real>,
    /// The unshot power just after each patch's last shot (`NaN`: never shot).
    power_then: Vec<Real>,
}

/// The state-wide quantities an overshoot needs, measured before each step.
#[derive(Clone, Debug)]
pub struct Ambient {
    /// `ΔB̄_c`.
    mean: Vec<Real>,
    /// The area-weighted mean of `max(ΔB_c, 0)`.
    positive: Vec<Real>,
    /// `Σ_c Σ_i A_i |ΔB_ic|`.
    power: Real,
    /// The fraction of the area outside the group (1 for a point shot).
    outside: Real,
}

impl Ambient {
    /// Measures the ambient quantities of `state`.
    pub fn measure(problem: &Problem<'_>, state: &State) -> Ambient {
        Ambient::measure_outside(problem, state, &[])
    }

    /// Measures the ambient quantities of `state` counting only the unshot radiosity outside
    /// `group` (sorted patch indices) in the means, still divided by the whole area: the
    /// light a group step's solve does not already account for. `power` counts every patch.
    pub fn measure_outside(problem: &Problem<'_>, state: &State, group: &[usize]) -> Ambient {
        let (area, k) = (problem.system().areas(), state.channels);
        let (mut mean, mut positive, mut power, mut total) = (vec![0.0; k], vec![0.0; k], 0.0, 0.0);
        let mut outside_area = 0.0;
        for (i, unshot) in state.unshot.chunks_exact(k).enumerate() {
            total += area[i];
            let outside = group.binary_search(&i).is_err();
            if outside {
                outside_area += area[i];
            }
            for (c, &u) in unshot.iter().enumerate() {
                if outside {
                    mean[c] += area[i] * u;
                    positive[c] += area[i] * u.max(0.0);
                }
                power += area[i] * u.abs();
            }
        }
        for c in 0..k {
            mean[c] /= total;
            positive[c] /= total;
        }
        Ambient { mean, positive, power, outside: outside_area / total }
    }

    /// `Σ_c Σ_i A_i |ΔB_ic|`.
    pub fn power(&self) -> Real {
        self.power
    }
}

impl OvershootTracker {
    /// A tracker for `rule`, choosing by area-weighted values (`by_area`) or plain ones.
    /// `rule.omega` must lie in `(0, 2)`.
    pub fn new(rule: Overshoot, by_area: bool) -> Result<OvershootTracker, SolverError> {
        if !(rule.omega > 0.0 && rule.omega < 2.0) {
            return Err(SolverError::BadParams(format!("relaxation needs 0 < ω < 2, not {}", rule.omega)));
        }
        Ok(OvershootTracker { rule, by_area, mean_rho: Vec::new(), last_row: Vec::new(), power_then: Vec::new() })
    }

    /// Prepares for a run on `problem`.
    pub fn init(&mut self, problem: &Problem<'_>) {
        let (system, k, n) = (problem.system(), problem.channels(), problem.n());
        let total: Real = system.areas().iter().sum();
        self.mean_rho =
            (0..k).map(|c| (0..n).map(|i| system.areas()[i] * system.rho(i, c)).sum::<Real>() / total).collect();
        self.last_row = vec![0.0; n * k];
        self.power_then = vec![Real::NAN; n];
    }

    /// The ambient weight `a_c`: `R̄ = 1/(1 − ρ̄)` for all bounces, `ρ̄ R̄` for the bounces after
    /// the first. For a group step, bounces that come back through the group are the group's
    /// own solve's business, so only the outside fraction `φ` of the area reflects:
    /// `1/(1 − ρ̄ φ)` and `ρ̄ φ/(1 − ρ̄ φ)`; `φ = 1` for a point shot.
    fn ambient_weight(&self, ambient: &Ambient, c: usize) -> Real {
        let reflected = self.mean_rho[c] * ambient.outside;
        match self.rule.ambient {
            AmbientTerm::Off => 0.0,
            AmbientTerm::AllBounces => 1.0 / (1.0 - reflected),
            AmbientTerm::LaterBounces => reflected / (1.0 - reflected),
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
            let weight = self.ambient_weight(ambient, c);
            plus[c] = rho * (row[c] + weight * ambient.mean[c]) + (self.rule.omega - 1.0) * unshot;
        }
    }

    /// The overshoot of patch `j` as estimated without its row, into `plus`.
    pub fn estimate(&self, problem: &Problem<'_>, state: &State, ambient: &Ambient, j: usize, plus: &mut [Real]) {
        let k = state.channels;
        // At most 3 channels: no allocation in this per-patch, per-step path.
        let mut row = [0.0; 3];
        let row = &mut row[..k];
        if let Some(term) = self.rule.row {
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
        self.overshoot(problem, state, ambient, j, row, plus);
    }

    /// The exact overshoot of patch `j` into `plus`, from its column (`column[i] = F_ij`;
    /// the row follows by reciprocity, `F_ji = F_ij A_i / A_j`), and its row term into `row`.
    /// The row term leaves out the patches of `group` (sorted; empty for a point shot), whose
    /// exchanges with `j` a group step solves exactly.
    #[allow(clippy::too_many_arguments)]
    pub fn exact(
        &self,
        problem: &Problem<'_>,
        state: &State,
        ambient: &Ambient,
        j: usize,
        column: &[Real],
        group: &[usize],
        row: &mut [Real],
        plus: &mut [Real],
    ) {
        row.fill(0.0);
        if let Some(term) = self.rule.row {
            let (area, k) = (problem.system().areas(), state.channels);
            for (i, &f) in column.iter().enumerate() {
                if f == 0.0 || (!group.is_empty() && group.binary_search(&i).is_ok()) {
                    continue;
                }
                let f_ji = f * area[i] / area[j];
                for (c, r) in row.iter_mut().enumerate() {
                    let u = state.unshot[i * k + c];
                    *r += f_ji * if term == RowTerm::Positive { u.max(0.0) } else { u };
                }
            }
        }
        self.overshoot(problem, state, ambient, j, row, plus);
    }

    /// The operations [`OvershootTracker::exact`] counts for one patch of `n` patches and `k`
    /// channels: `n k` for the sum along its row when the rule has a row term, `k` otherwise.
    pub fn exact_operations(&self, n: usize, k: usize) -> u64 {
        if self.rule.row.is_some() { (n * k) as u64 } else { k as u64 }
    }

    /// The selection value of patch `j` shooting with overshoot `plus`:
    /// `A_j Σ_c |ΔB_jc + ΔB⁺_jc|` (without `A_j` for Southwell).
    pub fn value(&self, problem: &Problem<'_>, state: &State, j: usize, plus: &[Real]) -> Real {
        let k = state.channels;
        let weight = if self.by_area { problem.system().areas()[j] } else { 1.0 };
        weight * state.unshot[j * k..(j + 1) * k].iter().zip(plus).map(|(u, p)| (u + p).abs()).sum::<Real>()
    }

    /// Every patch's estimated selection value.
    pub fn values(&self, problem: &Problem<'_>, state: &State, ambient: &Ambient) -> Vec<Real> {
        let mut plus = vec![0.0; state.channels];
        (0..problem.n())
            .map(|j| {
                self.estimate(problem, state, ambient, j, &mut plus);
                self.value(problem, state, j, &plus)
            })
            .collect()
    }

    /// Records that `j` shot with row term `row`, leaving unshot power `power`.
    pub fn record(&mut self, j: usize, row: &[Real], power: Real) {
        let k = row.len();
        self.last_row[j * k..(j + 1) * k].copy_from_slice(row);
        self.power_then[j] = power;
    }
}

/// The index of the largest value, lowest index on ties.
pub fn argmax(values: &[Real]) -> usize {
    let mut best = (0, Real::NEG_INFINITY);
    for (j, &v) in values.iter().enumerate() {
        if v > best.1 {
            best = (j, v);
        }
    }
    best.0
}

/// The `m` largest positive values among `candidates`, largest first (lower index first on
/// ties): fewer when fewer are positive.
pub fn top(values: &[Real], candidates: impl Iterator<Item = usize>, m: usize) -> Vec<usize> {
    let mut chosen: Vec<usize> = candidates.filter(|&j| values[j] > 0.0).collect();
    chosen.sort_by(|&a, &b| values[b].total_cmp(&values[a]).then(a.cmp(&b)));
    chosen.truncate(m);
    chosen
}

/// Point shooting with an overshoot: the solver behind `feda`, `shao`, `xu` and `relax-ω`.
#[derive(Debug)]
pub struct Overshooting {
    name: String,
    tracker: OvershootTracker,
    column: Vec<Real>,
}

impl Overshooting {
    /// An overshooting solver named `name` (as on the command line) using `rule`.
    pub fn new(name: impl Into<String>, rule: Overshoot) -> Result<Overshooting, SolverError> {
        Ok(Overshooting { name: name.into(), tracker: OvershootTracker::new(rule, true)?, column: Vec::new() })
    }
}

/// One point shot from `j` with its exact overshoot, through `column` (already fetched):
/// shoots `ΔB_j + ΔB⁺_j`, leaves `−ΔB⁺_j`, and records the shot in `tracker`.
pub fn shoot_with_overshoot(
    problem: &Problem<'_>,
    state: &mut State,
    tracker: &mut OvershootTracker,
    ambient: &Ambient,
    j: usize,
    column: &[Real],
) -> Result<(), SolverError> {
    let k = state.channels;
    let (mut row, mut plus) = (vec![0.0; k], vec![0.0; k]);
    tracker.exact(problem, state, ambient, j, column, &[], &mut row, &mut plus);
    let unshot = &state.unshot[j * k..(j + 1) * k];
    let amount: Vec<Real> = unshot.iter().zip(&plus).map(|(u, p)| u + p).collect();
    shoot_column(problem, state, &amount, column)?;
    for (c, p) in plus.iter().enumerate() {
        set_unshot(state, j * k + c, own_share(problem, j, c, amount[c], column) - p)?;
    }
    tracker.record(j, &row, Ambient::measure(problem, state).power);
    Ok(())
}

impl Solver for Overshooting {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn init(&mut self, problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        self.tracker.init(problem);
        self.column = vec![0.0; problem.n()];
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let ambient = Ambient::measure(problem, state);
        let j = argmax(&self.tracker.values(problem, state, &ambient));
        problem.column(j, &mut self.column);
        shoot_with_overshoot(problem, state, &mut self.tracker, &ambient, j, &self.column)?;
        Ok(Record::new())
    }

    fn residual_power(&self, problem: &Problem<'_>, state: &State) -> Option<Real> {
        Some(unshot_power(problem, state))
    }

    fn residual_bound(&self, problem: &Problem<'_>, state: &State) -> Option<ResidualBound> {
        Some(residual_bound::shooting(problem, state))
    }
}
