//! Radiosity solvers, generic over the form factors: they see only
//! [`radiosity_core::ColumnSource`], through a [`Problem`] that counts every column.
//!
//! Built after argmin: a [`Solver`] defines one step, the [`Executor`] loops until a stop
//! rule ([`StopRules`]) holds and calls [`Observer`]s between steps, outside the timed
//! region. Each solver lives in its own module, whose documentation gives its update rule
//! and references. This crate depends on `radiosity-core` only and is tested on small
//! in-memory matrices.
//!
//! Point solvers: `jacobi`, `gauss-seidel`, `sor-ω` (gathering); `southwell`, `pr` (shooting);
//! `feda`, `shao`, `xu` (with its parts `xu-direct`, `xu-ambient`) and `relax-ω` (overshooting).
//!
//! ```
//! use radiosity_core::{Channels, DenseColumns, LinearSystem};
//! use radiosity_solvers::{Executor, NoObserver, Problem, StopRules, TerminationReason, solver_by_name};
//!
//! // Two unit patches facing each other, each seeing a fifth of the other.
//! let system = LinearSystem::new(Channels::Grey, vec![1.0, 1.0], vec![0.5, 0.5], vec![1.0, 0.0]).unwrap();
//! let f = DenseColumns::from_rows(2, &[0.0, 0.2, 0.2, 0.0]).unwrap();
//! let problem = Problem::new(&system, &f).unwrap();
//! let mut pr = solver_by_name("pr").unwrap();
//! let run = Executor::new(pr.as_mut(), StopRules::parse("residual=1e-12").unwrap())
//!     .run(&problem, &mut NoObserver)
//!     .unwrap();
//! assert!(matches!(run.termination, TerminationReason::Residual(_)));
//! // B1 = E1 / (1 − ρ² F12 F21).
//! assert!((run.state.radiosity[0] - 1.0 / (1.0 - 0.25 * 0.04)).abs() < 1e-12);
//! ```

pub mod error;
pub mod executor;
pub mod feda;
pub mod gathering;
pub mod gauss_seidel;
pub mod jacobi;
pub mod memory;
pub mod overshooting;
pub mod problem;
pub mod progressive;
pub mod relax;
pub mod shao;
pub mod shooting;
pub mod southwell;
pub mod state;
pub mod stop;
pub mod xu;

pub use error::SolverError;
pub use executor::{Executor, NoObserver, Observer, Run, Solver};
pub use memory::ColumnMemory;
pub use problem::Problem;
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

/// The solver names accepted by [`solver_by_name`], as listed to users.
pub const SOLVER_NAMES: &str = "jacobi, gauss-seidel, sor-ω (e.g. sor-1.2), southwell, pr, feda, shao, xu, xu-direct, xu-ambient, relax-ω (e.g. relax-1.5)";

/// The solver a command-line name designates.
pub fn solver_by_name(name: &str) -> Result<Box<dyn Solver>, SolverError> {
    Ok(match name {
        "jacobi" => Box::new(jacobi::Jacobi::default()),
        "gauss-seidel" => Box::new(gauss_seidel::GaussSeidel::new(1.0)?),
        "southwell" => Box::new(southwell::Southwell::default()),
        "pr" => Box::new(progressive::ProgressiveRefinement::default()),
        "feda" => Box::new(feda::feda()),
        "shao" => Box::new(shao::shao()),
        "xu" => Box::new(xu::xu(xu::XuParts::BOTH)),
        "xu-direct" => Box::new(xu::xu(xu::XuParts { direct: true, ambient: false })),
        "xu-ambient" => Box::new(xu::xu(xu::XuParts { direct: false, ambient: true })),
        _ => {
            if let Some(omega) = name.strip_prefix("sor-").and_then(|w| w.parse::<f64>().ok()) {
                return Ok(Box::new(gauss_seidel::GaussSeidel::new(omega)?));
            }
            if let Some(omega) = name.strip_prefix("relax-").and_then(|w| w.parse::<f64>().ok()) {
                return Ok(Box::new(relax::relax(omega)?));
            }
            return Err(SolverError::BadParams(format!("unknown solver '{name}'; solvers are {SOLVER_NAMES}")));
        }
    })
}
