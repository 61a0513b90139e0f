//! `stochastic-jacobi`: stochastic relaxation, Jacobi iterations whose transport is estimated
//! with rays (Neumann's stochastic ray method, Bekaert's stochastic Jacobi); `F` is never
//! formed.
//!
//! ## The method
//!
//! Written in power, `P_i = A_i B_i`, the system is `P = Φ + R T P` with `Φ_i = A_i E_i`,
//! `R = diag(ρ)` and `T_ij = A_i F_ij / A_j` the fraction of `j`'s power that lands on `i`,
//! which a ray estimates ([`radiosity_core::transport`]).
//!
//! 1. **Incremental shooting.** The unshot power `ΔP^0 = Φ` is shot: `ΔP^{k+1} = R T̂ ΔP^k`
//!    with `N_k = ⌈N · |ΔP^k| / |Φ|⌉` rays, `N` the step's batch, so that every ray carries
//!    the same power; `P ← P + ΔP^{k+1}`. It stops once the unshot power is spent,
//!    `|ΔP^k| ≤ spent · |Φ|` (`spent=1e-4` by default); what is left is an underestimate of at
//!    most that fraction, which the regular iterations then remove.
//! 2. **Regular iterations.** Each shoots the whole estimate `P̄` once more with `N` rays,
//!    `P' = Φ + R T̂ P̄`, an unbiased estimate of the solution when `P̄` is one (`E[P'] = Φ +
//!    R T E[P̄]`, by linearity), and combines it with the estimates so far, weighted by the
//!    inverse of their variance: to first order (Dutré, Bekaert & Bala, Appendix C),
//!    `V[P̂_i] ≈ ρ_i P_T (P_i − Φ_i) / N` for `N` rays shooting total power `P_T`, and the
//!    incremental phase's `N_1` rays give the same variance as a regular iteration of `N_1`
//!    rays, so every estimate is weighted by the rays it cast.
//!
//! Options:
//! - `form=gathering`: the regular iterations gather, `B'_i = E_i + ρ_i Σ_j F_ij B̄_j`, every
//!   patch that reflects casting rays in proportion to its area ([`crate::stochastic::estimate`]);
//!   with `cv=true`, against a constant control variate `β` (the area-weighted mean of `B̄`,
//!   per channel): `Σ_j F_ij B̄_j = β r_i + Σ_j F_ij (B̄_j − β)`, which needs the row sums
//!   `r_i` from the sampler (a stored matrix; a closed scene, where they are 1).
//! - `lines=global`: every iteration's transport by global lines instead of rays from patches.
//! - `seq=random|sobol|halton`: the rays' sequence ([`crate::Sequence`]).
//! - `replicates=R` (4 by default, at least 2): `R` independent chains, each with `N / R` rays
//!   a step; the solver displays their mean and its standard error
//!   ([`crate::StandardError`]), the error bar that needs no reference.
//! - `batch=N` (by default `10n` and at least 1000): the rays of a regular iteration, and of
//!   the incremental phase's first, over all replicates; a batch that is written is kept as
//!   written (at least one ray a replicate), never raised;
//!   `seed=S` (1 by default).
//!
//! The first step is the whole incremental phase of every replicate, about `N / (1 − q)` rays
//! for a scene that reflects a fraction `q` of the power shot; every later step is one regular
//! iteration of every replicate ([`StepKind::Sampled`]). A step's cost is the rays cast
//! ([`crate::State::rays`]). A run stopped inside the incremental phase would display an
//! estimate short of the power still unshot: a bias every replicate shares, which the spread
//! between them cannot see, so the standard error would not cover the true error
//! (docs/stochastic.md).
//! Taken whole, the series leaves at most `spent` of the emitted power unshot, reported as
//! `unshot_power` in the solver's record ([`StochasticJacobi::unshot_power`]). No residual is
//! known without `F`, so none is reported ([`Solver::residual_power`]), and a run ends by its
//! stop rules or the step cap; the state's unshot radiosity is 0 once the series is shot.
//!
//! ## References
//!
//! - Neumann, Feda, Kopp & Tobler 1995, "A new stochastic radiosity method for highly complex
//!   scenes", Photorealistic Rendering Techniques (Eurographics Rendering Workshop 1994).
//! - Bekaert 1999, *Hierarchical and stochastic algorithms for radiosity*, PhD thesis, KU
//!   Leuven (stochastic Jacobi iterations, their variance, control variates).
//! - Dutré, Bekaert & Bala 2006, *Advanced Global Illumination*, 2nd ed., A K Peters: §6.3
//!   (stochastic relaxation radiosity) and Appendix C (the variance of incremental shooting).
//! - Sbert 1993, "An integral geometry based method for fast form-factor computation",
//!   Computer Graphics Forum 12(3) (global lines).

use crate::error::SolverError;
use crate::naming::{ParseSolverError, SolverParams, split_params, validated};
use crate::run::cost::Unit;
use crate::run::executor::{Solver, StepKind};
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::standard_error::StandardError;
use crate::run::state::State;
use crate::run::stop::Count;
use crate::stochastic::estimate::{Cast, Streams, gather, lines, shoot};
use crate::stochastic::ranks::Share;
use crate::stochastic::sequence::Sequence;
use radiosity_core::Real;
use rayon::prelude::*;
use std::str::FromStr;

/// Where the regular iterations take their transport from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum JacobiForm {
    /// Shooting the estimate's power (the default).
    #[default]
    Shooting,
    /// Gathering radiosity at every patch.
    Gathering,
}

/// The name `stochastic-jacobi[:form=…][:cv=true][:lines=global][:seq=…][:replicates=R]
/// [:batch=N][:seed=S][:spent=ε]` (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct StochasticJacobiParams {
    /// Shooting or gathering regular iterations.
    pub form: JacobiForm,
    /// The constant control variate (gathering only).
    pub control_variate: bool,
    /// Global lines instead of rays from patches.
    pub global_lines: bool,
    /// The rays' sequence.
    pub sequence: Sequence,
    /// Independent chains (at least 2).
    pub replicates: usize,
    /// Rays a step over all replicates, absolute or per patch (`batch=1e5`, `batch=10n`).
    pub batch: Count,
    /// The seed.
    pub seed: u64,
    /// The unshot power, relative to the emitted, at which incremental shooting ends.
    pub spent: Real,
}

impl Default for StochasticJacobiParams {
    fn default() -> Self {
        StochasticJacobiParams {
            form: JacobiForm::Shooting,
            control_variate: false,
            global_lines: false,
            sequence: Sequence::Random,
            replicates: 4,
            batch: Count::PerPatch(10.0),
            seed: 1,
            spent: 1e-4,
        }
    }
}

/// The smallest default batch.
const MIN_BATCH: u64 = 1000;

fn refuse(reason: String) -> ParseSolverError {
    SolverError::BadParams(format!("solver 'stochastic-jacobi': {reason}")).into()
}

impl FromStr for StochasticJacobiParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<StochasticJacobiParams, ParseSolverError> {
        let (head, params) = split_params(name);
        if head != "stochastic-jacobi" {
            return Err(ParseSolverError::OtherFamily);
        }
        let mut p = StochasticJacobiParams::default();
        for item in params.split(':').filter(|s| !s.is_empty()) {
            let (key, value) =
                item.split_once('=').ok_or_else(|| refuse(format!("expected key=value, not '{item}'")))?;
            match key {
                "form" => {
                    p.form = match value {
                        "shooting" => JacobiForm::Shooting,
                        "gathering" => JacobiForm::Gathering,
                        _ => return Err(refuse(format!("form is shooting or gathering, not '{value}'"))),
                    }
                }
                "cv" => {
                    p.control_variate = match value {
                        "true" => true,
                        "false" => false,
                        _ => return Err(refuse(format!("cv is true or false, not '{value}'"))),
                    }
                }
                "lines" => {
                    p.global_lines = match value {
                        "global" => true,
                        "local" => false,
                        _ => return Err(refuse(format!("lines is global or local, not '{value}'"))),
                    }
                }
                "seq" => {
                    p.sequence = Sequence::parse(value)
                        .ok_or_else(|| refuse(format!("seq is random, sobol or halton, not '{value}'")))?
                }
                "replicates" => {
                    p.replicates =
                        value.parse::<usize>().ok().filter(|r| (2..=1024).contains(r)).ok_or_else(|| {
                            refuse(format!("replicates is a whole number from 2 to 1024, not '{value}'"))
                        })?
                }
                "batch" => {
                    p.batch = Count::parse(value).map_err(|_| {
                        refuse(format!(
                            "batch is a number of rays or a multiple of n, such as 1e5 or 10n, not '{value}'"
                        ))
                    })?
                }
                "seed" => {
                    p.seed = value.parse().map_err(|_| refuse(format!("seed is a whole number, not '{value}'")))?
                }
                "spent" => {
                    p.spent = value
                        .parse::<Real>()
                        .ok()
                        .filter(|s| *s > 0.0 && *s < 1.0)
                        .ok_or_else(|| refuse(format!("spent is a number between 0 and 1, not '{value}'")))?
                }
                _ => {
                    return Err(refuse(format!(
                        "unknown parameter '{key}'; it takes form, cv, lines, seq, replicates, batch, seed and spent"
                    )));
                }
            }
        }
        validated(name, p)
    }
}

impl SolverParams for StochasticJacobiParams {
    const SYNTAX: &'static str =
        "stochastic-jacobi[:form=…][:cv=true][:lines=global][:seq=…][:replicates=R][:batch=N][:seed=S]";
    const HELP: &'static str = "stochastic relaxation: Jacobi iterations whose transport is estimated with rays (incremental shooting, then regular iterations averaged; form=shooting|gathering, seq=random|sobol|halton); never forms F; a standard error from R replicates";
    const EXAMPLES: &'static [&'static str] =
        &["stochastic-jacobi", "stochastic-jacobi:seq=sobol", "stochastic-jacobi:form=gathering:cv=true"];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        if let Count::Absolute(b) = self.batch {
            if b < self.replicates as u64 {
                return Err(SolverError::BadParams(format!(
                    "batch={b} gives fewer than one ray to each of {} replicates",
                    self.replicates
                )));
            }
        }
        if self.control_variate && self.form != JacobiForm::Gathering {
            return Err(SolverError::BadParams(
                "the constant control variate (cv=true) applies to the gathering form: add form=gathering".into(),
            ));
        }
        if self.control_variate && self.global_lines {
            return Err(SolverError::BadParams(
                "the constant control variate (cv=true) gathers along rays from patches, not global lines".into(),
            ));
        }
        Ok(Box::new(StochasticJacobi { params: self.clone(), chains: Vec::new(), emitted: 0.0, rays_here: 0 }))
    }
}

/// One replicate's chain.
#[derive(Clone, Debug)]
struct Chain {
    /// The combined estimate `B̄`, patch-major.
    estimate: Vec<Real>,
    /// Rays behind `estimate` (its weight in the combination).
    weight: Real,
    /// Whether the incremental phase is over.
    regular: bool,
    /// The power the incremental phase left unshot, relative to the emitted (at most `spent`).
    left: Real,
    /// Iterations taken.
    iteration: u64,
    /// Points each patch has drawn from its stream ([`crate::stochastic::estimate`]).
    drawn: Vec<u64>,
}

/// Stochastic Jacobi (module doc).
#[derive(Debug)]
pub struct StochasticJacobi {
    params: StochasticJacobiParams,
    chains: Vec<Chain>,
    /// `|Φ| = Σ_ic A_i |E_ic|`.
    emitted: Real,
    /// The rays this rank cast (all of them in one process).
    rays_here: u64,
}

impl StochasticJacobi {
    /// The power the incremental series left unshot, relative to the emitted, averaged over
    /// the replicates: 1 before the first step, at most `spent` after it. Every replicate
    /// leaves it out of its estimate, a bias which the regular iterations then shrink by the
    /// reflectance at each and which no standard error sees.
    pub fn unshot_power(&self) -> Real {
        if self.chains.is_empty() {
            return 1.0;
        }
        self.chains.iter().map(|c| c.left).sum::<Real>() / self.chains.len() as Real
    }

    /// The rays of a step for one replicate, for `n` patches.
    fn batch(&self, n: usize) -> u64 {
        let total = self.params.batch.resolve(n);
        // Only the default has a floor: tiny systems would cast a few rays a step.
        let total =
            if self.params.batch == StochasticJacobiParams::default().batch { total.max(MIN_BATCH) } else { total };
        (total / self.params.replicates as u64).max(1)
    }

    /// `Σ_ic A_i |v_ic|`.
    fn power(problem: &Problem<'_>, v: &[Real]) -> Real {
        // Element by element in order, as one sum, without a division an element.
        let areas = problem.system().areas();
        v.chunks(problem.channels()).zip(areas).flat_map(|(x, &a)| x.iter().map(move |x| a * x.abs())).sum()
    }

    /// One iteration of chain `r`.
    fn advance(&mut self, problem: &Problem<'_>, r: usize) -> Result<(), SolverError> {
        let (n, k) = (problem.n(), problem.channels());
        let system = problem.system();
        let areas = system.areas();
        let batch = self.batch(n);
        let name = self.name();
        let params = self.params.clone();
        let emitted = self.emitted;
        let share = Share::of(problem);
        let share = &share;
        // This rank's rays are counted as it casts them; the other ranks', once summed.
        let rays_here = &mut self.rays_here;
        let mut elsewhere = |cast: Cast| {
            problem.spent_elsewhere(Unit::Rays, cast.rays - cast.here);
            *rays_here += cast.here;
        };
        let chain = &mut self.chains[r];
        let mut streams = Streams {
            sequence: params.sequence,
            seed: params.seed,
            replicate: r as u64,
            iteration: chain.iteration,
            drawn: &mut chain.drawn,
        };
        if !chain.regular {
            // The whole incremental series in one step: a run stopped between two of its
            // iterations would show an estimate short of the power still unshot, a bias that
            // every replicate shares and no spread between them can see. Its unshot radiosity
            // lives only while it is shot: one vector over the patches, not one a replicate.
            let mut unshot = problem.system().emissions().to_vec();
            let mut x = vec![0.0; n * k];
            let mut incoming = vec![0.0; n * k];
            loop {
                let power = Self::power(problem, &unshot);
                if power <= params.spent * emitted {
                    chain.regular = true;
                    chain.left = power / emitted;
                    return Ok(());
                }
                streams.iteration = chain.iteration;
                chain.iteration += 1;
                let n_rays = ((batch as Real * power / emitted).ceil() as u64).max(1);
                // Power shot: A_j ΔB_j (each entry on its own, so on every thread).
                x.par_chunks_mut(k).zip(unshot.par_chunks(k)).zip(areas.par_iter()).for_each(|((p, b), a)| {
                    p.iter_mut().zip(b).for_each(|(p, b)| *p = a * b);
                });
                let cast = if params.global_lines {
                    problem
                        .cast(&name, |rays| lines(rays, share, &unshot, k, n_rays, &streams, &mut incoming))?
                        .ok_or_else(|| no_lines(&name))?
                } else {
                    problem.cast(&name, |rays| shoot(rays, share, &x, k, n_rays, &mut streams, &mut incoming))?
                };
                elsewhere(cast);
                (unshot.par_chunks_mut(k), chain.estimate.par_chunks_mut(k), incoming.par_chunks(k))
                    .into_par_iter()
                    .enumerate()
                    .for_each(|(i, (unshot, estimate, power))| {
                        for c in 0..k {
                            let delta = system.rho(i, c) * power[c] / areas[i];
                            unshot[c] = delta;
                            estimate[c] += delta;
                        }
                    });
                chain.weight += cast.rays as Real;
            }
        }
        streams.iteration = chain.iteration;
        chain.iteration += 1;
        // A regular iteration from the estimate, into `fresh`: what the rays bring, then, in
        // place, the new estimate `E + ρ ·` that (one vector over the patches, not two).
        let mut fresh = vec![0.0; n * k];
        let cast = match (params.form, params.global_lines) {
            (JacobiForm::Gathering, false) => {
                let beta: Option<Vec<Real>> = params.control_variate.then(|| {
                    let total: Real = areas.iter().sum();
                    (0..k).map(|c| (0..n).map(|i| areas[i] * chain.estimate[i * k + c]).sum::<Real>() / total).collect()
                });
                let reflects = |i: usize| (0..k).any(|c| system.rho(i, c) > 0.0);
                let cast = problem.cast(&name, |rays| {
                    let (b, beta) = (&chain.estimate, beta.as_deref());
                    gather(rays, share, b, k, areas, &reflects, beta, batch, &mut streams, &mut fresh)
                })?;
                elsewhere(cast);
                for (idx, g) in fresh.iter_mut().enumerate() {
                    let (i, c) = (idx / k, idx % k);
                    *g = system.e(i, c) + system.rho(i, c) * *g;
                }
                cast
            }
            (_, lines_too) => {
                let cast = if lines_too {
                    problem
                        .cast(&name, |rays| lines(rays, share, &chain.estimate, k, batch, &streams, &mut fresh))?
                        .ok_or_else(|| no_lines(&name))?
                } else {
                    let x: Vec<Real> =
                        chain.estimate.par_iter().enumerate().map(|(idx, b)| areas[idx / k] * b).collect();
                    problem.cast(&name, |rays| shoot(rays, share, &x, k, batch, &mut streams, &mut fresh))?
                };
                elsewhere(cast);
                fresh.par_chunks_mut(k).enumerate().for_each(|(i, fresh)| {
                    for (c, f) in fresh.iter_mut().enumerate() {
                        *f = system.e(i, c) + system.rho(i, c) * *f / areas[i];
                    }
                });
                cast
            }
        };
        let w = cast.rays as Real;
        if w > 0.0 {
            let total = chain.weight + w;
            let before = chain.weight;
            chain.estimate.par_iter_mut().zip(&fresh).for_each(|(b, f)| *b = (before * *b + w * f) / total);
            chain.weight = total;
        }
        Ok(())
    }
}

fn no_lines(name: &str) -> SolverError {
    SolverError::NotApplicable {
        solver: name.to_string(),
        reason: "it casts global lines (lines=global), which this transport sampler cannot give".into(),
    }
}

impl Solver for StochasticJacobi {
    fn name(&self) -> String {
        let p = &self.params;
        let mut name = "stochastic-jacobi".to_string();
        let d = StochasticJacobiParams::default();
        if p.form == JacobiForm::Gathering {
            name.push_str(":form=gathering");
        }
        if p.control_variate {
            name.push_str(":cv=true");
        }
        if p.global_lines {
            name.push_str(":lines=global");
        }
        if p.sequence != d.sequence {
            name.push_str(&format!(":seq={}", p.sequence.name()));
        }
        if p.replicates != d.replicates {
            name.push_str(&format!(":replicates={}", p.replicates));
        }
        if p.batch != d.batch {
            name.push_str(&format!(":batch={}", p.batch));
        }
        if p.seed != d.seed {
            name.push_str(&format!(":seed={}", p.seed));
        }
        if p.spent != d.spent {
            name.push_str(&format!(":spent={}", p.spent));
        }
        name
    }

    /// Refuses a problem without a transport sampler, and, with the control variate, one whose
    /// sampler does not know every row sum of F (rays in a scene that is not closed).
    fn applicable(&self, problem: &Problem<'_>) -> Result<(), SolverError> {
        let name = self.name();
        let rows_known = problem.cast(&name, |rays| (0..problem.n()).all(|i| rays.row_sum(i).is_some()))?;
        if self.params.control_variate && !rows_known {
            return Err(SolverError::NotApplicable {
                solver: name,
                reason: "its control variate needs the row sums of F exactly, which this transport sampler does not \
                         know (rays in a scene that is not closed)"
                    .into(),
            });
        }
        Ok(())
    }

    fn init(&mut self, problem: &Problem<'_>, _state: &mut State) -> Result<(), SolverError> {
        let emission = problem.system().emissions().to_vec();
        self.emitted = Self::power(problem, &emission);
        self.rays_here = 0;
        let n = problem.n();
        let chain =
            Chain { estimate: emission, weight: 0.0, regular: false, left: 1.0, iteration: 0, drawn: vec![0; n] };
        self.chains = vec![chain; self.params.replicates];
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        if self.emitted == 0.0 {
            return Ok(Record::new());
        }
        // Every rank advances every replicate, casting its share of each iteration's rays.
        for r in 0..self.chains.len() {
            self.advance(problem, r)?;
        }
        let r = self.chains.len() as Real;
        // A chain not yet in its series holds `E` unshot; one past it, nothing.
        let waiting = self.chains.iter().filter(|c| !c.regular).count() as Real / r;
        let emissions = problem.system().emissions();
        for (idx, b) in state.radiosity.iter_mut().enumerate() {
            let mean = self.chains.iter().map(|c| c.estimate[idx]).sum::<Real>() / r;
            let unshot = waiting * emissions[idx];
            if !mean.is_finite() {
                let k = state.channels;
                return Err(SolverError::NonFinite { step: state.step + 1, patch: idx / k, value: mean });
            }
            state.unshot[idx] = unshot;
            *b = mean;
        }
        Ok(Record::new())
    }

    /// None, but on a system that emits nothing (0: `B = 0` is exact). The unshot power of the
    /// incremental phase is no residual: it is an estimate, which is 0 whenever every ray of
    /// an iteration escapes, and a run that took it for one would stop at round-off with its
    /// series cut short.
    fn residual_power(&self, _problem: &Problem<'_>, _state: &State) -> Option<Real> {
        (self.emitted == 0.0).then_some(0.0)
    }

    fn standard_error(&self, _problem: &Problem<'_>, state: &State) -> Option<StandardError> {
        if self.chains.len() < 2 || state.step == 0 {
            return None;
        }
        let replicates: Vec<&[Real]> = self.chains.iter().map(|c| c.estimate.as_slice()).collect();
        let mut mean = vec![0.0; state.radiosity.len()];
        Some(StandardError::of_replicates(&replicates, &mut mean))
    }

    fn step_kind(&self) -> StepKind {
        StepKind::Sampled
    }

    fn record(&self) -> Record {
        let mut record = Record::new();
        record.set("replicates", self.chains.len());
        // How many replicates have shot their incremental series and iterate regularly.
        record.set("replicates_regular", self.chains.iter().filter(|c| c.regular).count());
        record.set("unshot_power", self.unshot_power());
        // Over ranks, the rays this rank cast; in one process, all of them.
        record.set("rays_here", self.rays_here);
        record
    }
}
