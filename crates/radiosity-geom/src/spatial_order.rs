//! A spatially coherent order of the patches: their centroids along a Morton (Z-order) curve,
//! so that patches consecutive in the order lie near each other.
//!
//! Group gathering (`radiosity_solvers::GroupGathering`, `:groups=spatial`) cuts this order
//! into consecutive groups of `m` patches. A group's solve resolves exactly the exchanges
//! inside the group, and near patches exchange more energy than far ones (the form factor
//! falls with the square of the distance), so groups of near patches take more of the
//! coupling into the exact part of each step than groups of arbitrary patches.
//!
//! The Morton code interleaves the bits of the three coordinates, each quantised to 21 bits
//! within the scene's bounding box (63 bits in all): sorting by it visits the box cell by cell
//! of an octree, depth first. It is cheap and deterministic; ties (patches whose centroids fall
//! in the same cell) keep their index order.
//!
//! ## References
//!
//! - Morton 1966, "A computer oriented geodetic data base and a new technique in file
//!   sequencing", IBM technical report.

use radiosity_core::{Real, Scene, Vec3};

/// Bits per axis of the Morton code.
const BITS: u32 = 21;

/// The patch indices of `scene` sorted by the Morton code of their centroids, quantised to 21
/// bits per axis within the scene's bounding box; ties keep index order. A permutation of
/// `0..scene.len()`.
pub fn spatial_order(scene: &Scene) -> Vec<usize> {
    let (lo, hi) = scene.bounds();
    let codes: Vec<u64> = scene.patches().iter().map(|p| morton(quantise(p.centroid(), lo, hi))).collect();
    let mut order: Vec<usize> = (0..scene.len()).collect();
    order.sort_by_key(|&i| (codes[i], i));
    order
}

/// The cell of `point` on a grid of `2^21` cells per axis over the box `[lo, hi]` (a flat
/// axis, or a non-finite coordinate, maps to cell 0).
fn quantise(point: Vec3, lo: Vec3, hi: Vec3) -> [u64; 3] {
    let cells = (1u64 << BITS) as Real;
    let axis = |p: Real, lo: Real, hi: Real| {
        let extent = hi - lo;
        let t = if extent > 0.0 { (p - lo) / extent } else { 0.0 };
        // `as` saturates: NaN maps to 0, and t = 1 to the last cell once clamped.
        ((t * cells) as u64).min((1 << BITS) - 1)
    };
    [axis(point.x, lo.x, hi.x), axis(point.y, lo.y, hi.y), axis(point.z, lo.z, hi.z)]
}

/// Interleaves the low 21 bits of each coordinate: bit `b` of axis `a` goes to bit `3b + a`.
fn morton(cell: [u64; 3]) -> u64 {
    cell.iter().enumerate().map(|(a, &v)| spread(v) << a).fold(0, |code, bits| code | bits)
}

/// Moves bit `b` of `v` (21 bits) to bit `3b`.
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_moves_each_bit_to_three_times_its_place() {
        for v in [0u64, 1, 2, 5, 0x1f_ffff, 0x15_5555, 123_456] {
            let naive = (0..BITS).filter(|b| v >> b & 1 == 1).fold(0u64, |x, b| x | 1 << (3 * b));
            assert_eq!(spread(v), naive, "{v:#x}");
        }
        assert_eq!(morton([1, 0, 0]), 1);
        assert_eq!(morton([0, 1, 0]), 2);
        assert_eq!(morton([0, 0, 1]), 4);
        assert_eq!(morton([0x1f_ffff; 3]), (1 << 63) - 1);
    }
}
