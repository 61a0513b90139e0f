//! Backend arguments: `analytic`, `hemicube`, `montecarlo` or `matrix`, each with its own
//! `:key=value` parameters, parsed into typed, validated parameter sets.
//!
//! `matrix` stores the full matrix of another backend, named by `of` (default `analytic`);
//! parameters it does not take itself go to that backend:
//! `matrix:of=hemicube:res=64:rebalance=true`.

use crate::error::FfError;
use radiosity_geom::{KeyValueParams, ParamDoc};

/// Parameters of the analytic backend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnalyticParams {
    /// The largest number of Gauss–Legendre points per direction on the receiving patch.
    pub order: usize,
    /// The relative quadrature error each pair's order is chosen to meet (1 = centroid).
    pub tolerance: f64,
    /// The fewest shadow rays of a pair, when the scene needs visibility.
    pub rays: usize,
    /// The shadow rays of a partially visible pair whose larger unoccluded form factor is 1:
    /// a pair gets `budget` times its larger unoccluded form factor, at least `rays`, and
    /// stiff scenes more ([`crate::pair_visibility::stiffness_factor`]).
    pub budget: usize,
    /// Seed of the jittered shadow rays.
    pub seed: u64,
    /// Mebibytes of recorded visible fractions, so that a pair is traced once
    /// ([`crate::visibility_cache`]; 0: none). It changes no entry, so the canonical argument
    /// leaves it out and caches of matrices and references ignore it.
    pub cache_mib: usize,
}

/// Parameters of the hemicube backend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HemicubeParams {
    /// Pixels along each edge of the hemicube's top face.
    pub resolution: usize,
    /// Seed of the random rotation about the normal.
    pub seed: u64,
}

/// Parameters of the Monte Carlo backend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MonteCarloParams {
    /// Cosine-weighted rays shot from each patch.
    pub rays: usize,
    /// Seed of the rays.
    pub seed: u64,
}

/// A parsed backend argument.
#[derive(Clone, Debug, PartialEq)]
pub enum BackendSpec {
    /// Lambert's point-to-polygon formula integrated over the receiver.
    Analytic(AnalyticParams),
    /// A ray-cast hemicube at the shooter.
    Hemicube(HemicubeParams),
    /// Cosine-weighted rays from the shooter.
    MonteCarlo(MonteCarloParams),
    /// The full matrix of another backend, assembled once.
    Matrix {
        /// The backend whose matrix is stored.
        of: Box<BackendSpec>,
        /// Symmetrise `A·F` and rescale rows to closure after assembly.
        rebalance: bool,
    },
}

/// Parameters of `analytic`.
pub const ANALYTIC_PARAMS: &[ParamDoc] = &[
    ParamDoc {
        key: "order",
        default: "8",
        doc: "largest Gauss-Legendre order on the receiver, 1 to 32 (1 = centroid only)",
    },
    ParamDoc { key: "tol", default: "1e-3", doc: "relative quadrature error each pair's order aims at, in (0, 1]" },
    ParamDoc {
        key: "rays",
        default: "1",
        doc: "fewest shadow rays per pair, 1 to 2^20 (none when nothing can occlude)",
    },
    ParamDoc {
        key: "budget",
        default: "24576",
        doc: "shadow rays of a partly visible pair per unit of its larger unoccluded form factor, 0 to 2^24 \
              (times ((1 - 0.8) / (1 - mean ρ))², at most 64, in scenes whose mean ρ exceeds 0.8)",
    },
    ParamDoc { key: "seed", default: "0", doc: "seed of the jittered shadow rays" },
    ParamDoc {
        key: "cache",
        default: "256",
        doc: "MiB of recorded visible fractions, so that no pair is traced twice, 0 to 2^20 (changes no value)",
    },
];

/// Parameters of `hemicube`.
pub const HEMICUBE_PARAMS: &[ParamDoc] = &[
    ParamDoc { key: "res", default: "128", doc: "pixels along an edge of the top face, 2 to 4096 (even)" },
    ParamDoc { key: "seed", default: "0", doc: "seed of the random rotation about the normal" },
];

/// Parameters of `montecarlo`.
pub const MONTECARLO_PARAMS: &[ParamDoc] = &[
    ParamDoc { key: "rays", default: "10000", doc: "cosine-weighted rays per shooting patch, 1 to 10^9" },
    ParamDoc { key: "seed", default: "0", doc: "seed of the rays" },
];

/// Parameters of `matrix` (others go to the backend named by `of`).
pub const MATRIX_PARAMS: &[ParamDoc] = &[
    ParamDoc { key: "of", default: "analytic", doc: "the backend whose matrix is assembled and stored" },
    ParamDoc {
        key: "rebalance",
        default: "false",
        doc: "symmetrise A·F, then rescale rows to closure (closed scenes)",
    },
];

/// The backend names, in the order listed to users.
pub const BACKENDS: &[&str] = &["analytic", "hemicube", "montecarlo", "matrix"];

impl Default for AnalyticParams {
    fn default() -> Self {
        AnalyticParams { order: 8, tolerance: 1e-3, rays: 1, budget: 24576, seed: 0, cache_mib: 256 }
    }
}

impl BackendSpec {
    /// Parses `NAME[:key=value…]`.
    pub fn parse(arg: &str) -> Result<BackendSpec, FfError> {
        let mut parts = arg.split(':').filter(|s| !s.is_empty());
        let name = parts.next().unwrap_or_default();
        let items: Vec<&str> = parts.collect();
        Self::parse_named(name, &items)
    }

    fn parse_named(name: &str, items: &[&str]) -> Result<BackendSpec, FfError> {
        let owner = format!("form-factor backend '{name}'");
        Ok(match name {
            "analytic" => {
                let p = KeyValueParams::parse(&owner, items.iter().copied(), ANALYTIC_PARAMS)?;
                let defaults = AnalyticParams::default();
                BackendSpec::Analytic(AnalyticParams {
                    order: p.count("order", defaults.order, 1, 32)?,
                    tolerance: p.real("tol", defaults.tolerance, |t| t > 0.0 && t <= 1.0, "a tolerance in (0, 1]")?,
                    rays: p.count("rays", defaults.rays, 1, 1 << 20)?,
                    budget: p.count("budget", defaults.budget, 0, 1 << 24)?,
                    seed: p.seed("seed", 0)?,
                    cache_mib: p.count("cache", defaults.cache_mib, 0, 1 << 20)?,
                })
            }
            "hemicube" => {
                let p = KeyValueParams::parse(&owner, items.iter().copied(), HEMICUBE_PARAMS)?;
                let resolution = p.count("res", 128, 2, crate::hemicube::MAX_RESOLUTION)?;
                if resolution % 2 == 1 {
                    // The side faces are res × res/2 pixels.
                    return Err(p.reject("res", "an even number of pixels from 2 to 4096").into());
                }
                BackendSpec::Hemicube(HemicubeParams { resolution, seed: p.seed("seed", 0)? })
            }
            "montecarlo" => {
                let p = KeyValueParams::parse(&owner, items.iter().copied(), MONTECARLO_PARAMS)?;
                BackendSpec::MonteCarlo(MonteCarloParams {
                    rays: p.count("rays", 10_000, 1, 1_000_000_000)?,
                    seed: p.seed("seed", 0)?,
                })
            }
            "matrix" => {
                let (own, inner): (Vec<&str>, Vec<&str>) =
                    items.iter().partition(|item| MATRIX_PARAMS.iter().any(|d| item.split('=').next() == Some(d.key)));
                let p = KeyValueParams::parse(&owner, own.iter().copied(), MATRIX_PARAMS)?;
                let of = own.iter().find_map(|i| i.strip_prefix("of=")).unwrap_or("analytic");
                if of == "matrix" {
                    let expected =
                        "analytic, hemicube or montecarlo: a stored matrix is assembled from a column backend";
                    return Err(p.reject("of", expected).into());
                }
                BackendSpec::Matrix {
                    of: Box::new(Self::parse_named(of, &inner)?),
                    rebalance: p.flag("rebalance", false)?,
                }
            }
            _ => return Err(FfError::UnknownBackend { name: name.to_string(), valid: BACKENDS.join(", ") }),
        })
    }

    /// The canonical argument, with every parameter that changes a value spelled out: specs
    /// that give the same entries give equal strings, so it keys caches and labels results
    /// (`analytic`'s `cache`, which changes no entry, is left out).
    pub fn canonical(&self) -> String {
        match self {
            BackendSpec::Analytic(p) => {
                format!(
                    "analytic:order={}:tol={:e}:rays={}:budget={}:seed={}",
                    p.order, p.tolerance, p.rays, p.budget, p.seed
                )
            }
            BackendSpec::Hemicube(p) => format!("hemicube:res={}:seed={}", p.resolution, p.seed),
            BackendSpec::MonteCarlo(p) => format!("montecarlo:rays={}:seed={}", p.rays, p.seed),
            BackendSpec::Matrix { of, rebalance } => {
                let inner = of.canonical();
                let (name, rest) = inner.split_once(':').unwrap_or((&inner, ""));
                format!("matrix:of={name}:rebalance={rebalance}:{rest}")
            }
        }
    }
}
