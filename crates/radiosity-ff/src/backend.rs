//! What a built backend is asked, whichever it is: [`FormFactorBackend`], a
//! [`ColumnSource`] with its capabilities (exact rows, clamped entries, single entries, a
//! stored matrix, figures to print, bytes to keep), implemented here by the built-ins and by
//! any backend of one's own; and [`FormFactorInput`], what backends are built from.
//!
//! A [`crate::BackendSpec`] builds its source ([`crate::BackendSpec::build`]); callers ask the
//! source what it can do instead of matching on which backend it is. A native product is
//! [`ColumnSource::multiply`]'s (`true` when the source has one).

use crate::analytic::AnalyticColumns;
use crate::hemicube::HemicubeColumns;
use crate::hierarchical::{HierarchicalColumns, HierarchyFigures};
use crate::matrix::StoredMatrix;
use crate::montecarlo::MonteCarloColumns;
use radiosity_core::{ColumnSource, Real, Scene};
use radiosity_geom::{SceneAnalysis, Visibility};
use std::fmt;

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

impl From<HierarchyFigures> for BackendFigures {
    fn from(h: HierarchyFigures) -> BackendFigures {
        let summary = format!(
            "{} nodes, {} far links ({} of them to zeroth order), {} near links ({} of them far pairs of patches), {} \
             shadow rays ({} links occluded, {} seen whole through clear shafts); {} rows capped at 1 by closure \
              (lowest weight {:.3}), {} above 1 by their near links alone",
            h.nodes,
            h.far_links,
            h.zeroth_links,
            h.near_links,
            h.far_pairs,
            h.rays,
            h.occluded,
            h.clear_shafts,
            h.capped,
            h.lowest_weight,
            h.near_above
        );
        let counts = [
            ("nodes", h.nodes as f64),
            ("far links", h.far_links as f64),
            ("zeroth-order links", h.zeroth_links as f64),
            ("near links", h.near_links as f64),
            ("far pairs", h.far_pairs as f64),
            ("shadow rays", h.rays as f64),
            ("occluded links", h.occluded as f64),
            ("clear shafts", h.clear_shafts as f64),
            ("capped rows", h.capped as f64),
            ("rows above 1", h.near_above as f64),
            ("lowest weight", h.lowest_weight),
        ];
        BackendFigures {
            seconds: h.seconds,
            bytes: h.bytes,
            loaded: h.loaded,
            counts: counts.into_iter().map(|(l, v)| (l.to_string(), v)).collect(),
            summary,
        }
    }
}

impl FormFactorBackend for AnalyticColumns<'_> {
    fn serves_rows(&self) -> bool {
        true
    }

    fn clamped(&self) -> u64 {
        AnalyticColumns::clamped(self)
    }

    fn pairs(&self) -> Option<&dyn PairEntries> {
        Some(self)
    }
}

impl PairEntries for AnalyticColumns<'_> {
    fn pair(&self, i: usize, j: usize) -> Real {
        AnalyticColumns::pair(self, i, j)
    }
}

/// Hemicube columns are not reciprocal: a row of the matrix they assemble would need every
/// column.
impl FormFactorBackend for HemicubeColumns<'_> {
    fn clamped(&self) -> u64 {
        HemicubeColumns::clamped(self)
    }
}

/// Monte Carlo columns are not reciprocal: a row of the matrix they assemble would need every
/// column.
impl FormFactorBackend for MonteCarloColumns<'_> {
    fn clamped(&self) -> u64 {
        MonteCarloColumns::clamped(self)
    }
}

impl FormFactorBackend for HierarchicalColumns {
    fn serves_rows(&self) -> bool {
        true
    }

    fn figures(&self) -> Option<BackendFigures> {
        Some(HierarchicalColumns::figures(self).into())
    }

    fn persist(&self, key: &str) -> Option<Vec<u8>> {
        Some(HierarchicalColumns::to_bytes(self, key))
    }
}

/// Clamped when it was assembled.
impl FormFactorBackend for StoredMatrix {
    fn serves_rows(&self) -> bool {
        true
    }

    fn stored(&self) -> Option<&StoredMatrix> {
        Some(self)
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
