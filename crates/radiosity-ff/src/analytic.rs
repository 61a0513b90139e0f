//! The `analytic` backend: Lambert's point-to-polygon formula integrated over the receiving
//! patch, times a visible fraction estimated with shadow rays ([`crate::pair_visibility`]).
//!
//! ## Rule
//!
//! `F_ij = V_ij · (1/A_i) Σ_q w_q F(dA_{x_q} → P_j)`, with `(x_q, w_q)` a Gauss–Legendre rule
//! on patch `i` ([`crate::quadrature`]) and `F(dA → P)` the clipped Lambert formula
//! ([`crate::ff_point_polygon`]; Baum, Rushmeier & Winget 1989).
//!
//! The rule adapts to the pair: the receiver gets the smallest order whose predicted relative
//! error, at its distance from `P_j`, is below `tol`, at most `order`
//! ([`crate::quadrature::order_for`]). Where even `order` is predicted to miss (the receiver
//! is near `P_j` compared with its size, as for patches touching along an edge), it is cut
//! into quarters and each is treated the same way, down to `2^-12` of the patch: panels grade
//! geometrically towards the shared edge, where the integrand varies fastest. Distant pairs
//! use the centroid. As `tol → 0` and `order` grows, the result converges to the exact
//! area-to-area form factor of an unoccluded pair; the tests measure it against Howell's
//! closed forms. Points behind `P_j`'s plane see its back and contribute
//! nothing; pairs entirely behind each other's planes are skipped before any work.
//!
//! Accuracy is tested against Howell's closed forms (opposed and perpendicular rectangles,
//! square and not, meshed 1 to 8 per side), the defaults held to 1e-3 relative. The errors
//! measured per setting are in docs/form-factors.md ("Accuracy of the analytic and hemicube
//! backends").
//!
//! ## Reciprocity
//!
//! Exact by construction: each unordered pair is evaluated once, by one rule, and both entries
//! come from it. The integral runs over the smaller patch of the pair (the lower index when
//! the areas agree to 1e-9) towards the larger, giving `A_s F_sl`, and the other entry is
//! `F_ls = A_s F_sl / A_l`; visibility is sampled identically for `(i, j)` and `(j, i)`. So
//! `A_i F_ij = A_j F_ji` to round-off in every column and row (tested on the built-in scenes).
//! Integrating over the smaller patch is also the easier side for the quadrature: it is the
//! one that is small against its distance to the other. Before, each column integrated over
//! its own receivers, and the worst pair of multi-cubes was off by 1.4e-2: a distant pair used
//! the centroid rule on the whole receiver, so a receiver straddling the shooter's plane
//! counted all or nothing of itself, whichever way round.
//!
//! The error model is conservative: `tol=1e-3` and `tol=1e-4` give the same worst case, which
//! is set by `order` and by the panel budget on touching pairs. Panels are quartered in both
//! directions; grading only across the shared edge would spend the budget better.
//!
//! Panels are quartered a level at a time, every panel of a level before any of the next.
//! Quartered depth first (before d31c293), a pair whose budget ran out had spent it all on its
//! first panels and integrated the rest whole, however near the shooter: a long strip whose
//! edge lies across the shooter (a chair seat's patch on its platform in RenderPark's office3)
//! came out 20% high (tested against cosine-weighted rays). A pair whose budget lasts gets the
//! same panels either way.
//!
//! The inner integral is analytic, so the `1/r²` singularity of the area-to-area kernel
//! never appears: patches touching along an edge give finite, accurate values.
//!
//! ## Visibility
//!
//! When the scene analysis says nothing can occlude, no ray is traced (`V_ij = 1`).
//! Otherwise `V_ij` is the pair's visible fraction weighted by the kernel, estimated by
//! [`crate::pair_visibility`]: each pair gets shadow rays in proportion to its larger
//! unoccluded form factor (`budget` per unit, times a stiffness factor in scenes whose mean
//! reflectivity exceeds 0.8, and at least `rays`), both ends drawn where and as
//! the kernel weighs them, each segment from its own point of the smaller patch (the side the
//! quadrature integrates over, where no point weighs more than `1/u` times the mean), with a
//! probe deciding which pairs are partly visible and fresh rays estimating them. The samples
//! are drawn from a Xoshiro256++ stream keyed by the seed and the unordered pair, so
//! `V_ij = V_ji` exactly and every column is the same whatever the thread that computes it.

use crate::backend::{FormFactorBackend, PairEntries};
use crate::ff_point_polygon::{MAX_CLIPPED, clip_above, distance_to_polygon, point_to_polygon, point_to_polygon_each};
use crate::guard::ClampCounter;
use crate::pair_visibility::{self, RayBudget, SamplingPath};
use crate::quadrature::{Panel, for_each_point_in, gauss_legendre, order_for, parametrisation};
use crate::rays::ShadowSegment;
use crate::visibility_cache::{CacheFigures, Record, VisibilityCache};
use radiosity_core::column::F64_PAIR_RECIPROCITY;
use radiosity_core::{ColumnSource, Patch, Real, Scene, Vec3};
use radiosity_geom::{ParamDoc, SceneAnalysis, Visibility};
use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;
use std::sync::{Arc, RwLock};

/// Parameters of the analytic backend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnalyticParams {
    /// The largest number of Gauss–Legendre points per direction on the receiving patch.
    pub order: usize,
    /// The relative quadrature error each pair's order is chosen to meet (1 = centroid).
    pub tolerance: f64,
    /// The fewest shadow rays of a pair, when the scene needs visibility.
    pub rays: usize,
    /// The shadow rays of a partially visible pair whose larger unoccluded form factor is 1:
    /// a pair gets `budget` times its larger unoccluded form factor, at least `rays`, and
    /// stiff scenes more ([`crate::pair_visibility::stiffness_factor`]).
    pub budget: usize,
    /// Seed of the shadow rays.
    pub seed: u64,
    /// Mebibytes of recorded visible fractions, so that a pair is traced once
    /// ([`crate::visibility_cache`]; 0: none). It changes no entry, so the canonical argument
    /// leaves it out and caches of matrices and references ignore it.
    pub cache_mib: usize,
}

/// Parameters of `analytic`.
pub const ANALYTIC_PARAMS: &[ParamDoc] = &[
    ParamDoc {
        key: "order",
        default: "8",
        doc: "largest Gauss-Legendre order on the receiver, 1 to 32 (1 = centroid only)",
    },
    ParamDoc { key: "tol", default: "1e-3", doc: "relative quadrature error each pair's order aims at, in (0, 1]" },
    ParamDoc {
        key: "rays",
        default: "1",
        doc: "fewest shadow rays per pair, 1 to 2^20 (none when nothing can occlude)",
    },
    ParamDoc {
        key: "budget",
        default: "24576",
        doc: "shadow rays of a partly visible pair per unit of its larger unoccluded form factor, 0 to 2^24 \
              (times ((1 - 0.8) / (1 - mean ρ))², at most 64, in scenes whose mean ρ exceeds 0.8)",
    },
    ParamDoc { key: "seed", default: "0", doc: "seed of the shadow rays" },
    ParamDoc {
        key: "cache",
        default: "256",
        doc: "MiB of recorded visible fractions, so that no pair is traced twice, 0 to 2^20 (changes no value)",
    },
];

impl Default for AnalyticParams {
    fn default() -> Self {
        AnalyticParams { order: 8, tolerance: 1e-3, rays: 1, budget: 24576, seed: 0, cache_mib: 256 }
    }
}

/// Areas of a pair closer than this, relative to the larger, count as equal when choosing the
/// patch a pair is integrated over (the lower index then).
const AREA_TIE: Real = 1e-9;
/// Relative tolerance (of the scene diagonal) for "behind a plane".
const PLANE_TOLERANCE: Real = 1e-9;
/// How many times a receiver panel may be quartered near the shooter (panels down to
/// `2^-12` of the patch).
const MAX_DEPTH: u32 = 12;
/// How many panels one pair may be cut into in all. Grading towards a shared edge needs a
/// few per level; patches nearly on top of each other (a thin slab) would otherwise split
/// everywhere at every level.
const PANEL_BUDGET: usize = 256;

/// Analytic form-factor columns of one scene.
#[derive(Debug)]
pub struct AnalyticColumns<'a> {
    scene: &'a Scene,
    visibility: Option<Visibility>,
    /// Gauss–Legendre nodes for orders 1 to `order` (index `q − 1`).
    nodes: Vec<Vec<(Real, Real)>>,
    /// The longest edge of each patch, the scale of its quadrature error.
    longest_edge: Vec<Real>,
    /// The largest distance from each patch's centroid to its vertices.
    reach: Vec<Real>,
    params: AnalyticParams,
    /// Shadow rays per unit of unoccluded form factor: `params.budget` times the scene's
    /// stiffness factor ([`pair_visibility::stiffness_factor`]).
    budget: usize,
    tolerance: Real,
    clamped: ClampCounter,
    /// The visible fractions of the pairs of every column and row computed so far, while
    /// their budget lasts ([`crate::visibility_cache`]); none when no ray is traced. Behind a
    /// lock only so that [`ColumnSource::reset_memory`] can start a fresh one: each line takes
    /// its own handle once.
    cache: Option<RwLock<Arc<VisibilityCache>>>,
    /// The cache's budget in bytes.
    cache_bytes: usize,
}

impl<'a> AnalyticColumns<'a> {
    /// Prepares the backend: quadrature points on every patch, and visibility only when the
    /// analysis says something can occlude.
    pub fn new(
        scene: &'a Scene,
        visibility: &Visibility,
        analysis: &SceneAnalysis,
        params: AnalyticParams,
    ) -> AnalyticColumns<'a> {
        AnalyticColumns {
            scene,
            visibility: analysis.occlusion.value.then(|| visibility.clone()),
            nodes: (1..=params.order.max(1)).map(gauss_legendre).collect(),
            longest_edge: scene.patches().iter().map(longest_edge).collect(),
            reach: scene.patches().iter().map(reach).collect(),
            budget: params.budget.saturating_mul(pair_visibility::stiffness_factor(stiffest_channel(scene))),
            params,
            tolerance: PLANE_TOLERANCE * scene.diagonal(),
            clamped: ClampCounter::default(),
            cache: analysis.occlusion.value.then(|| {
                RwLock::new(Arc::new(VisibilityCache::new(scene.len(), params.cache_mib.saturating_mul(1 << 20))))
            }),
            cache_bytes: params.cache_mib.saturating_mul(1 << 20),
        }
    }

    /// What the record of visible fractions holds and has saved, when rays are traced.
    pub fn visibility_cache(&self) -> Option<CacheFigures> {
        self.cache_handle().map(|c| c.figures())
    }

    /// The current record of visible fractions, when rays are traced.
    fn cache_handle(&self) -> Option<Arc<VisibilityCache>> {
        // A poisoned lock only means a column panicked elsewhere; the records stay valid.
        self.cache.as_ref().map(|lock| lock.read().unwrap_or_else(|e| e.into_inner()).clone())
    }

    /// Shadow rays per unit of unoccluded form factor in this scene: `budget` times the
    /// stiffness factor of its most reflective channel.
    pub fn ray_budget(&self) -> usize {
        self.budget
    }

    /// Whether shadow rays are traced.
    pub fn traces_shadow_rays(&self) -> bool {
        self.visibility.is_some()
    }

    /// Entries clamped into `[0, 1]` so far.
    pub fn clamped(&self) -> u64 {
        self.clamped.count()
    }

    /// The rays a pair gets: at least `rays`, and `budget` (times the scene's stiffness
    /// factor) per unit of its larger unoccluded form factor.
    fn ray_budget_of_pairs(&self) -> RayBudget {
        RayBudget { rays: self.params.rays, per_unit: self.budget }
    }

    /// `F_ij` before clamping, computed afresh (no record is read or written).
    pub fn pair(&self, i: usize, j: usize) -> Real {
        self.pair_known(i, j, None).0
    }

    /// [`AnalyticColumns::pair`], asking `clear` first, with the shadow rays the pair would
    /// trace, whether the pair is known to see itself whole (nothing lies between the two
    /// patches): then no ray is traced, and the entry is the one all-clear rays give. With the
    /// entry, the shadow rays it traced.
    pub fn pair_unless_clear(&self, i: usize, j: usize, clear: impl FnOnce(usize) -> bool) -> (Real, u64) {
        let Some(vis) = &self.visibility else { return (self.pair(i, j), 0) };
        let known = |rays: usize| clear(rays).then_some(1.0);
        let mut rays = 0;
        let f = self
            .pair_traced(i, j, known, &mut |p, from, q, to| {
                rays += 1;
                vis.unoccluded_between(p, from, q, to)
            })
            .0;
        (f, rays)
    }

    /// `F_ij` before clamping, with `V_ij = known` when it is given, and the visible fraction
    /// the entry used (`None` when the pair needed none).
    fn pair_known(&self, i: usize, j: usize, known: Option<Real>) -> (Real, Option<Real>) {
        match &self.visibility {
            Some(vis) => {
                self.pair_traced(i, j, |_| known, &mut |p, from, q, to| vis.unoccluded_between(p, from, q, to))
            }
            // Never called: nothing is traced without visibility.
            None => self.pair_traced(i, j, |_| None, &mut |_, _, _, _| true),
        }
    }

    /// Column (`column` true) or row `p` into `out`: entries `F_kp` or `F_pk`, in parallel.
    /// Visible fractions come from the record of `p` when there is one, otherwise from the
    /// record of each `k` that has one, and the ones used are recorded as `p`'s while the
    /// budget lasts ([`crate::visibility_cache`]). The entries are the same either way.
    fn fill_line(&self, p: usize, out: &mut [Real], column: bool) {
        let n = out.len();
        let entry = |k: usize, known: Option<Real>| {
            let (i, j) = if column { (k, p) } else { (p, k) };
            self.pair_known(i, j, known)
        };
        let handle = self.cache_handle();
        let cache = handle.as_deref();
        let own = cache.and_then(|c| c.record(p));
        let keep = cache.is_some_and(|c| own.is_none() && c.has_room(n));
        let known = |k: usize| match (cache, own) {
            (_, Some(record)) => record.get(k),
            (Some(c), None) => c.record(k).and_then(|record| record.get(p)),
            (None, None) => None,
        };
        let mut visible = if keep { vec![None; n] } else { Vec::new() };
        let reused: u64 = if keep {
            out.par_iter_mut()
                .zip(visible.par_iter_mut())
                .with_min_len(PAIRS_PER_TASK)
                .enumerate()
                .map(|(k, (f, v))| {
                    let given = known(k);
                    (*f, *v) = entry(k, given);
                    u64::from(given.is_some())
                })
                .sum()
        } else {
            out.par_iter_mut()
                .with_min_len(PAIRS_PER_TASK)
                .enumerate()
                .map(|(k, f)| {
                    let given = known(k);
                    *f = entry(k, given).0;
                    u64::from(given.is_some())
                })
                .sum()
        };
        if let Some(cache) = cache {
            cache.count_reused(reused);
            if keep {
                cache.insert(p, Record::new(&visible));
            }
        }
        self.clamped.clamp(out);
    }

    /// Appends to `out` every shadow-ray segment that computing column `j` traces, in the
    /// order the column traces them (receivers `i` in index order): nothing when the analysis
    /// says nothing can occlude. It runs the same code as [`ColumnSource::fill_column`], the
    /// kernel included (a segment is traced only for pairs whose unoccluded form factor is
    /// not zero), with each segment recorded instead of traced, so the segments are exactly
    /// those of the column and the column's values do not change. `cargo xtask bench` traces
    /// them straight through the BVH to set the backend against the ray-tracing limit.
    pub fn shadow_segments(&self, j: usize, out: &mut Vec<ShadowSegment>) {
        if self.visibility.is_none() {
            return;
        }
        for i in 0..self.scene.len() {
            self.pair_traced(i, j, |_| None, &mut |p, from, q, to| {
                out.push(ShadowSegment { p, from, q, to });
                true
            });
        }
    }

    /// `F_ij` before clamping and the visible fraction it used (`None` when the pair needed
    /// none), with `trace(p, from, q, to)` answering whether the segment from `p` on patch
    /// `from` to `q` on patch `to` is unoccluded; it is called only when shadow rays are
    /// traced and `known`, asked with the rays the pair would trace, does not give the visible
    /// fraction.
    fn pair_traced(
        &self,
        i: usize,
        j: usize,
        known: impl FnOnce(usize) -> Option<Real>,
        trace: &mut impl FnMut(Vec3, usize, Vec3, usize) -> bool,
    ) -> (Real, Option<Real>) {
        let Some(Roles { s, l, larger, unoccluded }) = self.roles(i, j) else { return (0.0, None) };
        match &self.visibility {
            Some(_) => {
                let v = known(self.ray_budget_of_pairs().rays(larger))
                    .unwrap_or_else(|| self.visible_fraction(s, l, larger, trace));
                (unoccluded * v, Some(v))
            }
            None => (unoccluded, None),
        }
    }

    /// The roles of the pair `(i, j)` and its unoccluded factors; `None` when `F_ij` is zero
    /// before visibility (`i = j`, either patch behind the other, or no flux).
    fn roles(&self, i: usize, j: usize) -> Option<Roles> {
        if i == j {
            return None;
        }
        let (pi, pj) = (&self.scene.patches()[i], &self.scene.patches()[j]);
        if behind(pj, pi, self.tolerance) || behind(pi, pj, self.tolerance) {
            return None;
        }
        // One rule for the unordered pair: integrate over the smaller patch (the lower index
        // on a tie) and take the other entry by reciprocity, so `A_i F_ij = A_j F_ji` holds to
        // round-off (module doc, "Reciprocity").
        // Areas equal to 1e-9 count as equal, so that the choice does not flip with the
        // round-off of a scaled or moved copy of the scene.
        let (ai, aj) = (pi.area(), pj.area());
        let smaller = if (ai - aj).abs() <= AREA_TIE * ai.max(aj) { i < j } else { ai < aj };
        // The pair's larger entry, the unoccluded factor of its smaller patch.
        let larger = if smaller { self.unoccluded(i, j, pi, pj) } else { self.unoccluded(j, i, pj, pi) };
        if larger == 0.0 {
            return None;
        }
        let unoccluded = if smaller { larger } else { larger * aj / ai };
        let (s, l) = if smaller { (i, j) } else { (j, i) };
        Some(Roles { s, l, larger, unoccluded })
    }

    /// `F_ij` before clamping, computed afresh as [`AnalyticColumns::pair`] does, and the
    /// shadow rays it traced: what a benchmark times pair by pair.
    pub fn pair_counting_rays(&self, i: usize, j: usize) -> (Real, usize) {
        let (value, rays) = self.pair_unless_clear(i, j, |_| false);
        (value, rays as usize)
    }

    /// How the visible fraction of the pair `(i, j)` is sampled
    /// ([`pair_visibility::sampling_path`]), found without sampling; `None` when it traces no
    /// ray (no visibility needed, or `F_ij` zero before visibility).
    pub fn sampling_path(&self, i: usize, j: usize) -> Option<SamplingPath> {
        self.visibility.as_ref()?;
        let Roles { s, l, larger, .. } = self.roles(i, j)?;
        let patches = self.scene.patches();
        pair_visibility::sampling_path(&patches[s], &patches[l], larger, self.ray_budget_of_pairs(), self.tolerance)
    }

    /// `(1/A_i) ∫_{A_i} F(dA_x → P_j) dA_x`.
    ///
    /// Points of `P_i` behind `P_j`'s plane contribute nothing. When that plane cuts `P_i`,
    /// the integrand has a kink along the cut, where Gauss–Legendre converges slowly; so the
    /// part of `P_i` in front is cut out exactly, fanned into triangles, and each integrated
    /// on its own.
    fn unoccluded(&self, i: usize, j: usize, pi: &Patch, pj: &Patch) -> Real {
        let (nj, oj) = (pj.normal(), pj.vertices()[0]);
        let shooter = Shooter { patch: pj, reach: self.reach[j] };
        // Distant pairs: the centroid rule meets the tolerance, and no cut is needed (a kink
        // far from the shooter costs little, since it is seen nearly edge-on there).
        let bound = (pi.centroid() - pj.centroid()).length() - self.reach[j];
        if order_for(bound, self.longest_edge[i], self.params.tolerance, 1).is_some() {
            let c = pi.centroid();
            return if nj.dot(c - oj) > 0.0 { point_to_polygon(c, pi.normal(), pj.vertices()) } else { 0.0 };
        }
        let mut front = [Vec3::ZERO; MAX_CLIPPED];
        // Clip against the plane moved a hair forward, so points on it count as behind.
        let count = clip_above(oj + nj * self.tolerance, nj, pi.vertices(), &mut front);
        // The receiver, or the triangles of its part in front (at most MAX_CLIPPED − 2), with
        // their longest edges; on the stack, since a pair allocates nothing.
        let mut pieces: [(Patch, Real); MAX_CLIPPED] = std::array::from_fn(|_| (pi.clone(), self.longest_edge[i]));
        let mut len = 1;
        if count != pi.vertices().len() || front[..count] != *pi.vertices() {
            len = 0;
            for k in 1..count.saturating_sub(1) {
                // A sliver too thin to be a patch carries no measurable flux.
                if let Ok(piece) = Patch::triangle([front[0], front[k], front[k + 1]], pi.material, pi.object) {
                    let edge = longest_edge(&piece);
                    pieces[len] = (piece, edge);
                    len += 1;
                }
            }
        }
        let pieces = &pieces[..len];
        // Pieces that the rule meets whole need no list of panels.
        let orders: [Option<usize>; MAX_CLIPPED] = std::array::from_fn(|k| {
            pieces.get(k).and_then(|(piece, edge)| self.panel_order(piece, *edge, shooter, Panel::WHOLE))
        });
        if orders[..len].iter().all(Option::is_some) {
            let whole = pieces.iter().zip(orders);
            return whole
                .map(|((piece, _), q)| self.panel_rule(piece, shooter, Panel::WHOLE, q.unwrap()))
                .sum::<Real>()
                / pi.area();
        }
        self.integrate_by_levels(pieces, shooter) / pi.area()
    }

    /// `∫ F(dA_x → P_j) dA_x` over `pieces` (patches and their longest edges): on each panel,
    /// Gauss–Legendre of the smallest order predicted to meet the tolerance at its distance
    /// from `P_j`, or, if none is, the sum over its quarters, while depth and the pair's panel
    /// budget last; near a shared edge this grades panels geometrically towards it. Panels are
    /// quartered a level at a time, every panel of a level before any of the next, so that a
    /// budget that runs out is spread over the receiver, not spent on its first corner.
    fn integrate_by_levels(&self, pieces: &[(Patch, Real)], shooter: Shooter<'_>) -> Real {
        // A level holds at most the pieces and four panels for each four of the budget; two
        // levels on the stack, since a pair allocates nothing.
        const MOST: usize = MAX_CLIPPED + PANEL_BUDGET;
        let mut budget = PANEL_BUDGET;
        let (mut level, mut next) = ([(0, Panel::WHOLE); MOST], [(0, Panel::WHOLE); MOST]);
        let mut len = pieces.len();
        for (k, slot) in level.iter_mut().enumerate().take(len) {
            *slot = (k, Panel::WHOLE);
        }
        let mut sum = 0.0;
        for depth in 0..=MAX_DEPTH {
            let mut filled = 0;
            for &(k, panel) in &level[..len] {
                let (piece, edge) = (&pieces[k].0, pieces[k].1);
                match self.panel_order(piece, edge, shooter, panel) {
                    None if depth < MAX_DEPTH && budget >= 4 => {
                        budget -= 4;
                        for q in panel.quarters() {
                            next[filled] = (k, q);
                            filled += 1;
                        }
                    }
                    order => sum += self.panel_rule(piece, shooter, panel, order.unwrap_or(self.params.order)),
                }
            }
            if filled == 0 {
                break;
            }
            (level, next, len) = (next, level, filled);
        }
        sum
    }

    /// The smallest order predicted to meet the tolerance on `panel` of `pi` (longest edge
    /// `edge`) at its distance from the shooter, or `None` when even `order` is not.
    fn panel_order(&self, pi: &Patch, edge: Real, shooter: Shooter<'_>, panel: Panel) -> Option<usize> {
        let pj = shooter.patch;
        let centre = parametrisation(pi, 0.5 * (panel.lo.0 + panel.hi.0), 0.5 * (panel.lo.1 + panel.hi.1)).0;
        let h = edge * panel.extent();
        // The distance to P_j's centroid less its reach is a cheap lower bound on the distance
        // to P_j; when it already allows the centroid rule, the exact distance is not needed.
        let bound = (centre - pj.centroid()).length() - shooter.reach;
        let d = if order_for(bound, h, self.params.tolerance, 1).is_some() {
            bound
        } else {
            distance_to_polygon(centre, pj.vertices(), pj.normal())
        };
        order_for(d, h, self.params.tolerance, self.params.order)
    }

    /// `∫_panel F(dA_x → P_j) dA_x` by Gauss–Legendre of `order`.
    fn panel_rule(&self, pi: &Patch, shooter: Shooter<'_>, panel: Panel, order: usize) -> Real {
        let pj = shooter.patch;
        // Four points at a time on SIMD lanes ([`point_to_polygon_x4`], bit for bit the
        // one-point values), summed in the rule's order.
        let mut sum = 0.0;
        let (mut points, mut weights) = ([Vec3::ZERO; 4], [0.0; 4]);
        let mut filled = 0;
        let flush = |points: &[Vec3], weights: &[Real], sum: &mut Real| {
            let mut values = [0.0; 4];
            point_to_polygon_each(points, pi.normal(), pj.vertices(), &mut values[..points.len()]);
            for (w, f) in weights.iter().zip(values) {
                *sum += w * f;
            }
        };
        for_each_point_in(pi, panel, &self.nodes[order - 1], |x, w| {
            (points[filled], weights[filled]) = (x, w);
            filled += 1;
            if filled == 4 {
                flush(&points, &weights, &mut sum);
                filled = 0;
            }
        });
        flush(&points[..filled], &weights[..filled], &mut sum);
        sum
    }

    /// The kernel-weighted visible fraction of the pair of the smaller patch `s` and the larger
    /// `l` ([`crate::pair_visibility`], which stratifies the points of the first patch it is
    /// given), the same for `(i, j)` and `(j, i)`: the roles follow the areas, as the quadrature
    /// does, and the stream the unordered pair.
    fn visible_fraction(
        &self,
        s: usize,
        l: usize,
        larger: Real,
        trace: &mut impl FnMut(Vec3, usize, Vec3, usize) -> bool,
    ) -> Real {
        let patches = self.scene.patches();
        let mut rng = pair_rng(self.params.seed, s.min(l), s.max(l));
        pair_visibility::visible_fraction(
            (&patches[s], s),
            (&patches[l], l),
            larger,
            self.ray_budget_of_pairs(),
            self.tolerance,
            &mut rng,
            trace,
        )
    }
}

/// The largest over channels of the area-weighted mean reflectivity: how strongly the scene
/// amplifies an error in its row sums.
fn stiffest_channel(scene: &Scene) -> Real {
    let mut weighted = [0.0; 3];
    for (i, p) in scene.patches().iter().enumerate() {
        for (w, r) in weighted.iter_mut().zip(scene.reflectivity(i).0) {
            *w += p.area() * r;
        }
    }
    weighted.into_iter().fold(0.0, Real::max) / scene.total_area()
}

/// The random stream of the unordered pair `lo < hi`: Xoshiro256++ seeded from the seed and
/// the pair (its SplitMix64 seeding decorrelates neighbouring pairs). A stream per pair makes
/// every pair's samples independent of the order and thread in which pairs are computed;
/// seeding ChaCha8 per pair took 8% of the backend's time, Xoshiro's seeding a few
/// nanoseconds. The algorithm is fixed by `rand_xoshiro`, so seeds give the same numbers
/// across versions and platforms.
fn pair_rng(seed: u64, lo: usize, hi: usize) -> Xoshiro256PlusPlus {
    let pair = ((lo as u64) << 32) | hi as u64;
    Xoshiro256PlusPlus::seed_from_u64(pair ^ seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).rotate_left(29))
}

/// The roles of a pair whose entries are not zero before visibility: the smaller patch `s`
/// (integrated over, its points stratified), the larger `l`, the larger entry `F_sl`
/// unoccluded, and the asked-for entry unoccluded.
struct Roles {
    s: usize,
    l: usize,
    larger: Real,
    unoccluded: Real,
}

/// The shooting patch of a pair, with its reach (centroid to farthest vertex).
#[derive(Clone, Copy)]
struct Shooter<'p> {
    patch: &'p Patch,
    reach: Real,
}

/// The largest distance from a patch's centroid to its vertices.
fn reach(p: &Patch) -> Real {
    p.vertices().iter().map(|v| (*v - p.centroid()).length_squared()).fold(0.0, Real::max).sqrt()
}

/// The longest edge of a patch.
fn longest_edge(p: &Patch) -> Real {
    let v = p.vertices();
    (0..v.len()).map(|k| (v[(k + 1) % v.len()] - v[k]).length()).fold(0.0, Real::max)
}

/// True when every vertex of `a` lies on or behind the plane of `b`.
fn behind(a: &Patch, b: &Patch, tolerance: Real) -> bool {
    let (n, o) = (b.normal(), b.centroid());
    a.vertices().iter().all(|v| n.dot(*v - o) <= tolerance)
}

/// Pairs computed by one rayon task: enough to outweigh the task's cost (a pair costs a few
/// hundred nanoseconds to microseconds).
const PAIRS_PER_TASK: usize = 64;

impl ColumnSource for AnalyticColumns<'_> {
    fn patch_count(&self) -> usize {
        self.scene.len()
    }

    /// The pairs of a column are independent, so they are computed on rayon's threads: a
    /// solver asks for one column at a time, and this is where its second core goes to work.
    /// Each entry is the same whichever thread computes it.
    fn fill_column(&self, j: usize, column: &mut [Real]) {
        self.fill_line(j, column, true);
    }

    /// Every pair is computed on its own, whichever column asks, so row `i` holds exactly the
    /// entries the columns hold, at the cost of one column.
    fn fill_row(&self, i: usize, row: &mut [Real]) -> bool {
        self.fill_line(i, row, false);
        true
    }

    /// Each unordered pair is integrated once and the other entry taken by reciprocity in
    /// `f64`; the guard's clamping into `[0, 1]` (counted by [`AnalyticColumns::clamped`])
    /// is the one exception, and moves a pair's entries only where the estimate left `[0, 1]`.
    fn reciprocity_bound(&self) -> Option<Real> {
        Some(F64_PAIR_RECIPROCITY)
    }

    /// Starts an empty record of visible fractions: later columns cost what the first ones did.
    fn reset_memory(&self) {
        if let Some(lock) = &self.cache {
            let fresh = Arc::new(VisibilityCache::new(self.scene.len(), self.cache_bytes));
            *lock.write().unwrap_or_else(|e| e.into_inner()) = fresh;
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
