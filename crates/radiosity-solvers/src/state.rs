//! The iterate of a solver and its accounting.
//!
//! `radiosity` is the displayed radiosity `B` and `unshot` the unshot radiosity `ΔB`, both
//! patch-major (`[i * channels + c]`); for shooting methods the shot radiosity is
//! `x = B − ΔB`, and the residual of `x` is exactly `ΔB` (DESIGN §5). Gathering methods keep
//! `unshot` as the last change of each patch.

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
    /// Columns computed so far.
    pub columns: u64,
    /// Columns served again from a solver's memory, at no cost: not counted in `columns`.
    pub columns_reused: u64,
    /// Seconds spent computing columns.
    pub ff_seconds: f64,
    /// Seconds spent in the solver outside column computations.
    pub solve_seconds: f64,
    /// Of `solve_seconds`, the seconds spent building and solving group systems.
    pub group_seconds: f64,
    /// Group shooting steps that did not solve their group system and shot its patches one
    /// after another instead ([`crate::group_step`]): the system was singular, not an
    /// M-matrix, or worse conditioned than [`crate::group_step::CONDITION_LIMIT`].
    pub group_fallbacks: u64,
    /// The largest estimate of the condition number `κ_∞(Φ_rr)` over the group shooting steps
    /// so far, the largest over channels in each step ([`crate::group_step`]): 0 while no
    /// group step has run, infinite once a step found a singular group system or one that is
    /// not an M-matrix.
    pub group_condition: Real,
}

impl State {
    /// The initial state `B = ΔB = E`.
    pub fn from_emission(emission: &[Real], channels: usize) -> State {
        State {
            channels,
            radiosity: emission.to_vec(),
            unshot: emission.to_vec(),
            step: 0,
            columns: 0,
            columns_reused: 0,
            ff_seconds: 0.0,
            solve_seconds: 0.0,
            group_seconds: 0.0,
            group_fallbacks: 0,
            group_condition: 0.0,
        }
    }

    /// The channels of patch `i` in `values`.
    pub fn of(values: &[Real], channels: usize, i: usize) -> &[Real] {
        &values[i * channels..(i + 1) * channels]
    }
}
