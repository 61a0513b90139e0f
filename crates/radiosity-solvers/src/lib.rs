//! Radiosity solvers, generic over the form factors: they see only
//! [`radiosity_core::ColumnSource`], through a [`Problem`] that counts every column.
//!
//! Built after argmin: a [`Solver`] defines one step, the [`Executor`] loops until a stop
//! rule ([`StopRules`]) holds and calls [`Observer`]s on the initial state, between steps and
//! on the finished run, outside the timed region ([`Every`] thins them out). Each solver
//! lives in its own module, whose documentation gives its update rule and references; what a
//! solver alone knows (its group steps, their condition numbers and fallbacks) comes back in
//! the run's [`Record`]. Every built-in solver also bounds, at no extra column, the residual
//! of the radiosity it displays ([`Solver::residual_bound`], [`residual_bound`]). This crate
//! depends on `radiosity-core` only and is tested on small in-memory matrices.
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
//!   `bicgstab` ([`BicgstabParams`]).
//!
//! A researcher's own solver goes beside them, typed ([`SolverRegistry::register`]) or as a
//! closure ([`SolverRegistry::register_fn`]).
//!
//! ```
//! use radiosity_core::{Channels, DenseColumns, LinearSystem, Real};
//! use radiosity_solvers::{
//!     Executor, NoObserver, Problem, Solver, SolverError, SolverRegistry, State, StopRules, TerminationReason,
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
//!     fn next_step(&mut self, _: &Problem<'_>, _: &mut State) -> Result<(), SolverError> {
//!         Ok(())
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
//!     .run(&problem, &mut NoObserver)
//!     .unwrap();
//! assert!(matches!(run.termination, TerminationReason::Residual(_)));
//! // B1 = E1 / (1 − ρ² F12 F21).
//! assert!((run.state.radiosity[0] - 1.0 / (1.0 - 0.25 * 0.04)).abs() < 1e-12);
//!
//! // Group shooting records its group steps: here every step is one.
//! let mut group_pr = registry.build("group-pr-g2").unwrap();
//! let rules = StopRules::parse("steps=4").unwrap();
//! let run = Executor::new(group_pr.as_mut(), rules).run(&problem, &mut NoObserver).unwrap();
//! assert_eq!(run.record.count("group_steps"), Some(4));
//! ```

pub mod bicgstab;
pub mod cg;
pub mod error;
pub mod executor;
pub mod feda;
pub mod gathering;
pub mod gauss_seidel;
pub mod gmres;
pub mod group_accelerated;
pub mod group_gathering;
pub mod group_shooting;
pub mod group_step;
pub mod jacobi;
pub mod krylov;
pub mod memory;
pub mod overshooting;
pub mod problem;
pub mod progressive;
pub mod record;
pub mod registry;
pub mod relax;
pub mod residual_bound;
pub mod shao;
pub mod shooting;
pub mod southwell;
pub mod state;
pub mod stop;
pub mod xu;

pub use bicgstab::{Bicgstab, BicgstabParams};
pub use cg::{CgParams, ConjugateGradients};
pub use error::SolverError;
pub use executor::{Every, Executor, NoObserver, Observer, Run, Solver};
pub use gauss_seidel::GaussSeidelParams;
pub use gmres::{Gmres, GmresParams};
pub use group_accelerated::{
    COLUMN_OPERATIONS_PER_ROOT_PATCH, Frequency, GroupAccelerated, GroupAcceleratedParams, GroupBuilding,
    column_operations,
};
pub use group_gathering::{GroupGathering, GroupGatheringParams};
pub use group_shooting::{GroupShooting, GroupShootingParams};
pub use group_step::{GroupStats, InnerSolve};
pub use jacobi::JacobiParams;
pub use memory::ColumnMemory;
pub use overshooting::{Overshoot, PointShootingParams, ShootingMethod};
pub use problem::Problem;
pub use record::{Record, Value};
pub use registry::{ParseSolverError, SolverEntry, SolverParams, SolverRegistry};
pub use residual_bound::{ResidualBound, area_norms};
pub use state::State;
pub use stop::{Count, StopRule, StopRules, TerminationReason};

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

/// The Krylov solvers, by canonical name (DESIGN §7's comparators): run by the scene-level
/// tests and the stress suite.
pub const KRYLOV_SOLVERS: [&str; 3] = ["cg", "gmres-30", "bicgstab"];

/// The solver a command-line name designates, from the built-in families
/// ([`SolverRegistry::builtin`], built once): a thin wrapper over [`SolverRegistry::build`].
/// Every refusal names the solver as written: [`SolverError::UnknownSolver`] for a name that
/// designates none (with the names there are and the nearest one), [`SolverError::BadParams`]
/// beginning `solver '…':` for parameters out of range.
pub fn solver_by_name(name: &str) -> Result<Box<dyn Solver>, SolverError> {
    registry::builtin().build(name)
}
