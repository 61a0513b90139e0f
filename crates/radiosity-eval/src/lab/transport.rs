//! The transport sampler of a lab's runs that sample transport (`StepKind::Sampled`): where
//! they cast their rays, as [`LabOptions::transport`] says ([`Lab::transport_sampler`]).
//!
//! A sampler is built only for the runs that sample transport, never for the others (building
//! the stored matrix's alias tables reads every column): once for a comparison, whatever the
//! number of its solvers that cast rays, and once for a single run. Its construction is
//! set-up, like the reference: its seconds are in no run's, and reports give them apart
//! ([`TransportBuilt::seconds`]).
//!
//! [`LabOptions::transport`]: crate::LabOptions::transport

use crate::error::LabError;
use crate::lab::options::Transport;
use crate::lab::setup::Lab;
use radiosity_core::{ColumnTransport, SampleCost, TransportSampler};
use radiosity_ff::SceneTransport;
use radiosity_solvers::{Solver, StepKind};
use std::time::Instant;

/// A lab's transport sampler, built ([`Lab::transport_sampler`]).
pub struct TransportBuilt<'p> {
    /// The sampler.
    pub sampler: Box<dyn TransportSampler + Send + 'p>,
    /// Where its rays go: `scene` or `matrix`.
    pub transport: Transport,
    /// The seconds it took to build: set-up, in no run's seconds.
    pub seconds: f64,
}

impl TransportBuilt<'_> {
    /// What one ray is.
    pub fn cost(&self) -> SampleCost {
        self.sampler.cost()
    }

    /// One phrase for reports: where the rays go, what one is, and the build's seconds.
    pub fn describe(&self) -> String {
        format!("`{}`, {}, sampler built in {:.3} s", self.transport, self.cost().ray, self.seconds)
    }
}

impl<'p> Lab<'p> {
    /// Where the lab's solvers that sample transport cast their rays.
    pub fn transport(&self) -> Transport {
        self.transport
    }

    /// Builds the transport sampler of the lab's runs that sample transport (module doc): rays
    /// in the scene, or the stored matrix sampled exactly. Fails, in one sentence, for
    /// `matrix` when the lab keeps no stored matrix.
    pub fn transport_sampler(&self) -> Result<TransportBuilt<'p>, LabError> {
        let start = Instant::now();
        let sampler: Box<dyn TransportSampler + Send + 'p> = match self.transport {
            // Declared closed (rows of F summing to 1) only where the scene analysis finds the
            // scene closed.
            Transport::Scene => Box::new(SceneTransport::from_prepared(self.prepared)?),
            Transport::Matrix => {
                let matrix = self.matrix.as_deref().ok_or_else(|| {
                    LabError::Invalid(format!(
                        "--transport matrix samples the lab's stored matrix, and this lab keeps none (its reference \
                         is {}): use --reference matrix, a stored backend, or --transport scene",
                        self.chosen.kind
                    ))
                })?;
                let sampler = ColumnTransport::new(matrix, self.system.areas())
                    .map_err(|e| LabError::Invalid(format!("the stored matrix cannot be sampled: {e}")))?;
                Box::new(sampler)
            }
        };
        Ok(TransportBuilt { sampler, transport: self.transport, seconds: start.elapsed().as_secs_f64() })
    }
}

impl Lab<'_> {
    /// Frees the scene's BVH when `solver` (the reference itself when `None`) casts no ray
    /// through the scene: the lab's backend is built and its reference solved by now, so a run
    /// that does not sample transport by rays never traces another. Returns the bytes freed:
    /// 0 when the run needs the rays, or when the backend shares the tree (one that computes
    /// its entries by rays, as the analytic one does), which then keeps it. Once it is freed,
    /// whatever asks the scene for rays is refused in one sentence
    /// ([`radiosity_geom::GeomError::VisibilityReleased`]).
    pub fn release_rays(&self, solver: Option<&dyn Solver>) -> usize {
        let casts = solver.is_some_and(|s| s.step_kind() == StepKind::Sampled) && self.transport == Transport::Scene;
        if casts { 0 } else { self.prepared.release_visibility() }
    }
}
