//! The stress suite: every solver on every form-factor backend over stiff and extreme scenes,
//! judged by certified error bounds, with what went wrong and why (`cargo xtask stress` prints
//! and writes it).
//!
//! ## The suite
//!
//! [`CASES`]: closed boxes with `ρ = 0.99` and `0.999`, channels with `ρ` of 0.99, 0.5 and 0,
//! a box inside a closed box at `ρ = 0.999`,
//! patch areas 1e6 apart, a tiny emitter of 1e6, a box touching the floor along its edges
//! and one 1e-6 above it, a thin slab, and one scene at coordinate scales 1e-4 and 1e4 (the
//! scenes are `furnace` and `inner-box`, whose module docs describe them). Each runs on
//! [`BACKENDS`]: `analytic`, the same with every row rescaled to sum to 1 in `f64` (closed
//! scenes only, see [`FormFactors::close_rows`]), `hemicube`, `montecarlo`,
//! `matrix:rebalance=true` and `hierarchical` (its defaults; its rows sum to 1 only to its
//! `eps`, so at `ρ = 0.999` it may amplify light, and then nothing is certified). Every solver
//! of `POINT_SOLVERS`, `GROUP_SOLVERS`, `BEYOND_PAPER_SOLVERS` and `KRYLOV_SOLVERS` runs on each
//! (`cg` refuses, in one sentence, the backends that state no reciprocity bound or one above
//! its limit), and so do four node shooters, one level over the stored matrix
//! ([`NODE_STRESS_SOLVERS`]), and the solvers that sample transport, [`STOCHASTIC_SOLVERS`].
//!
//! ## How a run is judged
//!
//! F is assembled once per scene and backend, and every solver reads its columns (and exact
//! rows) from it, so the suite measures solvers on one system and takes seconds. A run stops
//! at residual power 1e-13, at round-off, on divergence (the executor's rule), or after
//! [`STEP_CAP`]`·n` steps. Then:
//!
//! - **converged** means the *certified* bound on the final radiosity's relative L1 error,
//!   `Σ A|r| / (1 − q)` over `Σ A|B|` (docs/design.md §6.3, [`crate::evaluate`]), is at most
//!   [`CONVERGED`]; no claim rests on the change between iterates or on the solver's own
//!   estimate. Where `q ≥ 1` (ρ times some row sum of F reaches 1) nothing is certifiable;
//! - the **exact answer** is the furnace identity `E / (1 − ρ)` where the scene is closed and
//!   uniform, otherwise the reference solution of the same system; both errors are kept;
//! - columns to reach e_rms 1e-3 and 1e-6 are counted against the reference;
//! - non-finite values stop a run with an error naming the step and the patch; negative
//!   radiosities are counted;
//! - the **energy** is `Σ A·B` against the same sum for the exact answer;
//! - group systems report the largest `κ_∞` estimate met and how many fell back to point
//!   shots; the whole system's `κ_∞ = ‖Φ‖_∞ ‖Φ⁻¹‖_∞` is in each case's header, where
//!   `‖Φ⁻¹‖_∞ = max (Φ⁻¹ 1)` because `Φ⁻¹ ≥ 0` for an M-matrix (one extra solve).
//!
//! ## Solvers that sample transport
//!
//! They cast their rays on the same F, each column sampled exactly
//! ([`radiosity_core::ColumnTransport`], built once per scene and backend), on a problem with
//! no columns to read (`Problem::sampled`): the reference is then the exact answer of the very
//! system they estimate, which the occluded and `ρ` near 1 cases test for bias. A run stops
//! at [`STOCHASTIC_RAYS_PER_PATCH`]` · n` rays (a budget, as the residual target cannot be
//! reached by an estimate). No bound is certified for an estimate, so such a run is judged by
//! its own error bar, its standard error `s` (the spread of its replicates, relative as e_rms
//! is, [`radiosity_solvers::StandardError::relative_rms`]): it has **converged** when
//!
//! - `s ≤` [`STOCHASTIC_TOLERANCE`] (`5e-2`): the estimate is as precise as asked, a few
//!   percent, which the budget reaches at `ρ = 0.999`;
//! - its e_rms against the reference `≤` [`STOCHASTIC_TOLERANCE`] too: as accurate as asked
//!   (an e_rms of 4 standard errors of 5e-2 is no answer to 5e-2); and
//! - its e_rms against the reference `≤` [`STOCHASTIC_SPREADS`]` · s` (4): it is unbiased as
//!   far as its noise can show. The squared e_rms of an unbiased mean and its squared
//!   standard error have the same expectation. Where the errors of the patches are
//!   independent, both are sums over many patches and their ratio stays near 1; where they
//!   move together (a closed furnace, whose noise is mostly its level of energy), `e_rms / s`
//!   is at worst a Student's `t` with `R − 1` degrees of freedom: with the suite's `R = 16`,
//!   beyond 4 about 0.1% of the time (beyond 3 it would be 0.9%, and 5.8% with 4 replicates,
//!   which flagged unbiased runs at ρ = 0.99). Every run's seed is fixed, so a verdict is
//!   reproducible, and a flag is worth rerunning with other seeds; a bias of several standard
//!   errors, or a bar several times too narrow, is flagged.
//!
//! The furnace identity is not used for them: where F's rows do not sum exactly to 1, it is
//! not the answer of the system they sample. Their cells show e_rms against the reference
//! and `±s`; `stress.csv` gives their rays, standard error and replicates.
//!
//! Everything written is deterministic (no timings), so the report is snapshot-tested.
//!
//! [`FormFactors::close_rows`]: crate::FormFactors::close_rows

mod cases;
mod judge;
mod report;
mod suite;

pub use cases::{
    BACKENDS, CASES, CONVERGED, Case, NODE_STRESS_SOLVERS, RESIDUAL_TARGET, STEP_CAP, STOCHASTIC_RAYS_PER_PATCH,
    STOCHASTIC_SOLVERS, STOCHASTIC_SPREADS, STOCHASTIC_TOLERANCE, SuiteBackend, all_solvers, select,
};
pub use judge::StressReport;
pub use suite::StressSuite;
