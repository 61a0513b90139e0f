//! Tests of the hierarchical operator split over ranks (threads standing in for MPI ranks):
//! the ranks' links are disjoint and together the single process's, and products, columns and
//! rows are the single process's to 1e-12, the same bits on every rank and on every run; each
//! rank traces only its links' rays and holds only their bytes, which fall as the ranks grow.

use radiosity_core::{Collective, ColumnSource, InProcessRanks, Real};
use radiosity_ff::{HierarchicalColumns, HierarchicalParams, HierarchyLink, RankFigures};
use radiosity_geom::PreparedScene;
use std::collections::HashSet;
use std::sync::Arc;

/// A rank's view of an operator split over `K` ranks: its links, its figures, and what it
/// computed with it.
struct RankResult {
    links: Vec<HierarchyLink>,
    product: Vec<Real>,
    column: Vec<Real>,
    row: Vec<Real>,
    figures: radiosity_ff::HierarchyFigures,
    /// Every rank's figures (none in one process).
    ranks: Vec<RankFigures>,
    /// The bytes of this rank's links.
    link_bytes: usize,
}

/// A vector of `3n` values, varied enough that no product is special.
fn vector(n: usize) -> Vec<Real> {
    (0..3 * n).map(|k| 1.0 + ((k * 7919) % 97) as Real / 50.0).collect()
}

fn line(f: &impl ColumnSource, j: usize, row: bool) -> Vec<Real> {
    let mut v = vec![0.0; f.patch_count()];
    if row {
        assert!(f.fill_row(j, &mut v));
    } else {
        f.fill_column(j, &mut v);
    }
    v
}

fn single(p: &PreparedScene, params: HierarchicalParams) -> RankResult {
    let f = HierarchicalColumns::new(p.scene(), &p.visibility().unwrap(), &p.analysis, params);
    run(&f)
}

/// Tasks a rank: many, so that the frontier every rank expands goes deep into these small
/// scenes and settles links on the way, which rank 0 alone keeps.
const TASKS_PER_RANK: usize = 64;

fn split(p: &PreparedScene, params: HierarchicalParams, ranks: usize) -> Vec<RankResult> {
    InProcessRanks::run(ranks, |rank| {
        let collective: Arc<dyn Collective> = rank;
        let f = HierarchicalColumns::new_distributed(
            p.scene(),
            &p.visibility().unwrap(),
            &p.analysis,
            params,
            &|_| {},
            collective,
            TASKS_PER_RANK,
        );
        run(&f)
    })
}

fn run(f: &HierarchicalColumns) -> RankResult {
    let n = f.patch_count();
    let mut product = vec![0.0; 3 * n];
    assert!(f.multiply(&vector(n), 3, &mut product));
    RankResult {
        links: f.links(),
        product,
        column: line(f, n / 3, false),
        row: line(f, 2 * n / 3, true),
        figures: f.figures(),
        ranks: f.distribution().map(|d| d.ranks().to_vec()).unwrap_or_default(),
        link_bytes: f.link_bytes(),
    }
}

fn relative_gap(a: &[Real], b: &[Real]) -> Real {
    let scale = b.iter().fold(0.0, |m: Real, v| m.max(v.abs()));
    a.iter().zip(b).fold(0.0, |m: Real, (x, y)| m.max((x - y).abs())) / scale
}

fn check(arg: &str, params: HierarchicalParams) {
    let p = PreparedScene::load(arg).unwrap();
    let one = single(&p, params);
    assert!(one.links.len() > 100, "{arg}: too few links ({}) to split", one.links.len());
    // The largest rank's link bytes on one, two and three ranks.
    let mut largest_share = vec![one.link_bytes as u64];
    for ranks in [2, 3] {
        let parts = split(&p, params, ranks);
        // Disjoint, and together the single process's links.
        let mut union = HashSet::new();
        for part in &parts {
            assert!(!part.links.is_empty(), "{arg}, {ranks} ranks: a rank built no link");
            for l in &part.links {
                assert!(union.insert(*l), "{arg}, {ranks} ranks: {l:?} built by two ranks");
            }
        }
        let expected: HashSet<_> = one.links.iter().copied().collect();
        assert_eq!(union, expected, "{arg}, {ranks} ranks: the ranks' links are not the single process's");
        for (r, part) in parts.iter().enumerate() {
            // The same bits on every rank.
            assert_eq!(
                part.product, parts[0].product,
                "{arg}, {ranks} ranks: rank {r}'s product differs from rank 0's"
            );
            assert_eq!(part.column, parts[0].column);
            assert_eq!(part.row, parts[0].row);
            // The whole operator's figures, on every rank, from every rank's.
            assert_eq!(part.figures.far_links, one.figures.far_links, "{arg}, {ranks} ranks");
            assert_eq!(part.figures.near_links, one.figures.near_links, "{arg}, {ranks} ranks");
            assert_eq!(part.figures.rays, one.figures.rays, "{arg}, {ranks} ranks: rays counted twice or lost");
            assert_eq!(part.ranks, parts[0].ranks, "{arg}, {ranks} ranks: rank {r} sees other figures");
        }
        // What each rank did: its share of the links and the rays, fewer than the whole and
        // together the whole, and of the links' bytes (coded by their gaps, so a rank's few
        // links cost a little more each); the top of the refinement is a stage of its own.
        let each = &parts[0].ranks;
        assert_eq!(each.len(), ranks);
        let sum = |f: fn(&RankFigures) -> u64| each.iter().map(f).sum::<u64>();
        assert_eq!(sum(|r| r.far_links), one.figures.far_links as u64, "{arg}, {ranks} ranks");
        assert_eq!(sum(|r| r.rays), one.figures.rays, "{arg}, {ranks} ranks: the ranks' rays are not the whole");
        assert_eq!(sum(|r| r.near_links), one.figures.near_links as u64, "{arg}, {ranks} ranks");
        for (r, (rank, part)) in each.iter().zip(&parts).enumerate() {
            assert_eq!(rank.link_bytes, part.link_bytes as u64, "{arg}, {ranks} ranks: rank {r}'s own bytes");
            assert!(rank.rays < one.figures.rays, "{arg}, {ranks} ranks: rank {r} traced every ray");
            assert!(rank.link_bytes < one.link_bytes as u64, "{arg}, {ranks} ranks: rank {r} holds every link");
            assert!(rank.stages.frontier > 0.0 && rank.stages.refinement > 0.0, "{arg}: {:?}", rank.stages);
        }
        largest_share.push(each.iter().map(|r| r.link_bytes).max().unwrap_or(0));
        // The single process's to the order of summation (and the closure weights' rounding).
        for (what, a, b) in [
            ("product", &parts[0].product, &one.product),
            ("column", &parts[0].column, &one.column),
            ("row", &parts[0].row, &one.row),
        ] {
            let gap = relative_gap(a, b);
            assert!(gap <= 1e-12, "{arg}, {ranks} ranks: the {what} is {gap:e} from one process's");
        }
        // Deterministic for a given number of ranks.
        let again = split(&p, params, ranks);
        assert_eq!(again[0].product, parts[0].product, "{arg}, {ranks} ranks: two runs differ");
    }
    assert!(largest_share.windows(2).all(|w| w[1] < w[0]), "{arg}: the largest rank's link bytes {largest_share:?}");
}

#[test]
fn ranks_build_disjoint_links_that_make_the_single_process_operator() {
    // A coarse threshold, so that these small scenes have far links between clusters.
    check("cornell:res=8", HierarchicalParams { eps: 0.05, ..HierarchicalParams::default() });
    check("multi-cubes", HierarchicalParams { eps: 0.02, ..HierarchicalParams::default() });
}

#[test]
fn an_occluded_scene_with_refinement_passes_and_shafts_splits_the_same_way() {
    // Occluders: links that split on their rays hand their segments to the tasks below them;
    // a second pass refines each rank's own far links again under the split operator's
    // radiosity; shafts search for candidates inherited from the tasks above.
    check(
        "furnace:block=true:res=8",
        HierarchicalParams { eps: 0.02, passes: 2, shafts: true, ..HierarchicalParams::default() },
    );
}
