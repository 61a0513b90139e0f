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
pub mod group_accelerated;
pub mod group_gathering;
pub mod group_shooting;
pub mod group_step;
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
pub use group_accelerated::{Frequency, GroupAccelerated, GroupAcceleratedParams, GroupBuilding};
pub use group_gathering::GroupGathering;
pub use group_shooting::GroupShooting;
pub use group_step::InnerSolve;
pub use memory::ColumnMemory;
pub use overshooting::Overshoot;
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

/// The group solvers, by canonical name (the paper's, with fixed frequencies so that runs are
/// deterministic): run by the scene-level tests.
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

/// The solver names accepted by [`solver_by_name`], as listed to users.
pub const SOLVER_NAMES: &str = "jacobi, gauss-seidel, sor-ω (e.g. sor-1.2); southwell, pr, feda, shao, xu, xu-direct, \
     xu-ambient, relax-ω (e.g. relax-1.5); group-jacobi-gM and group-gs-gM, group gathering (group-jacobi-g30, \
     group-gs-g30), with :groups=index or :groups=spatial; group-S-gM for a shooting method S (group-pr-g30, \
     group-xu-g30); S-gM and S-gM-mK, group-accelerated (pr-g30, xu-g30-m480), with :f=N or :f=auto[:target=0.05], \
     and beyond the paper :groups=interaction, :inner=gs, :adaptive=0.1";

/// The overshoot and selection weighting of a shooting method's name (`pr`, `xu`, `relax-1.5`).
fn shooting_rule(name: &str) -> Option<Result<(Overshoot, bool), SolverError>> {
    let rule = match name {
        "southwell" => return Some(Ok((Overshoot::NONE, false))),
        "pr" => Overshoot::NONE,
        "feda" => feda::RULE,
        "shao" => shao::RULE,
        "xu" => xu::rule(xu::XuParts::BOTH),
        "xu-direct" => xu::rule(xu::XuParts { direct: true, ambient: false }),
        "xu-ambient" => xu::rule(xu::XuParts { direct: false, ambient: true }),
        _ => {
            let omega = name.strip_prefix("relax-")?.parse::<f64>().ok()?;
            if !(omega > 0.0 && omega < 2.0) {
                return Some(Err(SolverError::BadParams(format!("relaxation needs 0 < ω < 2, not {omega}"))));
            }
            relax::rule(omega)
        }
    };
    Some(Ok((rule, true)))
}

/// Splits `head-gM` into `head` and `M`.
fn split_size<'a>(name: &'a str, marker: &str) -> Option<(&'a str, usize)> {
    let (head, size) = name.rsplit_once(marker)?;
    if size.is_empty() || !size.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some((head, size.parse().ok()?))
}

/// The parameters of a group-accelerated name: `f=10`, `f=auto`, `target=0.05`,
/// `groups=unshot|interaction`, `inner=lu|gs`, `adaptive=0.1`.
fn parse_accelerated(
    name: &str,
    group: usize,
    memory: usize,
    params: &str,
) -> Result<GroupAcceleratedParams, SolverError> {
    let (mut fixed, mut target) = (None, 0.05);
    let mut out = GroupAcceleratedParams::paper(group, memory, Frequency::Auto { target });
    for pair in params.split(':').filter(|p| !p.is_empty()) {
        let bad = |why: &str| SolverError::BadParams(format!("solver '{name}': '{pair}' {why}"));
        let fraction = |v: &str| v.parse::<f64>().ok().filter(|t| *t > 0.0 && t.is_finite());
        match pair.split_once('=') {
            Some(("f", "auto")) => fixed = None,
            Some(("f", v)) => {
                fixed = Some(v.parse::<u64>().ok().filter(|&f| f > 0).ok_or_else(|| bad("needs f=auto or f ≥ 1"))?)
            }
            Some(("target", v)) => target = fraction(v).ok_or_else(|| bad("needs a positive number"))?,
            Some(("groups", "unshot")) => out.building = GroupBuilding::Unshot,
            Some(("groups", "interaction")) => out.building = GroupBuilding::Interaction,
            Some(("groups", _)) => return Err(bad("needs groups=unshot or groups=interaction")),
            Some(("inner", "lu")) => out.inner = InnerSolve::Lu,
            Some(("inner", "gs")) => out.inner = InnerSolve::GaussSeidel,
            Some(("inner", _)) => return Err(bad("needs inner=lu or inner=gs")),
            Some(("adaptive", v)) => {
                out.adaptive = Some(fraction(v).filter(|t| *t <= 1.0).ok_or_else(|| bad("needs a fraction in (0, 1]"))?)
            }
            _ => {
                return Err(bad(
                    "is not a parameter; group-accelerated solvers take f=N, f=auto, target=X, groups=unshot|interaction, \
                     inner=lu|gs and adaptive=X",
                ));
            }
        }
    }
    out.frequency = fixed.map_or(Frequency::Auto { target }, Frequency::Fixed);
    Ok(out)
}

/// The solver a command-line name designates. Every refusal names the solver as written:
/// [`SolverError::UnknownSolver`] for a name that designates none, [`SolverError::BadParams`]
/// beginning `solver '…':` for parameters out of range.
pub fn solver_by_name(name: &str) -> Result<Box<dyn Solver>, SolverError> {
    parse_solver(name).map_err(|e| match e {
        SolverError::BadParams(reason) if !reason.starts_with("solver '") => {
            SolverError::BadParams(format!("solver '{name}': {reason}"))
        }
        e => e,
    })
}

fn parse_solver(name: &str) -> Result<Box<dyn Solver>, SolverError> {
    let unknown = || SolverError::UnknownSolver { name: name.to_string(), valid: SOLVER_NAMES };
    let (head, params) = name.split_once(':').unwrap_or((name, ""));
    let no_params = || {
        if params.is_empty() {
            Ok(())
        } else {
            Err(SolverError::BadParams(format!("solver '{head}' takes no parameters, not '{params}'")))
        }
    };
    let simple: Option<Box<dyn Solver>> = match head {
        "jacobi" => Some(Box::new(jacobi::Jacobi::default())),
        "gauss-seidel" => Some(Box::new(gauss_seidel::GaussSeidel::new(1.0)?)),
        "southwell" => Some(Box::new(southwell::Southwell::default())),
        "pr" => Some(Box::new(progressive::ProgressiveRefinement::default())),
        _ => None,
    };
    if let Some(solver) = simple {
        no_params()?;
        return Ok(solver);
    }
    if let Some(omega) = head.strip_prefix("sor-").and_then(|w| w.parse::<f64>().ok()) {
        no_params()?;
        return Ok(Box::new(gauss_seidel::GaussSeidel::new(omega)?));
    }
    if let Some(rule) = shooting_rule(head) {
        no_params()?;
        return Ok(Box::new(overshooting::Overshooting::new(head, rule?.0)?));
    }
    if let Some((base @ ("jacobi" | "gs"), m)) = head.strip_prefix("group-").and_then(|rest| split_size(rest, "-g")) {
        let sweep = if base == "jacobi" { group_gathering::Sweep::Jacobi } else { group_gathering::Sweep::GaussSeidel };
        let partition = group_gathering::Partition::parse(head, params)?;
        return Ok(Box::new(GroupGathering::new(sweep, m, partition)?));
    }
    if let Some(rest) = head.strip_prefix("group-") {
        let (base, m) = split_size(rest, "-g").ok_or_else(unknown)?;
        let (rule, by_area) = shooting_rule(base).ok_or_else(unknown)??;
        no_params()?;
        return Ok(Box::new(GroupShooting::new(head, m, rule, by_area)?));
    }
    let (grouped, memory) = match split_size(head, "-m") {
        Some((grouped, k)) if grouped.contains("-g") => (grouped, Some(k)),
        _ => (head, None),
    };
    let (base, m) = split_size(grouped, "-g").ok_or_else(unknown)?;
    let (rule, by_area) = shooting_rule(base).ok_or_else(unknown)??;
    if !by_area {
        return Err(SolverError::BadParams(format!(
            "solver '{name}': group acceleration applies to PR and the overshooting methods, not to {base}"
        )));
    }
    let params = parse_accelerated(name, m, memory.unwrap_or(m), params)?;
    Ok(Box::new(GroupAccelerated::new(name, rule, params)?))
}
