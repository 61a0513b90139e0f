//! The `hemicube` backend: a ray-cast hemicube at the shooter's centroid gives the shooter's
//! row of form factors, and reciprocity turns that row into the column.
//!
//! ## Rule
//!
//! Around the centroid `x_j` of the shooter `j` sits a cube of half-width 1 cut in half by
//! the patch's plane (Cohen & Greenberg 1985). In the local frame `(t, b, n)` of the patch
//! (`n` its normal), the top face `z = 1` has `res × res` pixels and each of the four side
//! faces `x = ±1`, `y = ±1` has `res × res/2` pixels (`z ∈ (0, 1)`), all of side `2/res` and
//! area `ΔA = 4/res²`. Each pixel carries the delta form factor of the differential area at
//! `x_j` towards it:
//!
//! - top face: `ΔF = ΔA / (π (x² + y² + 1)²)`,
//! - side face (here `x = ±1`, the others alike): `ΔF = z ΔA / (π (y² + z² + 1)²)`,
//!
//! evaluated at the pixel centre. The row entry is `F_ji = Σ ΔF` over the pixels through
//! which `x_j` sees the front of patch `i`, and the column entry `F_ij = F_ji A_j / A_i`
//! (reciprocity, docs/design.md §3.3). A small receiver close to a much larger shooter can come out
//! with `F_ij > 1` (the centroid sees it large, and `A_j / A_i` magnifies that): the guard
//! clamps such entries and counts them ([`crate::guard`]).
//!
//! A z-buffer projects every patch onto the faces and keeps, per pixel, the patch nearest
//! along the ray from `x_j` through the pixel centre; that is exactly what
//! [`Visibility::first_hit`] returns for the ray `x_j + s · (pixel centre)`, so each pixel is
//! one ray, with patch `j` itself skipped. The hemicube therefore keeps its classic
//! behaviour, aliasing included, without a rasteriser, and its accuracy does not depend on a
//! depth buffer's precision.
//!
//! A pixel counts only if its ray arrives on the **front** side of the nearest patch (the
//! side its normal points to). A ray arriving on a patch's back is light leaving `j` into the
//! inside of an object or behind a one-sided surface: it reaches no patch that could receive
//! it, so it is dropped, as a z-buffer with back-face culling plus depth test would drop it.
//! In a closed scene whose patches all face inwards no such ray exists and every shooter's
//! row (`F_ji` over `i`) sums to exactly 1; elsewhere it sums to less.
//!
//! ## Discretisation and normalisation
//!
//! The delta form factors integrate `cos θ dω / π` over the hemisphere, so their exact
//! integral is 1, but the midpoint sums differ from 1 by `O(1/res²)`. Measured sums
//! ([`analytic_delta_sum`]):
//!
//! | res | Σ ΔF − 1 |
//! |---|---|
//! | 32 | `+5.30e-4` |
//! | 64 | `+1.32e-4` |
//! | 128 | `+3.31e-5` |
//! | 256 | `+8.27e-6` |
//!
//! The table is rescaled so that the delta form factors sum to exactly 1 (to rounding): a
//! shooter in a closed scene then distributes all of its power. The remaining error is the
//! hemicube's own: the form factor is the one from the *point* `x_j` (Cohen & Greenberg's
//! assumption), not averaged over the shooter, and the pixels alias against patch edges.
//! The first shrinks in aggregate as the mesh is refined, the second as `res` grows; the
//! tests measure both against Howell's closed forms and against the exact point-to-patch
//! form factor.
//!
//! The centroid assumption dominates: against the exact form factor from the centroid the
//! pixels are close, against Howell's area-to-area values a single patch is far off, and
//! meshing shrinks the aggregate (docs/form-factors.md, "Accuracy of the analytic and
//! hemicube backends"). For two perpendicular patches sharing an edge the centroid error is
//! scale-free, so it stays with every such pair however fine the mesh: the rows of an
//! assembled matrix (what every shooter's centroid sees of one patch) are off by a few percent
//! along the edges of a closed box, although each hemicube's own row sums to 1.
//!
//! ## Rotation and determinism
//!
//! To keep the aliasing from lining up with the scene's grid, the hemicube of shooter `j` is
//! turned about `n` by an angle drawn from a ChaCha8 stream keyed by the seed and `j`
//! (randomly rotated hemicubes: Cohen & Wallace 1993, ch. 4). Pixels are traced in parallel
//! (rayon) in blocks, and their delta form factors are summed in pixel order, so a column is
//! the same bit for bit whatever the thread count or the order in which columns are asked.
//!
//! The pixel directions and delta form factors are tabulated once in
//! [`HemicubeColumns::new`]. By symmetry one quarter of the top face holds every value: a
//! side pixel at `(y, z)` has `z` times the top value at `(|y|, z)`, so the table is
//! `res²/4` numbers, 33 MB at the largest resolution allowed (4096).
//!
//! ## References
//!
//! - M. F. Cohen, D. P. Greenberg, "The hemi-cube: a radiosity solution for complex
//!   environments", SIGGRAPH 1985 (Computer Graphics 19(3)), 31–40.
//! - M. F. Cohen, J. R. Wallace, *Radiosity and Realistic Image Synthesis*, Academic Press
//!   1993, ch. 4 (the hemicube, its aliasing, random rotation about the normal).

use crate::backend::FormFactorBackend;
use crate::guard::ClampCounter;
use radiosity_core::{ColumnSource, Real, Scene, Vec3};
use radiosity_geom::{ParamDoc, Visibility};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};

/// Parameters of the hemicube backend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HemicubeParams {
    /// Pixels along each edge of the hemicube's top face.
    pub resolution: usize,
    /// Seed of the random rotation about the normal.
    pub seed: u64,
}

/// Parameters of `hemicube`.
pub const HEMICUBE_PARAMS: &[ParamDoc] = &[
    ParamDoc { key: "res", default: "128", doc: "pixels along an edge of the top face, 2 to 4096 (even)" },
    ParamDoc { key: "seed", default: "0", doc: "seed of the random rotation about the normal" },
];

/// Pixels traced per parallel block (bounds the memory of one column's hits).
const BLOCK: usize = 1 << 16;
/// Smallest number of pixels a rayon task traces.
const MIN_TASK: usize = 512;

/// Hemicube form-factor columns of one scene.
#[derive(Debug)]
pub struct HemicubeColumns<'a> {
    scene: &'a Scene,
    visibility: Visibility,
    params: HemicubeParams,
    table: Table,
    clamped: ClampCounter,
}

/// The pixel centres and normalised delta form factors of one resolution.
#[derive(Clone)]
struct Table {
    /// Pixels along an edge of the top face (even, at least 2).
    res: usize,
    /// Pixel-centre coordinates along an edge of the top face, `−1 + (2k + 1)/res`.
    coords: Vec<Real>,
    /// Normalised top-face delta form factors of the quadrant `x, y > 0`:
    /// `quarter[p · res/2 + m]` at `x = coords[res/2 + p]`, `y = coords[res/2 + m]`.
    quarter: Vec<Real>,
    /// The sum of the delta form factors before normalisation.
    analytic_sum: Real,
}

impl std::fmt::Debug for Table {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Table")
            .field("res", &self.res)
            .field("analytic_sum", &self.analytic_sum)
            .finish_non_exhaustive()
    }
}

impl Table {
    fn new(resolution: usize) -> Table {
        let res = effective_resolution(resolution);
        let half = res / 2;
        let coords: Vec<Real> = (0..res).map(|k| -1.0 + (2 * k + 1) as Real / res as Real).collect();
        let area = 4.0 / (res * res) as Real;
        let mut quarter = Vec::with_capacity(half * half);
        for p in 0..half {
            for m in 0..half {
                let (x, y) = (coords[half + p], coords[half + m]);
                let d = x * x + y * y + 1.0;
                quarter.push(area / (PI * d * d));
            }
        }
        // Four quadrants of the top face, and on four side faces every quarter value twice
        // (y = ±x) times z.
        let mut top = 0.0;
        let mut side = 0.0;
        for p in 0..half {
            for m in 0..half {
                let w = quarter[p * half + m];
                top += w;
                side += coords[half + m] * w;
            }
        }
        let analytic_sum = 4.0 * top + 8.0 * side;
        for w in &mut quarter {
            *w /= analytic_sum;
        }
        Table { res, coords, quarter, analytic_sum }
    }

    fn pixel_count(&self) -> usize {
        3 * self.res * self.res
    }

    /// The index into `quarter` of coordinate index `k` folded onto the positive half.
    fn fold(&self, k: usize) -> usize {
        let half = self.res / 2;
        if k >= half { k - half } else { half - 1 - k }
    }

    /// The local direction (through the pixel centre, `z` along the normal) and the
    /// normalised delta form factor of pixel `p < pixel_count()`.
    fn pixel(&self, p: usize) -> (Vec3, Real) {
        let (res, half) = (self.res, self.res / 2);
        let c = &self.coords;
        if p < res * res {
            let (a, b) = (p / res, p % res);
            (Vec3::new(c[a], c[b], 1.0), self.quarter[self.fold(a) * half + self.fold(b)])
        } else {
            let r = p - res * res;
            let (face, s) = (r / (res * half), r % (res * half));
            let (a, m) = (s / half, s % half);
            let (y, z) = (c[a], c[half + m]);
            let direction = match face {
                0 => Vec3::new(1.0, y, z),
                1 => Vec3::new(-1.0, y, z),
                2 => Vec3::new(y, 1.0, z),
                _ => Vec3::new(y, -1.0, z),
            };
            (direction, z * self.quarter[self.fold(a) * half + m])
        }
    }
}

/// The largest resolution (the one [`crate::BackendSpec`] allows): 50 M pixels.
pub const MAX_RESOLUTION: usize = 4096;

/// The resolution actually used: `resolution` rounded up to an even number in
/// `2..=MAX_RESOLUTION` (the side faces are `res × res/2`; [`crate::BackendSpec`] only lets
/// such values through).
fn effective_resolution(resolution: usize) -> usize {
    let res = resolution.clamp(2, MAX_RESOLUTION);
    res + res % 2
}

/// The sum of the hemicube's delta form factors at `resolution` before normalisation: 1 plus
/// the midpoint rule's discretisation error (see the module documentation).
pub fn analytic_delta_sum(resolution: usize) -> Real {
    Table::new(resolution).analytic_sum
}

impl<'a> HemicubeColumns<'a> {
    /// Prepares the backend: tabulates the pixel directions and delta form factors of the
    /// resolution once. An odd resolution is rounded up to the next even one, and the
    /// resolution is kept within `2..=`[`MAX_RESOLUTION`].
    pub fn new(scene: &'a Scene, visibility: &Visibility, params: HemicubeParams) -> HemicubeColumns<'a> {
        HemicubeColumns {
            scene,
            visibility: visibility.clone(),
            params,
            table: Table::new(params.resolution),
            clamped: ClampCounter::default(),
        }
    }

    /// Entries clamped into `[0, 1]` so far.
    pub fn clamped(&self) -> u64 {
        self.clamped.count()
    }

    /// The resolution in use (pixels along an edge of the top face).
    pub fn resolution(&self) -> usize {
        self.table.res
    }

    /// Every pixel of the hemicube: the direction through its centre in the patch's local
    /// frame (`z` along the normal, before the rotation about it) and its normalised delta
    /// form factor. There are `3 · res²` of them and the delta form factors sum to 1.
    pub fn pixels(&self) -> impl Iterator<Item = (Vec3, Real)> + '_ {
        (0..self.table.pixel_count()).map(|p| self.table.pixel(p))
    }

    /// The hemicube of shooter `j`: its origin (the centroid) and the frame `(t, b, n)` that
    /// turns a pixel's local direction `d` into `t d.x + b d.y + n d.z`, randomly rotated about
    /// the normal by the seeded stream of `j`. `None` for a `j` out of range.
    pub(crate) fn frame(&self, j: usize) -> Option<(Vec3, [Vec3; 3])> {
        let patch = self.scene.patches().get(j)?;
        let n = patch.normal();
        let (t0, b0) = n.any_orthonormal_pair();
        let mut rng = ChaCha8Rng::seed_from_u64(self.params.seed);
        rng.set_stream(j as u64);
        let (sin, cos) = (TAU * rng.random::<Real>()).sin_cos();
        let t = t0 * cos + b0 * sin;
        Some((patch.centroid(), [t, n.cross(t), n]))
    }

    /// Row `j` before reciprocity: `row[i] = F_ji` from the hemicube at `j`'s centroid.
    fn row(&self, j: usize, row: &mut [Real]) {
        row.fill(0.0);
        let Some((origin, [t, b, n])) = self.frame(j) else {
            return;
        };
        let count = self.table.pixel_count();
        let mut hits: Vec<Option<(usize, Real)>> = Vec::new();
        for start in (0..count).step_by(BLOCK) {
            (start..(start + BLOCK).min(count))
                .into_par_iter()
                .with_min_len(MIN_TASK)
                .map(|p| {
                    let (d, weight) = self.table.pixel(p);
                    let direction = t * d.x + b * d.y + n * d.z;
                    self.visibility
                        .first_hit(origin, direction, Some(j))
                        .filter(|hit| hit.front)
                        .map(|hit| (hit.patch, weight))
                })
                .collect_into_vec(&mut hits);
            // Summed in pixel order: the same bits whatever the thread count.
            for &(i, weight) in hits.iter().flatten() {
                if let Some(f) = row.get_mut(i) {
                    *f += weight;
                }
            }
        }
    }
}

impl ColumnSource for HemicubeColumns<'_> {
    fn patch_count(&self) -> usize {
        self.scene.len()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        let patches = self.scene.patches();
        let mut row = vec![0.0; patches.len()];
        self.row(j, &mut row);
        column.fill(0.0);
        if let Some(shooter) = patches.get(j) {
            for ((f, fji), receiver) in column.iter_mut().zip(&row).zip(patches) {
                *f = fji * shooter.area() / receiver.area();
            }
        }
        self.clamped.clamp(column);
    }
}

/// Hemicube columns are not reciprocal: a row of the matrix they assemble would need every
/// column.
impl FormFactorBackend for HemicubeColumns<'_> {
    fn clamped(&self) -> u64 {
        HemicubeColumns::clamped(self)
    }
}
