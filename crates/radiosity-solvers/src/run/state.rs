//! The iterate of a solver and its accounting.
//!
//! `radiosity` is the displayed radiosity `B` and `unshot` the unshot radiosity `ΔB`, both
//! patch-major (`[i * channels + c]`); for shooting methods the shot radiosity is
//! `x = B − ΔB`, and the residual of `x` is exactly `ΔB` (docs/design.md §4.1). Gathering methods
//! keep `unshot` as the last change of each patch.
//!
//! The state is what every solver has: the iterate and its cost. Figures that only some
//! solvers have (group steps, condition numbers, fallbacks) are in their
//! [`crate::Record`].

use crate::run::cost::Cost;
use radiosity_core::Real;

/// A solver's iterate and what it cost.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Channels per patch.
    pub channels: usize,
    /// The displayed radiosity `B`, patch-major.
    pub radiosity: Vec<Real>,
    /// The unshot radiosity `ΔB` (shooting), or the last update of each patch (gathering).
    pub unshot: Vec<Real>,
    /// Steps taken: one shot, or one patch gathered.
    pub step: u64,
    /// What the run has spent so far: columns, products, rays, links and seconds on its clock
    /// ([`Cost`]).
    pub cost: Cost,
}

impl State {
    /// The initial state `B = ΔB = E`.
    pub fn from_emission(emission: &[Real], channels: usize) -> State {
        State { channels, radiosity: emission.to_vec(), unshot: emission.to_vec(), step: 0, cost: Cost::default() }
    }

    /// The channels of patch `i` in `values`.
    pub fn of(values: &[Real], channels: usize, i: usize) -> &[Real] {
        &values[i * channels..(i + 1) * channels]
    }
}
