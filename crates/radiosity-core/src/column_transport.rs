//! [`ColumnTransport`]: a column source's matrix sampled exactly, each column's landing
//! distribution an alias table ([`AliasTable`]), so that every stochastic solver can be tested
//! against an exact `F` with a known answer.
//!
//! Column `j` gives the landing probabilities of a ray from `j`, `T_ij = A_i F_ij / A_j`
//! (module doc of [`crate::transport`]); what is left, `1 − Σ_i T_ij`, is the probability of
//! escaping. A column whose sum exceeds 1 (quadrature error in a stored matrix) lands rays in
//! proportion to `T` and gives each ray the sum as its weight
//! ([`crate::TransportSampler::ray_weight`]), so every landing is still unbiased.
//!
//! A ray reads `u[0]` (the table's slot) and `u[1]` (the coin); a global line reads `u[0]`,
//! `u[1]` to choose its patch in proportion to area and `u[2]`, `u[3]` for its ray. A matrix
//! knows no lines, so a global line here is one ray from a patch drawn in proportion to its
//! area, which gives the transfer from `a` to `b` the expectation `A_a F_ab / A` per line
//! (`A` the total area, the area each transfer stands for): what a line through the scene
//! gives for that direction, without the transfer back, which a matrix that is not reciprocal
//! could not vouch for.
//!
//! Memory: 16 bytes per non-zero entry and per column. Building reads every column once.
//!
//! ## References
//!
//! - Walker 1977, "An efficient method for generating discrete random variables with general
//!   distributions", ACM TOMS 3(3); Vose 1991, "A linear algorithm for generating random
//!   numbers with a given distribution", IEEE TSE 17(9) (the construction used here).

use crate::column::ColumnSource;
use crate::error::CoreError;
use crate::math::Real;
use crate::transport::{LineTransfers, SampleCost, TransportSampler};

/// A discrete distribution over `0..len` drawn in `O(1)` (Walker's alias method, Vose's
/// construction).
#[derive(Clone, Debug, PartialEq)]
pub struct AliasTable {
    /// The probability of keeping slot `k` (else its alias).
    keep: Vec<Real>,
    alias: Vec<u32>,
}

impl AliasTable {
    /// The table of `weights` (non-negative, finite, not all zero), normalised.
    pub fn new(weights: &[Real]) -> Result<AliasTable, CoreError> {
        let total: Real = weights.iter().sum();
        if weights.is_empty() || !(total.is_finite() && total > 0.0) || weights.iter().any(|&w| w < 0.0) {
            return Err(CoreError::InvalidDistribution { len: weights.len(), total });
        }
        let m = weights.len();
        let mut keep: Vec<Real> = weights.iter().map(|w| w * m as Real / total).collect();
        let mut alias: Vec<u32> = (0..m as u32).collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..m).partition(|&k| keep[k] < 1.0);
        while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
            alias[s] = l as u32;
            keep[l] -= 1.0 - keep[s];
            if keep[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What is left over is 1 up to round-off.
        for k in large.into_iter().chain(small) {
            keep[k] = 1.0;
        }
        Ok(AliasTable { keep, alias })
    }

    /// The number of outcomes.
    pub fn len(&self) -> usize {
        self.keep.len()
    }

    /// Whether there is no outcome (never, for a table that was built).
    pub fn is_empty(&self) -> bool {
        self.keep.is_empty()
    }

    /// The outcome of `slot` (uniform in `[0, 1)`) and `coin` (uniform in `[0, 1)`).
    pub fn draw(&self, slot: Real, coin: Real) -> usize {
        let m = self.keep.len();
        let k = ((slot * m as Real) as usize).min(m - 1);
        if coin < self.keep[k] { k } else { self.alias[k] as usize }
    }
}

/// One column's landings: the patches it can reach, with escape as the last outcome when
/// there is any.
#[derive(Clone, Debug)]
struct Landings {
    table: AliasTable,
    /// The patch of each outcome; `u32::MAX` is escape.
    patches: Vec<u32>,
    /// `max(1, Σ_i T_ij)`.
    weight: Real,
}

/// A column source's matrix, sampled exactly (module doc).
#[derive(Clone, Debug)]
pub struct ColumnTransport {
    columns: Vec<Option<Landings>>,
    rows: Vec<Real>,
    areas: AliasTable,
    total_area: Real,
}

/// The outcome that stands for escape.
const ESCAPE: u32 = u32::MAX;

impl ColumnTransport {
    /// Samples `source`'s matrix, with the system's patch `areas`; reads every column once.
    pub fn new(source: &(impl ColumnSource + ?Sized), areas: &[Real]) -> Result<ColumnTransport, CoreError> {
        let n = source.patch_count();
        if areas.len() != n {
            return Err(CoreError::SizeMismatch { what: "patch areas", expected: n, found: areas.len() });
        }
        if let Some((patch, &area)) = areas.iter().enumerate().find(|(_, a)| !(a.is_finite() && **a > 0.0)) {
            return Err(CoreError::InvalidArea { patch, area });
        }
        let mut column = vec![0.0; n];
        let mut rows = vec![0.0; n];
        let mut columns = Vec::with_capacity(n);
        for j in 0..n {
            source.fill_column(j, &mut column);
            let (mut weights, mut patches) = (Vec::new(), Vec::new());
            for (i, &f) in column.iter().enumerate() {
                if !(f.is_finite() && f >= 0.0) {
                    return Err(CoreError::InvalidEntry { row: i, column: j, value: f });
                }
                rows[i] += f;
                if f > 0.0 {
                    weights.push(areas[i] * f / areas[j]);
                    patches.push(i as u32);
                }
            }
            let sum: Real = weights.iter().sum();
            if sum < 1.0 {
                weights.push(1.0 - sum);
                patches.push(ESCAPE);
            }
            columns.push(if sum > 0.0 {
                Some(Landings { table: AliasTable::new(&weights)?, patches, weight: sum.max(1.0) })
            } else {
                None
            });
        }
        Ok(ColumnTransport { columns, rows, areas: AliasTable::new(areas)?, total_area: areas.iter().sum() })
    }
}

impl TransportSampler for ColumnTransport {
    fn patch_count(&self) -> usize {
        self.columns.len()
    }

    fn cast(&self, from: usize, u: [Real; 4]) -> Option<usize> {
        let landings = self.columns[from].as_ref()?;
        let patch = landings.patches[landings.table.draw(u[0], u[1])];
        (patch != ESCAPE).then_some(patch as usize)
    }

    fn ray_weight(&self, from: usize) -> Real {
        self.columns[from].as_ref().map_or(1.0, |l| l.weight)
    }

    fn row_sum(&self, i: usize) -> Option<Real> {
        Some(self.rows[i])
    }

    fn global_line(&self, u: [Real; 4], line: &mut LineTransfers) -> bool {
        line.transfers.clear();
        let from = self.areas.draw(u[0], u[1]);
        if let Some(to) = self.cast(from, [u[2], u[3], 0.0, 0.0]) {
            line.transfers.push((from, to));
        }
        // A column that holds more than the patch's power lands with its weight: the line
        // stands for that much more area.
        line.area = self.total_area * self.ray_weight(from);
        line.rays = 1;
        true
    }

    fn cost(&self) -> SampleCost {
        SampleCost { ray: "one alias-table draw from a stored column".into(), constant: true }
    }
}
