//! The suite's scenes ([`CASES`]) and backends ([`BACKENDS`]), the thresholds a run is judged
//! by, and choosing among them by name.

use crate::error::LabError;
use radiosity_core::Real;
use radiosity_solvers::{BEYOND_PAPER_SOLVERS, GROUP_SOLVERS, KRYLOV_SOLVERS, POINT_SOLVERS};

/// Steps allowed to a run, in multiples of the patch count.
pub const STEP_CAP: f64 = 200.0;
/// The residual power at which a run stops.
pub const RESIDUAL_TARGET: Real = 1e-13;
/// The certified relative L1 error bound below which a run counts as converged.
pub const CONVERGED: Real = 1e-6;

/// Rays allowed to a run of a solver that samples transport, per patch (the rule
/// `rays=20000n`): its budget, in place of the residual target it cannot reach. At `ρ = 0.999`
/// incremental shooting spends about half of it before its first regular iteration (the
/// unshot power falls by `ρ` an iteration): a smaller budget ends runs on a truncated series,
/// whose bias no standard error shows.
pub const STOCHASTIC_RAYS_PER_PATCH: Real = 20_000.0;
/// The standard error (relative, as e_rms is) at or below which a run of a solver that
/// samples transport may count as converged: a few percent, what its budget reaches at
/// `ρ = 0.999`, since what the suite asks of an estimate is to be unbiased.
pub const STOCHASTIC_TOLERANCE: Real = 5e-2;
/// How many of its standard errors a converged stochastic run's e_rms may be from the
/// reference of the system it sampled.
pub const STOCHASTIC_SPREADS: Real = 4.0;
/// The solvers that sample transport the suite runs by default, with 16 replicates: their
/// error bars rest on 15 degrees of freedom (module doc of `stress`).
pub const STOCHASTIC_SOLVERS: [&str; 2] = ["stochastic-jacobi:replicates=16", "random-walk:replicates=16"];

/// One scene of the suite.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    /// A short name, as `--cases` takes it.
    pub key: &'static str,
    /// The scene argument.
    pub scene: &'static str,
    /// What it stresses.
    pub what: &'static str,
}

/// The stiff and extreme scenes.
pub const CASES: &[Case] = &[
    Case { key: "rho-0.99", scene: "furnace:res=3:rho=0.99", what: "closed box, ρ = 0.99" },
    Case { key: "rho-0.999", scene: "furnace:res=3:rho=0.999", what: "closed box, ρ = 0.999" },
    Case { key: "channels", scene: "furnace:res=3:rho=0.99/0.5/0", what: "channels with ρ of 0.99, 0.5 and 0" },
    Case {
        key: "inner-rho-0.999",
        scene: "inner-box:rho=0.999",
        what: "a box inside a closed box, ρ = 0.999: occluded and stiff",
    },
    Case {
        key: "area-ratio",
        scene: "inner-box:res=2:size=5e-4:height=5e-4",
        what: "patch areas 1e6 apart (a 5e-4 cube in a unit box)",
    },
    Case {
        key: "bright-emitter",
        scene: "inner-box:res=2:size=5e-4:height=5e-4:emission=0:inner-emission=1e6",
        what: "a tiny emitter of 1e6, the only light",
    },
    Case { key: "touching", scene: "inner-box:gap=0", what: "a box on the floor, touching it along its edges" },
    Case { key: "near-touching", scene: "inner-box:gap=1e-6", what: "a box 1e-6 above the floor" },
    Case { key: "thin-slab", scene: "inner-box:size=0.8:height=1e-4:gap=0.45", what: "a slab 1e-4 thick" },
    Case { key: "scale-1e-4", scene: "inner-box:scale=1e-4", what: "the default inner box at scale 1e-4" },
    Case { key: "scale-1e4", scene: "inner-box:scale=1e4", what: "the default inner box at scale 1e4" },
];

/// One form-factor backend of the suite.
#[derive(Clone, Copy, Debug)]
pub struct SuiteBackend {
    /// Its name in the report, as `--backends` takes it.
    pub label: &'static str,
    /// The backend argument.
    pub spec: &'static str,
    /// Whether rows are rescaled to sum to 1 in `f64` (closed scenes only).
    pub close_rows: bool,
}

/// The backends of the suite.
pub const BACKENDS: &[SuiteBackend] = &[
    SuiteBackend { label: "analytic", spec: "analytic", close_rows: false },
    SuiteBackend { label: "analytic+closure", spec: "analytic", close_rows: true },
    SuiteBackend { label: "hemicube", spec: "hemicube", close_rows: false },
    SuiteBackend { label: "montecarlo", spec: "montecarlo", close_rows: false },
    SuiteBackend { label: "matrix:rebalance=true", spec: "matrix:rebalance=true", close_rows: false },
    SuiteBackend { label: "hierarchical", spec: "hierarchical", close_rows: false },
];

/// Keeps the items of `all` named in the comma list `list` (all of them when `list` is
/// `None`), refusing unknown names; `what` names the items in errors.
pub fn select<T: Copy>(
    list: Option<&str>,
    all: &[T],
    name: impl Fn(&T) -> &str,
    what: &str,
) -> Result<Vec<T>, LabError> {
    let Some(list) = list else { return Ok(all.to_vec()) };
    let mut chosen = Vec::new();
    for wanted in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        match all.iter().find(|item| name(item) == wanted) {
            Some(item) => chosen.push(*item),
            None => {
                let valid: Vec<&str> = all.iter().map(&name).collect();
                return Err(LabError::Invalid(format!("unknown {what} '{wanted}'; {what}s are {}", valid.join(", "))));
            }
        }
    }
    if chosen.is_empty() {
        return Err(LabError::Invalid(format!("--{what}s names no {what}")));
    }
    Ok(chosen)
}

/// The node shooters the suite runs: over its stored matrices they run one level (every
/// patch a node, its column its links), which tests their rounds, bound, overshoot and the
/// paper's groups on stiff systems; groups of the tree's clusters or of a spatial order need
/// a hierarchy or an order, which the suite's problems do not have.
pub const NODE_STRESS_SOLVERS: [&str; 4] = ["h-southwell", "h-xu", "h-jacobi", "h-pr:groups=unshot"];

/// Every point, group, beyond-the-paper, Krylov, node and stochastic solver, by name: the
/// suite's default solvers.
pub fn all_solvers() -> Vec<String> {
    POINT_SOLVERS
        .iter()
        .chain(&GROUP_SOLVERS)
        .chain(&BEYOND_PAPER_SOLVERS)
        .chain(&KRYLOV_SOLVERS)
        .chain(&NODE_STRESS_SOLVERS)
        .chain(&STOCHASTIC_SOLVERS)
        .map(|s| s.to_string())
        .collect()
}
