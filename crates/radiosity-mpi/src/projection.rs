//! A model of a distributed solve's time and memory, phase by phase, fitted to measured runs
//! and projected to more patches and more machines (docs/distributed.md).
//!
//! One rank runs on each of `P` nodes, its threads on the node's `c` cores. Every phase of a
//! run (loading, the BVH, the analysis's probes, the operator or the sampler, solving) costs
//! seconds linear in the patches `n`, in three parts that differ in what divides them: a
//! serial part `s` (one thread, on every rank), a repeated part `r` (every rank does all of
//! it, over its cores) and a divided part `d` (split between all the ranks' cores):
//!
//! `t(P, c) = n (s + r / c + d / (P c))`.
//!
//! Three runs at one size fit the three parts of each phase: one process on one thread
//! (`t₁₁ = n (s + r + d)`), on two threads (`t₁₂ = n (s + (r + d) / 2)`), and two ranks of one
//! thread each (`t₂₁ = n (s + r + d / 2)`), so `d = 2 (t₁₁ − t₂₁) / n`,
//! `r = 2 (t₁₁ − t₁₂) / n − d` and `s = t₁₁ / n − r − d`. A part that comes out negative (noise
//! in a part too small to measure, or two threads slower than one) is taken as zero and the
//! others refitted without it ([`PhaseModel::fit`]). A run at a larger size on two threads, where there is one, rescales
//! each phase to its cost per patch there, its parts in the fitted proportions: a BVH is deeper
//! and an operator's links more numerous per patch at ten times the patches.
//!
//! Memory per node is `n (m_rep + m_div / P)`, from the peaks of one process and of a rank of
//! two (at the largest size measured both ways: a process's fixed memory weighs less there).
//! Where a rank of two peaks above one process, the excess is what the solve's sums hold, and
//! grows with their volume. The solve's collective sums (a product's for the hierarchical operator, a step's for
//! the stochastic solvers, [`Sums`]) are reduce-scatter then all-gather over a network of
//! latency `α` and bandwidth `β` per node (Hockney's model): `2 (P − 1) α + 2 (P − 1) / P · m /
//! β` for a sum of `m` bytes, zero on one node. Two ranks on one machine share its memory, so
//! the network is an input, stated wherever a projection is quoted, not a measurement.
//!
//! ## References
//!
//! - R. Hockney, "The communication challenge for MPP: Intel Paragon and Meiko CS-2", Parallel
//!   Computing 20(3), 1994 (the `α + m/β` model of a message).
//! - R. Thakur, R. Rabenseifner, W. Gropp, "Optimization of collective communication operations
//!   in MPICH", IJHPCA 19(1), 2005 (reduce-scatter and all-gather volumes).

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
    /// hierarchical operator sums `3n` values (24 bytes a patch).
    Fixed {
        /// Sums per solve.
        count: f64,
        /// Bytes per patch a sum.
        bytes: f64,
    },
    /// `count` sums of one block of `bytes` per patch for each replicate, with as many
    /// replicates as nodes and at least `least`: stochastic Jacobi shares every replicate's
    /// state after every step (`R (n k + n)` values), and needs a replicate a rank.
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

/// What the runs measured (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    /// Patches of the fitting runs.
    pub patches: f64,
    /// Every phase's seconds in them.
    pub phases: Vec<PhaseRuns>,
    /// Peak resident bytes of one process on two threads and of the larger of two ranks, and
    /// the patches of the runs they were measured in (the fitting runs', or a larger pair's).
    pub peaks: ([f64; 2], f64),
    /// The solve's collective sums.
    pub sums: Sums,
    /// A larger run on two threads, where there is one: its patches and each phase's seconds,
    /// in the order of `phases`.
    pub larger: Option<(f64, Vec<f64>)>,
}

/// One phase's three parts, seconds per patch (module doc).
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
}

impl PhaseModel {
    /// The parts of `runs` at `n` patches (module doc), each held at zero or above: where a
    /// part comes out negative, the best non-negative fit by one or two parts, the others
    /// held at zero (by least squares on the three equations).
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
        PhaseModel { name: runs.name.clone(), serial: parts[0], repeated: parts[1], divided: parts[2] }
    }

    /// Seconds for `n` patches on `nodes` nodes of `cores` cores.
    pub fn seconds(&self, n: f64, nodes: f64, cores: f64) -> f64 {
        n * (self.serial + self.repeated / cores + self.divided / (nodes * cores))
    }

    /// This phase with its parts scaled by `factor`.
    fn scaled(&self, factor: f64) -> PhaseModel {
        PhaseModel {
            name: self.name.clone(),
            serial: self.serial * factor,
            repeated: self.repeated * factor,
            divided: self.divided * factor,
        }
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

/// The model's coefficients (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// Every phase's parts, seconds per patch.
    pub phases: Vec<PhaseModel>,
    /// Bytes per patch every rank holds.
    pub memory_repeated: f64,
    /// Bytes per patch divided between the ranks.
    pub memory_divided: f64,
    /// Bytes per patch a rank holds beyond one process for the solve's sums (where a rank of
    /// two peaked above one process), at two nodes; it grows with a sum's volume.
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

impl Model {
    /// The coefficients from `m` (module doc).
    pub fn fit(m: &Measured) -> Model {
        let n = m.patches;
        let mut phases: Vec<PhaseModel> = m.phases.iter().map(|runs| PhaseModel::fit(runs, n)).collect();
        if let Some((large, seconds)) = &m.larger {
            for (phase, &t) in phases.iter_mut().zip(seconds) {
                let modelled = phase.seconds(*large, 1.0, 2.0);
                if modelled > 0.0 {
                    *phase = phase.scaled(t / modelled);
                }
            }
        }
        let ([one, rank], at) = m.peaks;
        let memory_divided = (2.0 * (one - rank) / at).max(0.0);
        Model {
            phases,
            memory_repeated: (one / at - memory_divided).max(0.0),
            memory_divided,
            memory_sums: ((rank - one) / at).max(0.0),
            sums: m.sums,
        }
    }

    /// The projection for `patches` on `nodes` nodes of `cores` cores over `network`.
    pub fn project(&self, patches: f64, nodes: f64, cores: f64, network: &Network) -> Projection {
        let at = |p: f64| {
            let phases: Vec<(String, f64)> =
                self.phases.iter().map(|ph| (ph.name.clone(), ph.seconds(patches, p, cores))).collect();
            let communication = if p > 1.0 {
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
        let sums = if nodes > 1.0 { self.memory_sums * self.sums.on(nodes).1 / self.sums.on(2.0).1 } else { 0.0 };
        Projection {
            memory_per_node: patches * (self.memory_repeated + self.memory_divided / nodes + sums),
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
        let phase = |name: &str, serial, repeated, divided| PhaseModel { name: name.into(), serial, repeated, divided };
        Model {
            phases: vec![
                phase("load", 1e-6, 0.0, 0.0),
                phase("bvh", 2e-7, 3e-6, 0.0),
                phase("probes", 1e-7, 1e-7, 2e-5),
                phase("build", 3e-6, 5e-6, 4e-4),
                phase("solve", 2e-7, 0.0, 1.5e-5),
            ],
            memory_repeated: 400.0,
            memory_divided: 3200.0,
            memory_sums: 0.0,
            sums: Sums::Fixed { count: 7.0, bytes: 24.0 },
        }
    }

    /// Runs made up from a known model, so that fitting must give it back.
    fn measured_from(truth: &Model, n: f64) -> Measured {
        let shared = Network { latency: 0.0, bandwidth: f64::INFINITY };
        let run = |p: f64, c: f64| truth.project(n, p, c, &shared);
        let (one, two, ranks) = (run(1.0, 1.0), run(1.0, 2.0), run(2.0, 1.0));
        Measured {
            patches: n,
            phases: truth
                .phases
                .iter()
                .enumerate()
                .map(|(k, ph)| PhaseRuns {
                    name: ph.name.clone(),
                    seconds: [one.phases[k].1, two.phases[k].1, ranks.phases[k].1],
                })
                .collect(),
            peaks: ([two.memory_per_node, ranks.memory_per_node], n),
            sums: truth.sums,
            larger: None,
        }
    }

    #[test]
    fn fitting_runs_of_a_known_model_gives_it_back() {
        let truth = truth();
        let fitted = Model::fit(&measured_from(&truth, 1e6));
        let close = |got: f64, want: f64| (got - want).abs() <= 1e-9 * want.abs().max(1e-12);
        for (got, want) in fitted.phases.iter().zip(&truth.phases) {
            assert!(
                close(got.serial, want.serial)
                    && close(got.repeated, want.repeated)
                    && close(got.divided, want.divided),
                "{got:?} against {want:?}"
            );
        }
        assert!(close(fitted.memory_repeated, truth.memory_repeated));
        assert!(close(fitted.memory_divided, truth.memory_divided));
    }

    #[test]
    fn a_larger_run_rescales_a_phase_and_keeps_its_parts_proportions() {
        let truth = truth();
        let mut measured = measured_from(&truth, 1e5);
        let shared = Network { latency: 0.0, bandwidth: f64::INFINITY };
        // At ten times the patches every phase costs 1.5 times as much per patch.
        let large = truth.project(1e6, 1.0, 2.0, &shared);
        measured.larger = Some((1e6, large.phases.iter().map(|(_, t)| 1.5 * t).collect()));
        let fitted = Model::fit(&measured);
        for (got, want) in fitted.phases.iter().zip(&truth.phases) {
            assert!((got.divided - 1.5 * want.divided).abs() <= 1e-9 * want.divided.max(1e-12), "{got:?}");
            assert!((got.serial - 1.5 * want.serial).abs() <= 1e-9 * want.serial.max(1e-12), "{got:?}");
        }
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
        // A slower network costs efficiency, all else equal.
        let slow = truth.project(1e7, 8.0, 32.0, &Network { latency: 2e-5, bandwidth: 1.25e9 });
        assert!(slow.efficiency < eight.efficiency && slow.communication > eight.communication);
        // Sums whose volume grows with the replicates, one a node, outgrow fixed ones.
        let replicated = Model { sums: Sums::Replicates { count: 7.0, bytes: 24.0, least: 4.0 }, ..truth.clone() };
        let sixty_four = |m: &Model| m.project(1e7, 64.0, 32.0, &net).communication;
        assert!(sixty_four(&replicated) > 10.0 * sixty_four(&truth));
        // What a rank holds for those sums grows with them: 16 times the replicates at 64
        // nodes as at 2 (at least 4), none on one node.
        let holding = Model { memory_sums: 100.0, ..replicated };
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
