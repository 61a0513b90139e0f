//! Closure: every row of the operator held to at most 1 by weighing its far links and far
//! pairs at both ends, reciprocity kept.
//!
//! A far link's visible fraction is one number for all its pairs. A cluster that holds
//! patches inside an enclosure (a bookcase's shelves) and patches outside it gives the inside
//! ones light that only the outside ones see, on top of the near links that already close
//! their rows; the visible fraction of the three probe rays of a far pair of patches is noisy
//! in the same way. A row above 1 sends more light than a patch receives, whatever its
//! reflectivity, so closure (`closure`, on by default) holds every row to at most 1, the
//! summation rule, keeping reciprocity, as view factors estimated by sampling are corrected in
//! thermal radiation (Larsen & Howell 1986). Each patch gets a weight in `[0, 1]`, and each
//! entry of a far link or a far pair is multiplied by the weights of both its patches, so
//! `A_i F_ij = A_j F_ji` and `F ≥ 0` still hold and no entry grows. The near links, the
//! analytic backend's entries, are left as they are: their rows' noise is that estimator's
//! (its shadow rays, `budget`), and capping it too biases every row below 1, which the
//! factor `1/(1 − ρ)` amplifies in bright scenes. A row whose near part alone sums above 1
//! keeps it, its estimated part weighed to 0.
//!
//! The weights are found by `CLOSURE_STEPS` fixed-point steps from 1, each giving every row
//! the weight that brings it to 1 (at most 1) against the others' weights of the step
//! before, then one step that only lowers the weights of the rows still above 1. Lowering a
//! weight lowers every other row, so after it no row is above 1 but by its near part
//! (rounding aside). A step is a product over the estimated links with one channel. Closure
//! removes leaked light where it shows, in rows above 1; a leak into a row that stays below 1,
//! and light missing from the outside patches of such a cluster, are not corrected. Rows are
//! never raised towards 1, even in a closed scene: spreading a row's missing light over its
//! estimated links puts it in the wrong places. What it costs and changes, and the steps'
//! number, are measured in `docs/hierarchical.md` (Closure).
//!
//! ## References
//!
//! - J. Larsen, J. Howell, "Least-squares smoothing of direct-exchange areas in zonal
//!   analysis", J. Heat Transfer 108, 1986.

use super::HierarchicalColumns;
use radiosity_core::Real;

/// Closure's fixed-point steps at most, and the largest change of a weight at which they
/// stop (the choice measured in `docs/hierarchical.md`, Closure).
const CLOSURE_STEPS: usize = 4;
const CLOSURE_SETTLED: Real = 1e-3;

impl HierarchicalColumns {
    /// Holds every row to at most 1 (closure, module doc) as far as its estimated part can:
    /// the weights that bring each row whose near part and weighed estimated part sum above 1
    /// down to 1.
    /// `near` holds each row's near part ([`Self::near_sums`]).
    pub(super) fn close(&mut self, near: &[Real]) {
        let ones = vec![1.0; self.areas.len()];
        let weights = capped_weights(near, |w, out| {
            self.estimated_product(&ones, 1, w, out);
            self.summed(out);
        });
        self.figures.capped = weights.iter().filter(|&&w| w < 1.0).count();
        self.figures.lowest_weight = weights.iter().copied().fold(1.0, Real::min);
        self.weights = weights;
    }
}

/// The weights `w ≤ 1` that hold every row `fixed_i + w_i Σ_j M_ij w_j` to at most 1, with
/// `product(w, out)` writing `Σ_j M_ij w_j` (`M ≥ 0`): fixed-point steps from 1, each giving
/// every row the weight that brings it to 1 (at most 1) against the others' weights of the
/// step before, then one step that only lowers the weights of the rows still above 1.
/// Lowering a weight lowers every other row, so that step leaves no row above 1 (rounding
/// aside), whatever the steps before converged to.
fn capped_weights(fixed: &[Real], product: impl Fn(&[Real], &mut [Real])) -> Vec<Real> {
    let n = fixed.len();
    let bringing = |fixed: Real, sum: Real| if sum > 0.0 { ((1.0 - fixed) / sum).clamp(0.0, 1.0) } else { 1.0 };
    let (mut weights, mut sums) = (vec![1.0; n], vec![0.0; n]);
    for _ in 0..CLOSURE_STEPS {
        product(&weights, &mut sums);
        let mut moved: Real = 0.0;
        for i in 0..n {
            let next = bringing(fixed[i], sums[i]);
            moved = moved.max((next - weights[i]).abs());
            weights[i] = next;
        }
        if moved < CLOSURE_SETTLED {
            break;
        }
    }
    product(&weights, &mut sums);
    for i in 0..n {
        if fixed[i] + weights[i] * sums[i] > 1.0 {
            weights[i] = weights[i].min(bringing(fixed[i], sums[i]));
        }
    }
    weights
}
