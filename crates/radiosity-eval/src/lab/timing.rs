//! What timings are taken over and summed up with: a seeded sample of columns spread over the
//! scene ([`sample`]) and the median of repeated measurements ([`median`]). A lab's column
//! charge ([`crate::ColumnCharge`]) and the bench ([`crate::bench`]) both use them.

/// `count` distinct columns spread over `0..n`: one drawn (seeded) from each of `count`
/// equal strata of the index range, in increasing order. Patches are numbered object by
/// object, so every object of the scene is represented.
pub fn sample(n: usize, count: usize, seed: u64) -> Vec<usize> {
    if count >= n {
        return (0..n).collect();
    }
    (0..count)
        .map(|k| {
            let (lo, hi) = (k * n / count, (k + 1) * n / count);
            lo + (splitmix(seed ^ k as u64) % (hi - lo) as u64) as usize
        })
        .collect()
}

/// SplitMix64: one well-mixed number from `x`.
fn splitmix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The median of `values` (the mean of the middle two for an even count), NaNs left out; NaN
/// when nothing is left.
pub fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let k = v.len();
    if k % 2 == 1 { v[k / 2] } else { 0.5 * (v[k / 2 - 1] + v[k / 2]) }
}

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn medians_of_odd_and_even_counts_leave_nans_out() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(&[f64::NAN, 5.0]), 5.0);
        assert!(median(&[]).is_nan());
    }
}
