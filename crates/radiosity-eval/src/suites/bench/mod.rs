//! Performance measurements: columns per second against the ray-tracing limit, matrix
//! assembly, group solves, time and memory from scene load to accuracy, and the cost of a
//! column as scenes grow; their medians, their Markdown sections and their JSON keys.
//!
//! Form factors dominate the cost of radiosity, so speed is measured where it is spent and
//! against what limits it:
//!
//! - [`columns`]: form-factor columns per second on 1 and 2 threads over a fixed, seeded
//!   sample of columns, beside the rate at which **the same rays** are traced straight through
//!   the BVH ([`radiosity_ff::ColumnRays`] lists them); [`columns::time_parallel`] and
//!   [`columns::time_sequential`] time any [`ColumnSource`](radiosity_core::ColumnSource), a
//!   researcher's own included.
//! - [`assembly`]: the analytic backend's full matrix assembled with each pair computed once
//!   (reciprocity) at k = 1 and k = 4 shadow rays per pair, beside column by column.
//! - [`lu`]: one group system solved by LU, nalgebra against faer, as the group grows.
//! - [`e2e`]: wall time from scene load (load, BVH, analysis, form-factor setup, solve) to
//!   e_rms ≤ 1e-1, 1e-2 and 1e-3 for any [`Solver`](radiosity_solvers::Solver), with the
//!   time spent measuring e_rms taken out, and the peak resident memory.
//! - [`stochastic`]: wall time and rays from scene load to e_rms ≤ 1e-2, 3e-3 and 1e-3 for
//!   the solvers that sample transport with rays in a real scene.
//! - [`scale`]: the same without a reference or a matrix, to a certified bound, with the growth
//!   exponent of the time per column in `n`.
//! - [`peer`]: a RenderPark executable the user supplies, timed on the stochastic section's
//!   scene in the same run (process wall and CPU seconds); without one, a sentence saying so.
//!
//! What a run measures and how it is judged is [`plan`]: the sections and their defaults
//! ([`plan::BenchConfig`]), the cases of each, the report's header and its performance targets
//! ([`plan::targets`]). The heavy cases run in child processes ([`children`]: the reference
//! they share in a file, what a child runs and the JSON line it answers with).
//!
//! Each measurement returns typed figures; [`median`] aggregates runs, each section module
//! writes its Markdown section from them, and [`BenchJson`] holds the figures under the stable
//! keys of `cargo xtask bench --json`. Spawning the child processes, so that each peak memory
//! is its own, is the caller's part: the command line re-invokes itself with a
//! [`children::ChildCase`] and reads back the JSON line it prints.

pub mod assembly;
pub mod children;
pub mod columns;
pub mod e2e;
mod json;
pub mod lu;
pub mod peer;
pub mod plan;
pub use crate::reports::report_text;
pub mod scale;
pub mod stochastic;

pub use crate::lab::timing::median;
pub use crate::memory::peak_rss;
pub use json::{BenchJson, ColumnsJson, E2eJson, Machine, SceneJson};
