//! Radiosity solvers, generic over the form factors: they see only
//! [`radiosity_core::ColumnSource`], through a [`Problem`] that counts every column.
//!
//! Built after argmin: a [`Solver`] defines one step, the [`Executor`] loops until a stop
//! rule ([`StopRules`]) holds and calls [`Observer`]s on the initial state, between steps and
//! on the finished run, outside the timed region, each as its [`ObserverMode`] says; the
//! `rms=` rule asks a separate [`ErrorMonitor`]. Each solver lives in its own module, in a
//! folder by family (`run`, `gathering`, `shooting`, `group`, `krylov`, `stochastic`), whose
//! documentation gives its update rule and references; the modules are private (`cargo doc
//! --document-private-items` shows them) and everything public is re-exported at the crate
//! root. What a solver alone knows (its group steps, their condition numbers and fallbacks)
//! comes back in the run's [`Record`]. Every built-in solver that works through `F` also
//! bounds, at no extra column, the residual of the radiosity it displays
//! ([`Solver::residual_bound`], [`ResidualBound`]); one that samples transport by rays gives
//! the standard error of its estimate instead ([`Solver::standard_error`]). This crate
//! depends on `radiosity-core` (and on `rayon`, to cast rays in parallel) and is tested on
//! small in-memory matrices.
//!
//! Solvers are built from their command-line names by a [`SolverRegistry`], which tries its
//! families of names in order; each family is a parameter struct ([`SolverParams`]:
//! `FromStr`, a syntax, a help line, examples and `build`). The built-in families:
//!
//! - point gathering: `jacobi`, `gauss-seidel`, `sor-ω` ([`JacobiParams`],
//!   [`GaussSeidelParams`]);
//! - point shooting: `southwell`, `pr`, and the overshooting `feda`, `shao`, `xu` (with its
//!   parts `xu-direct`, `xu-ambient`) and `relax-ω` ([`PointShootingParams`]);
//! - group gathering `group-jacobi-gM`, `group-gs-gM` ([`GroupGatheringParams`]) and group
//!   shooting `group-S-gM` ([`GroupShootingParams`]);
//! - group-accelerated shooting, the paper's method: `pr-g30`, `xu-g30-m480:f=10`
//!   ([`GroupAcceleratedParams`]);
//! - Krylov methods, the numerical analyst's comparators, whose step is one product by `F`:
//!   `cg` on the symmetrized system ([`CgParams`]), `gmres-K` ([`GmresParams`]) and
//!   `bicgstab` ([`BicgstabParams`]);
//! - stochastic relaxation, which samples transport with rays and never forms `F`
//!   ([`Problem::with_transport`], [`Problem::cast`]): `stochastic-jacobi`
//!   ([`StochasticJacobiParams`]), with a standard error from independent replicates
//!   ([`Solver::standard_error`], [`StandardError`]);
//! - shooting on the hierarchy, from the nodes of a tree through their own links, at their
//!   cost ([`Problem::link_source`], [`NodeShootingParams`]): `h-southwell`, `h-pr`, `h-xu`,
//!   `h-jacobi`, `h-gauss-seidel`, with groups solved at every pull
//!   (`groups=clusters|spatial|unshot`);
//! - random walks over rays, which never form `F` and need a problem that samples transport
//!   ([`Problem::with_transport`]): `random-walk`, shooting from the emitters or gathering
//!   from every patch, scored by collision or absorption, its error bar the spread of
//!   independent replicates ([`RandomWalkParams`], [`Solver::standard_error`]).
//!
//! A researcher's own solver goes beside them, typed ([`SolverRegistry::register`]) or as a
//! closure ([`SolverRegistry::register_fn`]).
//!
//! ```
//! use radiosity_core::{Channels, DenseColumns, LinearSystem, Real};
//! use radiosity_solvers::{
//!     Executor, Problem, Record, Solver, SolverError, SolverRegistry, State, StopRules, TerminationReason,
//! };
//!
//! // Two unit patches facing each other, each seeing a fifth of the other.
//! let system = LinearSystem::new(Channels::Grey, vec![1.0, 1.0], vec![0.5, 0.5], vec![1.0, 0.0]).unwrap();
//! let f = DenseColumns::from_rows(2, &[0.0, 0.2, 0.2, 0.0]).unwrap();
//! let problem = Problem::new(&system, &f).unwrap();
//!
//! // A solver of one's own, registered beside the built-in ones: it does nothing.
//! struct Idle;
//! impl Solver for Idle {
//!     fn name(&self) -> String {
//!         "idle".into()
//!     }
//!     fn next_step(&mut self, _: &Problem<'_>, _: &mut State) -> Result<Record, SolverError> {
//!         Ok(Record::new())
//!     }
//!     fn residual_power(&self, _: &Problem<'_>, _: &State) -> Option<Real> {
//!         None
//!     }
//! }
//! let mut registry = SolverRegistry::builtin();
//! registry.register_fn("idle", "does nothing", ["idle"], |name| {
//!     Ok((name == "idle").then(|| Box::new(Idle) as Box<dyn Solver>))
//! });
//! assert_eq!(registry.build("idle").unwrap().name(), "idle");
//! assert!(registry.build("gaus-seidel").err().unwrap().to_string().contains("did you mean 'gauss-seidel'?"));
//!
//! let mut pr = registry.build("pr").unwrap();
//! let run = Executor::new(pr.as_mut(), StopRules::parse("residual=1e-12").unwrap())
//!     .run(&problem)
//!     .unwrap();
//! assert!(matches!(run.termination, TerminationReason::Residual(_)));
//! // B1 = E1 / (1 − ρ² F12 F21).
//! assert!((run.state.radiosity[0] - 1.0 / (1.0 - 0.25 * 0.04)).abs() < 1e-12);
//!
//! // Group shooting records its group steps: here every step is one.
//! let mut group_pr = registry.build("group-pr-g2").unwrap();
//! let rules = StopRules::parse("steps=4").unwrap();
//! let run = Executor::new(group_pr.as_mut(), rules).run(&problem).unwrap();
//! assert_eq!(run.record.count("group_steps"), Some(4));
//! ```

mod error;
mod gathering;
mod group;
mod hierarchy;
mod krylov;
mod naming;
mod registry;
mod run;
mod shooting;
mod stochastic;

pub use error::SolverError;
pub use gathering::gauss_seidel::{GaussSeidel, GaussSeidelParams};
pub use gathering::jacobi::{Jacobi, JacobiParams};
pub use group::group_accelerated::{
    COLUMN_OPERATIONS_PER_ROOT_PATCH, DEFAULT_TARGET, Frequency, GroupAccelerated, GroupAcceleratedParams,
    GroupBuilding, MIN_ADAPTIVE_GROUP, column_operations,
};
pub use group::group_gathering::{GroupGathering, GroupGatheringParams, Partition, Sweep};
pub use group::group_shooting::{GroupShooting, GroupShootingParams};
pub use group::group_step::{CONDITION_LIMIT, GroupShot, GroupStats, InnerSolve, group_shot};
pub use group::memory::ColumnMemory;
pub use hierarchy::groups::Grouping;
pub use hierarchy::node_shooting::{
    DEFAULT_BLOCKS, DEFAULT_GROUP, DEFAULT_SHARE, NodeOrder, NodeShooting, NodeShootingParams,
};
pub use krylov::bicgstab::{Bicgstab, BicgstabParams};
pub use krylov::cg::{CgParams, ConjugateGradients};
pub use krylov::gmres::{Gmres, GmresParams};
pub use naming::{ParseSolverError, SolverParams};
pub use registry::{SolverEntry, SolverRegistry};
pub use run::cost::{Cost, Unit};
pub use run::executor::{
    DIVERGENCE_FACTOR, DIVERGENCE_FLOOR, ErrorMonitor, Executor, Observer, ObserverMode, Run, Solver, StepKind,
};
pub use run::problem::{Problem, Rays};
pub use run::record::{Entries, Record, Value};
pub use run::residual_bound::{ResidualBound, area_norms};
pub use run::standard_error::{StandardError, t_coverage_of_two};
pub use run::state::State;
pub use run::stop::{Count, StopRule, StopRules, TerminationReason};
pub use shooting::overshooting::overshoot::{AmbientTerm, Overshoot, RowTerm};
pub use shooting::overshooting::step::{Overshooting, PointShootingParams, ShootingMethod};
pub use shooting::overshooting::xu::XuParts;
pub use shooting::progressive::ProgressiveRefinement;
pub use shooting::rule::unshot_power;
pub use shooting::southwell::Southwell;
pub use stochastic::random_walk::{RandomWalk, RandomWalkParams, WalkForm, WalkScore};
pub use stochastic::sequence::{PointStream, Sequence};
pub use stochastic::stochastic_jacobi::{JacobiForm, StochasticJacobi, StochasticJacobiParams};

/// The point solvers, by canonical name: every one of them is run by the scene-level tests
/// and snapshots.
pub const POINT_SOLVERS: [&str; 11] = [
    "jacobi",
    "gauss-seidel",
    "sor-1.2",
    "southwell",
    "pr",
    "feda",
    "shao",
    "xu",
    "xu-direct",
    "xu-ambient",
    "relax-1.5",
];

/// The group solvers, by canonical name (the paper's, with fixed frequencies, so that the
/// snapshots do not move with the cost model of `:f=auto`): run by the scene-level tests.
pub const GROUP_SOLVERS: [&str; 10] = [
    "group-southwell-g30",
    "group-pr-g30",
    "group-feda-g30",
    "group-xu-g30",
    "pr-g30:f=10",
    "pr-g30-m480:f=10",
    "xu-g30:f=10",
    "xu-g30-m480:f=10",
    "group-jacobi-g30",
    "group-gs-g30",
];

/// The group-accelerated variants beyond the paper (its future work, §4.2 and §5), each
/// compared against the paper's rule (`xu-g30-m480:f=10`): groups built for interaction,
/// group systems solved by Gauss–Seidel, and an adaptive group size. Run by the scene-level
/// tests.
pub const BEYOND_PAPER_SOLVERS: [&str; 3] =
    ["xu-g30-m480:f=10:groups=interaction", "xu-g30-m480:f=10:inner=gs", "xu-g30-m480:f=10:adaptive=0.1"];

/// The node shooters on the hierarchy, by canonical name, without groups and with each kind
/// of group (`groups=clusters` needs a hierarchy, `groups=spatial` a patch order): run on
/// real hierarchies by radiosity-eval's `node_shooting` tests.
pub const NODE_SOLVERS: [&str; 8] = [
    "h-southwell",
    "h-pr",
    "h-xu",
    "h-jacobi",
    "h-gauss-seidel",
    "h-xu:groups=clusters",
    "h-xu:groups=spatial",
    "h-pr:groups=unshot",
];

/// The Krylov solvers, by canonical name (the comparators of docs/design.md §4.8): run by the
/// scene-level tests and the stress suite.
pub const KRYLOV_SOLVERS: [&str; 3] = ["cg", "gmres-30", "bicgstab"];

/// The solver a command-line name designates, from the built-in families
/// ([`SolverRegistry::builtin`], built once): a thin wrapper over [`SolverRegistry::build`].
/// Every refusal names the solver as written: [`SolverError::UnknownSolver`] for a name that
/// designates none (with the names there are and the nearest one), [`SolverError::BadParams`]
/// beginning `solver '…':` for parameters out of range.
pub fn solver_by_name(name: &str) -> Result<Box<dyn Solver>, SolverError> {
    registry::builtin().build(name)
}
