//! Typed errors of the evaluation crate: mismatched sizes, invalid form factors, matrices too
//! large to hold, reference solves that fail, and pictures, plots and files that cannot be
//! made or written.

use radiosity_core::Real;
use radiosity_ff::FfError;
use radiosity_geom::GeomError;
use radiosity_solvers::SolverError;
use thiserror::Error;

/// What can go wrong while solving a reference or measuring a vector against it. Messages
/// are single sentences meant for end users.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum EvalError {
    /// Two things that must have the same size do not.
    #[error("{what} has length {found}, expected {expected}")]
    SizeMismatch {
        /// What was measured.
        what: &'static str,
        /// The expected length.
        expected: usize,
        /// The length found.
        found: usize,
    },
    /// A form factor that is negative, NaN or infinite.
    #[error("form factor F[{i}][{j}] is {value}; form factors must be finite and at least 0")]
    InvalidFormFactor {
        /// The receiving patch (row).
        i: usize,
        /// The shooting patch (column).
        j: usize,
        /// The offending value.
        value: Real,
    },
    /// The dense form-factor matrix would not fit in the memory allowed for it.
    #[error("a dense form-factor matrix of {n} patches needs {bytes} bytes, more than the {limit} allowed")]
    MatrixTooLarge {
        /// The number of patches.
        n: usize,
        /// The bytes the matrix would need (saturated at `usize::MAX`).
        bytes: usize,
        /// The limit ([`crate::ReferenceParams::max_matrix_bytes`]).
        limit: usize,
    },
    /// The LU factorisation met a zero or non-finite pivot.
    #[error("the system of channel {channel} is singular (LU pivot {pivot} is {value})")]
    Singular {
        /// The channel whose system is singular.
        channel: usize,
        /// The index of the pivot.
        pivot: usize,
        /// The pivot's value.
        value: Real,
    },
    /// Gauss–Seidel did not reach the requested bound within the allowed sweeps.
    #[error("Gauss-Seidel reached a relative bound of {reached:e} after {sweeps} sweeps, not the {target:e} asked for")]
    NotConverged {
        /// Sweeps done.
        sweeps: usize,
        /// The relative bound (or relative residual, if uncertified) reached.
        reached: Real,
        /// The relative bound asked for.
        target: Real,
    },
    /// The shooting reference could not be run.
    #[error("the shooting reference with {solver} cannot run: {message}")]
    ShootingReference {
        /// The solver.
        solver: String,
        /// Why.
        message: String,
    },
    /// The shooting reference stopped before its bound was reached.
    #[error(
        "the shooting reference with {solver} reached a certified relative bound of {reached:e} after {steps} steps, \
         not the {target:e} asked for ({termination})"
    )]
    ShootingNotConverged {
        /// The solver.
        solver: String,
        /// Steps taken.
        steps: u64,
        /// The bound reached.
        reached: Real,
        /// The bound asked for.
        target: Real,
        /// Why the run ended.
        termination: String,
    },
    /// Gauss–Seidel produced a NaN or an infinity.
    #[error("Gauss-Seidel diverged after {sweeps} sweeps")]
    Diverged {
        /// Sweeps done.
        sweeps: usize,
    },
    /// A relative error was asked against a reference that is zero everywhere.
    #[error("the reference solution is zero everywhere (nothing emits), so relative errors are undefined")]
    ZeroReference,
    /// Parameters that make no sense.
    #[error("invalid parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// Its value, as given.
        value: String,
        /// What is required of it.
        reason: &'static str,
    },
    /// A stored reference solution that cannot be used.
    #[error("the stored reference solution cannot be used: {0}")]
    StoredReference(String),
    /// A plot could not be drawn or written.
    #[error("cannot draw the plot: {0}")]
    Plot(String),
    /// A radiosity value that is NaN or infinite, which cannot be shown or exported.
    #[error("the radiosity of patch {patch} is not finite, so there is nothing to show")]
    NonFiniteRadiosity {
        /// The first patch with a non-finite channel.
        patch: usize,
    },
    /// A camera that cannot be parsed or looks nowhere.
    #[error("invalid camera '{camera}': {reason}")]
    InvalidCamera {
        /// The camera as written (`x,y,z:tx,ty,tz[:fov]`), or as given in numbers.
        camera: String,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A scene larger than binary glTF's 32-bit sizes and indices can describe.
    #[error("binary glTF can hold at most {limit} {what}, and this scene needs {needed}")]
    GltfTooLarge {
        /// What overflows (`vertices`, `bytes`).
        what: &'static str,
        /// How many the scene needs.
        needed: u64,
        /// The most glTF can hold.
        limit: u64,
    },
    /// The glTF JSON or container could not be serialised.
    #[error("cannot write the binary glTF: {0}")]
    Gltf(String),
    /// An image could not be encoded.
    #[error("cannot encode the image: {0}")]
    Image(String),
    /// A file could not be written.
    #[error("cannot write {}: {message}", path.display())]
    Write {
        /// The file.
        path: std::path::PathBuf,
        /// Why, as the operating system says it.
        message: String,
    },
}

/// What can stop an experiment: bad input at any layer, or a file that cannot be written.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum LabError {
    /// The scene could not be loaded.
    #[error(transparent)]
    Scene(#[from] GeomError),
    /// The form factors could not be computed.
    #[error(transparent)]
    FormFactors(#[from] FfError),
    /// A solver refused its input or stopped with an error.
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// A reference or a metric could not be computed.
    #[error(transparent)]
    Eval(#[from] EvalError),
    /// The scene emits nothing, so there is no error to measure.
    #[error(
        "scene '{0}' emits no light (no patch has an emission above 0), so its radiosity is zero everywhere and \
         there is no error to measure"
    )]
    NoEmitters(String),
    /// A file or folder could not be written.
    #[error("cannot write {path}: {message}")]
    Write {
        /// The file or folder.
        path: String,
        /// Why.
        message: String,
    },
    /// Arguments that make no sense together.
    #[error("{0}")]
    Invalid(String),
}

impl LabError {
    /// The error for writing `path`.
    pub fn write(path: &std::path::Path, e: impl std::fmt::Display) -> LabError {
        LabError::Write { path: path.display().to_string(), message: e.to_string() }
    }
}
