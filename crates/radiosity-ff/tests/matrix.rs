//! Tests of the matrix backend: assembly against a known matrix, the dense or sparse choice,
//! files, determinism across thread counts, and rebalancing.

use radiosity_core::{ColumnSource, DenseColumns, Real};
use radiosity_ff::guard::matrix_figures;
use radiosity_ff::matrix::{FORMAT_VERSION, MAGIC, Storage};
use radiosity_ff::{AnalyticColumns, AnalyticParams, FfError, StoredMatrix};
use radiosity_geom::{SceneAnalysis, Visibility, load_scene};
use std::sync::atomic::{AtomicUsize, Ordering};

fn assemble(source: &impl ColumnSource) -> StoredMatrix {
    StoredMatrix::assemble(source, &|_| {})
}

/// A deterministic value in `(0, 1)` for entry `(i, j)`.
fn hash01(i: usize, j: usize) -> Real {
    let mut x = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 29;
    ((x >> 11) as Real + 0.5) / (1u64 << 53) as Real
}

/// About `fill` of the entries non-zero, in a pattern that is not symmetric.
fn random_matrix(n: usize, fill: Real) -> DenseColumns {
    DenseColumns::from_fn(n, |i, j| if i != j && hash01(j, i) < fill { hash01(i, j) / n as Real } else { 0.0 })
}

fn assert_same_entries(m: &StoredMatrix, source: &DenseColumns) {
    let n = source.patch_count();
    assert_eq!(m.patch_count(), n);
    for j in 0..n {
        for i in 0..n {
            assert_eq!(m.get(i, j), Real::from(source.get(i, j) as f32), "entry ({i}, {j})");
        }
    }
}

#[test]
fn assembled_matrix_equals_its_source_to_f32_precision() {
    for fill in [0.05, 0.5, 1.0] {
        let source = random_matrix(37, fill);
        let m = assemble(&source);
        assert_same_entries(&m, &source);
        for j in 0..37 {
            for i in 0..37 {
                let exact = source.get(i, j);
                assert!((m.get(i, j) - exact).abs() <= exact * 1e-7, "({i}, {j})");
            }
        }
        let nonzeros = (0..37 * 37).filter(|k| source.get(k % 37, k / 37) != 0.0).count();
        assert_eq!(m.nonzeros(), nonzeros, "fill {fill}");
    }
}

#[test]
fn sparse_matrices_are_stored_sparse_and_full_ones_dense() {
    let n = 100;
    let sparse = assemble(&random_matrix(n, 0.05));
    assert_eq!(sparse.storage(), Storage::Sparse);
    assert_eq!(sparse.bytes(), 8 * sparse.nonzeros() + 4 * (n + 1));
    let full = assemble(&random_matrix(n, 1.0));
    assert_eq!(full.storage(), Storage::Dense);
    assert_eq!(full.bytes(), 4 * n * n);
    assert_eq!(full.nonzeros(), n * n - n);
    // The break-even: 8·nnz + 4(n + 1) < 4n² holds up to nnz = 4949 at n = 100.
    let first = |k: usize| assemble(&DenseColumns::from_fn(n, |i, j| if j * n + i < k { 0.01 } else { 0.0 }));
    let below = first(4949);
    assert_eq!((below.storage(), below.nonzeros(), below.bytes()), (Storage::Sparse, 4949, 39996));
    let at = first(4950);
    assert_eq!((at.storage(), at.nonzeros(), at.bytes()), (Storage::Dense, 4950, 40000));
    assert_eq!(format!("{} {}", Storage::Dense, Storage::Sparse), "dense sparse");
}

#[test]
fn assembly_switches_to_dense_midway_and_keeps_every_entry() {
    // Empty first columns, then full ones: assembly starts sparse, and goes dense once the
    // non-zeros show that sparse cannot be smaller (after the first block of columns).
    let n = 700;
    let source = DenseColumns::from_fn(n, |i, j| if j >= 300 { hash01(i, j) / n as Real } else { 0.0 });
    let m = assemble(&source);
    assert_eq!(m.storage(), Storage::Dense);
    assert_same_entries(&m, &source);
    // The mirror image stays sparse to the end.
    let source = DenseColumns::from_fn(n, |i, j| if j < 150 { hash01(i, j) / n as Real } else { 0.0 });
    let m = assemble(&source);
    assert_eq!(m.storage(), Storage::Sparse);
    assert_same_entries(&m, &source);
}

#[test]
fn served_columns_and_rows_equal_get() {
    for fill in [0.05, 1.0] {
        let m = assemble(&random_matrix(53, fill));
        let mut column = vec![f64::NAN; 53];
        let mut row = vec![f64::NAN; 53];
        for j in 0..53 {
            m.fill_column(j, &mut column);
            assert!(m.fill_row(j, &mut row), "a stored matrix serves rows");
            for (i, &v) in column.iter().enumerate() {
                assert_eq!(v, m.get(i, j), "{} ({i}, {j})", m.storage());
                assert_eq!(row[i], m.get(j, i), "{} row {j}, entry {i}", m.storage());
            }
        }
    }
}

#[test]
fn figures_and_row_sums_agree_with_the_guard() {
    let area: Vec<Real> = (0..41).map(|i| 1.0 + i as Real).collect();
    for fill in [0.05, 1.0] {
        let m = assemble(&random_matrix(41, fill));
        assert_eq!(m.figures(&area), matrix_figures(&area, |i, j| m.get(i, j)));
        let sums = m.row_sums();
        for (i, s) in sums.iter().enumerate() {
            let expected: Real = (0..41).map(|j| m.get(i, j)).sum();
            assert!((s - expected).abs() <= 1e-12, "row {i}");
        }
    }
}

#[test]
fn progress_counts_every_column() {
    let source = random_matrix(300, 0.1);
    let max = AtomicUsize::new(0);
    let calls = AtomicUsize::new(0);
    StoredMatrix::assemble(&source, &|done| {
        max.fetch_max(done, Ordering::Relaxed);
        calls.fetch_add(1, Ordering::Relaxed);
    });
    assert_eq!(max.into_inner(), 300);
    assert_eq!(calls.into_inner(), 300);
}

#[test]
fn bytes_round_trip() {
    for fill in [0.05, 1.0] {
        let m = assemble(&random_matrix(60, fill));
        let bytes = m.to_bytes("test key");
        let back = StoredMatrix::from_bytes(&bytes, "test key").unwrap();
        assert_eq!(back, m);
        assert_eq!(back.storage(), m.storage());
        assert_eq!(back.nonzeros(), m.nonzeros());
    }
    let empty = assemble(&DenseColumns::from_fn(0, |_, _| 0.0));
    assert_eq!(StoredMatrix::from_bytes(&empty.to_bytes("k"), "k").unwrap(), empty);
}

fn refusal(bytes: &[u8], key: &str) -> String {
    match StoredMatrix::from_bytes(bytes, key) {
        Err(e @ FfError::StoredMatrix(_)) => e.to_string(),
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn a_different_key_or_version_is_refused() {
    let m = assemble(&random_matrix(20, 0.5));
    let bytes = m.to_bytes("scene a; analytic:order=3");
    let e = refusal(&bytes, "scene b; analytic:order=3");
    assert!(e.contains("stored form-factor matrix is unusable"), "{e}");
    assert!(e.contains("'scene a; analytic:order=3'") && e.contains("'scene b; analytic:order=3'"), "{e}");
    // The version follows the magic string (one length byte, then its bytes).
    let mut other = bytes.clone();
    assert_eq!(&other[1..1 + MAGIC.len()], MAGIC.as_bytes());
    assert_eq!(u32::from(other[1 + MAGIC.len()]), FORMAT_VERSION);
    other[1 + MAGIC.len()] += 1;
    let e = refusal(&other, "scene a; analytic:order=3");
    assert!(e.contains(&format!("version {}", FORMAT_VERSION + 1)), "{e}");
    assert!(e.contains(&format!("this build reads version {FORMAT_VERSION}")), "{e}");
    let e = refusal(b"P6 not a matrix at all", "k");
    assert!(e.contains("not a stored form-factor matrix"), "{e}");
}

#[test]
fn truncated_or_corrupted_bytes_are_refused_without_panic() {
    for fill in [0.05, 1.0] {
        let m = assemble(&random_matrix(12, fill));
        let bytes = m.to_bytes("k");
        for len in 0..bytes.len() {
            refusal(&bytes[..len], "k");
        }
        let mut padded = bytes.clone();
        padded.push(0);
        assert!(refusal(&padded, "k").contains("truncated or padded"));
        for at in [bytes.len() / 2, bytes.len() - 1] {
            let mut corrupted = bytes.clone();
            corrupted[at] ^= 0x10;
            assert!(refusal(&corrupted, "k").contains("checksum"), "byte {at}");
        }
    }
}

#[test]
fn assembly_is_the_same_on_one_and_two_threads() {
    // A real backend with seeded shadow rays.
    let scene = load_scene("furnace:res=2:block=true").unwrap().scene;
    let vis = Visibility::new(&scene);
    let analysis = SceneAnalysis::new(&scene, &vis);
    let params = AnalyticParams { order: 2, rays: 4, ..AnalyticParams::default() };
    let source = AnalyticColumns::new(&scene, &vis, &analysis, params);
    assert!(source.traces_shadow_rays());
    let on = |k: usize| rayon::ThreadPoolBuilder::new().num_threads(k).build().unwrap().install(|| assemble(&source));
    let one = on(1);
    let two = on(2);
    assert_eq!(one, two);
    let mut column = vec![0.0; scene.len()];
    source.fill_column(7, &mut column);
    for (i, v) in column.iter().enumerate() {
        assert_eq!(one.get(i, 7), Real::from(*v as f32));
    }
}

#[test]
fn analytic_rows_hold_exactly_what_the_columns_hold() {
    // Shadow rays, clipped receivers and graded panels: every pair is computed on its own, so
    // row i is bit for bit the i-th entries of the columns; and each pair by one rule, so
    // A_i F_ij = A_j F_ji to round-off.
    let scene = load_scene("furnace:res=2:block=true").unwrap().scene;
    let vis = Visibility::new(&scene);
    let analysis = SceneAnalysis::new(&scene, &vis);
    let source = AnalyticColumns::new(&scene, &vis, &analysis, AnalyticParams { rays: 4, ..AnalyticParams::default() });
    let n = scene.len();
    let columns: Vec<Vec<Real>> = (0..n)
        .map(|j| {
            let mut column = vec![0.0; n];
            source.fill_column(j, &mut column);
            column
        })
        .collect();
    let area: Vec<Real> = scene.patches().iter().map(|p| p.area()).collect();
    let mut worst_reciprocity: Real = 0.0;
    let mut row = vec![f64::NAN; n];
    for i in 0..n {
        assert!(source.fill_row(i, &mut row));
        for j in 0..n {
            assert_eq!(row[j].to_bits(), columns[j][i].to_bits(), "F_{i},{j}");
            let (a, b) = (area[i] * row[j], area[j] * columns[i][j]);
            if a.max(b) > 0.0 {
                worst_reciprocity = worst_reciprocity.max((a - b).abs() / a.max(b));
            }
        }
    }
    assert!(worst_reciprocity <= 4.0 * f64::EPSILON, "reciprocity off by {worst_reciprocity:e}");
}

/// `F'_ij = (A_i F_ij + A_j F_ji) / (2 A_i)`, in `f64` from the stored entries.
fn symmetrised(m: &StoredMatrix, area: &[Real]) -> Vec<Real> {
    let n = area.len();
    let mut f = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            f[i * n + j] = (area[i] * m.get(i, j) + area[j] * m.get(j, i)) / (2.0 * area[i]);
        }
    }
    f
}

#[test]
fn rebalancing_makes_area_times_f_symmetric_then_rows_sum_to_one() {
    let n = 30;
    let area: Vec<Real> = (0..n).map(|i| 0.5 + hash01(i, 999) * 3.0).collect();
    // Full (dense) and sparse with an asymmetric pattern (so symmetrising fills in entries).
    for fill in [1.0, 0.1] {
        let original = assemble(&random_matrix(n, fill));
        let before = original.figures(&area);
        assert!(before.max_reciprocity_error > 0.1, "the test matrix must be far from reciprocal");
        let expected = symmetrised(&original, &area);

        let mut open = original.clone();
        let report = open.rebalance(&area, false).unwrap();
        assert!(!report.rescaled && report.scale_min == 1.0 && report.scale_max == 1.0);
        for i in 0..n {
            for j in 0..n {
                let (a, b) = (area[i] * open.get(i, j), area[j] * open.get(j, i));
                assert!((a - b).abs() <= 1e-6 * a.max(b), "A·F not symmetric at ({i}, {j})");
                let e = expected[i * n + j];
                assert!((open.get(i, j) - e).abs() <= 1e-6 * e, "({i}, {j})");
            }
        }
        assert!(report.symmetrised.max_reciprocity_error <= 1e-6, "{report:?}");
        assert_eq!(report.symmetrised, open.figures(&area));
        if fill < 1.0 {
            assert!(report.filled > 0 && open.nonzeros() > original.nonzeros(), "{report:?}");
        }
        assert!(report.max_relative_change > 0.1 && report.max_change > 0.0, "{report:?}");

        let mut closed = original.clone();
        let report = closed.rebalance(&area, true).unwrap();
        assert!(report.rescaled);
        for (i, s) in closed.row_sums().iter().enumerate() {
            assert!((s - 1.0).abs() <= 1e-6, "row {i} sums to {s}");
        }
        // Each row of the symmetrised matrix is scaled by its own factor.
        for i in 0..n {
            let sum: Real = (0..n).map(|j| expected[i * n + j]).sum();
            for j in 0..n {
                let e = expected[i * n + j] / sum;
                assert!((closed.get(i, j) - e).abs() <= 1e-6 * e, "({i}, {j})");
            }
        }
        assert!(report.scale_min <= report.scale_max && report.scale_min > 0.0);
        // Rescaling breaks reciprocity again, by about the spread of the factors.
        let after = closed.figures(&area);
        let spread = report.scale_max / report.scale_min - 1.0;
        assert!(after.max_reciprocity_error > 1e-3 && after.max_reciprocity_error <= spread, "{after:?}");
    }
}

#[test]
fn rebalancing_refuses_bad_areas() {
    let mut m = assemble(&random_matrix(5, 1.0));
    let e = m.rebalance(&[1.0; 4], true).unwrap_err().to_string();
    assert!(e.contains("5 patches") && e.contains("4 areas"), "{e}");
    let e = m.rebalance(&[1.0, 1.0, 0.0, 1.0, 1.0], true).unwrap_err().to_string();
    assert!(e.contains("patch 2"), "{e}");
}

#[test]
fn a_stored_matrix_states_the_reciprocity_it_has_and_keeps_it_in_its_file() {
    // A symmetric power exchange G over unequal areas: F_ij = G_ij / A_i is reciprocal.
    let n = 24;
    let area: Vec<Real> = (0..n).map(|i| 0.5 + hash01(i, 1000)).collect();
    let g = |i: usize, j: usize| if i == j { 0.0 } else { hash01(i.min(j), i.max(j)) / (4 * n) as Real };
    let stated = DenseColumns::from_fn(n, |i, j| g(i, j) / area[i]).with_measured_reciprocity(&area).unwrap();
    assert!(stated.reciprocity_bound().unwrap() < 1e-15);
    // Column by column: the source's bound plus f32 rounding; none from a source that states none.
    let m = assemble(&stated);
    let bound = m.reciprocity_bound().unwrap();
    assert!(bound >= radiosity_core::column::F32_ROUNDING && bound < 2.0 * f32::EPSILON as Real, "{bound:e}");
    let measured = radiosity_core::measured_reciprocity(&m, &area).unwrap();
    assert!(measured <= bound, "measured {measured:e} above the stated {bound:e}");
    assert_eq!(assemble(&random_matrix(n, 0.5)).reciprocity_bound(), None);
    // By reciprocity: measured on the f32 entries.
    let (pairs, _) = StoredMatrix::assemble_reciprocal(&area, &|r, s| g(r, s) / area[r], &|_| {}).unwrap();
    let bound = pairs.reciprocity_bound().unwrap();
    assert_eq!(bound, radiosity_core::measured_reciprocity(&pairs, &area).unwrap());
    assert!(bound <= f32::EPSILON as Real, "{bound:e}");
    // The file keeps it.
    let back = StoredMatrix::from_bytes(&pairs.to_bytes("k"), "k").unwrap();
    assert_eq!(back.reciprocity_bound(), Some(bound));
    // Rebalancing a matrix that is not reciprocal makes it so (to f32), unless rows are
    // rescaled afterwards, which the measured bound then shows.
    let mut open = assemble(&random_matrix(n, 0.5));
    open.rebalance(&area, false).unwrap();
    assert!(open.reciprocity_bound().unwrap() <= f32::EPSILON as Real);
    let mut closed = assemble(&random_matrix(n, 0.5));
    let report = closed.rebalance(&area, true).unwrap();
    assert!(report.scale_max / report.scale_min > 1.1, "{report:?}");
    let bound = closed.reciprocity_bound().unwrap();
    assert_eq!(bound, radiosity_core::measured_reciprocity(&closed, &area).unwrap());
    assert!(bound > 1e-2, "{bound:e}");
}
