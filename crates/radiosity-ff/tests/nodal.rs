//! Tests of the hierarchical operator's links shown to solvers (`LinkSource`): every node
//! sending the charges of one vector gives the product; each node sends a disjoint part of a
//! column; blocks hold the columns' entries; and the send shares are the largest shares the
//! nodes send.

use radiosity_core::{ColumnSource, LinkSource, Real};
use radiosity_ff::{HierarchicalColumns, HierarchicalParams};
use radiosity_geom::PreparedScene;

/// The Cornell box at a coarse threshold: far links between clusters, to first order and to
/// zeroth, near links and far pairs (as `hierarchical.rs` checks).
fn operator() -> (PreparedScene, HierarchicalColumns) {
    let p = PreparedScene::load("cornell:res=6").unwrap();
    let params = HierarchicalParams { eps: 0.05, ..HierarchicalParams::default() };
    let f = HierarchicalColumns::new(p.scene(), &p.visibility().unwrap(), &p.analysis, params);
    (p, f)
}

/// What the nodes marked in `sending` send of `x` (`channels` channels), evaluated.
fn sent(f: &HierarchicalColumns, x: &[Real], channels: usize, sending: &[bool]) -> Vec<Real> {
    let nodes = f.parents().len();
    let mut charges = vec![0.0; nodes * channels * f.charge_len()];
    let mut fields = vec![0.0; nodes * channels * f.field_len()];
    f.charges(x, channels, &mut charges);
    f.shoot(&charges, sending, channels, &mut fields);
    let mut out = vec![0.0; f.patch_count() * channels];
    f.evaluate(&mut fields, channels, &mut out);
    assert!(fields.iter().all(|v| *v == 0.0), "evaluating clears the fields");
    out
}

/// The nodes from the leaf of `patch` to the root.
fn ancestors(f: &HierarchicalColumns, patch: usize) -> Vec<usize> {
    let mut k = f.leaves()[patch];
    let mut path = Vec::new();
    while k != radiosity_core::NO_PARENT {
        path.push(k as usize);
        k = f.parents()[k as usize];
    }
    path
}

#[test]
fn every_node_sending_one_vector_gives_the_product() {
    let (_, f) = operator();
    let n = f.patch_count();
    let x: Vec<Real> = (0..3 * n).map(|k| 0.1 + ((k * 7919) % 101) as Real / 101.0).collect();
    let all = vec![true; f.parents().len()];
    let by_links = sent(&f, &x, 3, &all);
    let mut product = vec![0.0; 3 * n];
    assert!(f.multiply(&x, 3, &mut product));
    let scale = product.iter().fold(0.0, |m: Real, v| m.max(v.abs()));
    for (a, b) in by_links.iter().zip(&product) {
        // The same moments and forms in another order of summation: a few roundings apart.
        assert!((a - b).abs() <= 1e-12 * scale, "{a} by the links, {b} by the product");
    }
}

#[test]
fn the_ancestors_of_a_patch_send_disjoint_parts_of_its_column() {
    let (_, f) = operator();
    let n = f.patch_count();
    let nodes = f.parents().len();
    let mut column = vec![0.0; n];
    for j in (0..n).step_by(7) {
        f.fill_column(j, &mut column);
        let mut x = vec![0.0; n];
        x[j] = 1.0;
        let mut covered = vec![0.0; n];
        let mut parts = 0;
        for k in ancestors(&f, j) {
            let mut sending = vec![false; nodes];
            sending[k] = true;
            let part = sent(&f, &x, 1, &sending);
            for i in 0..n {
                assert!(part[i] >= -1e-15, "node {k} sends {} to {i} from {j}", part[i]);
                if part[i] > 0.0 {
                    assert_eq!(covered[i], 0.0, "F_{i}{j} sent by two nodes");
                    covered[i] = part[i];
                }
            }
            parts += usize::from(part.iter().any(|v| *v > 0.0));
        }
        for i in 0..n {
            assert!((covered[i] - column[i]).abs() <= 1e-12 * column[i].abs().max(1e-3), "F_{i}{j}");
        }
        assert!(parts >= 1);
    }
}

#[test]
fn a_block_holds_the_columns_entries() {
    let (_, f) = operator();
    let n = f.patch_count();
    let patches: Vec<usize> = (0..n).step_by(5).chain([1, 2, 3]).collect();
    let m = patches.len();
    let mut block = vec![0.0; m * m];
    f.block(&patches, &mut block);
    let mut column = vec![0.0; n];
    let mut nonzero = 0;
    for (b, &j) in patches.iter().enumerate() {
        f.fill_column(j, &mut column);
        for (a, &i) in patches.iter().enumerate() {
            assert_eq!(block[a * m + b], column[i], "F_{i}{j}");
            nonzero += usize::from(column[i] > 0.0);
        }
    }
    assert!(nonzero > m, "{nonzero} entries of {m} × {m} are not zero");
}

#[test]
fn a_send_share_is_the_largest_share_its_node_sends() {
    let (p, f) = operator();
    let n = f.patch_count();
    let nodes = f.parents().len();
    let rho: Vec<Real> = (0..n).map(|i| p.scene().reflectivity(i).0[1]).collect();
    let area: Vec<Real> = p.scene().patches().iter().map(|q| q.area()).collect();
    let mut shares = vec![0.0; nodes];
    assert!(f.send_shares(&rho, 1, &mut shares));
    // The share node k sends from each of its patches j, Σ_i ρ_i A_i (S_k)_ij / A_j.
    let mut largest = vec![0.0 as Real; nodes];
    for j in 0..n {
        let mut x = vec![0.0; n];
        x[j] = 1.0;
        for k in ancestors(&f, j) {
            let mut sending = vec![false; nodes];
            sending[k] = true;
            let part = sent(&f, &x, 1, &sending);
            let share: Real = (0..n).map(|i| rho[i] * area[i] * part[i]).sum::<Real>() / area[j];
            largest[k] = largest[k].max(share);
        }
    }
    for k in 0..nodes {
        // Raised by a relative 1e-9 against rounding; computed by reciprocity, a few roundings
        // from the entries' own sum.
        assert!(shares[k] >= largest[k], "node {k}: share {} below {}", shares[k], largest[k]);
        assert!(shares[k] <= largest[k] * (1.0 + 1e-8) + 1e-15, "node {k}: share {} above {}", shares[k], largest[k]);
    }
    assert!(largest.iter().any(|s| *s > 0.0));
}
