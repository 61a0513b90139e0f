//! One stochastic Jacobi iteration's transport, estimated by rays: the power a vector shoots,
//! the radiosity patches gather, or both along global lines ([`Estimator`]).
//!
//! Each estimator is unbiased for the quantity it names, with the landing probabilities of
//! [`radiosity_core::transport`] (`T_ij = A_i F_ij / A_j` for a ray from `j`):
//!
//! - [`shoot`]: `in_i = Σ_j T_ij x_j`, the power landing on `i` when every patch `j` sends out
//!   power `x_j`. Patch `j` is due `m_j = N |x_j| / Σ|x|` rays (`|x_j|` summed over channels).
//!   Where `m_j ≥ 1` it casts `N_j = round(m_j)` rays, each carrying `w_j x_j / N_j` (`w_j` the
//!   sampler's ray weight), so that the power it shoots is exactly `x_j` and only where it
//!   lands is random; where `m_j < 1` it casts one ray with probability `m_j`, carrying
//!   `w_j x_j / m_j`. Either way the expected power landed on `i` is `Σ_j T_ij x_j`. Rounding
//!   at random where `m_j ≥ 1` too would also be unbiased, but would add the noise of how much
//!   each patch shoots, which no quasi-random sequence removes.
//! - [`gather`]: `g_i = Σ_j F_ij b_j` for the patches that reflect: patch `i` casts
//!   `max(1, ⌈N A_i / Σ A⌉)` rays and averages `b` where they land (0 when they escape), times
//!   its ray weight. A ray from `i` lands on `j` with probability `T_ji`, which is `F_ij` where
//!   `F` is reciprocal (rays in a scene); for a stored matrix that is not, this gathers the
//!   reciprocal row, as gathering by columns does ([`crate::Problem::row`]). With a constant
//!   control variate `β` (per channel), `g_i = β r_i + mean(b_land − β)`, unbiased when the
//!   sampler knows the row sum `r_i` exactly.
//! - [`lines`]: `in_b = Σ_a A_a F_ab b_a` by `N` global lines: every transfer from `a` to `b`
//!   adds `b_a W / N` to `in_b`, `W` the area a transfer stands for.
//!
//! Rays are cast in parallel over fixed blocks of patches, each patch's rays from its own
//! stream, and landings are summed in patch order afterwards: the same seed gives the same
//! numbers whatever the thread count. A patch's stream is keyed by the seed, the replicate and
//! the patch, and continues from one iteration to the next ([`Streams::drawn`] counts the
//! points each patch used): with a quasi-random sequence, the rays a patch casts over a whole
//! run are one low-discrepancy sequence, not a short one each iteration (where a patch casts
//! a few rays an iteration, as most do, there would be nothing to stratify). The landing of
//! the `k`-th ray is the same function of its point in every iteration; only the power it
//! carries changes (Keller 1996). A pseudo-random stream is keyed by the iteration too.
//!
//! ## References
//!
//! - Bekaert 1999, *Hierarchical and stochastic algorithms for radiosity*, PhD thesis, KU
//!   Leuven (stochastic Jacobi, its variance, the constant control variate).
//! - Sbert 1993, "An integral geometry based method for fast form-factor computation",
//!   Computer Graphics Forum 12(3) (global lines).

use crate::run::problem::Rays;
use crate::stochastic::sequence::Sequence;
use radiosity_core::{LineTransfers, Real};
use rayon::prelude::*;

/// Patches per parallel block: fixed, so that no result depends on the thread count.
const BLOCK: usize = 64;

/// The blocks cast in parallel before their landings are summed ([`cast_per_patch`]).
const WINDOW: usize = 1024;

/// A block of global lines: every transfer `(from, to, area it stands for)` in line order,
/// and the rays they cost.
type LineBlock = (Vec<(usize, usize, Real)>, u64);

/// Lines per parallel block.
const LINE_BLOCK: usize = 1024;

/// How a chain's streams are keyed (module doc): the run's seed and sequence, the replicate,
/// and the points each patch has drawn so far.
#[derive(Debug)]
pub(crate) struct Streams<'c> {
    pub sequence: Sequence,
    pub seed: u64,
    pub replicate: u64,
    /// The iteration (keys the lines, and the pseudo-random streams with the points drawn).
    pub iteration: u64,
    /// Points drawn so far by each patch in this chain; advanced by each estimate.
    pub drawn: &'c mut [u64],
}

impl Streams<'_> {
    /// Patch `patch`'s stream from its next point on.
    fn of(&self, patch: usize) -> crate::stochastic::sequence::PointStream {
        let stream = self.sequence.stream(self.seed, [self.replicate, 0, patch as u64]);
        stream.from_index(self.drawn[patch]).rekeyed(self.iteration)
    }

    /// Global lines' stream for block `block` of this iteration.
    fn lines(&self, block: u64) -> crate::stochastic::sequence::PointStream {
        self.sequence.stream(self.seed, [self.replicate, 1 + self.iteration, u64::MAX - block])
    }
}

/// What an estimate cost and found.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Cast {
    /// Rays cast (a global line counts its segments).
    pub rays: u64,
}

/// The rays from each patch in `0..n`, cast in parallel blocks: `count(j, stream)` says how
/// many rays patch `j` casts (drawing any rounding from its stream), and the landings are
/// handed to `land(j, landing)` in patch order, then ray order.
fn cast_per_patch(
    rays: &Rays<'_>,
    n: usize,
    streams: &mut Streams<'_>,
    count: &(dyn Fn(usize, &mut dyn FnMut() -> Real) -> usize + Sync),
    mut land: impl FnMut(usize, Option<usize>),
) -> Cast {
    // A block's patches with their numbers of rays, and all their landings in one list. The
    // blocks go in windows of `WINDOW`, each cast in parallel and then landed, so that the
    // landings held are a window's (a few megabytes), not an iteration's (16 bytes a ray:
    // 1.8 GB for the 114 M rays of an iteration at ten million patches). Landed in the same
    // order, the results do not depend on the windows.
    type Landed = (Vec<(usize, usize)>, Vec<Option<usize>>);
    let mut cast = Cast::default();
    let blocks = n.div_ceil(BLOCK);
    for window in (0..blocks).step_by(WINDOW) {
        let landed: Vec<Landed> = (window..(window + WINDOW).min(blocks))
            .into_par_iter()
            .map(|b| {
                let (mut patches, mut landings) = (Vec::new(), Vec::new());
                let mut points = Vec::new();
                for j in b * BLOCK..((b + 1) * BLOCK).min(n) {
                    // A patch's stream is keyed only when it is drawn from: most patches cast
                    // no ray in most iterations of the incremental series.
                    let mut stream = None;
                    let k = count(j, &mut || stream.get_or_insert_with(|| streams.of(j)).uniform());
                    if k == 0 {
                        continue;
                    }
                    let stream = stream.get_or_insert_with(|| streams.of(j));
                    points.clear();
                    points.extend((0..k).map(|_| stream.next_point()));
                    let at = landings.len();
                    landings.resize(at + k, None);
                    rays.cast_batch(j, &points, &mut landings[at..]);
                    patches.push((j, k));
                }
                (patches, landings)
            })
            .collect();
        for (patches, landings) in landed {
            let mut landings = landings.into_iter();
            for (j, k) in patches {
                cast.rays += k as u64;
                // The next iteration's rays go on from the next point.
                streams.drawn[j] += k as u64;
                for landing in landings.by_ref().take(k) {
                    land(j, landing);
                }
            }
        }
    }
    cast
}

/// `⌊m⌋` or `⌈m⌉`, with expectation `m`, from `u` uniform in `[0, 1)`.
fn round_at_random(m: Real, u: Real) -> usize {
    let floor = m.floor();
    floor as usize + usize::from(u < m - floor)
}

/// `in_i = Σ_j T_ij x_j` by about `n_rays` rays (module doc); `x` and `incoming` patch-major
/// with `k` channels; `incoming` is overwritten.
pub(crate) fn shoot(
    rays: &Rays<'_>,
    x: &[Real],
    k: usize,
    n_rays: u64,
    streams: &mut Streams<'_>,
    incoming: &mut [Real],
) -> Cast {
    let n = x.len() / k;
    let norm = |j: usize| x[j * k..(j + 1) * k].iter().map(|v| v.abs()).sum::<Real>();
    let total: Real = (0..n).map(norm).sum();
    incoming.fill(0.0);
    if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || n_rays == 0 {
        return Cast::default();
    }
    let expected = |j: usize| n_rays as Real * norm(j) / total;
    // Rays due at least one are cast in their rounded number, carrying the patch's power
    // between them; the others one at a time, at random.
    let cast_count = |m: Real| if m >= 1.0 { m.round() } else { m };
    let count = |j: usize, uniform: &mut dyn FnMut() -> Real| {
        let m = expected(j);
        match m {
            m if m >= 1.0 => m.round() as usize,
            m if m > 0.0 => round_at_random(m, uniform()),
            _ => 0,
        }
    };
    // What each of a patch's rays carries per unit of its power, worked out once a patch.
    let scale: Vec<Real> = (0..n)
        .into_par_iter()
        .map(|j| {
            let m = expected(j);
            if m > 0.0 { rays.ray_weight(j) / cast_count(m) } else { 0.0 }
        })
        .collect();
    cast_per_patch(rays, n, streams, &count, |j, landing| {
        if let Some(i) = landing {
            for c in 0..k {
                incoming[i * k + c] += x[j * k + c] * scale[j];
            }
        }
    })
}

/// `g_i = Σ_j F_ij b_j` for every patch where `reflects(i)`, by about `n_rays` rays in
/// proportion to area (module doc), with the constant control variate `beta` (per channel)
/// when given; `gathered` is overwritten (0 where a patch does not reflect).
#[allow(clippy::too_many_arguments)]
pub(crate) fn gather(
    rays: &Rays<'_>,
    b: &[Real],
    k: usize,
    areas: &[Real],
    reflects: &(dyn Fn(usize) -> bool + Sync),
    beta: Option<&[Real]>,
    n_rays: u64,
    streams: &mut Streams<'_>,
    gathered: &mut [Real],
) -> Cast {
    let n = areas.len();
    let area: Real = (0..n).filter(|&i| reflects(i)).map(|i| areas[i]).sum();
    gathered.fill(0.0);
    if area.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Cast::default();
    }
    let count = |i: usize, _: &mut dyn FnMut() -> Real| {
        if reflects(i) { ((n_rays as Real * areas[i] / area).ceil() as usize).max(1) } else { 0 }
    };
    let mut cast_from = vec![0usize; n];
    let cast = cast_per_patch(rays, n, streams, &count, |i, landing| {
        cast_from[i] += 1;
        // A ray that escapes gathers nothing, also against the control variate.
        if let Some(j) = landing {
            for c in 0..k {
                gathered[i * k + c] += b[j * k + c] - beta.map_or(0.0, |beta| beta[c]);
            }
        }
    });
    for i in (0..n).filter(|&i| cast_from[i] > 0) {
        let weight = rays.ray_weight(i);
        let row = beta.map_or(0.0, |_| rays.row_sum(i).unwrap_or(0.0));
        for c in 0..k {
            let base = beta.map_or(0.0, |beta| beta[c] * row);
            gathered[i * k + c] = base + weight * gathered[i * k + c] / cast_from[i] as Real;
        }
    }
    cast
}

/// `in_b = Σ_a A_a F_ab b_a` by `n_lines` global lines (module doc); `false` (and nothing
/// cast) when the sampler has no lines; `incoming` is overwritten.
pub(crate) fn lines(
    rays: &Rays<'_>,
    b: &[Real],
    k: usize,
    n_lines: u64,
    streams: &Streams<'_>,
    incoming: &mut [Real],
) -> Option<Cast> {
    incoming.fill(0.0);
    let blocks = n_lines.div_ceil(LINE_BLOCK as u64);
    let found: Vec<Option<LineBlock>> = (0..blocks)
        .into_par_iter()
        .map(|block| {
            let mut stream = streams.lines(block);
            let mut line = LineTransfers::default();
            let (mut transfers, mut block_rays) = (Vec::new(), 0);
            let first = block * LINE_BLOCK as u64;
            for _ in first..(first + LINE_BLOCK as u64).min(n_lines) {
                if !rays.global_line(stream.next_point(), &mut line) {
                    return None;
                }
                transfers.extend(line.transfers.iter().map(|&(from, to)| (from, to, line.area)));
                block_rays += line.rays;
            }
            Some((transfers, block_rays))
        })
        .collect();
    let mut cast = Cast::default();
    for block in found {
        let (transfers, block_rays) = block?;
        cast.rays += block_rays;
        for (from, to, area) in transfers {
            for c in 0..k {
                incoming[to * k + c] += b[from * k + c] * area / n_lines as Real;
            }
        }
    }
    Some(cast)
}
