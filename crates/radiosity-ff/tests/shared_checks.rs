//! What the tests on built-in scenes (`lib.rs`'s modules) and on scenes written by others
//! (`third_party_scenes.rs`) both use: row sums column by column, and the check that shaft
//! culling changes nothing in the hierarchical operator.

use radiosity_core::{ColumnSource, Real};
use radiosity_ff::{HierarchicalColumns, HierarchicalParams};
use radiosity_geom::PreparedScene;

/// The row sums of `f`, column by column.
pub fn row_sums(f: &impl ColumnSource) -> Vec<Real> {
    let n = f.patch_count();
    let mut sums = vec![0.0; n];
    let mut column = vec![0.0; n];
    for j in 0..n {
        f.fill_column(j, &mut column);
        for (s, c) in sums.iter_mut().zip(&column) {
            *s += c;
        }
    }
    sums
}

/// With `shafts`, a link between patches or flat clusters whose shaft holds no other patch
/// is taken as clear without its rays: every segment they could draw lies in the shaft. So
/// the operator of `p` (scene argument `arg`) at threshold `eps` must be the same to the bit
/// with and without shafts, with fewer rays and some clear shafts.
pub fn clear_shafts_give_the_same_operator(p: &PreparedScene, arg: &str, eps: Real) {
    let build = |shafts: bool| {
        let params = HierarchicalParams { eps, shafts, ..HierarchicalParams::default() };
        HierarchicalColumns::new(p.scene(), &p.visibility().unwrap(), &p.analysis, params)
    };
    let (with, without) = (build(true), build(false));
    let (a, b) = (with.figures(), without.figures());
    assert!(a.clear_shafts > 0 && b.clear_shafts == 0, "{arg}: {} links seen through clear shafts", a.clear_shafts);
    assert!(a.rays <= b.rays, "{arg}: {} rays with shafts, {} without", a.rays, b.rays);
    assert_eq!(
        (a.far_links, a.near_links, a.far_pairs, a.zeroth_links, a.occluded),
        (b.far_links, b.near_links, b.far_pairs, b.zeroth_links, b.occluded),
        "{arg}"
    );
    let n = with.patch_count();
    let (mut x, mut y) = (vec![0.0; n], vec![0.0; n]);
    for j in 0..n {
        with.fill_column(j, &mut x);
        without.fill_column(j, &mut y);
        assert!(x.iter().zip(&y).all(|(u, v)| u.to_bits() == v.to_bits()), "{arg}: an entry of column {j} differs");
    }
}
