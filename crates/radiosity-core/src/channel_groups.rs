//! Channels taken a group at a time: groups sized to a byte budget, and a patch-major vector's
//! channels cut out for a group and put back. A channel's arithmetic is its own, so whatever
//! goes a group at a time gives the bits it gives in one pass.

use crate::math::Real;
use std::ops::Range;

/// The channels `0..channels` in consecutive groups of as many as `budget` bytes hold at
/// `per_channel` bytes a channel, one channel a group at least: one group when all fit.
pub fn channel_groups(channels: usize, per_channel: usize, budget: usize) -> Vec<Range<usize>> {
    let size = (budget / per_channel.max(1)).clamp(1, channels.max(1));
    (0..channels).step_by(size).map(|first| first..(first + size).min(channels)).collect()
}

/// Channels `group` of `x` (patch-major, `channels` channels) into `out` (patch-major, the
/// group's channels).
pub fn pick_channels(x: &[Real], channels: usize, group: Range<usize>, out: &mut [Real]) {
    for (out, x) in out.chunks_exact_mut(group.len()).zip(x.chunks_exact(channels)) {
        out.copy_from_slice(&x[group.clone()]);
    }
}

/// Puts `part` (patch-major, the group's channels) into channels `group` of `x` (patch-major,
/// `channels` channels).
pub fn put_channels(part: &[Real], channels: usize, group: Range<usize>, x: &mut [Real]) {
    for (x, part) in x.chunks_exact_mut(channels).zip(part.chunks_exact(group.len())) {
        x[group.clone()].copy_from_slice(part);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_fit_the_budget_cover_every_channel_once_and_cut_and_put_back_a_vector() {
        assert_eq!(channel_groups(3, 10, 100), vec![0..3]);
        assert_eq!(channel_groups(3, 10, 20), vec![0..2, 2..3]);
        assert_eq!(channel_groups(3, 10, 1), vec![0..1, 1..2, 2..3]);
        assert_eq!(channel_groups(0, 10, 100), Vec::<Range<usize>>::new());
        let x: Vec<Real> = (0..12).map(Real::from).collect();
        let mut part = vec![0.0; 8];
        pick_channels(&x, 3, 1..3, &mut part);
        assert_eq!(part, [1.0, 2.0, 4.0, 5.0, 7.0, 8.0, 10.0, 11.0]);
        let mut back = vec![0.0; 12];
        put_channels(&part, 3, 1..3, &mut back);
        put_channels(&[0.0, 3.0, 6.0, 9.0], 3, 0..1, &mut back);
        assert_eq!(back, x);
    }
}
