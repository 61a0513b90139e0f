//! The [`TransportSampler`] trait: transport estimated with rays, for the solvers that never
//! form `F` (stochastic relaxation and random walks), beside [`crate::ColumnSource`].
//!
//! A ray leaves patch `j` from a uniform point, in a cosine-distributed direction, and lands on
//! the first patch it reaches, or escapes. The probability that it lands on patch `i` is the
//! fraction of `j`'s power that reaches `i`,
//!
//! `T_ij = A_i F_ij / A_j` (`= F_ji` where `F` is reciprocal),
//!
//! with `F` the matrix the system is written with (`B_i = E_i + ρ_i Σ_j F_ij B_j`, column `j`
//! of `F` is what shooting from `j` needs). A ray that lands on the back of a patch is absorbed
//! there and lands nowhere: a patch receives light on its front side only, as form factors
//! count it. Rays shot from `i` in gathering land on `j` with probability `T_ji = F_ij` (row
//! `i`), the same question asked from the other end.
//!
//! **Random numbers come from the caller**: a ray is a point `u` of the unit cube `[0, 1)^4`
//! ([`TransportSampler::cast`]), so pseudo-random and quasi-random sequences plug in alike, and
//! the same points give the same landings whatever the thread count. What each coordinate
//! means is the sampler's business; a sampler that needs fewer ignores the rest.
//!
//! **Global lines** ([`TransportSampler::global_line`]): a line uniformly distributed over the
//! lines that meet the scene crosses surfaces one after another, and every two consecutive
//! surfaces that face each other along it exchange light in both directions. A line hands back
//! its transfers and the area `W` each stands for: over many lines, the expected number of
//! transfers from `a` to `b` times `W` is `A_a F_ab`. A sampler without lines says so (`None`).
//!
//! **Cost**: one [`TransportSampler::cast`] is one ray; a global line costs the rays it traced,
//! which it reports. [`TransportSampler::cost`] says what one ray is (a BVH traversal, an alias
//! draw), for reports.
//!
//! Implementations: [`crate::ColumnTransport`], any column source's matrix sampled exactly
//! (alias tables, for tests and exact comparisons), and the rays-in-the-scene sampler of
//! `radiosity-ff`.

use crate::math::Real;

/// What one ray of a sampler is, for reports ([`TransportSampler::cost`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SampleCost {
    /// One line: what a ray does (`one ray through a BVH of 12,345 triangles`).
    pub ray: String,
    /// Whether a ray costs about the same wherever it goes (an alias draw) or depends on the
    /// scene (a traversal).
    pub constant: bool,
}

/// One global line's transfers ([`TransportSampler::global_line`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LineTransfers {
    /// Directed transfers `(from, to)`: `from`'s front faces `to`'s front along the line, with
    /// nothing in between. Cleared by the sampler before it fills them.
    pub transfers: Vec<(usize, usize)>,
    /// The area each transfer stands for (`W`, module doc).
    pub area: Real,
    /// The rays the line cost (its segments traced).
    pub rays: u64,
}

/// Transport estimated by rays (module doc). `Sync`, so rays are cast in parallel.
pub trait TransportSampler: Sync {
    /// The number of patches.
    fn patch_count(&self) -> usize;

    /// The patch a ray leaving the front of patch `from` lands on first, driven by `u` in
    /// `[0, 1)^4`; `None` when it escapes or is absorbed on a back face. Lands on `i` with
    /// probability `T_i,from / weight(from)` (module doc, [`TransportSampler::ray_weight`]).
    fn cast(&self, from: usize, u: [Real; 4]) -> Option<usize>;

    /// [`TransportSampler::cast`] for a batch of rays from one patch, `landings[k]` for
    /// `u[k]`; the same landings as one at a time. Both slices have the same length.
    fn cast_batch(&self, from: usize, u: &[[Real; 4]], landings: &mut [Option<usize>]) {
        for (landing, &point) in landings.iter_mut().zip(u) {
            *landing = self.cast(from, point);
        }
    }

    /// The power a ray from `from` carries, in units of the share it was cast for: 1 for rays
    /// in a scene. A sampler whose column `from` holds more than all of the patch's power
    /// (`Σ_i T_i,from > 1`: quadrature error in a stored matrix) lands rays in proportion to
    /// `T` and gives each that sum, so that the expected power landed on `i` is still
    /// `T_i,from` times the power shot.
    fn ray_weight(&self, from: usize) -> Real {
        let _ = from;
        1.0
    }

    /// `Σ_j F_ij`, when the sampler knows it exactly (a stored matrix; a scene from which no
    /// ray escapes: 1), for a control variate. `None` by default.
    fn row_sum(&self, i: usize) -> Option<Real> {
        let _ = i;
        None
    }

    /// One global line driven by `u` (module doc): its transfers, the area each stands for,
    /// and its rays, written into `line`; `false` when the sampler has no lines (the default).
    fn global_line(&self, u: [Real; 4], line: &mut LineTransfers) -> bool {
        let _ = (u, line);
        false
    }

    /// What one ray is, for reports.
    fn cost(&self) -> SampleCost;
}

impl<T: TransportSampler + ?Sized> TransportSampler for &T {
    fn patch_count(&self) -> usize {
        (**self).patch_count()
    }

    fn cast(&self, from: usize, u: [Real; 4]) -> Option<usize> {
        (**self).cast(from, u)
    }

    fn cast_batch(&self, from: usize, u: &[[Real; 4]], landings: &mut [Option<usize>]) {
        (**self).cast_batch(from, u, landings)
    }

    fn ray_weight(&self, from: usize) -> Real {
        (**self).ray_weight(from)
    }

    fn row_sum(&self, i: usize) -> Option<Real> {
        (**self).row_sum(i)
    }

    fn global_line(&self, u: [Real; 4], line: &mut LineTransfers) -> bool {
        (**self).global_line(u, line)
    }

    fn cost(&self) -> SampleCost {
        (**self).cost()
    }
}

impl<T: TransportSampler + ?Sized + Send> TransportSampler for std::sync::Arc<T> {
    fn patch_count(&self) -> usize {
        (**self).patch_count()
    }

    fn cast(&self, from: usize, u: [Real; 4]) -> Option<usize> {
        (**self).cast(from, u)
    }

    fn cast_batch(&self, from: usize, u: &[[Real; 4]], landings: &mut [Option<usize>]) {
        (**self).cast_batch(from, u, landings)
    }

    fn ray_weight(&self, from: usize) -> Real {
        (**self).ray_weight(from)
    }

    fn row_sum(&self, i: usize) -> Option<Real> {
        (**self).row_sum(i)
    }

    fn global_line(&self, u: [Real; 4], line: &mut LineTransfers) -> bool {
        (**self).global_line(u, line)
    }

    fn cost(&self) -> SampleCost {
        (**self).cost()
    }
}
