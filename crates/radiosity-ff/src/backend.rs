//! What a built backend is asked, whichever it is: [`FormFactorBackend`], a
//! [`ColumnSource`] with its capabilities (exact rows, clamped entries, single entries, a
//! stored matrix, figures to print, bytes to keep); [`FormFactorInput`], what backends are
//! built from; and [`BuildObserver`], what a backend reports while it builds.
//!
//! This file is the vocabulary only and names no backend but the stored matrix its trait
//! returns: each built-in implements [`FormFactorBackend`] in its own file ([`crate::analytic`],
//! [`crate::hemicube`], [`crate::montecarlo`], [`crate::hierarchical`],
//! [`crate::matrix_backend`]), as a backend of one's own does in its crate.
//!
//! A [`crate::BackendSpec`] builds its source ([`crate::BackendSpec::build`]); callers ask the
//! source what it can do instead of matching on which backend it is. A native product is
//! [`ColumnSource::multiply`]'s (`true` when the source has one).

use crate::matrix::StoredMatrix;
use radiosity_core::{ColumnSource, Real, Scene};
use radiosity_geom::{SceneAnalysis, Visibility};
use std::fmt;

/// What column backends are built from.
#[derive(Clone, Debug)]
pub struct FormFactorInput<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its BVH: a handle a backend that traces rays keeps a clone of.
    pub visibility: Visibility,
    /// Its analysis (whether shadow rays are needed, whether rows should sum to 1).
    pub analysis: &'a SceneAnalysis,
}

impl<'a> TryFrom<&'a radiosity_geom::PreparedScene> for FormFactorInput<'a> {
    type Error = radiosity_geom::GeomError;

    /// The prepared scene's parts; an error once its BVH is released.
    fn try_from(prepared: &'a radiosity_geom::PreparedScene) -> Result<Self, Self::Error> {
        Ok(FormFactorInput {
            scene: &prepared.loaded.scene,
            visibility: prepared.visibility_for("building a form-factor backend")?,
            analysis: &prepared.analysis,
        })
    }
}

/// A built form-factor source and what it can do. Every capability has a default: a backend
/// of one's own implements [`ColumnSource`] and overrides what it has. It is `Send`, so that
/// a built source can move to the thread that uses it.
pub trait FormFactorBackend: ColumnSource + Send {
    /// Whether [`ColumnSource::fill_row`] gives exact rows of the matrix the columns assemble
    /// (false by default: a row would need every column).
    fn serves_rows(&self) -> bool {
        false
    }

    /// Entries clamped into `[0, 1]` so far (0 by default).
    fn clamped(&self) -> u64 {
        0
    }

    /// Single entries `F_ij` before clamping, reciprocal by construction, so that the matrix
    /// is assembled each pair once ([`StoredMatrix::assemble_backend`]); `None` by default.
    fn pairs(&self) -> Option<&dyn PairEntries> {
        None
    }

    /// The stored matrix, when the source is one (`None` by default).
    fn stored(&self) -> Option<&StoredMatrix> {
        None
    }

    /// What building the source found and cost, for reports (`None` by default).
    fn figures(&self) -> Option<BackendFigures> {
        None
    }

    /// The source as bytes that [`crate::BackendArgument::load`] reads back, headed by `key`,
    /// for a backend whose build is worth keeping (`None` by default).
    fn persist(&self, _key: &str) -> Option<Vec<u8>> {
        None
    }
}

/// What a backend reports while it builds: stages, each with a count of steps (the lab shows
/// them as progress bars). Every method does nothing by default.
pub trait BuildObserver: Sync {
    /// A stage begins: `total` steps of `unit` (0: unknown).
    fn begin(&self, _stage: &str, _total: u64, _unit: &str) {}
    /// `done` steps of the stage are done.
    fn advance(&self, _done: u64, _note: &str) {}
    /// The stage ended.
    fn end(&self) {}
    /// Something the user should know that does not stop the build.
    fn warn(&self, _message: &str) {}
}

/// A [`BuildObserver`] that shows nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unobserved;

impl BuildObserver for Unobserved {}

/// Single form-factor entries ([`FormFactorBackend::pairs`]).
pub trait PairEntries: Sync {
    /// `F_ij` before clamping.
    fn pair(&self, i: usize, j: usize) -> Real;
}

/// What building a backend found and cost ([`FormFactorBackend::figures`]): the build's
/// seconds and bytes, whether it was read back rather than built, and labelled counts.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BackendFigures {
    /// Seconds to build (the build's, when read back).
    pub seconds: f64,
    /// Bytes held.
    pub bytes: usize,
    /// Whether it was read back ([`FormFactorBackend::persist`]) rather than built now.
    pub loaded: bool,
    /// Counts, each with its label (`far links`).
    pub counts: Vec<(String, f64)>,
    /// One line, as `cargo xtask ff --against` prints it (without the bytes).
    pub summary: String,
    /// Each rank's part, in rank order, when the source is split over ranks (its `seconds`,
    /// `bytes` and `counts` the rank's own); empty for one process.
    pub ranks: Vec<BackendFigures>,
    /// The build's seconds stage by stage, each with its name, where the backend times them.
    pub stages: Vec<(String, f64)>,
    /// The bytes held part by part, each with its name, where the backend counts them.
    pub parts: Vec<(String, usize)>,
}

impl BackendFigures {
    /// The count labelled `label`, if there is one.
    pub fn count(&self, label: &str) -> Option<f64> {
        self.counts.iter().find(|(l, _)| l == label).map(|&(_, v)| v)
    }
}

impl fmt::Display for BackendFigures {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.summary)
    }
}

impl<T: FormFactorBackend + ?Sized> FormFactorBackend for Box<T> {
    fn serves_rows(&self) -> bool {
        (**self).serves_rows()
    }

    fn clamped(&self) -> u64 {
        (**self).clamped()
    }

    fn pairs(&self) -> Option<&dyn PairEntries> {
        (**self).pairs()
    }

    fn stored(&self) -> Option<&StoredMatrix> {
        (**self).stored()
    }

    fn figures(&self) -> Option<BackendFigures> {
        (**self).figures()
    }

    fn persist(&self, key: &str) -> Option<Vec<u8>> {
        (**self).persist(key)
    }
}
