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
//! stream, and the deposits are summed exactly ([`ExactSum`]): the same seed gives the same
//! numbers whatever the thread count and the ranks. Over ranks ([`Share`]), each rank casts
//! the rays of its share of the blocks (of lines, for global lines), every replicate's, and
//! one sum over the ranks gives every rank the iteration's deposits and the world's rays. A
//! patch's stream is keyed by the seed, the replicate and
//! the patch, and continues from one iteration to the next ([`Streams::drawn`] counts the
//! points each patch used): with a quasi-random sequence, the rays a patch casts over a whole
//! run are one low-discrepancy sequence, not a short one each iteration (where a patch casts
//! a few rays an iteration, as most do, there would be nothing to stratify). The landing of
//! the `k`-th ray is the same function of its point in every iteration; only the power it
//! carries changes (Keller 1996). A pseudo-random stream is keyed by the iteration too. A
//! patch's blocks are always the same rank's, so the points it drew are counted on that rank.
//!
//! ## References
//!
//! - Bekaert 1999, *Hierarchical and stochastic algorithms for radiosity*, PhD thesis, KU
//!   Leuven (stochastic Jacobi, its variance, the constant control variate).
//! - Sbert 1993, "An integral geometry based method for fast form-factor computation",
//!   Computer Graphics Forum 12(3) (global lines).

use crate::run::problem::Rays;
use crate::stochastic::exact_sum::ExactSum;
use crate::stochastic::ranks::Share;
use crate::stochastic::sequence::{PointStream, Sequence};
use radiosity_core::{LineTransfers, Real};
use rayon::prelude::*;

/// Patches per parallel block at most. No result depends on the blocks (each patch draws from
/// its own stream, and deposits are summed exactly), only how the work is divided.
const BLOCK: usize = 16;

/// Patches per block for `n` patches: smaller in small scenes, so that their blocks still
/// go to every thread and rank.
fn block_of(n: usize) -> usize {
    (n / 256).clamp(1, BLOCK)
}

/// A block of global lines: every transfer `(from, to, area it stands for)` in line order,
/// and the rays they cost.
type LineBlock = (Vec<(usize, usize, Real)>, u64);

/// What takes a patch's landings: the patch, its rays' landings in ray order, and its `k`
/// entries of the output ([`cast_per_patch`]).
type Land<'a> = &'a (dyn Fn(usize, &[Option<usize>], &mut [Real]) + Sync);

/// A patch whose rays are cast in parts: the patch, its stream, its rays.
type Many = (usize, PointStream, usize);

/// Lines per parallel block at most (each block's lines from a stream of its own).
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
    /// Patch `patch`'s stream from its point `drawn` on.
    fn of(&self, patch: usize, drawn: u64) -> PointStream {
        let stream = self.sequence.stream(self.seed, [self.replicate, 0, patch as u64]);
        stream.from_index(drawn).rekeyed(self.iteration)
    }

    /// Global lines' stream for block `block` of this iteration.
    fn lines(&self, block: u64) -> PointStream {
        self.sequence.stream(self.seed, [self.replicate, 1 + self.iteration, u64::MAX - block])
    }
}

/// What an estimate cost and found.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Cast {
    /// Rays cast by every rank (a global line counts its segments).
    pub rays: u64,
    /// Of them, this rank's.
    pub here: u64,
}

/// A patch's rays cast as one task at most where its landings may be taken in parts
/// (shooting): the many rays of a light, which the first iterations of the incremental series
/// give to a few patches, are shared by the threads instead of cast by the one that holds its
/// block.
const RAYS_A_TASK: usize = 2048;

/// The rays from each patch of this rank's blocks, cast in parallel blocks: `count(j,
/// stream)` says how many rays patch `j` casts (drawing any rounding from its stream), and
/// `land(j, landings, out_j)` takes each patch's landings in ray order, with `out_j`, patch
/// `j`'s `k` entries of `out`, on whatever thread cast them. With `in_parts`, `land` adds up
/// what each ray brings and never writes `out_j`: a patch's rays beyond [`RAYS_A_TASK`] are
/// then cast in tasks of their own, each from its place in the patch's stream, and landed in
/// parts (an empty `out_j`). Returns this rank's rays.
fn cast_per_patch(
    rays: &Rays<'_>,
    share: &Share<'_>,
    streams: &mut Streams<'_>,
    (out, k): (&mut [Real], usize),
    count: &(dyn Fn(usize, &mut dyn FnMut() -> Real) -> usize + Sync),
    land: Land<'_>,
    in_parts: bool,
) -> u64 {
    let keys = Streams { drawn: &mut [], ..*streams };
    let keys = &keys;
    let block = block_of(streams.drawn.len());
    let cast_one = |j: usize,
                    mut stream: PointStream,
                    m: usize,
                    points: &mut Vec<[Real; 4]>,
                    landings: &mut Vec<Option<usize>>,
                    out: &mut [Real]| {
        points.clear();
        points.extend((0..m).map(|_| stream.next_point()));
        landings.clear();
        landings.resize(m, None);
        rays.cast_batch(j, points, landings);
        land(j, landings, out);
    };
    // Each block's patches with few rays cast at once; the patches with many, to be cast in parts.
    let blocks: Vec<(u64, Vec<Many>)> = streams
        .drawn
        .par_chunks_mut(block)
        .zip(out.par_chunks_mut(block * k))
        .enumerate()
        .filter(|(b, _)| share.mine(*b))
        .map(|(b, (drawn, out))| {
            let (mut points, mut landings, mut cast, mut many) = (Vec::new(), Vec::new(), 0, Vec::new());
            for (at, (drawn, out)) in drawn.iter_mut().zip(out.chunks_mut(k)).enumerate() {
                let j = b * block + at;
                // A patch's stream is keyed only when it is drawn from: most patches cast
                // no ray in most iterations of the incremental series.
                let mut stream = None;
                let m = count(j, &mut || stream.get_or_insert_with(|| keys.of(j, *drawn)).uniform());
                if m == 0 {
                    continue;
                }
                let stream = stream.unwrap_or_else(|| keys.of(j, *drawn));
                if in_parts && m > RAYS_A_TASK {
                    many.push((j, stream, m));
                } else {
                    cast_one(j, stream, m, &mut points, &mut landings, out);
                }
                // The next iteration's rays go on from the next point.
                *drawn += m as u64;
                cast += m as u64;
            }
            (cast, many)
        })
        .collect();
    let parts: Vec<(usize, &PointStream, usize, usize)> = blocks
        .iter()
        .flat_map(|(_, many)| many)
        .flat_map(|(j, stream, m)| {
            (0..m.div_ceil(RAYS_A_TASK))
                .map(move |p| (*j, stream, p * RAYS_A_TASK, (m - p * RAYS_A_TASK).min(RAYS_A_TASK)))
        })
        .collect();
    parts.par_iter().for_each_init(
        || (Vec::new(), Vec::new()),
        |(points, landings), &(j, stream, first, m)| {
            cast_one(j, stream.clone().skipped(first as u64), m, points, landings, &mut []);
        },
    );
    blocks.iter().map(|(cast, _)| cast).sum()
}

/// `cast` with the world's rays from this rank's `here` (one sum over the ranks with `more`,
/// whose sums replace them); `cast` alone in one process.
fn world(share: &Share<'_>, here: u64, more: &mut [Real]) -> Cast {
    if share.collective().is_none() {
        return Cast { rays: here, here };
    }
    let mut v = more.to_vec();
    v.push(here as Real);
    share.sum(&mut v);
    more.copy_from_slice(&v[..more.len()]);
    Cast { rays: v[more.len()] as u64, here }
}

/// The deposits `sums` of this rank's `here` rays, summed over the ranks into `out`, and the
/// world's rays.
fn deposited(mut sums: ExactSum, share: &Share<'_>, here: u64, out: &mut [Real]) -> Cast {
    sums.sum_over(share.collective());
    sums.write(out);
    world(share, here, &mut [])
}

/// `⌊m⌋` or `⌈m⌉`, with expectation `m`, from `u` uniform in `[0, 1)`.
fn round_at_random(m: Real, u: Real) -> usize {
    let floor = m.floor();
    floor as usize + usize::from(u < m - floor)
}

/// `in_i = Σ_j T_ij x_j` by about `n_rays` rays (module doc), this rank's share cast here;
/// `x` and `incoming` patch-major with `k` channels; `incoming` is overwritten on every rank.
pub(crate) fn shoot(
    rays: &Rays<'_>,
    share: &Share<'_>,
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
    // No ray carries more than `most` (a largest, the same in any order, so taken on every
    // thread), and there are at most `n_rays + n` of them: a bound on every deposit's sum from
    // what every rank holds. The sums are made afresh for each estimate, so that a solver
    // holds none between its steps.
    let most = (0..n).into_par_iter().map(|j| scale[j] * norm(j)).reduce(|| 0.0, Real::max);
    let sums = ExactSum::new(n * k, most * (n_rays + n as u64) as Real);
    // What each ray brings is added on its own, so a patch's rays may be cast in parts.
    let land = |j: usize, landings: &[Option<usize>], _: &mut [Real]| {
        for &i in landings.iter().flatten() {
            for c in 0..k {
                sums.add(i * k + c, x[j * k + c] * scale[j]);
            }
        }
    };
    let here = cast_per_patch(rays, share, streams, (incoming, k), &count, &land, true);
    deposited(sums, share, here, incoming)
}

/// `g_i = Σ_j F_ij b_j` for every patch where `reflects(i)`, by about `n_rays` rays in
/// proportion to area (module doc), with the constant control variate `beta` (per channel)
/// when given; `gathered` is overwritten (0 where a patch does not reflect) on every rank, each
/// patch's from the rank whose share it is in.
#[allow(clippy::too_many_arguments)]
pub(crate) fn gather(
    rays: &Rays<'_>,
    share: &Share<'_>,
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
    // A patch gathers its own rays alone, in their order: its sum is the same on any thread,
    // and over the ranks only its own rank's is not zero.
    let here = cast_per_patch(
        rays,
        share,
        streams,
        (gathered, k),
        &count,
        &|i, landings, out| {
            let weight = rays.ray_weight(i);
            let row = beta.map_or(0.0, |_| rays.row_sum(i).unwrap_or(0.0));
            for (c, out) in out.iter_mut().enumerate() {
                let shift = beta.map_or(0.0, |beta| beta[c]);
                // A ray that escapes gathers nothing, also against the control variate.
                let sum: Real = landings.iter().flatten().map(|&j| b[j * k + c] - shift).sum();
                *out = shift * row + weight * sum / landings.len() as Real;
            }
        },
        false,
    );
    world(share, here, gathered)
}

/// `in_b = Σ_a A_a F_ab b_a` by `n_lines` global lines (module doc), this rank's blocks of
/// them cast here; `None` (and nothing cast) when the sampler has no lines; `incoming` is
/// overwritten on every rank.
pub(crate) fn lines(
    rays: &Rays<'_>,
    share: &Share<'_>,
    b: &[Real],
    k: usize,
    n_lines: u64,
    streams: &Streams<'_>,
    incoming: &mut [Real],
) -> Option<Cast> {
    incoming.fill(0.0);
    // Blocks of lines smaller in small batches, so that they still go to every thread and rank.
    let size = (n_lines / 256).clamp(1, LINE_BLOCK as u64);
    let blocks = n_lines.div_ceil(size);
    let found: Vec<Option<LineBlock>> = (0..blocks)
        .into_par_iter()
        .filter(|&block| share.mine(block as usize))
        .map(|block| {
            let mut stream = streams.lines(block);
            let mut line = LineTransfers::default();
            let (mut transfers, mut block_rays) = (Vec::new(), 0);
            let first = block * size;
            for _ in first..(first + size).min(n_lines) {
                if !rays.global_line(stream.next_point(), &mut line) {
                    return None;
                }
                transfers.extend(line.transfers.iter().map(|&(from, to)| (from, to, line.area)));
                block_rays += line.rays;
            }
            Some((transfers, block_rays))
        })
        .collect();
    // Whether every rank's sampler has lines, and a bound on every deposit's sum: the largest
    // transfer's area (a largest is the same over any ranks) times the transfers.
    let found: Option<Vec<LineBlock>> = found.into_iter().collect();
    let has = found.is_some();
    let found = found.unwrap_or_default();
    let widest = found.iter().flat_map(|(t, _)| t.iter().map(|t| t.2.abs())).fold(0.0, Real::max);
    let count = found.iter().map(|(t, _)| t.len()).sum::<usize>();
    let here: u64 = found.iter().map(|(_, r)| r).sum();
    let largest = b.iter().map(|x| x.abs()).fold(0.0, Real::max);
    let figures = share.gathered(&[Real::from(u8::from(!has)), widest, count as Real]);
    let lacking = figures.iter().any(|f| f[0] > 0.0);
    let widest = figures.iter().map(|f| f[1]).fold(0.0, Real::max);
    let count: Real = figures.iter().map(|f| f[2]).sum();
    if lacking {
        return None;
    }
    let sums = ExactSum::new(b.len(), largest * widest / n_lines as Real * count);
    found.par_iter().for_each(|(transfers, _)| {
        for &(from, to, area) in transfers {
            for c in 0..k {
                sums.add(to * k + c, b[from * k + c] * area / n_lines as Real);
            }
        }
    });
    Some(deposited(sums, share, here, incoming))
}
