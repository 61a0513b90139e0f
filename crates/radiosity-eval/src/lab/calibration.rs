//! Whether a solver's standard error covers its true error: one run per seed of each solver
//! that samples transport, under the same rules, against the lab's reference
//! ([`Lab::calibrate`]).
//!
//! Two figures say it ([`Calibration`]): the mean over seeds of e_rms² over the mean of the
//! standard error² (about 1 for an honest bar, since the summary squared estimates the expected
//! e_rms squared, `radiosity_solvers::StandardError`), and the fraction of seeds whose e_rms
//! lies within 2 standard errors. A bias that every replicate shares, which their spread cannot
//! see, shows as a ratio well above 1 and a fraction near 0.

use crate::error::LabError;
use crate::lab::recorder::RecordPlan;
use crate::lab::setup::Lab;
use crate::progress::NoProgress;
use radiosity_core::Real;
use radiosity_solvers::Unit;
use radiosity_solvers::{SolverRegistry, StopRules};

/// One solver's error bar over seeds (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    /// The solver's name, without its seed.
    pub solver: String,
    /// The mean of the rays the runs cast.
    pub rays: Real,
    /// The seeds run (`1..=seeds`).
    pub seeds: u64,
    /// Mean e_rms² over mean standard error².
    pub ratio: Real,
    /// The fraction of seeds with e_rms within 2 standard errors.
    pub within_two: Real,
    /// The mean e_rms.
    pub e_rms: Real,
    /// The mean standard error.
    pub standard_error: Real,
}

impl Lab<'_> {
    /// Runs `solver:seed=s` for `s` in `1..=seeds` under `rules` and compares its standard
    /// error with its e_rms against the reference (module doc). Fails without a reference, or
    /// when the solver gives no standard error.
    pub fn calibrate(&self, solver: &str, rules: &StopRules, seeds: u64) -> Result<Calibration, LabError> {
        let registry = SolverRegistry::builtin();
        let (mut e2, mut s2, mut rays, mut within, mut e, mut s) = (0.0, 0.0, 0.0, 0u64, 0.0, 0.0);
        for seed in 1..=seeds {
            let mut run = registry.build(&format!("{solver}:seed={seed}"))?;
            let outcome = self.run(run.as_mut(), rules, &RecordPlan::errors_only(), &NoProgress)?;
            let (Some(e_rms), Some(se)) = (outcome.last.e_rms, outcome.last.standard_error) else {
                return Err(LabError::Invalid(format!(
                    "{solver} has no standard error against a reference here, so it cannot be calibrated"
                )));
            };
            e2 += e_rms * e_rms;
            s2 += se * se;
            e += e_rms;
            s += se;
            rays += outcome.state.cost[Unit::Rays] as Real;
            within += u64::from(e_rms <= 2.0 * se);
        }
        let n = seeds.max(1) as Real;
        Ok(Calibration {
            solver: solver.to_string(),
            rays: rays / n,
            seeds,
            ratio: e2 / s2,
            within_two: within as Real / n,
            e_rms: e / n,
            standard_error: s / n,
        })
    }
}
