//! `--ff matrix`: over the analytic backend it is assembled each pair once, the other entry by
//! reciprocity, in parallel, with the same bits whatever the thread count and the very entries
//! the columns give; over a backend that is not reciprocal it is assembled column by column.

use radiosity_core::{ColumnSource, Real};
use radiosity_eval::NoProgress;
use radiosity_eval::{assembly_of, obtain_matrix};
use radiosity_ff::{BackendSpec, StoredMatrix};
use radiosity_geom::PreparedScene;

/// The matrix `spec` names, assembled fresh on a pool of `threads` threads.
fn assembled(prepared: &PreparedScene, spec: &BackendSpec, threads: usize) -> StoredMatrix {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| obtain_matrix(prepared, spec, None, &NoProgress).unwrap().matrix)
}

fn columns(m: &dyn ColumnSource) -> Vec<Vec<Real>> {
    let n = m.patch_count();
    (0..n)
        .map(|j| {
            let mut c = vec![0.0; n];
            m.fill_column(j, &mut c);
            c
        })
        .collect()
}

#[test]
fn an_analytic_matrix_is_assembled_each_pair_once_reciprocal_and_thread_independent() {
    // An occluded scene, so that shadow rays decide part of every entry.
    let prepared = PreparedScene::load("cornell:res=2").unwrap();
    assert!(prepared.analysis.occlusion.value, "the Cornell box's blocks occlude");
    let spec = BackendSpec::parse("matrix:of=analytic:budget=1024").unwrap();
    assert_eq!(assembly_of(&spec), "each pair once");
    let one = assembled(&prepared, &spec, 1);
    let two = assembled(&prepared, &spec, 2);
    assert_eq!(one.to_bytes("k"), two.to_bytes("k"), "1 and 2 threads assemble different bits");

    let area: Vec<Real> = prepared.scene().patches().iter().map(|p| p.area()).collect();
    let stored = columns(&one);
    let direct = columns(&spec.columns().build((&prepared).try_into().unwrap()).unwrap());
    let n = area.len();
    let mut nonzero = 0;
    for j in 0..n {
        for i in 0..n {
            let (f_ij, f_ji) = (stored[j][i], stored[i][j]);
            // The same entries as the columns, to the f32 rounding of storage.
            assert!(
                (f_ij - direct[j][i]).abs() <= 2e-7 * direct[j][i].abs(),
                "({i}, {j}): {f_ij} against the column's {}",
                direct[j][i]
            );
            // Reciprocal to that rounding.
            let (g_ij, g_ji) = (area[i] * f_ij, area[j] * f_ji);
            assert!((g_ij - g_ji).abs() <= 2e-7 * g_ij.max(g_ji), "({i}, {j}): A_i F_ij = {g_ij}, A_j F_ji = {g_ji}");
            nonzero += usize::from(f_ij > 0.0);
        }
    }
    assert!(nonzero > n * n / 4, "only {nonzero} non-zero entries of {}", n * n);
}

#[test]
fn a_hemicube_matrix_is_assembled_column_by_column() {
    let prepared = PreparedScene::load("cornell:res=2").unwrap();
    let spec = BackendSpec::parse("matrix:of=hemicube:res=32").unwrap();
    assert_eq!(assembly_of(&spec), "column by column");
    let stored = columns(&assembled(&prepared, &spec, 2));
    let direct = columns(&spec.columns().build((&prepared).try_into().unwrap()).unwrap());
    for (j, (s, d)) in stored.iter().zip(&direct).enumerate() {
        for (i, (a, b)) in s.iter().zip(d).enumerate() {
            assert_eq!(*a, *b as f32 as Real, "({i}, {j})");
        }
    }
}
