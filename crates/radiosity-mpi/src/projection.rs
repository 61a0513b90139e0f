//! A model of a distributed solve's time and memory, phase by phase: fitted to measured runs,
//! checked on runs it was not fitted to, and projected to more patches and more machines
//! (docs/distributed.md).
//!
//! One rank runs on each of `P` nodes, its threads on the node's `c` cores. Every phase of a
//! run (loading, the BVH, the analysis's probes, the operator or the sampler, solving) costs
//! seconds in three parts that differ in what divides them: a serial part `s` (one thread, on
//! every rank), a repeated part `r` (every rank does all of it, over its cores) and a divided
//! part `d` (split between all the ranks' cores), each per patch and growing with the scene as
//! `(n / n₀)^g` (a deeper BVH, a larger working set, more links a patch):
//!
//! `t(n, P, c) = n (n / n₀)^g (s + r / c + d / (P c))`.
//!
//! **Fitting** ([`Model::fit`]). Three kinds of run at one size `n₀` fit the three parts of
//! each phase: one process on one thread (`t₁₁ = n (s + r + d)`), on two threads (`t₁₂ = n (s +
//! (r + d) / 2)`), and two ranks of one thread each (`t₂₁ = n (s + r + d / 2)`), so `d = 2 (t₁₁
//! − t₂₁) / n`, `r = 2 (t₁₁ − t₁₂) / n − d` and `s = t₁₁ / n − r − d`; each kind's seconds are
//! the median of its repeats, since single runs on one machine differ by up to 15%. A part that
//! comes out negative (noise in a part too small to measure, or two threads slower than one) is
//! taken as zero and the others refitted without it ([`PhaseModel::fit`]). A run on two threads
//! at a larger size fits each phase's growth `g`; without one, `g = 0`. Where the runs on two
//! threads give each phase's CPU seconds, the serial part is instead the time one thread worked
//! alone, `2 t₁₂ − cpu` ([`PhaseModel::fit_with_cpu`]), and threads that contend for memory,
//! which spend more CPU seconds rather than leave one idle, no longer count as serial code;
//! from wall seconds alone they do, and are carried to many cores by Amdahl's law.
//! [`Model::excess_as_overhead`] reads what two ranks cost beyond one process as an overhead on
//! the divided work rather than as work every rank repeats: the same runs, another projection.
//!
//! **Checking** ([`Model::check`]). A run the fit did not see (another size, another
//! configuration) is modelled phase by phase and compared with what it measured. The checks,
//! not the fit's residuals, say how far a projection can be trusted.
//!
//! Memory per node is `m₀ + m_r + n (m_rep + m_div / P)`: `m₀` and the bytes a patch from one
//! process's peaks at two sizes (at one size, `m₀ = 0`); `m_div` from the program's own count
//! of what ranks divide (a hierarchical operator's link bytes) where the runs give it, else from
//! the peaks of one process and of a rank of two at `n₀`; `m_r` a rank's bytes beyond one
//! process where a rank of two peaks above it (MPI's and the sums' buffers), fixed, or growing
//! with the replicates where every rank holds every replicate's sums. The solve's collective sums (a product's
//! for the hierarchical operator, an iteration's for stochastic Jacobi, [`Sums`]) are
//! reduce-scatter then all-gather over a network of latency `α` and bandwidth `β` per node
//! (Hockney's model): `2 (P − 1) α + 2 (P − 1) / P · m / β` for a sum of `m` bytes, zero on one
//! node. Two ranks on one machine share its memory, so the network is an input, stated wherever
//! a projection is quoted, not a measurement; a check on one machine models no sums (the
//! run's own are in its phases).
//!
//! ## References
//!
//! - G. Amdahl, "Validity of the single processor approach to achieving large scale computing
//!   capabilities", AFIPS 1967.
//! - R. Hockney, "The communication challenge for MPP: Intel Paragon and Meiko CS-2", Parallel
//!   Computing 20(3), 1994 (the `α + m/β` model of a message).
//! - R. Thakur, R. Rabenseifner, W. Gropp, "Optimization of collective communication operations
//!   in MPICH", IJHPCA 19(1), 2005 (reduce-scatter and all-gather volumes).

/// One measured run: its size, its configuration and what it measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// Its patches.
    pub patches: f64,
    /// Each rank's threads.
    pub threads: f64,
    /// Its ranks (1 for one process).
    pub ranks: f64,
    /// Every phase, in the order of its phase table.
    pub phases: Vec<RunPhase>,
    /// The peak resident bytes of its largest process.
    pub peak: f64,
    /// The bytes of what ranks divide, as the program counts them (a hierarchical operator's
    /// links), where it does: all of them in a run of one process.
    pub divided_bytes: Option<f64>,
}

/// One phase of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunPhase {
    /// Its name.
    pub name: String,
    /// Its wall seconds.
    pub seconds: f64,
    /// The CPU seconds of all the process's threads in it, where the run says (rank 0's under
    /// ranks).
    pub cpu: Option<f64>,
}

impl Run {
    /// Its seconds in all its phases.
    pub fn total(&self) -> f64 {
        self.phases.iter().map(|p| p.seconds).sum()
    }

    /// Its seconds in phase `name` (0 where it has no such phase).
    fn phase(&self, name: &str) -> f64 {
        self.phases.iter().find(|p| p.name == name).map_or(0.0, |p| p.seconds)
    }

    /// Its CPU seconds in phase `name`, where it says (0 where it has no such phase).
    fn cpu(&self, name: &str) -> Option<f64> {
        self.phases.iter().find(|p| p.name == name).map_or(Some(0.0), |p| p.cpu)
    }

    /// Whether it is one of `kind` (threads, ranks) at `patches`.
    fn is(&self, patches: f64, (threads, ranks): (f64, f64)) -> bool {
        self.patches == patches && self.threads == threads && self.ranks == ranks
    }
}

/// Why runs cannot be fitted.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ProjectionError {
    /// A kind of run the fit needs is missing.
    #[error(
        "the fit needs, at one size, runs of one process on one thread, of one process on two threads and of two ranks \
         of one thread each; at {patches} patches there is no run of {missing}"
    )]
    Missing {
        /// The size of the fit's runs on one thread.
        patches: f64,
        /// The kind missing, in words.
        missing: &'static str,
    },
    /// No run of one process on one thread.
    #[error("the fit needs runs of one process on one thread; none of the runs is one")]
    NoSingleThread,
}

/// One phase's wall seconds in the three fitting runs at one size: one process on one
/// thread, on two threads, and two ranks of one thread each (the slower rank).
#[derive(Clone, Debug, PartialEq)]
pub struct PhaseRuns {
    /// The phase's name.
    pub name: String,
    /// Its seconds: `[one thread, two threads, two ranks]`.
    pub seconds: [f64; 3],
}

/// The collective sums of a solve: how many, and how many bytes each per patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sums {
    /// `count` sums of `bytes` per patch each, whatever the nodes: a product of the
    /// hierarchical operator sums `3n` values (24 bytes a patch); stochastic Jacobi's
    /// iterations each sum the deposits.
    Fixed {
        /// Sums per solve.
        count: f64,
        /// Bytes per patch a sum.
        bytes: f64,
    },
    /// `count` sums of one block of `bytes` per patch for each replicate, with as many
    /// replicates as nodes and at least `least`: random walks deal whole replicates to the
    /// ranks and share every replicate's state after every step.
    Replicates {
        /// Sums per solve (its steps).
        count: f64,
        /// Bytes per patch per replicate a sum.
        bytes: f64,
        /// The fewest replicates.
        least: f64,
    },
}

impl Sums {
    /// The sums a solve makes and the bytes per patch of each, on `nodes` nodes.
    fn on(&self, nodes: f64) -> (f64, f64) {
        match *self {
            Sums::Fixed { count, bytes } => (count, bytes),
            Sums::Replicates { count, bytes, least } => (count, bytes * nodes.max(least)),
        }
    }
}

/// One phase's three parts, seconds per patch at `at` patches, and their growth (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct PhaseModel {
    /// The phase's name.
    pub name: String,
    /// Serial on every rank.
    pub serial: f64,
    /// Repeated on every rank, over its cores.
    pub repeated: f64,
    /// Divided between all the ranks' cores.
    pub divided: f64,
    /// The parallel parts' work on one thread over their work on two or more (below 1 where
    /// threads contend for memory; 1 where the runs gave no CPU seconds).
    pub alone: f64,
    /// What the divided part costs on more than one rank over its cost on one node: 1, but in
    /// [`Model::excess_as_overhead`].
    pub overhead: f64,
    /// The exponent `g`: a patch costs `(n / at)^g` times as much at `n` patches.
    pub growth: f64,
    /// The patches the parts were fitted at, `n₀`.
    pub at: f64,
}

impl PhaseModel {
    /// The parts of `runs` at `n` patches (module doc), each held at zero or above: where a
    /// part comes out negative, the best non-negative fit by one or two parts, the others
    /// held at zero (by least squares on the three equations). No growth.
    pub fn fit(runs: &PhaseRuns, n: f64) -> PhaseModel {
        let [t11, t12, t21] = runs.seconds.map(|t| t / n);
        // Rows: the coefficients of (s, r, d) in each run.
        let rows = [[1.0, 1.0, 1.0], [1.0, 0.5, 0.5], [1.0, 1.0, 0.5]];
        let t = [t11, t12, t21];
        let exact = {
            let d = 2.0 * (t11 - t21);
            let r = 2.0 * (t11 - t12) - d;
            [t11 - r - d, r, d]
        };
        let parts = if exact.iter().all(|&x| x >= 0.0) {
            exact
        } else {
            // The best fit by one or two of the parts, the others held at zero, over the
            // choices whose parts stay non-negative.
            let choices: [&[usize]; 6] = [&[0, 1], &[0, 2], &[1, 2], &[0], &[1], &[2]];
            choices
                .iter()
                .filter_map(|&keep| {
                    let x = least_squares(&rows, &t, keep);
                    if x.iter().any(|&v| v < 0.0) {
                        return None;
                    }
                    let mut parts = [0.0; 3];
                    for (&k, v) in keep.iter().zip(x) {
                        parts[k] = v;
                    }
                    let misfit: f64 = (0..3)
                        .map(|i| (rows[i].iter().zip(&parts).map(|(a, p)| a * p).sum::<f64>() - t[i]).powi(2))
                        .sum();
                    Some((misfit, parts))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map_or([t11.max(0.0), 0.0, 0.0], |(_, parts)| parts)
        };
        PhaseModel {
            name: runs.name.clone(),
            serial: parts[0],
            repeated: parts[1],
            divided: parts[2],
            alone: 1.0,
            overhead: 1.0,
            growth: 0.0,
            at: n,
        }
    }

    /// The parts of `runs` at `n` patches where the run on two threads also gave its CPU
    /// seconds, `cpu`: the serial part is what ran on one thread alone, `2 t₁₂ − cpu` (the
    /// other thread idle), so threads that contend for memory, which spend more CPU seconds
    /// than one thread would, are not taken for serial code; the parallel work is the rest of
    /// the CPU seconds, split into repeated and divided by the run on two ranks, and the run on
    /// one thread gives that work without contention (`alone`).
    pub fn fit_with_cpu(runs: &PhaseRuns, cpu: f64, n: f64) -> PhaseModel {
        let [t11, t12, t21] = runs.seconds;
        let serial = (2.0 * t12 - cpu).clamp(0.0, t12.max(0.0));
        let work = (cpu - serial).max(0.0);
        // Two ranks of one thread: t₂₁ = s + r + d / 2 with r + d the work.
        let divided = (2.0 * (serial + work - t21)).clamp(0.0, work);
        let alone = if work > 0.0 { ((t11 - serial) / work).max(0.0) } else { 1.0 };
        PhaseModel {
            name: runs.name.clone(),
            serial: serial / n,
            repeated: (work - divided) / n,
            divided: divided / n,
            alone,
            overhead: 1.0,
            growth: 0.0,
            at: n,
        }
    }

    /// Seconds for `n` patches on `nodes` nodes of `cores` cores, each node its own machine.
    pub fn seconds(&self, n: f64, nodes: f64, cores: f64) -> f64 {
        self.seconds_busy(n, nodes, cores, cores)
    }

    /// [`Self::seconds`] with `busy` threads working on each machine: the parallel work is
    /// done at its pace alone on one, at its pace beside another on more.
    fn seconds_busy(&self, n: f64, nodes: f64, cores: f64, busy: f64) -> f64 {
        let work = if busy > 1.0 { 1.0 } else { self.alone };
        let overhead = if nodes > 1.0 { self.overhead } else { 1.0 };
        let per_patch = self.serial + work * (self.repeated / cores + overhead * self.divided / (nodes * cores));
        n * (n / self.at).powf(self.growth) * per_patch
    }

    /// This phase with the growth that gives it `seconds` at `n` patches on one node of
    /// `cores` cores (none where either time is zero, or `n` is the fit's size).
    fn grown_to(&self, n: f64, cores: f64, seconds: f64) -> PhaseModel {
        let flat = PhaseModel { growth: 0.0, ..self.clone() }.seconds(n, 1.0, cores);
        let growth =
            if flat > 0.0 && seconds > 0.0 && n != self.at { (seconds / flat).ln() / (n / self.at).ln() } else { 0.0 };
        PhaseModel { growth, ..self.clone() }
    }
}

/// The least-squares solution of `rows · x = t` over one or two columns `cols` of `rows`.
fn least_squares(rows: &[[f64; 3]; 3], t: &[f64; 3], cols: &[usize]) -> Vec<f64> {
    let column = |c: usize| rows.iter().map(move |r| r[c]);
    let dot = |a: usize, b: usize| column(a).zip(column(b)).map(|(x, y)| x * y).sum::<f64>();
    let against = |a: usize| column(a).zip(t).map(|(x, y)| x * y).sum::<f64>();
    match *cols {
        [a] => vec![against(a) / dot(a, a)],
        [a, b] => {
            let det = dot(a, a) * dot(b, b) - dot(a, b) * dot(a, b);
            vec![
                (against(a) * dot(b, b) - against(b) * dot(a, b)) / det,
                (dot(a, a) * against(b) - dot(a, b) * against(a)) / det,
            ]
        }
        _ => unreachable!("one or two columns"),
    }
}

/// The median of `values` (the mean of the middle two for an even count; 0 for none).
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        k if k % 2 == 1 => v[k / 2],
        k => 0.5 * (v[k / 2 - 1] + v[k / 2]),
    }
}

/// The model's coefficients (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// Every phase's parts, seconds per patch.
    pub phases: Vec<PhaseModel>,
    /// Bytes every process holds whatever the patches.
    pub memory_fixed: f64,
    /// Bytes per patch every rank holds.
    pub memory_repeated: f64,
    /// Bytes per patch divided between the ranks.
    pub memory_divided: f64,
    /// Bytes a rank holds beyond one process (where a rank of two peaked above one process:
    /// MPI's buffers and the sums'), at two nodes: fixed for [`Sums::Fixed`], whose sums go in
    /// chunks of a fixed size; growing with the replicates for [`Sums::Replicates`].
    pub memory_sums: f64,
    /// The solve's collective sums.
    pub sums: Sums,
}

/// A network: latency and bandwidth per node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Network {
    /// Seconds of one message's start.
    pub latency: f64,
    /// Bytes per second a node sends.
    pub bandwidth: f64,
}

impl Network {
    /// Ranks on one machine: their sums are in the measured phases, so none is modelled.
    pub const SHARED: Network = Network { latency: 0.0, bandwidth: f64::INFINITY };
}

/// What the model projects for one scene size on one cluster.
#[derive(Clone, Debug, PartialEq)]
pub struct Projection {
    /// Bytes per node.
    pub memory_per_node: f64,
    /// Every phase's seconds, in the model's order.
    pub phases: Vec<(String, f64)>,
    /// Seconds in the solve's sums.
    pub communication: f64,
    /// All of it.
    pub total: f64,
    /// The one-node time over `P` times this time.
    pub efficiency: f64,
    /// What takes longest: a phase's name, or "sums".
    pub limit: String,
}

/// A run the fit did not see, against the model ([`Model::check`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Check {
    /// The run.
    pub run: Run,
    /// Each of the model's phases: measured and modelled seconds.
    pub phases: Vec<(String, f64, f64)>,
    /// The run's seconds in all its phases, and the model's.
    pub total: (f64, f64),
    /// The run's peak and the model's memory for its largest process.
    pub peak: (f64, f64),
}

impl Check {
    /// The model's total time over the run's, less 1.
    pub fn error(&self) -> f64 {
        self.total.1 / self.total.0 - 1.0
    }

    /// The model's memory over the run's peak, less 1.
    pub fn memory_error(&self) -> f64 {
        self.peak.1 / self.peak.0 - 1.0
    }
}

impl Model {
    /// The model of `runs` (module doc), with the solve's `sums`: the three kinds of run at the
    /// smallest size run on one thread, each kind's median, and the growth from the largest
    /// size run on two threads above it, where there is one.
    pub fn fit(runs: &[Run], sums: Sums) -> Result<Model, ProjectionError> {
        let n = runs
            .iter()
            .filter(|r| r.threads == 1.0 && r.ranks == 1.0)
            .map(|r| r.patches)
            .min_by(f64::total_cmp)
            .ok_or(ProjectionError::NoSingleThread)?;
        let kinds = [(1.0, 1.0), (2.0, 1.0), (1.0, 2.0)];
        let words = ["one process on one thread", "one process on two threads", "two ranks of one thread each"];
        let of = |patches: f64, kind| runs.iter().filter(move |r: &&Run| r.is(patches, kind));
        for (kind, missing) in kinds.iter().zip(words) {
            if of(n, *kind).next().is_none() {
                return Err(ProjectionError::Missing { patches: n, missing });
            }
        }
        // The phases in the order of the first run that has them.
        let mut names: Vec<&str> = Vec::new();
        for r in kinds.iter().flat_map(|&k| of(n, k)) {
            for phase in &r.phases {
                if !names.contains(&phase.name.as_str()) {
                    names.push(&phase.name);
                }
            }
        }
        let medians =
            |patches: f64, kind, name: &str| median(&of(patches, kind).map(|r| r.phase(name)).collect::<Vec<_>>());
        let cpus = |name: &str| of(n, (2.0, 1.0)).map(|r| r.cpu(name)).collect::<Option<Vec<f64>>>();
        let mut phases: Vec<PhaseModel> = names
            .iter()
            .map(|name| {
                let runs = PhaseRuns { name: name.to_string(), seconds: kinds.map(|k| medians(n, k, name)) };
                match cpus(name) {
                    Some(cpu) => PhaseModel::fit_with_cpu(&runs, median(&cpu), n),
                    None => PhaseModel::fit(&runs, n),
                }
            })
            .collect();
        let peak = |patches: f64, kind| median(&of(patches, kind).map(|r| r.peak).collect::<Vec<_>>());
        let larger = runs
            .iter()
            .filter(|r| r.is(r.patches, (2.0, 1.0)) && r.patches > n)
            .map(|r| r.patches)
            .max_by(f64::total_cmp);
        let (one, rank) = (peak(n, (2.0, 1.0)), peak(n, (1.0, 2.0)));
        let (memory_fixed, per_patch) = match larger {
            Some(large) => {
                for phase in &mut phases {
                    *phase = phase.grown_to(large, 2.0, medians(large, (2.0, 1.0), &phase.name));
                }
                let slope = (peak(large, (2.0, 1.0)) - one) / (large - n);
                ((one - slope * n).max(0.0), slope)
            }
            None => (0.0, one / n),
        };
        // What ranks divide: the program's own count at the largest size on two threads where
        // it gives one, else what a rank of two holds less than one process.
        let largest = larger.unwrap_or(n);
        let counted = of(largest, (2.0, 1.0)).map(|r| r.divided_bytes).collect::<Option<Vec<f64>>>();
        let memory_divided = match counted {
            Some(bytes) => median(&bytes) / largest,
            None => 2.0 * (one - rank) / n,
        }
        .clamp(0.0, per_patch.max(0.0));
        Ok(Model {
            phases,
            memory_fixed,
            memory_repeated: (per_patch - memory_divided).max(0.0),
            memory_divided,
            memory_sums: (rank - one).max(0.0),
            sums,
        })
    }

    /// The same fit read the other way: what two ranks cost beyond one process, which the fit
    /// calls repeated, taken instead as an overhead on the divided work of every rank count
    /// above one (its imbalance between the ranks, and two processes contending on one
    /// machine, which nodes of their own would not), `κ = (2r + d) / (r + d)`. Both readings fit
    /// the same runs; they part at more nodes, where the repeated part stays and an overhead
    /// divides.
    pub fn excess_as_overhead(&self) -> Model {
        let phases = self
            .phases
            .iter()
            .map(|p| {
                let work = p.repeated + p.divided;
                let overhead = if work > 0.0 { (2.0 * p.repeated + p.divided) / work } else { 1.0 };
                PhaseModel { repeated: 0.0, divided: work, overhead, ..p.clone() }
            })
            .collect();
        Model { phases, ..self.clone() }
    }

    /// `run` against the model: its phases on its ranks and threads, all on one machine.
    pub fn check(&self, run: &Run) -> Check {
        let busy = run.ranks * run.threads;
        let modelled = self.project_busy(run.patches, run.ranks, run.threads, &Network::SHARED, busy);
        let phases: Vec<(String, f64, f64)> =
            modelled.phases.iter().map(|(name, t)| (name.clone(), run.phase(name), *t)).collect();
        Check {
            run: run.clone(),
            phases,
            total: (run.total(), modelled.total),
            peak: (run.peak, modelled.memory_per_node),
        }
    }

    /// The projection for `patches` on `nodes` nodes of `cores` cores over `network`.
    pub fn project(&self, patches: f64, nodes: f64, cores: f64, network: &Network) -> Projection {
        self.project_busy(patches, nodes, cores, network, cores)
    }

    /// [`Self::project`] with `busy` threads working on each machine.
    fn project_busy(&self, patches: f64, nodes: f64, cores: f64, network: &Network, busy: f64) -> Projection {
        let at = |p: f64| {
            let phases: Vec<(String, f64)> =
                self.phases.iter().map(|ph| (ph.name.clone(), ph.seconds_busy(patches, p, cores, busy))).collect();
            let communication = if p > 1.0 && network.bandwidth.is_finite() {
                let (count, bytes) = self.sums.on(p);
                count * (2.0 * (p - 1.0) * network.latency + 2.0 * (p - 1.0) / p * bytes * patches / network.bandwidth)
            } else {
                0.0
            };
            let total = phases.iter().map(|(_, t)| t).sum::<f64>() + communication;
            (phases, communication, total)
        };
        let (phases, communication, total) = at(nodes);
        let (_, _, one) = at(1.0);
        let limit = phases
            .iter()
            .map(|(name, t)| (name.as_str(), *t))
            .chain([("sums", communication)])
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map_or_else(String::new, |(name, _)| name.to_string());
        let sums = match self.sums {
            _ if nodes <= 1.0 || self.memory_sums <= 0.0 => 0.0,
            Sums::Fixed { .. } => self.memory_sums,
            Sums::Replicates { .. } => self.memory_sums * self.sums.on(nodes).1 / self.sums.on(2.0).1,
        };
        Projection {
            memory_per_node: self.memory_fixed + sums + patches * (self.memory_repeated + self.memory_divided / nodes),
            phases,
            communication,
            total,
            efficiency: one / (nodes * total),
            limit,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth() -> Model {
        let phase = |name: &str, serial, repeated, divided| PhaseModel {
            name: name.into(),
            serial,
            repeated,
            divided,
            alone: 1.0,
            overhead: 1.0,
            growth: 0.0,
            at: 1e6,
        };
        Model {
            phases: vec![
                phase("load", 1e-6, 0.0, 0.0),
                phase("bvh", 2e-7, 3e-6, 0.0),
                phase("probes", 1e-7, 1e-7, 2e-5),
                phase("build", 3e-6, 5e-6, 4e-4),
                phase("solve", 2e-7, 0.0, 1.5e-5),
            ],
            memory_fixed: 0.0,
            memory_repeated: 400.0,
            memory_divided: 3200.0,
            memory_sums: 0.0,
            sums: Sums::Fixed { count: 7.0, bytes: 24.0 },
        }
    }

    /// A run of `threads` threads on each of `ranks` ranks made up from a known model.
    fn made_by(truth: &Model, n: f64, threads: f64, ranks: f64) -> Run {
        let p = truth.project(n, ranks, threads, &Network::SHARED);
        let phases = p.phases.into_iter().map(|(name, seconds)| RunPhase { name, seconds, cpu: None }).collect();
        Run { patches: n, threads, ranks, phases, peak: p.memory_per_node, divided_bytes: None }
    }

    /// The three kinds of fitting run, made up from a known model.
    fn fitting_runs(truth: &Model, n: f64) -> Vec<Run> {
        vec![made_by(truth, n, 1.0, 1.0), made_by(truth, n, 2.0, 1.0), made_by(truth, n, 1.0, 2.0)]
    }

    /// A run written by hand.
    fn by_hand(patches: f64, threads: f64, ranks: f64, seconds: f64, peak: f64) -> Run {
        let phases = vec![RunPhase { name: "work".into(), seconds, cpu: None }];
        Run { patches, threads, ranks, phases, peak, divided_bytes: None }
    }

    fn close(got: f64, want: f64, tolerance: f64) -> bool {
        (got - want).abs() <= tolerance * want.abs().max(1e-12)
    }

    #[test]
    fn fitting_runs_of_a_known_model_gives_it_back() {
        let truth = truth();
        let fitted = Model::fit(&fitting_runs(&truth, 1e6), truth.sums).unwrap();
        for (got, want) in fitted.phases.iter().zip(&truth.phases) {
            assert!(
                close(got.serial, want.serial, 1e-9)
                    && close(got.repeated, want.repeated, 1e-9)
                    && close(got.divided, want.divided, 1e-9),
                "{got:?} against {want:?}"
            );
        }
        assert!(close(fitted.memory_repeated, truth.memory_repeated, 1e-9));
        assert!(close(fitted.memory_divided, truth.memory_divided, 1e-9));
        // Read with the ranks' excess as an overhead on the divided work, the same runs are
        // fitted as well, and more nodes divide what the other reading repeats.
        let overhead = fitted.excess_as_overhead();
        for run in fitting_runs(&truth, 1e6) {
            assert!(close(overhead.check(&run).total.1, run.total(), 1e-9), "{run:?}");
        }
        let net = Network { latency: 2e-6, bandwidth: 12.5e9 };
        assert!(overhead.project(1e7, 8.0, 32.0, &net).total < fitted.project(1e7, 8.0, 32.0, &net).total);
    }

    #[test]
    fn repeats_are_fitted_by_their_median_so_that_one_slow_run_does_not_move_the_fit() {
        let truth = truth();
        let mut runs = fitting_runs(&truth, 1e6);
        // Two more of each kind, one of them 40% slower in every phase.
        runs.extend(fitting_runs(&truth, 1e6));
        for mut slow in fitting_runs(&truth, 1e6) {
            slow.phases.iter_mut().for_each(|p| p.seconds *= 1.4);
            runs.push(slow);
        }
        assert_eq!(Model::fit(&runs, truth.sums).unwrap(), Model::fit(&fitting_runs(&truth, 1e6), truth.sums).unwrap());
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }

    #[test]
    fn a_larger_run_on_two_threads_fits_each_phase_s_growth() {
        let truth = truth();
        let mut runs = fitting_runs(&truth, 1e5);
        // At ten times the patches every phase costs 1.5 times as much per patch.
        let mut large = made_by(&truth, 1e6, 2.0, 1.0);
        large.phases.iter_mut().for_each(|p| p.seconds *= 1.5);
        runs.push(large);
        let fitted = Model::fit(&runs, truth.sums).unwrap();
        for (got, want) in fitted.phases.iter().zip(&truth.phases) {
            assert!(close(got.growth, 1.5f64.ln() / 10f64.ln(), 1e-9), "{got:?}");
            assert!(close(got.divided, want.divided, 1e-9) && got.at == 1e5, "{got:?}");
            // At a hundred times the patches, 1.5² times as much per patch, on any machine.
            let want = 1.5
                * 1.5
                * made_by(&truth, 1e7, 32.0, 8.0).phases.iter().find(|p| p.name == want.name).unwrap().seconds;
            assert!(close(got.seconds(1e7, 8.0, 32.0), want, 1e-9), "{got:?}");
        }
    }

    #[test]
    fn runs_written_by_hand_for_a_known_amdahl_curve_project_to_it() {
        // 10% serial, the rest divided, at 1e5 patches: 100 s on one thread, 55 s on two, 55
        // s on two ranks of one; 30% dearer a patch at ten times the patches. Memory: 30 MB
        // fixed, 1,000 bytes a patch on every rank and 2,000 divided.
        let runs = vec![
            by_hand(1e5, 1.0, 1.0, 100.0, 3.3e8),
            by_hand(1e5, 2.0, 1.0, 55.0, 3.3e8),
            by_hand(1e5, 1.0, 2.0, 55.0, 2.3e8),
            by_hand(1e6, 2.0, 1.0, 715.0, 3.03e9),
        ];
        let model = Model::fit(&runs, Sums::Fixed { count: 0.0, bytes: 0.0 }).unwrap();
        let net = Network { latency: 2e-6, bandwidth: 12.5e9 };
        // Amdahl at the fit's size: 10 + 90 / 256 seconds on 8 nodes of 32 cores, 10 + 90 /
        // 32 on one, an efficiency of 12.8125 / (8 × 10.3515625).
        let eight = model.project(1e5, 8.0, 32.0, &net);
        assert!(close(eight.total, 10.3515625, 1e-12), "{eight:?}");
        assert!(close(eight.efficiency, 0.154717, 1e-5), "{eight:?}");
        // A hundred times the patches on one thread: 100 × 100 × 1.3² seconds.
        assert!(close(model.project(1e7, 1.0, 1.0, &net).total, 16900.0, 1e-12));
        // 30 MB and 1,000 + 2,000 / 8 bytes a patch for 1e7 patches on 8 nodes.
        assert!(close(model.project(1e7, 8.0, 32.0, &net).memory_per_node, 1.253e10, 1e-12));
        // A run the fit did not see: two ranks at 1e6 patches, modelled at 1.3 × 1e6 × (1e-4
        // + 4.5e-4) = 715 s and 3e7 + 1e6 × 2,000 bytes, measured at 786.5 s and 2.2e9.
        let check = model.check(&by_hand(1e6, 1.0, 2.0, 786.5, 2.2e9));
        assert!(close(check.total.1, 715.0, 1e-12) && close(check.error(), 715.0 / 786.5 - 1.0, 1e-12), "{check:?}");
        assert!(close(check.peak.1, 2.03e9, 1e-12) && close(check.memory_error(), 2.03 / 2.2 - 1.0, 1e-12));
    }

    #[test]
    fn cpu_seconds_tell_serial_code_from_threads_that_contend() {
        // Written by hand: 100 s on one thread; 60 s on two, which used 110 CPU seconds, so 10
        // s ran on one thread and the other 100 CPU seconds (90 alone) on both; 60 s on two
        // ranks, so that work is all divided.
        let with_cpu = |threads: f64, ranks: f64, seconds: f64, cpu: Option<f64>| Run {
            phases: vec![RunPhase { name: "work".into(), seconds, cpu }],
            ..by_hand(1e5, threads, ranks, seconds, 1e8)
        };
        let runs = [
            with_cpu(1.0, 1.0, 100.0, Some(100.0)),
            with_cpu(2.0, 1.0, 60.0, Some(110.0)),
            with_cpu(1.0, 2.0, 60.0, None),
        ];
        let model = Model::fit(&runs, Sums::Fixed { count: 0.0, bytes: 0.0 }).unwrap();
        let p = &model.phases[0];
        assert!(close(p.serial * 1e5, 10.0, 1e-12) && close(p.divided * 1e5, 100.0, 1e-12), "{p:?}");
        assert!(p.repeated.abs() < 1e-15 && close(p.alone, 0.9, 1e-12), "{p:?}");
        // It gives back the runs it was fitted to, each on one machine.
        for run in &runs {
            assert!(close(model.check(run).total.1, run.total(), 1e-12), "{run:?}");
        }
        // On 8 nodes of 32 cores: 10 + 100 / 256 seconds. Without the CPU seconds the same
        // walls fit 20 s of serial code, the contention taken for it.
        let net = Network { latency: 2e-6, bandwidth: 12.5e9 };
        assert!(close(model.project(1e5, 8.0, 32.0, &net).total, 10.390625, 1e-12));
        // Read with the ranks' excess as an overhead, the same runs are fitted as well.
        let overhead = model.excess_as_overhead();
        for run in &runs {
            assert!(close(overhead.check(run).total.1, run.total(), 1e-12), "{run:?}");
        }
        let walls: Vec<Run> = runs.iter().map(|r| with_cpu(r.threads, r.ranks, r.total(), None)).collect();
        let wall_only = Model::fit(&walls, Sums::Fixed { count: 0.0, bytes: 0.0 }).unwrap();
        assert!(close(wall_only.phases[0].serial * 1e5, 20.0, 1e-12), "{:?}", wall_only.phases[0]);
    }

    #[test]
    fn the_program_s_count_of_what_ranks_divide_splits_the_memory_where_it_is_given() {
        let sums = Sums::Fixed { count: 0.0, bytes: 0.0 };
        let mut runs = vec![
            by_hand(1e5, 1.0, 1.0, 100.0, 3.3e8),
            by_hand(1e5, 2.0, 1.0, 55.0, 3.3e8),
            by_hand(1e5, 1.0, 2.0, 55.0, 3.0e8),
            by_hand(1e6, 2.0, 1.0, 715.0, 3.03e9),
        ];
        // 2,000 bytes a patch of links at 1e6 patches, of the 3,000 a patch above 30 MB.
        runs[3].divided_bytes = Some(2e9);
        let m = Model::fit(&runs, sums).unwrap();
        assert!(close(m.memory_divided, 2000.0, 1e-12) && close(m.memory_repeated, 1000.0, 1e-12), "{m:?}");
        assert!(close(m.memory_fixed, 3e7, 1e-12) && m.memory_sums == 0.0, "{m:?}");
        // Without it, what a rank of two holds less: 2 (3.3e8 − 3.0e8) / 1e5 bytes a patch.
        runs[3].divided_bytes = None;
        assert!(close(Model::fit(&runs, sums).unwrap().memory_divided, 600.0, 1e-12));
        // A rank that holds more than one process holds it beside what it divides, in bytes.
        runs[2].peak = 3.5e8;
        let m = Model::fit(&runs, sums).unwrap();
        assert!(close(m.memory_sums, 2e7, 1e-12) && m.memory_divided == 0.0, "{m:?}");
        let net = Network { latency: 2e-6, bandwidth: 12.5e9 };
        assert!(close(m.project(1e7, 8.0, 32.0, &net).memory_per_node, 3e7 + 2e7 + 1e7 * 3000.0, 1e-12));
    }

    #[test]
    fn a_fit_without_every_kind_of_run_says_which_is_missing() {
        let runs = [by_hand(1e5, 1.0, 1.0, 100.0, 1.0), by_hand(1e5, 2.0, 1.0, 55.0, 1.0)];
        let sums = Sums::Fixed { count: 0.0, bytes: 0.0 };
        let err = Model::fit(&runs, sums).unwrap_err();
        assert_eq!(err, ProjectionError::Missing { patches: 1e5, missing: "two ranks of one thread each" });
        assert!(
            err.to_string().ends_with("at 100000 patches there is no run of two ranks of one thread each"),
            "{err}"
        );
        assert_eq!(Model::fit(&runs[1..], sums).unwrap_err(), ProjectionError::NoSingleThread);
    }

    #[test]
    fn a_negative_part_is_dropped_and_the_others_fitted_without_it() {
        // Two threads slower than one (noise, or memory contention): no part may go negative,
        // and what is left is all serial or repeated.
        let runs = PhaseRuns { name: "x".into(), seconds: [10.0, 10.5, 10.0] };
        let p = PhaseModel::fit(&runs, 1.0);
        assert!(p.serial >= 0.0 && p.repeated >= 0.0 && p.divided >= 0.0, "{p:?}");
        assert!((p.serial + p.repeated + p.divided - 10.0).abs() < 0.5, "{p:?}");
    }

    #[test]
    fn one_node_is_fully_efficient_and_more_nodes_divide_only_the_divided_parts() {
        let truth = truth();
        let net = Network { latency: 2e-6, bandwidth: 12.5e9 };
        let one = truth.project(1e7, 1.0, 32.0, &net);
        assert_eq!(one.communication, 0.0);
        assert!((one.efficiency - 1.0).abs() < 1e-12);
        let eight = truth.project(1e7, 8.0, 32.0, &net);
        assert!(eight.total < one.total && eight.efficiency < 1.0);
        assert!(eight.memory_per_node < one.memory_per_node);
        assert_eq!(eight.phases[0], one.phases[0], "every rank loads the whole scene");
        assert_eq!(one.limit, "build");
        // The repeated parts stay: memory never falls below them.
        let many = truth.project(1e7, 1e6, 32.0, &net);
        assert!(many.memory_per_node >= 1e7 * truth.memory_repeated);
        // A slower network costs efficiency, all else equal; ranks on one machine model none.
        let slow = truth.project(1e7, 8.0, 32.0, &Network { latency: 2e-5, bandwidth: 1.25e9 });
        assert!(slow.efficiency < eight.efficiency && slow.communication > eight.communication);
        assert_eq!(truth.project(1e7, 8.0, 32.0, &Network::SHARED).communication, 0.0);
        // Sums whose volume grows with the replicates, one a node, outgrow fixed ones.
        let replicated = Model { sums: Sums::Replicates { count: 7.0, bytes: 24.0, least: 4.0 }, ..truth.clone() };
        let sixty_four = |m: &Model| m.project(1e7, 64.0, 32.0, &net).communication;
        assert!(sixty_four(&replicated) > 10.0 * sixty_four(&truth));
        // What a rank holds for those sums grows with them: 16 times the replicates at 64
        // nodes as at 2 (at least 4), none on one node.
        let holding = Model { memory_sums: 1e9, ..replicated };
        let extra = |nodes: f64| {
            holding.project(1e7, nodes, 32.0, &net).memory_per_node - {
                let plain = Model { memory_sums: 0.0, ..holding.clone() };
                plain.project(1e7, nodes, 32.0, &net).memory_per_node
            }
        };
        assert_eq!(extra(1.0), 0.0);
        assert!((extra(2.0) - 1e9).abs() < 1.0 && (extra(64.0) - 16e9).abs() < 16.0, "{} {}", extra(2.0), extra(64.0));
    }
}
