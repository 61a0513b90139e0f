//! The `montecarlo` backend (stub: the interface is fixed, the method is not written yet).

use crate::guard::ClampCounter;
use crate::spec::MonteCarloParams;
use radiosity_core::{ColumnSource, Real, Scene};
use radiosity_geom::Visibility;

/// MonteCarlo form-factor columns of one scene.
#[derive(Debug)]
pub struct MonteCarloColumns<'a> {
    scene: &'a Scene,
    #[allow(dead_code)]
    visibility: &'a Visibility,
    #[allow(dead_code)]
    params: MonteCarloParams,
    clamped: ClampCounter,
}

impl<'a> MonteCarloColumns<'a> {
    /// Prepares the backend.
    pub fn new(scene: &'a Scene, visibility: &'a Visibility, params: MonteCarloParams) -> MonteCarloColumns<'a> {
        MonteCarloColumns { scene, visibility, params, clamped: ClampCounter::default() }
    }

    /// Entries clamped into `[0, 1]` so far.
    pub fn clamped(&self) -> u64 {
        self.clamped.count()
    }
}

impl ColumnSource for MonteCarloColumns<'_> {
    fn patch_count(&self) -> usize {
        self.scene.len()
    }

    fn fill_column(&self, _j: usize, column: &mut [Real]) {
        column.fill(0.0);
    }
}
