//! A model of a distributed hierarchical solve's time and memory, fitted to measured runs and
//! projected to more patches and more machines (docs/distributed.md).
//!
//! One rank runs on each node, its threads on the node's `c` cores. Every cost is linear in the
//! patches `n` (links grow about linearly with them, docs/hierarchical.md) and made of parts
//! that differ in what divides them: the links (their refinement, their memory, their share of a
//! product) are divided between the ranks and their threads; the scene's load (BVH, analysis)
//! and part of the build (the near field's set-up, the brightness, closure's passes) are
//! repeated by every rank but spread over its threads; and some work is serial on every rank
//! (the cluster tree, the frontier, a product's passes up and down the tree). For `P` nodes:
//!
//! - memory per node `M = n (m_rep + m_link / P)`;
//! - load `n (l_s + l_p / c)`, build `n (b_s + b_r / c + b_d / (P c))`, and `k` products of
//!   `n (p_s + p_d / (P c)) + comm` each;
//! - a product's sum, all-to-all then all-gather of its `3n` values (`radiosity_mpi::world`),
//!   `comm = 2 (P − 1) α + 2 (P − 1) / P · 24 n / β` over a network of latency `α` and
//!   bandwidth `β` per node (Hockney's model), zero on one node.
//!
//! The coefficients come from measured runs ([`Measured`]): the large scene in one process on
//! two threads and as two ranks of one thread each (which split the memory, the load and the
//! build's repeated parallel part from the rest), and a smaller scene in one process on one
//! thread and on two (whose build and product give their serial shares, taken to hold at the
//! larger size). The network is not measured here (two ranks on one machine share memory): its
//! latency and bandwidth are inputs, stated wherever a projection is quoted.
//!
//! ## References
//!
//! - R. Hockney, "The communication challenge for MPP: Intel Paragon and Meiko CS-2", Parallel
//!   Computing 20(3), 1994 (the `α + m/β` model of a message).
//! - R. Thakur, R. Rabenseifner, W. Gropp, "Optimization of collective communication operations
//!   in MPICH", IJHPCA 19(1), 2005 (reduce-scatter and all-gather volumes).

/// One run of the large scene: wall seconds loading the scene (everything but the build and
/// the products), building the operator and per product, and the peak resident memory in bytes
/// (for several ranks, the slowest rank's seconds and the largest peak).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Run {
    /// Seconds loading and preparing the scene.
    pub load: f64,
    /// Seconds building the operator.
    pub build: f64,
    /// Seconds per product.
    pub product: f64,
    /// Peak resident memory, in bytes.
    pub peak: f64,
}

/// What the runs measured (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// Patches of the large scene.
    pub patches: f64,
    /// Products of its solve.
    pub products: f64,
    /// The large scene in one process on two threads.
    pub single: Run,
    /// The large scene as two ranks of one thread each.
    pub split: Run,
    /// The small scene's build seconds in one process on one thread and on two.
    pub small_build: [f64; 2],
    /// Its seconds per product on one thread and on two.
    pub small_product: [f64; 2],
}

/// The model's coefficients, per patch (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Model {
    /// Bytes every rank holds.
    pub memory_repeated: f64,
    /// Bytes of links, divided between the ranks.
    pub memory_links: f64,
    /// Load seconds, serial on every rank.
    pub load_serial: f64,
    /// Load core-seconds, on every rank, spread over its cores.
    pub load_parallel: f64,
    /// Build seconds, serial on every rank.
    pub build_serial: f64,
    /// Build core-seconds every rank repeats, spread over its cores.
    pub build_repeated: f64,
    /// Build core-seconds divided between the ranks' cores.
    pub build_divided: f64,
    /// A product's seconds, serial on every rank.
    pub product_serial: f64,
    /// A product's core-seconds divided between the ranks' cores.
    pub product_divided: f64,
    /// Products a solve takes.
    pub products: f64,
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
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Bytes per node.
    pub memory_per_node: f64,
    /// Seconds loading the scene.
    pub load: f64,
    /// Seconds building the operator.
    pub build: f64,
    /// Seconds in the products' own work.
    pub products: f64,
    /// Seconds in the products' sums.
    pub communication: f64,
    /// All of it.
    pub total: f64,
    /// The one-node time over `P` times this time.
    pub efficiency: f64,
}

/// The serial share of a time measured on one thread and on two (`t1 = s + p`,
/// `t2 = s + p / 2`), held within `[0, 1]` against noise.
fn serial_share([one, two]: [f64; 2]) -> f64 {
    ((2.0 * two - one) / one).clamp(0.0, 1.0)
}

impl Model {
    /// The coefficients from `m` (module doc). A part that comes out negative (noise in a part
    /// too small to measure) is taken as zero.
    pub fn fit(m: &Measured) -> Model {
        let n = m.patches;
        let (single, split) = (&m.single, &m.split);
        // Memory: one process holds all the links, each of two ranks half of them.
        let memory_links = (2.0 * (single.peak - split.peak) / n).max(0.0);
        let memory_repeated = (single.peak / n - memory_links).max(0.0);
        // Load, all repeated: on two threads `s + p/2`, each rank on one thread `s + p`.
        let load_parallel = (2.0 * (split.load - single.load) / n).max(0.0);
        let load_serial = (single.load / n - load_parallel / 2.0).max(0.0);
        // Build: on two threads `s + (r + d)/2`; two ranks of one thread `s + r + d/2`; the
        // serial share of one thread's `s + r + d` from the small scene.
        let build_repeated = (2.0 * (split.build - single.build) / n).max(0.0);
        let sigma = serial_share(m.small_build);
        let parallel = single.build / n / (sigma / (1.0 - sigma).max(1e-12) + 0.5);
        let build_serial = single.build / n - parallel / 2.0;
        let build_divided = (parallel - build_repeated).max(0.0);
        // A product: on two threads `s + d/2`, the serial share from the small scene.
        let sigma = serial_share(m.small_product);
        let product_divided = single.product / n / (sigma / (1.0 - sigma).max(1e-12) + 0.5);
        let product_serial = single.product / n - product_divided / 2.0;
        Model {
            memory_repeated,
            memory_links,
            load_serial,
            load_parallel,
            build_serial,
            build_repeated,
            build_divided,
            product_serial,
            product_divided,
            products: m.products,
        }
    }

    /// The projection for `patches` on `nodes` nodes of `cores` cores over `network`.
    pub fn project(&self, patches: f64, nodes: f64, cores: f64, network: &Network) -> Projection {
        let at = |p: f64| {
            let load = patches * (self.load_serial + self.load_parallel / cores);
            let build = patches * (self.build_serial + self.build_repeated / cores + self.build_divided / (p * cores));
            let products = self.products * patches * (self.product_serial + self.product_divided / (p * cores));
            let communication = if p > 1.0 {
                let bytes = 2.0 * (p - 1.0) / p * 24.0 * patches;
                self.products * (2.0 * (p - 1.0) * network.latency + bytes / network.bandwidth)
            } else {
                0.0
            };
            (load, build, products, communication)
        };
        let (load, build, products, communication) = at(nodes);
        let total = load + build + products + communication;
        let (l1, b1, p1, c1) = at(1.0);
        Projection {
            memory_per_node: patches * (self.memory_repeated + self.memory_links / nodes),
            load,
            build,
            products,
            communication,
            total,
            efficiency: (l1 + b1 + p1 + c1) / (nodes * total),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRUTH: Model = Model {
        memory_repeated: 400.0,
        memory_links: 3200.0,
        load_serial: 1e-5,
        load_parallel: 3e-5,
        build_serial: 2e-5,
        build_repeated: 3e-5,
        build_divided: 4e-4,
        product_serial: 2e-7,
        product_divided: 1.5e-6,
        products: 40.0,
    };

    /// Runs made up from a known model, so that fitting must give it back.
    fn measured_from(truth: &Model, n: f64, small: f64) -> Measured {
        let run = |p: f64, c: f64| Run {
            load: n * (truth.load_serial + truth.load_parallel / c),
            build: n * (truth.build_serial + truth.build_repeated / c + truth.build_divided / (p * c)),
            product: n * (truth.product_serial + truth.product_divided / (p * c)),
            peak: n * (truth.memory_repeated + truth.memory_links / p),
        };
        let parallel = truth.build_repeated + truth.build_divided;
        Measured {
            patches: n,
            products: truth.products,
            single: run(1.0, 2.0),
            split: run(2.0, 1.0),
            small_build: [1.0, 2.0].map(|c| small * (truth.build_serial + parallel / c)),
            small_product: [1.0, 2.0].map(|c| small * (truth.product_serial + truth.product_divided / c)),
        }
    }

    #[test]
    fn fitting_runs_of_a_known_model_gives_it_back() {
        let fitted = Model::fit(&measured_from(&TRUTH, 1e6, 1e5));
        for (got, want) in [
            (fitted.memory_repeated, TRUTH.memory_repeated),
            (fitted.memory_links, TRUTH.memory_links),
            (fitted.load_serial, TRUTH.load_serial),
            (fitted.load_parallel, TRUTH.load_parallel),
            (fitted.build_serial, TRUTH.build_serial),
            (fitted.build_repeated, TRUTH.build_repeated),
            (fitted.build_divided, TRUTH.build_divided),
            (fitted.product_serial, TRUTH.product_serial),
            (fitted.product_divided, TRUTH.product_divided),
        ] {
            assert!((got - want).abs() <= 1e-9 * want, "{got} against {want}");
        }
    }

    #[test]
    fn one_node_is_fully_efficient_and_more_nodes_divide_only_the_divided_parts() {
        let net = Network { latency: 2e-6, bandwidth: 12.5e9 };
        let one = TRUTH.project(1e7, 1.0, 32.0, &net);
        assert_eq!(one.communication, 0.0);
        assert!((one.efficiency - 1.0).abs() < 1e-12);
        let eight = TRUTH.project(1e7, 8.0, 32.0, &net);
        assert!(eight.total < one.total && eight.efficiency < 1.0);
        assert!(eight.memory_per_node < one.memory_per_node);
        assert_eq!(eight.load, one.load, "every rank loads the whole scene");
        // The repeated parts stay: memory never falls below them.
        let many = TRUTH.project(1e7, 1e6, 32.0, &net);
        assert!(many.memory_per_node >= 1e7 * TRUTH.memory_repeated);
        // A slower network costs efficiency, all else equal.
        let slow = TRUTH.project(1e7, 8.0, 32.0, &Network { latency: 2e-5, bandwidth: 1.25e9 });
        assert!(slow.efficiency < eight.efficiency && slow.communication > eight.communication);
    }
}
