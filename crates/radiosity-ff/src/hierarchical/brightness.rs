//! What the refinement oracle weighs a link by: how much light its nodes send and how much of
//! what they receive they reflect (Hanrahan, Salzman & Aupperle's BF refinement).
//!
//! A link's error changes a receiver's radiosity by `ρ_i δF_ij B_j`, and `e_rms` measures
//! radiosity relative to its area-weighted RMS `B_ref` (docs/design.md §6.1), so the oracle bounds,
//! for each end as receiver, `ρ_max · Φ / (π r²)` with `Φ = Σ A_j B_j / B_ref` the other end's flux
//! in units of `B_ref`: a link between dim or black patches may stay coarse, links from the
//! lights are refined further than the geometric oracle would. With `B = B_ref` and `ρ = 1`
//! everywhere this is the geometric bound `max(A_A, A_B) / (π r²)`.
//!
//! `B` is not known when the links are built. The estimate is the emission plus one ambient
//! bounce, `B_i ≈ E_i + ρ_i B_amb` with `B_amb = Σ A E / (Σ A (1 − ρ̄))` (the ambient term of
//! Cohen, Chen, Wallace & Greenberg 1988, "A progressive refinement approach to fast radiosity
//! image generation", SIGGRAPH), per channel, the largest channel taken. The estimate is wrong
//! where a patch is lit or shadowed more than on average, so neither weight falls below `floor`:
//! every link is still within `eps / floor` of a row of `F` towards a receiver that reflects,
//! and within `eps / floor²` between two patches that are both near black and dim. A later
//! refinement pass takes `B` from the operator's own radiosity ([`Brightness::from_radiosity`]).

use super::tree::ClusterTree;
use radiosity_core::{Real, Scene};

/// Each patch's weights from an estimate of its radiosity: relative to the estimate's
/// area-weighted RMS and its reflectivity, neither below `floor`; left as they are when the
/// estimate is zero everywhere.
fn weigh(scene: &Scene, estimate: &[Real], floor: Real, brightness: &mut [Real], reflect: &mut [Real]) {
    let area = scene.total_area();
    let mean_square = scene.patches().iter().zip(estimate).map(|(p, b)| p.area() * b * b).sum::<Real>() / area;
    if mean_square > 0.0 {
        let reference = mean_square.sqrt();
        for i in 0..scene.len() {
            brightness[i] = (estimate[i] / reference).max(floor);
            reflect[i] = scene.reflectivity(i).max().max(floor);
        }
    }
}

/// Per node of the tree: its flux in units of `B_ref` and the largest reflectivity of its
/// patches.
#[derive(Clone, Debug)]
pub(crate) struct Brightness {
    /// `Σ A_j max(B_j / B_ref, floor)` over the node's patches.
    pub flux: Vec<Real>,
    /// `max(ρ_j, floor)` over the node's patches, the largest channel of each.
    pub reflect: Vec<Real>,
}

/// How the oracle weighs links.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Oracle {
    /// By area alone: every link within `eps` of a row of `F`.
    Area,
    /// By the estimated flux of its sender and the reflectivity of its receiver (module doc).
    Flux,
}

impl Brightness {
    /// The weights of every node of `tree` over `scene`. `Oracle::Area`, or a scene that emits
    /// nothing, gives the area and a reflectivity of 1.
    pub fn estimate(scene: &Scene, tree: &ClusterTree, oracle: Oracle, floor: Real) -> Brightness {
        let n = scene.len();
        let (mut brightness, mut reflect) = (vec![1.0; n], vec![1.0; n]);
        if oracle == Oracle::Flux {
            let area: Real = scene.total_area();
            let ambient: [Real; 3] = std::array::from_fn(|c| {
                let emitted: Real =
                    scene.patches().iter().enumerate().map(|(i, p)| p.area() * scene.emission(i).0[c]).sum();
                let mean_rho: Real = scene
                    .patches()
                    .iter()
                    .enumerate()
                    .map(|(i, p)| p.area() * scene.reflectivity(i).0[c])
                    .sum::<Real>()
                    / area;
                emitted / (area * (1.0 - mean_rho))
            });
            let estimate: Vec<Real> = (0..n)
                .map(|i| {
                    let (e, rho) = (scene.emission(i), scene.reflectivity(i));
                    (0..3).map(|c| e.0[c] + rho.0[c] * ambient[c]).fold(0.0, Real::max)
                })
                .collect();
            weigh(scene, &estimate, floor, &mut brightness, &mut reflect);
        }
        Brightness::of_patches(scene, tree, &brightness, &reflect)
    }

    /// The weights of every node of `tree` from a radiosity `b` of `scene` (3 channels,
    /// patch-major; the largest channel taken), each no smaller than `floor`: the oracle of a
    /// refinement pass driven by the solution (multigridding).
    pub fn from_radiosity(scene: &Scene, tree: &ClusterTree, b: &[Real], floor: Real) -> Brightness {
        let n = scene.len();
        let estimate: Vec<Real> = (0..n).map(|i| b[3 * i..3 * i + 3].iter().copied().fold(0.0, Real::max)).collect();
        let (mut brightness, mut reflect) = (vec![1.0; n], vec![1.0; n]);
        weigh(scene, &estimate, floor, &mut brightness, &mut reflect);
        Brightness::of_patches(scene, tree, &brightness, &reflect)
    }

    /// The nodes' flux and largest reflectivity from their patches' weights.
    fn of_patches(scene: &Scene, tree: &ClusterTree, brightness: &[Real], reflect: &[Real]) -> Brightness {
        let nodes = &tree.nodes;
        let (mut flux, mut most) = (vec![0.0; nodes.len()], vec![0.0; nodes.len()]);
        // Children come after their parent: a backward pass sees them first.
        for k in (0..nodes.len()).rev() {
            match nodes[k].children {
                None => {
                    let p = tree.order[nodes[k].first as usize] as usize;
                    flux[k] = scene.patches()[p].area() * brightness[p];
                    most[k] = reflect[p];
                }
                Some([a, b]) => {
                    flux[k] = flux[a as usize] + flux[b as usize];
                    most[k] = most[a as usize].max(most[b as usize]);
                }
            }
        }
        Brightness { flux, reflect: most }
    }

    /// The most one end of the link between `a` and `b` at distance `r` may receive from the
    /// other, in units of `B_ref`: `max(ρ_a Φ_b, ρ_b Φ_a) / (π r²)`.
    pub fn bound(&self, a: u32, b: u32, r: Real) -> Real {
        let (a, b) = (a as usize, b as usize);
        (self.reflect[a] * self.flux[b]).max(self.reflect[b] * self.flux[a]) / (std::f64::consts::PI * r * r)
    }
}
