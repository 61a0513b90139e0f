//! The suite to run ([`StressSuite`]): its cases, backends and solvers, each scene loaded once
//! and run on every backend.

use crate::error::LabError;
use crate::progress::Progress;
use crate::suites::stress::cases::{BACKENDS, CASES, Case, SuiteBackend, all_solvers};
use crate::suites::stress::judge::{CaseResult, StressReport, run_backend};
use radiosity_ff::BackendRegistry;
use radiosity_geom::PreparedScene;
use radiosity_solvers::SolverRegistry;

/// The suite to run: cases, backends and solvers (built by name from registries, so that a
/// researcher's own solver or backend, registered there, runs beside the built-in ones).
pub struct StressSuite<'r> {
    /// The scenes.
    pub cases: Vec<Case>,
    /// The backends.
    pub backends: Vec<SuiteBackend>,
    /// The solvers' names.
    pub solvers: Vec<String>,
    /// Where the solvers are built from.
    pub registry: &'r SolverRegistry,
    /// Where the backends' arguments are parsed ([`BackendRegistry::builtin`] by default).
    pub backend_registry: &'r BackendRegistry,
}

impl<'r> StressSuite<'r> {
    /// Every case, backend and solver.
    pub fn full(registry: &'r SolverRegistry) -> StressSuite<'r> {
        StressSuite {
            cases: CASES.to_vec(),
            backends: BACKENDS.to_vec(),
            solvers: all_solvers(),
            registry,
            backend_registry: radiosity_ff::builtins::builtin(),
        }
    }

    /// Runs the suite; `progress` counts scene-and-backend pairs.
    pub fn run(&self, progress: &dyn Progress) -> Result<StressReport, LabError> {
        if self.solvers.is_empty() {
            return Err(LabError::Invalid("--solvers names no solver".into()));
        }
        for name in &self.solvers {
            self.registry.build(name)?;
        }
        progress.begin("stress", (self.cases.len() * self.backends.len()) as u64, "runs");
        let mut results = Vec::new();
        let mut done = 0;
        for case in &self.cases {
            let prepared = PreparedScene::load(case.scene)?;
            let mut runs = Vec::new();
            for backend in &self.backends {
                progress.advance(done, &format!("{} · {}", case.key, backend.label));
                let backends = self.backend_registry;
                runs.push(run_backend(&prepared, *backend, backends, &self.solvers, self.registry)?);
                done += 1;
            }
            results.push(CaseResult { case: *case, patches: prepared.scene().len(), runs });
        }
        progress.end();
        Ok(StressReport { results, solvers: self.solvers.clone() })
    }
}
