//! The iterate of a solver and its accounting.
//!
//! `radiosity` is the displayed radiosity `B` and `unshot` the unshot radiosity `ΔB`, both
//! patch-major (`[i * channels + c]`); for shooting methods the shot radiosity is
//! `x = B − ΔB`, and the residual of `x` is exactly `ΔB` (docs/design.md §4.1). Gathering methods
//! keep `unshot` as the last change of each patch.
//!
//! `ff_seconds` holds the form factors' seconds, or the rays' for a solver that samples
//! transport.
//!
//! The state is what every solver has: the iterate and its cost. Figures that only some
//! solvers have (group steps, condition numbers, fallbacks) are in their
//! [`crate::Record`].

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
    /// Products `F x` the source computed itself ([`crate::Problem::multiply`]), each in
    /// `O(links + n)` or a pass over a stored matrix: counted beside `columns`, not in them.
    pub products: u64,
    /// Rays cast by a solver that samples transport ([`crate::Problem::cast`]): its cost, as
    /// columns are the others'.
    pub rays: u64,
    /// Links touched, when the source shows its links ([`crate::Problem::links_touched`]): the
    /// cost of shooting from the nodes of a hierarchy, and of columns and products over it.
    pub links: u64,
    /// Seconds the columns and products cost, on the run's clock ([`crate::Problem::clock`]):
    /// measured, or charged by the source.
    pub ff_seconds: f64,
    /// Seconds spent in the solver outside column computations.
    pub solve_seconds: f64,
    /// Of `solve_seconds`, the seconds of the group steps' own work: building and solving
    /// group systems and shooting their solution, and for group-accelerated shooting choosing
    /// the group too. Time accounting, shown beside the form-factor time; what the group steps
    /// did is in the solver's record ([`crate::Run::record`]).
    pub group_seconds: f64,
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
            products: 0,
            rays: 0,
            links: 0,
            ff_seconds: 0.0,
            solve_seconds: 0.0,
            group_seconds: 0.0,
        }
    }

    /// The channels of patch `i` in `values`.
    pub fn of(values: &[Real], channels: usize, i: usize) -> &[Real] {
        &values[i * channels..(i + 1) * channels]
    }
}
