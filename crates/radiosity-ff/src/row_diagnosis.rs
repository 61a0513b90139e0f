//! Why a row of `F` misses its sum: the worst rows of a stored matrix, each with the cause the
//! scene's geometry points to.
//!
//! A row of a closed scene should sum to 1 and no row should exceed 1 (docs/design.md §3.2). When
//! one does not, the usual causes are in the geometry, which [`radiosity_geom::hidden`] has probed:
//!
//! - **touching**: the patch lies against another surface over part of its area, where the
//!   kernel is singular and shadow rays graze;
//! - **overlap**: the patch, or patches it sees, lie on top of coplanar copies, so the light they
//!   exchange is counted twice;
//! - **narrow gap**: one facing patch takes half the row or more across a gap narrower than the
//!   patch, where the quadrature and the visibility of the surfaces around the gap are least
//!   accurate;
//! - otherwise **visibility noise**: the row's shadow rays are a sample, with the variance
//!   [`pair_visibility`](crate::pair_visibility) states; or, in a scene without shadow rays,
//!   **quadrature** error, within the backend's tolerance.
//!
//! Hidden patches are not in the matrix at all: they were left out of the system.

use crate::matrix::StoredMatrix;
use radiosity_core::{Real, Scene};
use radiosity_geom::SceneAnalysis;
use serde::Serialize;
use std::collections::HashSet;

/// The share of a row one entry must hold to count as a narrow gap.
const NARROW_GAP_SHARE: Real = 0.5;

/// The cause a row's geometry points to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RowCause {
    /// The patch touches another surface over part of its area.
    Touching,
    /// The patch, or what it sees, overlaps coplanar patches.
    Overlap,
    /// One facing patch across a narrow gap holds most of the row.
    NarrowGap,
    /// None of the above, in a scene with shadow rays: their noise.
    VisibilityNoise,
    /// None of the above, in a scene without shadow rays: the quadrature's error.
    Quadrature,
}

impl RowCause {
    /// The cause in a word or two.
    pub fn as_str(self) -> &'static str {
        match self {
            RowCause::Touching => "touching",
            RowCause::Overlap => "overlap",
            RowCause::NarrowGap => "narrow gap",
            RowCause::VisibilityNoise => "visibility noise",
            RowCause::Quadrature => "quadrature",
        }
    }
}

/// One row that misses its sum, with its cause.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RowDiagnosis {
    /// The patch (the row).
    pub patch: usize,
    /// Its object.
    pub object: String,
    /// `Σ_j F_ij`.
    pub row_sum: Real,
    /// The cause.
    pub cause: RowCause,
    /// What was found, one phrase.
    pub detail: String,
}

/// The `count` worst rows of `matrix` (the form factors of `scene`, analysed by `analysis`):
/// in a closed scene those farthest from 1, in an open one those farthest above 1 (none when
/// no row exceeds 1), each with its cause.
pub fn worst_rows(scene: &Scene, analysis: &SceneAnalysis, matrix: &StoredMatrix, count: usize) -> Vec<RowDiagnosis> {
    let sums = matrix.row_sums();
    let closed = analysis.closure.value.is_closed();
    let mut order: Vec<usize> = (0..sums.len()).filter(|&i| closed || sums[i] > 1.0).collect();
    order.sort_by(|&a, &b| (sums[b] - 1.0).abs().total_cmp(&(sums[a] - 1.0).abs()).then(a.cmp(&b)));
    order.truncate(count);
    let found = &analysis.hidden.value;
    let overlapping: HashSet<usize> = found.overlapping.iter().map(|c| c.patch).collect();
    order
        .into_iter()
        .map(|i| {
            let (cause, detail) = cause(scene, matrix, i, sums[i], analysis, &overlapping);
            RowDiagnosis { patch: i, object: scene.object_of(i).to_string(), row_sum: sums[i], cause, detail }
        })
        .collect()
}

fn cause(
    scene: &Scene,
    matrix: &StoredMatrix,
    i: usize,
    sum: Real,
    analysis: &SceneAnalysis,
    overlapping: &HashSet<usize>,
) -> (RowCause, String) {
    let found = &analysis.hidden.value;
    if let Some(c) = found.touching.iter().find(|c| c.patch == i) {
        let detail = format!("touches '{}' over {:.0}% of its probe points", c.other_object, 100.0 * c.fraction);
        return (RowCause::Touching, detail);
    }
    if let Some(c) = found.overlapping.iter().find(|c| c.patch == i) {
        let detail = format!(
            "lies on a coplanar patch of '{}' over {:.0}% of its probe points",
            c.other_object,
            100.0 * c.fraction
        );
        return (RowCause::Overlap, detail);
    }
    let row: Vec<Real> = (0..matrix.len()).map(|j| matrix.get(i, j)).collect();
    let to_overlaps: Real = overlapping.iter().map(|&j| row[j]).sum();
    if to_overlaps > 0.0 && to_overlaps >= 0.5 * (sum - 1.0).abs() {
        return (RowCause::Overlap, format!("sees overlapping coplanar patches with F = {to_overlaps:.3} in all"));
    }
    let (largest, value) =
        row.iter().enumerate().fold((i, 0.0), |best, (j, &v)| if v > best.1 { (j, v) } else { best });
    if value >= NARROW_GAP_SHARE * sum.max(Real::MIN_POSITIVE) {
        let (p, q) = (&scene.patches()[i], &scene.patches()[largest]);
        let gap = (q.centroid() - p.centroid()).dot(p.normal()).abs();
        if gap < p.area().sqrt() {
            let detail = format!(
                "F = {value:.3} to patch {largest} of '{}' across a gap of {gap:.3e}, narrower than the patch",
                scene.object_of(largest)
            );
            return (RowCause::NarrowGap, detail);
        }
    }
    match analysis.occlusion.value {
        true => (RowCause::VisibilityNoise, "no contact, overlap or narrow gap found".to_string()),
        false => {
            (RowCause::Quadrature, "no shadow rays are traced, and no contact, overlap or narrow gap found".to_string())
        }
    }
}
