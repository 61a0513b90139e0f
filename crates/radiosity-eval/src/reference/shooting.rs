//! The `shooting` reference: a long run of a shooting solver over the backend's own columns,
//! to a certified relative bound, with no matrix at all (docs/design.md §6.2).
//!
//! For scenes whose form-factor matrix does not fit in memory, the reference is obtained
//! the way solvers work: shooting columns, `O(n)` memory beside the solver's own column
//! memory. Shooting keeps the unshot `ΔB` as the residual of the shot radiosity, so the
//! residual of the displayed `B` is `ρ F ΔB` and, under the hypothesis of docs/design.md §6.3 (rows
//! of `F` sum to at most 1 and `F` is reciprocal, so `κ_c ≤ ρ_max,c`: [`Contraction::assumed`]),
//!
//! `Σ_c ‖B_c − B*_c‖_A ≤ Σ_c ρ_max,c ‖ΔB_c‖_A / (1 − ρ_max,c)`
//!
//! at no extra column ([`SolverBound`]). The run stops at the residual power
//! `R = Σ A |ΔB| / Σ A E ≤ ε (1 − q) / q` with `q = max_c ρ_max,c`, which makes the bound
//! relative to `Σ A |B*|` at most `ε` (since `B* ≥ E` elementwise, `Σ A |B*| ≥ Σ A E`); the
//! certificate is then worked out from the final state. When a stored matrix is at hand its
//! measured contraction replaces the hypothesis, but then the `matrix` reference is cheaper.
//!
//! The solver is `xu` by default (Xu et al.'s overshooting with the ambient term), the
//! fastest certified method of `docs/bench-office.md`; any solver of the built-in registry
//! that returns a residual bound may be named. The cost is the run: typically a few times
//! `n` columns to `ε = 1e-8`, which is hours at `10⁵` patches on two cores; the progress bar
//! shows the bound as it falls.
//!
//! **Through products.** Over a source that multiplies a whole vector itself and states its
//! reciprocity (the hierarchical operator, whose product costs as much as a few hundred
//! columns and carries all `n`), the run is `gmres-30` by default
//! ([`ShootingParams::products_solver`]), whose residual is computed exactly by products, and
//! the contraction is bounded by two products ([`Contraction::from_products`]) instead of
//! assumed: the certificate is then proven without that hypothesis.

use crate::error::EvalError;
use crate::progress::Progress;
use crate::reference::certificate::{Contraction, SolverBound};
use crate::reference::solution::{Certificate, Method, ReferenceSolution};
use radiosity_core::{ColumnSource, LinearSystem, Real};
use radiosity_solvers::Unit;
use radiosity_solvers::{
    Executor, Observer, ObserverMode, Problem, Record, ResidualBound, SolverRegistry, State, StopRules,
};

/// How a shooting reference is computed.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct ShootingParams {
    /// The solver, by its command-line name. Default `xu`.
    pub solver: String,
    /// The solver over a source that multiplies natively (module doc). Default `gmres-30`.
    pub products_solver: String,
    /// The certified relative bound to reach. Default `1e-8`.
    pub certified: Real,
    /// Steps allowed, as a multiple of `n`. Default 200.
    pub max_steps_per_patch: u64,
}

impl Default for ShootingParams {
    fn default() -> Self {
        ShootingParams {
            solver: "xu".into(),
            products_solver: "gmres-30".into(),
            certified: 1e-8,
            max_steps_per_patch: 200,
        }
    }
}

impl ShootingParams {
    /// Sets [`ShootingParams::solver`].
    pub fn with_solver(mut self, solver: &str) -> Self {
        self.solver = solver.to_string();
        self
    }

    /// Sets [`ShootingParams::products_solver`].
    pub fn with_products_solver(mut self, solver: &str) -> Self {
        self.products_solver = solver.to_string();
        self
    }

    /// Sets [`ShootingParams::certified`].
    pub fn with_certified(mut self, certified: Real) -> Self {
        self.certified = certified;
        self
    }
}

/// Solves `system` over the columns of `source` by a long shooting run (module doc),
/// reporting the bound to `progress`.
pub fn solve_by_shooting(
    system: &LinearSystem,
    source: &dyn ColumnSource,
    params: &ShootingParams,
    progress: &dyn Progress,
) -> Result<ReferenceSolution, EvalError> {
    if !(params.certified.is_finite() && params.certified > 0.0) {
        let value = params.certified.to_string();
        return Err(EvalError::InvalidParameter { name: "certified", value, reason: "it must be finite and positive" });
    }
    // Over a source that multiplies natively: its product's solver and measured contraction.
    let (contraction, solver_name) = match Contraction::from_products(system, source)? {
        Some(measured) => (measured, &params.products_solver),
        None => (Contraction::assumed(system), &params.solver),
    };
    if !contraction.certified() {
        return Err(EvalError::InvalidParameter {
            name: "reference",
            value: "shooting".into(),
            reason: "a patch has a reflectivity of 1 or the form factors amplify light, so no run can certify its error",
        });
    }
    let q = contraction.max_factor();
    let residual = if q > 0.0 { params.certified * (1.0 - q) / q } else { params.certified };
    let rules = StopRules::parse(&format!("residual={residual:e},steps={}n", params.max_steps_per_patch))
        .map_err(|e| invalid_solver(solver_name, &e.to_string()))?;
    let mut solver =
        SolverRegistry::builtin().build(solver_name).map_err(|e| invalid_solver(solver_name, &e.to_string()))?;
    let problem = Problem::new(system, source).map_err(|e| invalid_solver(solver_name, &e.to_string()))?;
    let mut watch = BoundWatch { system, contraction: &contraction, progress, last: None };
    progress.begin("reference (shooting)", 0, "columns");
    let run = Executor::new(solver.as_mut(), rules).add_observer(&mut watch, ObserverMode::Always).run(&problem);
    progress.end();
    let run = run.map_err(|e| invalid_solver(solver_name, &e.to_string()))?;
    let known = solver
        .residual_bound(&problem, &run.state)
        .ok_or_else(|| invalid_solver(solver_name, "it knows no bound on its residual"))?;
    let bound = SolverBound::new(system, &contraction, &known, &run.state.radiosity);
    if bound.relative > params.certified {
        return Err(EvalError::ShootingNotConverged {
            solver: solver_name.clone(),
            steps: run.state.step,
            reached: bound.relative,
            target: params.certified,
            termination: run.termination.to_string(),
        });
    }
    let k = system.channels().count();
    let residual_norm = (0..k).map(|c| known.residual_norm(c, contraction.kappa[c])).sum();
    let certificate = Certificate {
        residual_norm,
        bound: bound.absolute,
        relative_bound: bound.relative,
        certified: true,
        contraction,
    };
    let method =
        Method::Shooting { solver: solver_name.clone(), steps: run.state.step, columns: run.state.cost[Unit::Columns] };
    Ok(ReferenceSolution::from_parts(system, run.state.radiosity, method, certificate))
}

fn invalid_solver(solver: &str, why: &str) -> EvalError {
    EvalError::ShootingReference { solver: solver.to_string(), message: why.to_string() }
}

/// Reports the certified bound every [`REPORT_EVERY`] steps.
struct BoundWatch<'a> {
    system: &'a LinearSystem,
    contraction: &'a Contraction,
    progress: &'a dyn Progress,
    last: Option<ResidualBound>,
}

/// Steps between two progress reports of a shooting reference.
const REPORT_EVERY: u64 = 32;

impl Observer for BoundWatch<'_> {
    fn observe_step(&mut self, state: &State, _figures: &Record) {
        if let Some(known) = self.last.take() {
            let bound = SolverBound::new(self.system, self.contraction, &known, &state.radiosity);
            self.progress.advance(state.cost[Unit::Columns], &format!("bound {:.2e}", bound.relative));
        }
    }

    fn wants_residual_bound(&self) -> bool {
        true
    }

    fn observe_residual_bound(&mut self, state: &State, bound: Option<&ResidualBound>) {
        if state.step % REPORT_EVERY == 0 {
            self.last = bound.cloned();
        }
    }
}
