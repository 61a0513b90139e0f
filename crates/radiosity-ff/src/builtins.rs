//! The built-in backends as arguments: each one's typed, validated parameters as a
//! [`BackendArgument`] (canonical argument, build, rays per column), their registration
//! ([`BackendRegistry::builtin`], [`builtin`]) and [`BackendSpec::parse`], which reads an
//! argument with them.
//!
//! The built-ins: `analytic`, `hemicube`, `montecarlo`, `hierarchical` ([`BackendParams`]
//! each) and `matrix` ([`MatrixParams`]), which stores the full matrix of another backend named
//! by `of` (default `analytic`), read through the same registry; parameters it does not take
//! itself go to that backend: `matrix:of=hemicube:res=64:rebalance=true`.
//!
//! This is the one file that knows both the registry ([`crate::registry`], [`crate::spec`])
//! and the backends; neither knows it.

use crate::analytic::AnalyticColumns;
pub use crate::analytic::{ANALYTIC_PARAMS, AnalyticParams};
use crate::backend::{BuildObserver, FormFactorBackend, FormFactorInput};
use crate::error::FfError;
use crate::hemicube::HemicubeColumns;
pub use crate::hemicube::{HEMICUBE_PARAMS, HemicubeParams};
use crate::hierarchical::{BuildProgress, HierarchicalColumns};
pub use crate::hierarchical::{HIERARCHICAL_PARAMS, HierarchicalParams, Oracle};
use crate::matrix::StoredMatrix;
use crate::montecarlo::MonteCarloColumns;
pub use crate::montecarlo::{MONTECARLO_PARAMS, MonteCarloParams};
use crate::registry::{BackendRegistry, owner};
use crate::spec::{BackendArgument, BackendParams, BackendSpec};
use crate::traced::ColumnRays;
use radiosity_core::{Collective, Real};
use radiosity_geom::{KeyValueParams, ParamDoc};
use std::sync::{Arc, OnceLock};

impl BackendSpec {
    /// Parses `NAME[:key=value…]` with the built-in backends
    /// ([`BackendRegistry::builtin`]).
    pub fn parse(arg: &str) -> Result<BackendSpec, FfError> {
        builtin().parse(arg)
    }
}

impl BackendRegistry {
    /// The built-in backends ([`crate::builtins`]). Cheap: five entries.
    pub fn builtin() -> BackendRegistry {
        let mut registry = BackendRegistry::empty();
        registry
            .register::<AnalyticParams>()
            .register::<HemicubeParams>()
            .register::<MonteCarloParams>()
            .register::<HierarchicalParams>()
            .register_fn(MatrixParams::NAME, MatrixParams::HELP, MatrixParams::PARAMS, |items, registry| {
                Ok(Arc::new(MatrixParams::parse(items, registry)?))
            });
        registry
    }
}

impl BackendRegistry {
    /// The built-in backends for a process that is one of the ranks of `world`, when it is one
    /// of several: [`BackendRegistry::builtin_split`] with [`crate::TASKS_PER_RANK`] tasks a
    /// rank; for a single process, [`BackendRegistry::builtin`].
    pub fn for_ranks(world: Option<Arc<dyn Collective>>) -> BackendRegistry {
        match world {
            Some(world) => BackendRegistry::builtin_split(world, crate::TASKS_PER_RANK),
            None => BackendRegistry::builtin(),
        }
    }

    /// The built-in backends with `hierarchical` split over the ranks of `collective`: on each
    /// rank, that rank's part of the operator ([`HierarchicalColumns::new_distributed`], about
    /// `tasks_per_rank` refinement tasks a rank). Every rank parses the same arguments and
    /// builds the same sources in the same order; the parts are not kept in a cache.
    pub fn builtin_split(collective: Arc<dyn Collective>, tasks_per_rank: usize) -> BackendRegistry {
        let mut registry = BackendRegistry::empty();
        let split = move |items: &[&str], _: &BackendRegistry| -> Result<Arc<dyn BackendArgument>, FfError> {
            let name = HierarchicalParams::NAME;
            let params = KeyValueParams::parse(&owner(name), items.iter().copied(), HierarchicalParams::PARAMS)?;
            let params = HierarchicalParams::from_params(&params)?;
            Ok(Arc::new(SplitHierarchical { params, collective: collective.clone(), tasks_per_rank }))
        };
        registry
            .register::<AnalyticParams>()
            .register::<HemicubeParams>()
            .register::<MonteCarloParams>()
            .register_fn(HierarchicalParams::NAME, HierarchicalParams::HELP, HierarchicalParams::PARAMS, split)
            .register_fn(MatrixParams::NAME, MatrixParams::HELP, MatrixParams::PARAMS, |items, registry| {
                Ok(Arc::new(MatrixParams::parse(items, registry)?))
            });
        registry
    }
}

/// `hierarchical` split over ranks ([`BackendRegistry::builtin_split`]).
struct SplitHierarchical {
    params: HierarchicalParams,
    collective: Arc<dyn Collective>,
    tasks_per_rank: usize,
}

impl std::fmt::Debug for SplitHierarchical {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SplitHierarchical")
            .field("params", &self.params)
            .field("rank", &self.collective.rank())
            .field("ranks", &self.collective.ranks())
            .finish()
    }
}

impl BackendArgument for SplitHierarchical {
    /// The single process's: the same links, summed in another order.
    fn canonical(&self) -> String {
        self.params.canonical()
    }

    fn build<'a>(
        &self,
        input: FormFactorInput<'a>,
        observer: &dyn BuildObserver,
    ) -> Result<Box<dyn FormFactorBackend + 'a>, FfError> {
        let ranks = self.collective.ranks();
        observer.begin(
            &format!("building this rank's part of the hierarchical operator ({ranks} ranks)"),
            1000,
            "‰ of its pairs settled",
        );
        let observe = |p: BuildProgress| {
            observer.advance((p.settled * 1000.0) as u64, &format!("{} links", p.links));
        };
        let built = HierarchicalColumns::new_distributed(
            input.scene,
            &input.visibility,
            input.analysis,
            self.params,
            &observe,
            self.collective.clone(),
            self.tasks_per_rank,
        );
        observer.end();
        Ok(Box::new(built))
    }
}

/// The built-in registry, built once ([`BackendSpec::parse`]).
pub fn builtin() -> &'static BackendRegistry {
    static BUILTIN: OnceLock<BackendRegistry> = OnceLock::new();
    BUILTIN.get_or_init(BackendRegistry::builtin)
}

impl BackendArgument for AnalyticParams {
    fn canonical(&self) -> String {
        format!(
            "analytic:order={}:tol={:e}:rays={}:budget={}:seed={}",
            self.order, self.tolerance, self.rays, self.budget, self.seed
        )
    }

    fn build<'a>(
        &self,
        input: FormFactorInput<'a>,
        _: &dyn BuildObserver,
    ) -> Result<Box<dyn FormFactorBackend + 'a>, FfError> {
        Ok(Box::new(AnalyticColumns::new(input.scene, &input.visibility, input.analysis, *self)))
    }

    fn pairs_once(&self) -> bool {
        true
    }

    fn column_rays<'a>(&self, input: FormFactorInput<'a>) -> Option<ColumnRays<'a>> {
        Some(ColumnRays::analytic(AnalyticColumns::new(input.scene, &input.visibility, input.analysis, *self)))
    }
}

impl BackendParams for AnalyticParams {
    const NAME: &'static str = "analytic";
    const HELP: &'static str =
        "Lambert's point-to-polygon formula integrated over the receiver, times the pair's visible fraction";
    const PARAMS: &'static [ParamDoc] = ANALYTIC_PARAMS;

    fn from_params(p: &KeyValueParams) -> Result<AnalyticParams, FfError> {
        let defaults = AnalyticParams::default();
        Ok(AnalyticParams {
            order: quadrature_order(p, defaults.order)?,
            tolerance: quadrature_tolerance(p, defaults.tolerance)?,
            rays: p.count("rays", defaults.rays, 1, 1 << 20)?,
            budget: p.count("budget", defaults.budget, 0, 1 << 24)?,
            seed: p.seed("seed", 0)?,
            cache_mib: p.count("cache", defaults.cache_mib, 0, 1 << 20)?,
        })
    }
}

impl BackendArgument for HemicubeParams {
    fn canonical(&self) -> String {
        format!("hemicube:res={}:seed={}", self.resolution, self.seed)
    }

    fn build<'a>(
        &self,
        input: FormFactorInput<'a>,
        _: &dyn BuildObserver,
    ) -> Result<Box<dyn FormFactorBackend + 'a>, FfError> {
        Ok(Box::new(HemicubeColumns::new(input.scene, &input.visibility, *self)))
    }

    fn column_rays<'a>(&self, input: FormFactorInput<'a>) -> Option<ColumnRays<'a>> {
        Some(ColumnRays::hemicube(HemicubeColumns::new(input.scene, &input.visibility, *self)))
    }
}

impl BackendParams for HemicubeParams {
    const NAME: &'static str = "hemicube";
    const HELP: &'static str = "a ray-cast hemicube at the shooter, giving its row";
    const PARAMS: &'static [ParamDoc] = HEMICUBE_PARAMS;

    fn from_params(p: &KeyValueParams) -> Result<HemicubeParams, FfError> {
        let resolution = p.count("res", 128, 2, crate::hemicube::MAX_RESOLUTION)?;
        if resolution % 2 == 1 {
            // The side faces are res × res/2 pixels.
            return Err(p.reject("res", "an even number of pixels from 2 to 4096").into());
        }
        Ok(HemicubeParams { resolution, seed: p.seed("seed", 0)? })
    }
}

impl BackendArgument for MonteCarloParams {
    fn canonical(&self) -> String {
        format!("montecarlo:rays={}:seed={}", self.rays, self.seed)
    }

    fn build<'a>(
        &self,
        input: FormFactorInput<'a>,
        _: &dyn BuildObserver,
    ) -> Result<Box<dyn FormFactorBackend + 'a>, FfError> {
        Ok(Box::new(MonteCarloColumns::new(input.scene, &input.visibility, *self)))
    }

    fn column_rays<'a>(&self, input: FormFactorInput<'a>) -> Option<ColumnRays<'a>> {
        Some(ColumnRays::montecarlo(input.scene, *self))
    }
}

impl BackendParams for MonteCarloParams {
    const NAME: &'static str = "montecarlo";
    const HELP: &'static str = "cosine-weighted rays from the shooter, giving its row";
    const PARAMS: &'static [ParamDoc] = MONTECARLO_PARAMS;

    fn from_params(p: &KeyValueParams) -> Result<MonteCarloParams, FfError> {
        Ok(MonteCarloParams { rays: p.count("rays", 10_000, 1, 1_000_000_000)?, seed: p.seed("seed", 0)? })
    }
}

impl BackendArgument for HierarchicalParams {
    fn canonical(&self) -> String {
        format!(
            "hierarchical:eps={:e}:shadows={}:rays={}:trust={}:budget={}:order={}:tol={:e}:seed={}:oracle={}:floor={}:passes={}:closure={}",
            self.eps,
            self.shadows,
            self.rays,
            self.trust,
            self.budget,
            self.order,
            self.tolerance,
            self.seed,
            match self.oracle {
                Oracle::Flux => "flux",
                Oracle::Area => "area",
            },
            self.floor,
            self.passes,
            self.closure
        )
    }

    fn build<'a>(
        &self,
        input: FormFactorInput<'a>,
        observer: &dyn BuildObserver,
    ) -> Result<Box<dyn FormFactorBackend + 'a>, FfError> {
        // The count is of thousandths of the pairs of patches settled: links high in the tree
        // settle many at once, so it runs fast at first and slows down.
        observer.begin("building the hierarchical operator", 1000, "‰ pairs settled");
        let observe = |p: BuildProgress| {
            observer.advance((p.settled * 1000.0) as u64, &format!("{} links", p.links));
        };
        let built = HierarchicalColumns::new_observed(input.scene, &input.visibility, input.analysis, *self, &observe);
        observer.end();
        Ok(Box::new(built))
    }

    fn cache_kind(&self) -> Option<&'static str> {
        Some("hierarchical")
    }

    fn load<'a>(
        &self,
        bytes: &[u8],
        key: &str,
        input: FormFactorInput<'a>,
    ) -> Result<Box<dyn FormFactorBackend + 'a>, FfError> {
        Ok(Box::new(HierarchicalColumns::from_bytes(bytes, key, input.scene)?))
    }
}

impl BackendParams for HierarchicalParams {
    const NAME: &'static str = "hierarchical";
    const HELP: &'static str = "links between clusters of a tree over the patches, refined to an error threshold";
    const PARAMS: &'static [ParamDoc] = HIERARCHICAL_PARAMS;

    fn from_params(p: &KeyValueParams) -> Result<HierarchicalParams, FfError> {
        let defaults = HierarchicalParams::default();
        Ok(HierarchicalParams {
            eps: p.real("eps", defaults.eps, |e| e > 0.0 && e <= 1.0, "a threshold in (0, 1]")?,
            shadows: p.real("shadows", defaults.shadows, |s| s > 0.0 && s <= 1.0, "a fraction in (0, 1]")?,
            rays: p.count("rays", defaults.rays, 1, 4096)?,
            trust: p.real("trust", defaults.trust, |t| t > 0.0 && t <= 4096.0, "a number in (0, 4096]")?,
            budget: p.count("budget", defaults.budget, 0, 1 << 24)?,
            order: quadrature_order(p, defaults.order)?,
            tolerance: quadrature_tolerance(p, defaults.tolerance)?,
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
}

/// Parameters of `matrix`: the full matrix of another backend, assembled once and stored.
#[derive(Clone, Debug, PartialEq)]
pub struct MatrixParams {
    /// The backend whose matrix is stored.
    pub of: BackendSpec,
    /// Symmetrise `A·F` and rescale rows to closure after assembly.
    pub rebalance: bool,
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

impl MatrixParams {
    /// The name on the command line.
    pub const NAME: &'static str = "matrix";
    /// What the backend does, in one line.
    pub const HELP: &'static str = "the full matrix of another backend (of=NAME), assembled once and stored";
    /// The keys it takes itself.
    pub const PARAMS: &'static [ParamDoc] = MATRIX_PARAMS;

    /// Reads `of` and `rebalance` from `items`, and the backend `of` names, with the other
    /// items, through `registry`. A stored matrix of a stored matrix is refused.
    pub fn parse(items: &[&str], registry: &BackendRegistry) -> Result<MatrixParams, FfError> {
        let (own, inner): (Vec<&str>, Vec<&str>) =
            items.iter().partition(|item| MATRIX_PARAMS.iter().any(|d| item.split('=').next() == Some(d.key)));
        let p = KeyValueParams::parse(&owner(Self::NAME), own.iter().copied(), MATRIX_PARAMS)?;
        let of = own.iter().find_map(|i| i.strip_prefix("of=")).unwrap_or("analytic");
        let of = registry.parse_named(of, &inner)?;
        if of.stores().is_some() {
            let expected =
                format!("a backend other than '{}': a stored matrix is assembled from a column backend", of.name());
            return Err(p.reject("of", &expected).into());
        }
        Ok(MatrixParams { of, rebalance: p.flag("rebalance", false)? })
    }
}

impl BackendArgument for MatrixParams {
    fn canonical(&self) -> String {
        let inner = self.of.canonical();
        let (name, rest) = inner.split_once(':').unwrap_or((&inner, ""));
        format!("matrix:of={name}:rebalance={}:{rest}", self.rebalance)
    }

    /// Assembles the matrix of `of` ([`StoredMatrix::assemble_backend`]) and rebalances it when
    /// asked; the lab obtains it from its cache instead.
    fn build<'a>(
        &self,
        input: FormFactorInput<'a>,
        observer: &dyn BuildObserver,
    ) -> Result<Box<dyn FormFactorBackend + 'a>, FfError> {
        let source = self.of.build_observed(input.clone(), observer)?;
        let area: Vec<Real> = input.scene.patches().iter().map(|p| p.area()).collect();
        let (mut matrix, _) = StoredMatrix::assemble_backend(&area, source.as_ref(), observer)?;
        if self.rebalance {
            matrix.rebalance(&area, input.analysis.closure.value.is_closed())?;
        }
        Ok(Box::new(matrix))
    }

    fn stores(&self) -> Option<(&BackendSpec, bool)> {
        Some((&self.of, self.rebalance))
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
