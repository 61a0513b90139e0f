//! Backend arguments: `analytic`, `hemicube`, `montecarlo`, `hierarchical` or `matrix`, each with its own
//! `:key=value` parameters, parsed into typed, validated parameter sets.
//!
//! `matrix` stores the full matrix of another backend, named by `of` (default `analytic`);
//! parameters it does not take itself go to that backend:
//! `matrix:of=hemicube:res=64:rebalance=true`.

pub use crate::analytic::{ANALYTIC_PARAMS, AnalyticParams};
use crate::error::FfError;
pub use crate::hemicube::{HEMICUBE_PARAMS, HemicubeParams};
pub use crate::hierarchical::{HIERARCHICAL_PARAMS, HierarchicalParams, Oracle};
pub use crate::montecarlo::{MONTECARLO_PARAMS, MonteCarloParams};
use radiosity_geom::{KeyValueParams, ParamDoc};

/// A parsed backend argument.
#[derive(Clone, Debug, PartialEq)]
pub enum BackendSpec {
    /// Lambert's point-to-polygon formula integrated over the receiver.
    Analytic(AnalyticParams),
    /// A ray-cast hemicube at the shooter.
    Hemicube(HemicubeParams),
    /// Cosine-weighted rays from the shooter.
    MonteCarlo(MonteCarloParams),
    /// Links between clusters of a tree over the patches, refined to an error threshold.
    Hierarchical(HierarchicalParams),
    /// The full matrix of another backend, assembled once.
    Matrix {
        /// The backend whose matrix is stored.
        of: Box<BackendSpec>,
        /// Symmetrise `A·F` and rescale rows to closure after assembly.
        rebalance: bool,
    },
}

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
pub const BACKENDS: &[&str] = &["analytic", "hemicube", "montecarlo", "hierarchical", "matrix"];

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
                    order: quadrature_order(&p, defaults.order)?,
                    tolerance: quadrature_tolerance(&p, defaults.tolerance)?,
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
            "hierarchical" => {
                let p = KeyValueParams::parse(&owner, items.iter().copied(), HIERARCHICAL_PARAMS)?;
                let defaults = HierarchicalParams::default();
                BackendSpec::Hierarchical(HierarchicalParams {
                    eps: p.real("eps", defaults.eps, |e| e > 0.0 && e <= 1.0, "a threshold in (0, 1]")?,
                    shadows: p.real("shadows", defaults.shadows, |s| s > 0.0 && s <= 1.0, "a fraction in (0, 1]")?,
                    rays: p.count("rays", defaults.rays, 1, 4096)?,
                    budget: p.count("budget", defaults.budget, 0, 1 << 24)?,
                    order: quadrature_order(&p, defaults.order)?,
                    tolerance: quadrature_tolerance(&p, defaults.tolerance)?,
                    seed: p.seed("seed", 0)?,
                    oracle: match p.given().find(|(k, _)| *k == "oracle").map(|(_, v)| v) {
                        None | Some("flux") => Oracle::Flux,
                        Some("area") => Oracle::Area,
                        Some(_) => return Err(p.reject("oracle", "flux or area").into()),
                    },
                    floor: p.real("floor", defaults.floor, |f| f > 0.0 && f <= 1.0, "a weight in (0, 1]")?,
                    passes: p.count("passes", defaults.passes, 1, 4)?,
                    closure: p.flag("closure", defaults.closure)?,
                    shafts: p.flag("shafts", defaults.shafts)?,
                })
            }
            "matrix" => {
                let (own, inner): (Vec<&str>, Vec<&str>) =
                    items.iter().partition(|item| MATRIX_PARAMS.iter().any(|d| item.split('=').next() == Some(d.key)));
                let p = KeyValueParams::parse(&owner, own.iter().copied(), MATRIX_PARAMS)?;
                let of = own.iter().find_map(|i| i.strip_prefix("of=")).unwrap_or("analytic");
                if of == "matrix" {
                    let expected = "analytic, hemicube, montecarlo or hierarchical: a stored matrix is assembled from a column backend";
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
            BackendSpec::Hierarchical(p) => {
                format!(
                    "hierarchical:eps={:e}:shadows={}:rays={}:budget={}:order={}:tol={:e}:seed={}:oracle={}:floor={}:passes={}:closure={}",
                    p.eps,
                    p.shadows,
                    p.rays,
                    p.budget,
                    p.order,
                    p.tolerance,
                    p.seed,
                    match p.oracle {
                        Oracle::Flux => "flux",
                        Oracle::Area => "area",
                    },
                    p.floor,
                    p.passes,
                    p.closure
                )
            }
            BackendSpec::Matrix { of, rebalance } => {
                let inner = of.canonical();
                let (name, rest) = inner.split_once(':').unwrap_or((&inner, ""));
                format!("matrix:of={name}:rebalance={rebalance}:{rest}")
            }
        }
    }
}

/// A quadrature's largest Gauss–Legendre order (`order`, 1 to 32): the analytic backend's, and
/// the hierarchical operator's near pairs'.
fn quadrature_order(p: &KeyValueParams, default: usize) -> Result<usize, FfError> {
    Ok(p.count("order", default, 1, 32)?)
}

/// A quadrature's relative error target (`tol`, in (0, 1]): the analytic backend's, and the
/// hierarchical operator's near pairs'.
fn quadrature_tolerance(p: &KeyValueParams, default: f64) -> Result<f64, FfError> {
    Ok(p.real("tol", default, |t| t > 0.0 && t <= 1.0, "a tolerance in (0, 1]")?)
}
