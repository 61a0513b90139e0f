//! The laboratory: a prepared scene set up for measurement (its linear system, a form-factor
//! backend, F and the reference solution), running any [`Solver`] value under stop rules with
//! one recorder, and comparing many.
//!
//! ```no_run
//! use radiosity_eval::{Lab, LabOptions, NoProgress};
//! use radiosity_ff::BackendSpec;
//! use radiosity_solvers::{SolverRegistry, StopRules};
//!
//! let scene = radiosity_geom::PreparedScene::load("cornell:res=4")?;
//! let lab = Lab::new(&scene, &BackendSpec::parse("analytic")?, LabOptions::default(), &NoProgress)?;
//! let registry = SolverRegistry::builtin();
//! let solvers = vec![registry.build("pr")?, registry.build("xu-g30-m480")?];
//! let comparison = lab.compare(solvers, &StopRules::parse("columns=2n")?, &NoProgress)?;
//! comparison.write("results/my-study".as_ref())?;
//! print!("{}", comparison.summary());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## What is measured, and when
//!
//! The reference is obtained once, outside every run, as [`LabOptions::kind`] says
//! ([`crate::reference::kind`]): from the stored matrix (`matrix`), by a long shooting run
//! without a matrix (`shooting`), or not at all (`none`); `auto` takes the matrix when it fits
//! the memory budget. A run's columns, steps and seconds are the solver's alone. The
//! [`Recorder`] is an observer: the executor calls it between steps, outside the timed region.
//! After every step it computes e_rms against the reference (`O(n)`, when there is one) and the
//! certified bound on the displayed radiosity's relative L1 error from what the solver knows
//! without extra columns ([`SolverBound`], `O(n)`, with or without a reference); at about 100
//! points of a run and at `n/4`, `n/2`, `n` and `2n` columns it also computes, when the stored
//! matrix is kept, e_max and the residual power of the displayed radiosity (a product with F,
//! `O(nnz)`). Its own time is reported apart, as measurement.
//!
//! **Solvers that sample transport** (`StepKind::Sampled`: `stochastic-jacobi`, `random-walk`)
//! get a transport sampler on their problem, as [`LabOptions::transport`] says: rays in the
//! scene (the default) or the lab's stored matrix sampled exactly ([`Lab::transport_sampler`],
//! built only for them, once per comparison, outside every run). Their cost is counted in rays,
//! every step of theirs is recorded, and the recorder also takes their standard error, the
//! error bar that needs no reference, beside the certified bound (which, for them, only F
//! gives). A run whose rules only count columns, which such a solver never computes, is
//! refused before any work ([`check_rules`]).
//!
//! **The bound's hypothesis.** With a stored matrix the contraction `κ_c` is measured on it;
//! over a source that multiplies natively and states its reciprocity (the hierarchical
//! operator), it is bounded by two products ([`Contraction::from_products`]); otherwise it is
//! the hypothesis of docs/design.md §6.3, rows of F summing to at most 1 and F reciprocal, so
//! `κ_c ≤ ρ_max,c` ([`Contraction::assumed`]). The analytic backend is exactly reciprocal and
//! its rows sum to 1 within its stated accuracy.
//!
//! ## The reference cache
//!
//! With a [`Cache`], the reference solution is stored on disk with its certificate, under a key
//! of the scene ([`crate::scene_key`]), the backend's label (for built-in backends, the
//! canonical argument with every parameter), a fingerprint of three of its columns (so that a
//! backend whose numbers change never reads an old entry), the reference's kind and parameters
//! and the format version, and read back next time. A lab that does not keep residuals
//! ([`LabOptions::residuals`] false: `solve`, `render`, `export`) then assembles no F at all
//! when the reference is in the cache, so a second run on a large scene starts at once; its
//! final residual is then the solver's own (for shooting methods that of the shot radiosity
//! `B − ΔB`, whose residual is `ΔB`), and [`FinalMetrics`] says which it has. Comparisons
//! keep the matrix whenever the reference is `matrix`, so their residual columns never
//! depend on the cache.
//!
//! [`Solver`]: radiosity_solvers::Solver
//! [`LabOptions::kind`]: crate::LabOptions::kind
//! [`Recorder`]: crate::Recorder
//! [`SolverBound`]: crate::SolverBound
//! [`Contraction::assumed`]: crate::Contraction::assumed
//! [`Contraction::from_products`]: crate::Contraction::from_products
//! [`Cache`]: crate::Cache
//! [`LabOptions::residuals`]: crate::LabOptions::residuals
//! [`FinalMetrics`]: crate::FinalMetrics
//! [`LabOptions::transport`]: crate::LabOptions::transport
//! [`Lab::transport_sampler`]: crate::Lab::transport_sampler
//! [`check_rules`]: crate::check_rules

pub(crate) mod backends;
pub(crate) mod calibration;
pub(crate) mod charged;
pub(crate) mod compare;
pub(crate) mod options;
pub(crate) mod outcome;
pub(crate) mod ranks;
pub(crate) mod recorder;
pub(crate) mod run;
pub(crate) mod setup;
pub(crate) mod summary;
pub(crate) mod timing;
pub(crate) mod transport;
