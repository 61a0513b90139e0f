//! `random-walk`: discrete random walks over rays ([`crate::Problem::cast`]), shooting from the
//! emitters or gathering from every patch, scored at every landing (collision) or where the
//! walk is absorbed (absorption); `F` is never formed.
//!
//! Names: `random-walk[:form=shooting|gathering][:score=collision|absorption][:walks=N]
//! [:replicates=R][:seed=S][:seq=random|sobol|halton]` (one word), defaults first.
//!
//! ## Rule
//!
//! The system is `B_i = E_i + ρ_i Σ_j F_ij B_j` per channel `c`. A ray leaving patch `x` lands
//! on `i` with probability `T_ix / w_x`, `T_ix = A_i F_ix / A_x` (module doc of
//! [`radiosity_core::TransportSampler`]), and carries `w_x` (its ray weight, 1 for rays in a
//! scene) times the power it was cast with. `ρ̄_i` is the largest of `ρ_ic` over the channels,
//! below 1 in every system. (Not their mean: with the mean, a channel's factor `ρ_ic / ρ̄_i`
//! exceeds 1 where channels differ, and the walk's second moment grows by `ρ_ic² / ρ̄_i` a
//! landing, 1.97 for ρ = 0.99, 0.5 and 0: an unbiased estimate of infinite variance, whose
//! standard error means nothing. With the largest, every factor is at most 1.) Every walk carries one weight per channel, `W_c`. At each landing
//! on `i` the walk survives with probability `ρ̄_i`, its weights multiplied by `ρ_ic / ρ̄_i`
//! (`E[·] = ρ_ic W_c`: the reflection, per channel, from one decision for all channels), and
//! is otherwise absorbed; a ray that escapes ends it, and so does a weight of zero in every
//! channel (all it could still score is zero). Walks end with probability 1: each landing
//! survives with probability `ρ̄ ≤ max ρ̄ < 1`.
//!
//! **Shooting** (Pattanaik & Mudur's particle model, on patches). In powers `P_i = A_i B_i`,
//! `Φ_i = A_i E_i`, the system reads `P = Φ + ρ T P`, and its reflected part is
//! `P − Φ = Σ_{m≥1} (ρ T)^m Φ`. A walk starts at emitter `s` with probability
//! `p_s = A_s Ē_s / Φ̄` (`Ē_s = Σ_c E_sc`, `Φ̄ = Σ_s A_s Ē_s`: in proportion to emitted power)
//! with weights `W_c = A_s E_sc / p_s = Φ̄ E_sc / Ē_s`, and casts from `s` at once (the emitted
//! power all leaves). At each landing on `i`:
//!
//! - collision: it scores `W_c ρ_ic` to the reflected power of `i`, whether it survives or not;
//! - absorption: it scores `W_c ρ_ic / (1 − ρ̄_i)` to `i`, only when it is absorbed there.
//!
//! `B_ic = E_ic + S_ic / (N A_i)` over `N` walks with total score `S_ic`. *Unbiased*: let
//! `Q^(m)` be the expected weight a walk carries into its `m`-th flight, per patch it leaves
//! from; `Q^(1) = Φ`. The flight lands on `i` an expected `(T Q^(m))_i` (the ray weight
//! cancels `1/w_x`); collision scores `ρ_i (T Q^(m))_i` in expectation, and absorption the same,
//! `(1 − ρ̄_i) · ρ_i (T Q^(m))_i / (1 − ρ̄_i)`. Survival gives `Q^(m+1) = ρ T Q^(m) = (ρ T)^m Φ`,
//! so the expected score, summed over flights, is `Σ_{m≥1} (ρ T)^m Φ = P − Φ`. Shooting reads
//! the columns of `F` only (`T` is what the sampler draws): it needs no reciprocity.
//!
//! **Gathering** (the adjoint walk, von Neumann and Ulam's estimator of one unknown). `B_i` is
//! estimated from walks started at `i` itself: `G_i = B_i − E_i = ρ_i Σ_j F_ij B_j`. A ray from
//! `i` lands on `j` with probability `T_ji / w_i`, which is `F_ij / w_i` where `F` is reciprocal
//! (`A_i F_ij = A_j F_ji`; module doc of [`radiosity_core::TransportSampler`]); where it is not,
//! gathering solves the system whose `F_ij` is `T_ji`, the transpose of what the columns
//! transport (for a scene, the same up to the sampler's own error). A walk starts at `i` with
//! weights `W_c = ρ_ic` and casts from `i` at once. At each landing on `j`:
//!
//! - collision: it scores `W_c E_jc`, whether it survives or not;
//! - absorption: it scores `W_c E_jc / (1 − ρ̄_j)`, only when it is absorbed there.
//!
//! `B_ic = E_ic + S_ic / M` over `M` walks from `i`. *Unbiased*: by induction on the walk's
//! remaining length, a walk that lands on `j` with weights `W` scores `W_c (E_jc + G_jc)` in
//! expectation (the score at `j`, `W_c E_jc` for both estimators as above, plus the survivor's
//! `ρ̄_j · (ρ_jc / ρ̄_j) W_c · Σ_l F_jl B_lc`), so a walk from `i` scores
//! `Σ_j (F_ij / w_i) · w_i ρ_ic (E_jc + G_jc) = ρ_ic (F B)_ic = G_ic`.
//!
//! **Collision or absorption.** Both have the same expectation at every landing; they differ in
//! where the variance is. In a closed grey furnace (`Σ_j F_ij = 1`, uniform `ρ` and `E`), a
//! gathering walk lands `L` times, `L` geometric with mean `1/(1 − ρ)`: collision scores
//! `ρ E L`, variance `ρ³ E² / (1 − ρ)²` a walk, while absorption scores `ρ E / (1 − ρ)` every
//! time, variance zero; shooting by absorption there scores the exact total reflected power,
//! `Φ̄ ρ / (1 − ρ)`, with every walk (derived here; the tests check both). Absorption loses
//! where walks escape or end away from what they score (a score of `0` or of
//! `W / (1 − ρ̄)`, rare and large as `ρ̄ → 1`), and where emission is concentrated on a few
//! patches that gathering walks rarely end on; collision spreads each walk's score over every
//! landing. As `ρ̄ → 0` the two coincide (every landing absorbs). Sbert 1997 compares three
//! unbiased estimators of each form, with closed forms and bounds for their variances.
//!
//! ## Steps, replicates and random numbers
//!
//! One step is one batch of walks in each of `R` replicates (`replicates=R`, default 4, at
//! least 2): `walks=N` walks (or `walks=2n`, a multiple of the patch count; default `n`) from
//! the emitters in shooting, and `⌈N / n⌉` walks from every patch in gathering. A replicate's
//! estimate is the running mean over all its walks so far; the displayed radiosity is the
//! mean of the replicates (all have walked the same number of walks, so it is the pooled mean
//! over every walk), and [`Solver::standard_error`] the spread between them
//! ([`StandardError::of_replicates`]: the replicates are independent and each unbiased). With
//! ρ around 0.5 a step casts about `2 R N` rays, `8 n` by default.
//!
//! Walks move breadth-first, one depth at a time: the `k`-th walk still alive at depth `d`
//! casts with the `k`-th point of the stream keyed by (`seed`, replicate, step, batch and `d`)
//! in shooting and (`seed`, replicate, step, patch and `d`) in gathering ([`Sequence::stream`];
//! depth 0 chooses the emitters). Each depth's stream is independent of every other, so a
//! walk's bounces are independent even where the points of one stream are not
//! (`seq=sobol|halton`: the walks of one depth are stratified across each other, and every
//! point is uniform, so the estimates stay unbiased); the survival decisions draw from the
//! same stream's pseudo-random part. Shooting walks go in batches of
//! [`RandomWalk::WALKS_PER_BATCH`], cast in parallel and added to the replicate in batch
//! order; the gathering walks of each patch add to that patch alone. Nothing depends on the
//! thread that ran it: the same seed gives the same numbers whatever the thread count.
//!
//! The solver knows no residual without `F` ([`Solver::residual_power`] is `None`), except on a
//! system that emits nothing, whose answer `B = E = 0` it knows exactly (residual 0). Its
//! record holds the walks so far (`walks`, every replicate) and the rays each cast on average
//! (`mean_walk_length`). Memory: `2 R n k` reals.
//!
//! ## References
//!
//! - Spanier & Gelbard 1969, *Monte Carlo Principles and Neutron Transport Problems*
//!   (collision and absorption estimators of random walks).
//! - Pattanaik & Mudur 1992, "Computation of global illumination by Monte Carlo simulation of
//!   the particle model of light", Third Eurographics Workshop on Rendering.
//! - Sbert 1997, "Error and complexity of random walk Monte Carlo radiosity", IEEE TVCG 3(1)
//!   (shooting and gathering random walks, their estimators and variances).
//! - Bekaert 1999, *Hierarchical and stochastic algorithms for radiosity*, PhD thesis,
//!   KU Leuven (random walk radiosity among the Monte Carlo radiosity methods).

use crate::error::SolverError;
use crate::naming::{ParseSolverError, SolverParams, split_params};
use crate::run::cost::Unit;
use crate::run::executor::{Solver, StepKind};
use crate::run::problem::{Problem, Rays};
use crate::run::record::Record;
use crate::run::standard_error::StandardError;
use crate::run::state::State;
use crate::run::stop::Count;
use crate::stochastic::ranks::Deal;
use crate::stochastic::sequence::Sequence;
use radiosity_core::{LinearSystem, Real};
use rayon::prelude::*;
use std::str::FromStr;

/// Where walks start ([`RandomWalkParams::form`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WalkForm {
    /// From the emitters, in proportion to emitted power, scoring where they land (the default).
    #[default]
    Shooting,
    /// From every patch, collecting the emission they reach.
    Gathering,
}

/// What a walk scores ([`RandomWalkParams::score`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WalkScore {
    /// At every landing (the default).
    #[default]
    Collision,
    /// Only where the walk is absorbed, divided by the probability of absorption.
    Absorption,
}

/// Batches cast in parallel at once, their scores then added in order: bounds the scores held.
const WAVE: usize = 64;

/// The names `random-walk[:form=…][:score=…][:walks=N][:replicates=R][:seed=S][:seq=…]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RandomWalkParams {
    /// Shooting or gathering.
    pub form: WalkForm,
    /// Collision or absorption.
    pub score: WalkScore,
    /// Walks of each replicate a step (module doc).
    pub walks: Count,
    /// Independent replicates, at least 2.
    pub replicates: usize,
    /// The seed of every stream.
    pub seed: u64,
    /// The sequence the rays are drawn from.
    pub seq: Sequence,
}

impl Default for RandomWalkParams {
    fn default() -> RandomWalkParams {
        RandomWalkParams {
            form: WalkForm::Shooting,
            score: WalkScore::Collision,
            walks: Count::PerPatch(1.0),
            replicates: RandomWalkParams::DEFAULT_REPLICATES,
            seed: 1,
            seq: Sequence::Random,
        }
    }
}

impl RandomWalkParams {
    /// Replicates by default.
    pub const DEFAULT_REPLICATES: usize = 4;

    /// The most replicates a name may ask for: each holds two vectors of the system's size.
    pub const MAX_REPLICATES: usize = 1024;

    /// The name, with the parameters that differ from the defaults in the syntax's order.
    pub fn canonical_name(&self) -> String {
        let default = RandomWalkParams::default();
        let mut name = String::from("random-walk");
        if self.form != default.form {
            name.push_str(":form=gathering");
        }
        if self.score != default.score {
            name.push_str(":score=absorption");
        }
        if self.walks != default.walks {
            name.push_str(&format!(":walks={}", self.walks));
        }
        if self.replicates != default.replicates {
            name.push_str(&format!(":replicates={}", self.replicates));
        }
        if self.seed != default.seed {
            name.push_str(&format!(":seed={}", self.seed));
        }
        if self.seq != default.seq {
            name.push_str(&format!(":seq={}", self.seq.name()));
        }
        name
    }
}

impl FromStr for RandomWalkParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<RandomWalkParams, ParseSolverError> {
        let (head, params) = split_params(name);
        if head != "random-walk" {
            return Err(ParseSolverError::OtherFamily);
        }
        let mut out = RandomWalkParams::default();
        for pair in params.split(':') {
            let bad = |why: &str| SolverError::BadParams(format!("solver '{name}': '{pair}' {why}"));
            match pair.split_once('=') {
                Some(("form", "shooting")) => out.form = WalkForm::Shooting,
                Some(("form", "gathering")) => out.form = WalkForm::Gathering,
                Some(("form", _)) => return Err(bad("needs form=shooting or form=gathering").into()),
                Some(("score", "collision")) => out.score = WalkScore::Collision,
                Some(("score", "absorption")) => out.score = WalkScore::Absorption,
                Some(("score", _)) => return Err(bad("needs score=collision or score=absorption").into()),
                Some(("walks", v)) => {
                    out.walks = Count::parse(v)
                        .map_err(|_| bad("needs a positive number of walks, such as walks=1000 or walks=2n"))?;
                }
                Some(("replicates", v)) => {
                    let r = v.parse::<usize>().ok().filter(|r| (2..=RandomWalkParams::MAX_REPLICATES).contains(r));
                    out.replicates = r.ok_or_else(|| {
                        bad(&format!(
                            "needs a whole number from 2 to {}, since the error bar is the spread between replicates",
                            RandomWalkParams::MAX_REPLICATES
                        ))
                    })?;
                }
                Some(("seed", v)) => {
                    out.seed = v.parse::<u64>().map_err(|_| bad("needs a whole number from 0 to 2^64 − 1"))?;
                }
                Some(("seq", v)) => {
                    out.seq = Sequence::parse(v).ok_or_else(|| bad("needs seq=random, seq=sobol or seq=halton"))?;
                }
                _ if pair.is_empty() && params.is_empty() => {}
                _ => {
                    return Err(bad(
                        "is not a parameter; random-walk takes form=, score=, walks=, replicates=, seed= and seq=",
                    )
                    .into());
                }
            }
        }
        Ok(out)
    }
}

impl SolverParams for RandomWalkParams {
    /// Shortened so that the list of names wraps within its width; the values are in the help.
    const SYNTAX: &'static str = "random-walk[:form=…][:score=…][:walks=N][:replicates=R][:seed=S][:seq=…]";
    const HELP: &'static str = "random walks over rays, never forming F: form=shooting (from the emitters) or gathering \
                                (from every patch), score=collision (every landing) or absorption, \
                                seq=random|sobol|halton; the error bar from R replicates";
    const EXAMPLES: &'static [&'static str] =
        &["random-walk", "random-walk:form=gathering", "random-walk:score=absorption:seq=sobol"];

    /// Refuses, for parameters built by hand, what a name could not say: fewer than two
    /// replicates or more than [`RandomWalkParams::MAX_REPLICATES`], and no walks.
    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        let max = RandomWalkParams::MAX_REPLICATES;
        if !(2..=max).contains(&self.replicates) {
            return Err(SolverError::BadParams(format!(
                "random-walk needs 2 to {max} replicates, not {}, since the error bar is the spread between replicates",
                self.replicates
            )));
        }
        let walks = match self.walks {
            Count::Absolute(k) => k > 0,
            Count::PerPatch(m) => m.is_finite() && m > 0.0,
        };
        if !walks {
            return Err(SolverError::BadParams(format!(
                "random-walk needs a positive number of walks a step, not walks={}",
                self.walks
            )));
        }
        Ok(Box::new(RandomWalk::new(*self)))
    }
}

/// The emitters of a shooting walk, drawn in proportion to emitted power.
#[derive(Clone, Debug, Default)]
struct Emitters {
    /// The patches that emit.
    patches: Vec<usize>,
    /// `Σ A Ē` up to and including each of them: strictly increasing.
    cumulative: Vec<Real>,
}

impl Emitters {
    fn of(system: &LinearSystem) -> Emitters {
        let k = system.channels().count();
        let mut out = Emitters::default();
        let mut total = 0.0;
        for i in 0..system.len() {
            let power = system.areas()[i] * (0..k).map(|c| system.e(i, c)).sum::<Real>();
            if power > 0.0 {
                total += power;
                out.patches.push(i);
                out.cumulative.push(total);
            }
        }
        out
    }

    /// `Φ̄`, the power emitted in all channels.
    fn total(&self) -> Real {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// The emitter `u` in `[0, 1)` draws (inverting the cumulative power).
    fn pick(&self, u: Real) -> usize {
        let target = u * self.total();
        let at = self.cumulative.partition_point(|&c| c <= target);
        self.patches[at.min(self.patches.len() - 1)]
    }
}

/// What the walks of one shooting batch scored: `values[e * k + c]` to `patches[e]`.
#[derive(Debug, Default)]
struct Tally {
    patches: Vec<u32>,
    values: Vec<Real>,
    casts: u64,
}

/// Which walks a stream serves (module doc): a replicate's batch (shooting) or patch
/// (gathering) in one step.
#[derive(Clone, Copy, Debug)]
struct Batch {
    replicate: usize,
    step: u64,
    /// The batch of shooting walks, or the patch gathering walks start from.
    id: u64,
}

impl Batch {
    /// The key of the stream of depth `depth` (0: the starts).
    fn key(self, depth: u64) -> [u64; 3] {
        [self.replicate as u64, self.step, (self.id << 32) | depth]
    }
}

/// What every walk of a step reads: the rays, the system and the parameters.
struct Walker<'a> {
    rays: &'a Rays<'a>,
    system: &'a LinearSystem,
    params: &'a RandomWalkParams,
}

impl Walker<'_> {
    /// The walks of `batch`, breadth-first (module doc): they start at `at` with weights
    /// `weight` (`k` a walk); `score(patch, weights, scale)` is called at every scored landing
    /// with the walk's weights and the factor (1, or `1 / (1 − ρ̄)` at an absorption) that
    /// multiplies them and `ρ` (shooting) or `E` (gathering) of `patch`. Returns the rays cast.
    fn walk(
        &self,
        batch: Batch,
        at: &mut Vec<usize>,
        weight: &mut Vec<Real>,
        mut score: impl FnMut(usize, &[Real], Real),
    ) -> u64 {
        let (system, params) = (self.system, self.params);
        let k = system.channels().count();
        let mut casts = 0;
        let mut depth = 1;
        while !at.is_empty() {
            let mut stream = params.seq.stream(params.seed, batch.key(depth));
            let mut kept = 0;
            for walk in 0..at.len() {
                let w = walk * k;
                if weight[w..w + k].iter().all(|&x| x == 0.0) {
                    continue;
                }
                let from = at[walk];
                casts += 1;
                let Some(i) = self.rays.cast(from, stream.next_point()) else { continue };
                let carried = self.rays.ray_weight(from);
                let rho = &system.reflectivities()[i * k..(i + 1) * k];
                let survival = rho.iter().copied().fold(0.0, Real::max);
                let survives = stream.uniform() < survival;
                let weights = &mut weight[w..w + k];
                weights.iter_mut().for_each(|x| *x *= carried);
                match params.score {
                    WalkScore::Collision => score(i, weights, 1.0),
                    WalkScore::Absorption if !survives => score(i, weights, 1.0 / (1.0 - survival)),
                    WalkScore::Absorption => {}
                }
                if survives {
                    for (x, r) in weights.iter_mut().zip(rho) {
                        *x *= r / survival;
                    }
                    at[kept] = i;
                    weight.copy_within(w..w + k, kept * k);
                    kept += 1;
                }
            }
            at.truncate(kept);
            weight.truncate(kept * k);
            depth += 1;
        }
        casts
    }

    /// `count` shooting walks of `batch` from `emitters` (module doc), what they scored.
    fn shoot(&self, emitters: &Emitters, batch: Batch, count: u64) -> Tally {
        let system = self.system;
        let k = system.channels().count();
        let mut start = self.params.seq.stream(self.params.seed, batch.key(0));
        let (mut at, mut weight) = (Vec::with_capacity(count as usize), Vec::with_capacity(count as usize * k));
        let total = emitters.total();
        for _ in 0..count {
            let s = emitters.pick(start.next_point()[0]);
            let emitted = &system.emissions()[s * k..(s + 1) * k];
            let sum: Real = emitted.iter().sum();
            at.push(s);
            weight.extend(emitted.iter().map(|e| total * e / sum));
        }
        let mut tally = Tally::default();
        tally.casts = self.walk(batch, &mut at, &mut weight, |i, w, scale| {
            let rho = &system.reflectivities()[i * k..(i + 1) * k];
            tally.patches.push(i as u32);
            tally.values.extend(w.iter().zip(rho).map(|(w, r)| w * r * scale));
        });
        tally
    }

    /// `count` gathering walks from the patch of `batch` (module doc): their scores added to
    /// `sum` (`k` values), the rays cast returned.
    fn gather(&self, batch: Batch, count: u64, sum: &mut [Real]) -> u64 {
        let system = self.system;
        let (k, patch) = (system.channels().count(), batch.id as usize);
        let rho = &system.reflectivities()[patch * k..(patch + 1) * k];
        let mut at = vec![patch; count as usize];
        let mut weight: Vec<Real> = (0..count).flat_map(|_| rho.iter().copied()).collect();
        self.walk(batch, &mut at, &mut weight, |j, w, scale| {
            let e = &system.emissions()[j * k..(j + 1) * k];
            for ((s, w), e) in sum.iter_mut().zip(w).zip(e) {
                *s += w * e * scale;
            }
        })
    }
}

/// Random walks over rays (module doc).
#[derive(Debug)]
pub struct RandomWalk {
    params: RandomWalkParams,
    /// Every replicate's summed scores, replicate-major, each patch-major.
    sums: Vec<Real>,
    /// Every replicate's running estimate, laid out like `sums`.
    estimates: Vec<Real>,
    emitters: Emitters,
    /// Walks of each replicate a step: from the emitters, or from each patch.
    per_step: u64,
    /// Steps taken.
    steps: u64,
    /// Walks so far, every replicate.
    walks: u64,
    /// Rays the walks cast so far.
    rays: u64,
    /// Of them, those this rank cast (all of them in one process).
    rays_here: u64,
    /// Whether the system emits nothing (its answer is `B = 0`).
    dark: bool,
}

impl RandomWalk {
    /// Shooting walks per batch (module doc): one stream per depth, one parallel task.
    pub const WALKS_PER_BATCH: u64 = 256;

    /// The solver `params` designate.
    pub fn new(params: RandomWalkParams) -> RandomWalk {
        RandomWalk {
            params,
            sums: Vec::new(),
            estimates: Vec::new(),
            emitters: Emitters::default(),
            per_step: 0,
            steps: 0,
            walks: 0,
            rays: 0,
            rays_here: 0,
            dark: false,
        }
    }

    /// One step of shooting: every replicate's batches, added in order.
    fn shoot_step(&mut self, problem: &Problem<'_>) -> Result<(), SolverError> {
        let (name, system, params) = (self.name(), problem.system(), self.params);
        let (n, k) = (problem.n(), problem.channels());
        let (per_step, step, emitters) = (self.per_step, self.steps, &self.emitters);
        let batches = per_step.div_ceil(RandomWalk::WALKS_PER_BATCH);
        let deal = Deal::of(problem);
        let tasks: Vec<(usize, u64)> =
            (0..params.replicates).filter(|&r| deal.mine(r)).flat_map(|r| (0..batches).map(move |b| (r, b))).collect();
        for wave in tasks.chunks(WAVE) {
            let tallies: Vec<Tally> = problem.cast(&name, |rays| {
                let walker = Walker { rays, system, params: &params };
                wave.par_iter()
                    .map(|&(replicate, id)| {
                        let batch = RandomWalk::WALKS_PER_BATCH;
                        let count = batch.min(per_step - id * batch);
                        walker.shoot(emitters, Batch { replicate, step, id }, count)
                    })
                    .collect()
            })?;
            for (tally, &(r, _)) in tallies.iter().zip(wave) {
                let sums = &mut self.sums[r * n * k..(r + 1) * n * k];
                for (&i, values) in tally.patches.iter().zip(tally.values.chunks_exact(k)) {
                    for (s, v) in sums[i as usize * k..(i as usize + 1) * k].iter_mut().zip(values) {
                        *s += v;
                    }
                }
                self.rays += tally.casts;
            }
        }
        Ok(())
    }

    /// One step of gathering: every patch of every replicate, each adding to its own sum.
    fn gather_step(&mut self, problem: &Problem<'_>) -> Result<(), SolverError> {
        let (name, system, params) = (self.name(), problem.system(), self.params);
        let (n, k) = (problem.n(), problem.channels());
        let (per_patch, step) = (self.per_patch(n), self.steps);
        let sums = &mut self.sums;
        let deal = Deal::of(problem);
        let casts: u64 = problem.cast(&name, |rays| {
            let walker = Walker { rays, system, params: &params };
            sums.par_chunks_mut(k)
                .enumerate()
                .with_min_len(16)
                .filter(|(idx, _)| deal.mine(idx / n))
                .map(|(idx, sum)| {
                    walker.gather(Batch { replicate: idx / n, step, id: (idx % n) as u64 }, per_patch, sum)
                })
                .sum()
        })?;
        self.rays += casts;
        Ok(())
    }

    /// Gathering walks from each patch a step: `⌈N / n⌉`.
    fn per_patch(&self, n: usize) -> u64 {
        self.per_step.div_ceil(n as u64).max(1)
    }
}

impl Solver for RandomWalk {
    fn name(&self) -> String {
        self.params.canonical_name()
    }

    /// Refuses a problem without a transport sampler, before any work.
    fn applicable(&self, problem: &Problem<'_>) -> Result<(), SolverError> {
        if problem.samples_transport() { Ok(()) } else { problem.cast(&self.name(), |_| ()) }
    }

    fn init(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        let system = problem.system();
        let r = self.params.replicates;
        self.sums = vec![0.0; r * system.emissions().len()];
        self.estimates = system.emissions().repeat(r);
        self.emitters = Emitters::of(system);
        self.per_step = self.params.walks.resolve(problem.n()).max(1);
        self.steps = 0;
        self.walks = 0;
        self.rays = 0;
        self.rays_here = 0;
        self.dark = self.emitters.patches.is_empty();
        state.radiosity.copy_from_slice(system.emissions());
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        if self.dark {
            return Ok(Record::new());
        }
        let (n, k, r) = (problem.n(), problem.channels(), self.params.replicates);
        let (before, rays_before) = (problem.spent(Unit::Rays), self.rays);
        let walks_each = match self.params.form {
            WalkForm::Shooting => {
                self.shoot_step(problem)?;
                self.per_step
            }
            WalkForm::Gathering => {
                self.gather_step(problem)?;
                self.per_patch(n)
            }
        };
        // Over ranks, every replicate's sums from the rank that walked it (module doc of
        // `stochastic::ranks`), and the walks' rays of every rank.
        let deal = Deal::of(problem);
        let here = problem.spent(Unit::Rays) - before;
        self.rays_here += here;
        if deal.split() {
            let mut parts: Vec<Vec<Real>> = self.sums.chunks_exact(n * k).map(<[Real]>::to_vec).collect();
            let world = deal.share(problem, &mut parts, here);
            self.sums = parts.concat();
            self.rays = rays_before + world;
        }
        self.steps += 1;
        let starts = if self.params.form == WalkForm::Gathering { n as u64 } else { 1 };
        self.walks += walks_each * starts * r as u64;
        // Each replicate's running estimate, then their mean.
        let system = problem.system();
        let walked = (self.steps * walks_each) as Real;
        for (idx, (b, s)) in self.estimates.iter_mut().zip(&self.sums).enumerate() {
            let (i, c) = ((idx / k) % n, idx % k);
            let per = match self.params.form {
                WalkForm::Shooting => walked * system.areas()[i],
                WalkForm::Gathering => walked,
            };
            *b = system.e(i, c) + s / per;
        }
        let size = n * k;
        for idx in 0..size {
            let mean = (0..r).map(|q| self.estimates[q * size + idx]).sum::<Real>() / r as Real;
            if !mean.is_finite() {
                return Err(SolverError::NonFinite { step: state.step + 1, patch: idx / k, value: mean });
            }
            state.unshot[idx] = mean - state.radiosity[idx];
            state.radiosity[idx] = mean;
        }
        Ok(Record::new())
    }

    /// None: no residual is known without `F`; 0 on a system that emits nothing.
    fn residual_power(&self, _problem: &Problem<'_>, _state: &State) -> Option<Real> {
        self.dark.then_some(0.0)
    }

    /// The spread between the replicates' running estimates, from the first step (or at
    /// once, zero, on a system that emits nothing).
    fn standard_error(&self, problem: &Problem<'_>, _state: &State) -> Option<StandardError> {
        if self.steps == 0 && !self.dark {
            return None;
        }
        let size = problem.n() * problem.channels();
        let replicates: Vec<&[Real]> = self.estimates.chunks_exact(size).collect();
        let mut mean = vec![0.0; size];
        Some(StandardError::of_replicates(&replicates, &mut mean))
    }

    /// One batch of walks in every replicate.
    fn step_kind(&self) -> StepKind {
        StepKind::Sampled
    }

    /// `walks` (every replicate's, so far), `mean_walk_length` (rays a walk) and
    /// `unshot_power`, 0: every walk is followed until it ends, so no power is left out.
    fn record(&self) -> Record {
        // Over ranks, `rays_here` is the rays this rank cast; in one process, all of them.
        let mut record =
            Record::new().with("walks", self.walks).with("unshot_power", 0.0).with("rays_here", self.rays_here);
        if self.walks > 0 {
            record.set("mean_walk_length", self.rays as Real / self.walks as Real);
        }
        record
    }
}
