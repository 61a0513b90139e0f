//! One type for "whichever backend the user chose": [`Backend`] dispatches `ColumnSource`
//! to the backend a [`BackendSpec`] names.
//!
//! Column backends are built here from the scene, its BVH and its analysis. The `matrix`
//! backend is built by its caller, which decides where a stored matrix comes from (a cache
//! file, or assembly from the backend it names): files are the business of the crates that
//! write them.

use crate::analytic::AnalyticColumns;
use crate::hemicube::HemicubeColumns;
use crate::hierarchical::HierarchicalColumns;
use crate::matrix::StoredMatrix;
use crate::montecarlo::MonteCarloColumns;
use crate::spec::BackendSpec;
use radiosity_core::{ColumnSource, Real, Scene};
use radiosity_geom::{SceneAnalysis, Visibility};

/// What column backends are built from.
#[derive(Clone, Copy, Debug)]
pub struct FormFactorInput<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its BVH.
    pub visibility: &'a Visibility,
    /// Its analysis (whether shadow rays are needed, whether rows should sum to 1).
    pub analysis: &'a SceneAnalysis,
}

impl<'a> From<&'a radiosity_geom::PreparedScene> for FormFactorInput<'a> {
    fn from(prepared: &'a radiosity_geom::PreparedScene) -> Self {
        FormFactorInput {
            scene: &prepared.loaded.scene,
            visibility: &prepared.visibility,
            analysis: &prepared.analysis,
        }
    }
}

/// A form-factor backend of any kind.
#[derive(Debug)]
pub enum Backend<'a> {
    /// See [`AnalyticColumns`].
    Analytic(AnalyticColumns<'a>),
    /// See [`HemicubeColumns`].
    Hemicube(HemicubeColumns<'a>),
    /// See [`MonteCarloColumns`].
    MonteCarlo(MonteCarloColumns<'a>),
    /// See [`HierarchicalColumns`].
    Hierarchical(Box<HierarchicalColumns>),
    /// See [`StoredMatrix`].
    Matrix(StoredMatrix),
}

impl<'a> Backend<'a> {
    /// Builds the column backend `spec` names. For `matrix`, builds the backend it stores
    /// (`of`), which the caller assembles into a [`StoredMatrix`].
    pub fn columns(spec: &BackendSpec, input: FormFactorInput<'a>) -> Backend<'a> {
        match spec {
            BackendSpec::Analytic(p) => {
                Backend::Analytic(AnalyticColumns::new(input.scene, input.visibility, input.analysis, *p))
            }
            BackendSpec::Hemicube(p) => Backend::Hemicube(HemicubeColumns::new(input.scene, input.visibility, *p)),
            BackendSpec::MonteCarlo(p) => {
                Backend::MonteCarlo(MonteCarloColumns::new(input.scene, input.visibility, *p))
            }
            BackendSpec::Hierarchical(p) => Backend::Hierarchical(Box::new(HierarchicalColumns::new(
                input.scene,
                input.visibility,
                input.analysis,
                *p,
            ))),
            BackendSpec::Matrix { of, .. } => Backend::columns(of, input),
        }
    }

    /// Entries clamped into `[0, 1]` so far (zero for a stored matrix, which was clamped
    /// when assembled).
    pub fn clamped(&self) -> u64 {
        match self {
            Backend::Analytic(b) => b.clamped(),
            Backend::Hemicube(b) => b.clamped(),
            Backend::MonteCarlo(b) => b.clamped(),
            Backend::Hierarchical(_) | Backend::Matrix(_) => 0,
        }
    }

    /// Whether [`ColumnSource::fill_row`] gives exact rows: for the analytic and hierarchical
    /// backends and a stored matrix. Hemicube and Monte Carlo columns are not reciprocal, and
    /// a row of the matrix they assemble would need every column.
    pub fn serves_rows(&self) -> bool {
        matches!(self, Backend::Analytic(_) | Backend::Hierarchical(_) | Backend::Matrix(_))
    }

    fn source(&self) -> &dyn ColumnSource {
        match self {
            Backend::Analytic(b) => b,
            Backend::Hemicube(b) => b,
            Backend::MonteCarlo(b) => b,
            Backend::Hierarchical(b) => b.as_ref(),
            Backend::Matrix(b) => b,
        }
    }
}

impl ColumnSource for Backend<'_> {
    fn patch_count(&self) -> usize {
        self.source().patch_count()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        self.source().fill_column(j, column)
    }

    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        self.source().fill_row(i, row)
    }

    fn reciprocity_bound(&self) -> Option<Real> {
        self.source().reciprocity_bound()
    }

    fn reset_memory(&self) {
        self.source().reset_memory()
    }

    fn multiply(&self, x: &[Real], channels: usize, out: &mut [Real]) -> bool {
        self.source().multiply(x, channels, out)
    }
}
