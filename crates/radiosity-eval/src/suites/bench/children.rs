//! The bench's cases that run in child processes of their own, so that each peak memory is its
//! own and nothing one allocates is left to the next: the reference they share, solved once
//! outside every timed run and handed over in a file ([`ReferenceFile`]), and what a child does
//! ([`ChildCase::run`]): load the scene on the clock, run its case
//! ([`crate::bench::e2e::time_to_accuracy`], [`crate::bench::stochastic::sampled_run`],
//! [`crate::bench::scale::scale_run`]) and return its report as one JSON line, which the parent
//! reads back. Spawning the child is the command line's part.

use crate::error::LabError;
use crate::lab::options::LabOptions;
use crate::lab::setup::Lab;
use crate::progress::Progress;
use crate::suites::bench::e2e::{self, ReferenceNote};
use crate::suites::bench::{scale, stochastic};
use radiosity_core::Real;
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::SolverRegistry;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One case, as a child process runs it.
#[derive(Clone, Debug, PartialEq)]
pub enum ChildCase {
    /// `solver` over the backend `ff` to e_rms 1e-3 against the reference in `reference`.
    EndToEnd {
        /// The solver.
        solver: String,
        /// The backend.
        ff: String,
        /// The reference file ([`ReferenceFile`]).
        reference: PathBuf,
    },
    /// `solver` with rays in the scene, or over the backend `ff`, against the reference.
    Sampled {
        /// The solver.
        solver: String,
        /// The backend of a comparator; `None`: rays in the scene.
        ff: Option<String>,
        /// The reference file ([`ReferenceFile`]).
        reference: PathBuf,
    },
    /// `solver` over the backend `ff` with no reference, to a certified bound.
    Scale {
        /// The solver.
        solver: String,
        /// The backend.
        ff: String,
    },
}

impl ChildCase {
    /// Runs the case on `scene` (loaded here, on the clock) for at most `max_seconds` of solver
    /// time, and returns its report as one line of JSON.
    pub fn run(&self, scene: &str, max_seconds: Real) -> Result<String, LabError> {
        let registry = SolverRegistry::builtin();
        let json = match self {
            ChildCase::EndToEnd { solver, ff, reference } => {
                let (spec, mut solver, star) =
                    (BackendSpec::parse(ff)?, registry.build(solver)?, read_reference(reference)?);
                let (prepared, start, scene_seconds) = load(scene)?;
                let report =
                    e2e::time_to_accuracy(&prepared, start, scene_seconds, solver.as_mut(), &spec, &star, max_seconds)?;
                serde_json::to_string(&report)
            }
            ChildCase::Sampled { solver, ff, reference } => {
                let case = match ff {
                    None => stochastic::Case::Rays,
                    Some(ff) => stochastic::Case::Backend(BackendSpec::parse(ff)?),
                };
                let (mut solver, star) = (registry.build(solver)?, read_reference(reference)?);
                let (prepared, start, scene_seconds) = load(scene)?;
                let report = stochastic::sampled_run(
                    &prepared,
                    start,
                    scene_seconds,
                    solver.as_mut(),
                    &case,
                    &star,
                    max_seconds,
                )?;
                serde_json::to_string(&report)
            }
            ChildCase::Scale { solver, ff } => {
                let (spec, mut solver) = (BackendSpec::parse(ff)?, registry.build(solver)?);
                let (prepared, start, scene_seconds) = load(scene)?;
                let report = scale::scale_run(&prepared, start, scene_seconds, solver.as_mut(), &spec, max_seconds)?;
                serde_json::to_string(&report)
            }
        };
        json.map_err(|e| LabError::Invalid(format!("cannot write the child's report: {e}")))
    }
}

/// The scene loaded on a clock started just before: the scene, the start and the seconds the
/// load took.
fn load(scene: &str) -> Result<(PreparedScene, Instant, Real), LabError> {
    let start = Instant::now();
    let prepared = PreparedScene::load(scene)?;
    Ok((prepared, start, start.elapsed().as_secs_f64()))
}

/// The analytic reference of a scene, solved (or read from the cache) once, outside every
/// timed run, in a file the children read ([`read_reference`]: raw little-endian `f64`),
/// removed when dropped.
#[derive(Debug)]
pub struct ReferenceFile {
    path: PathBuf,
    note: ReferenceNote,
}

impl ReferenceFile {
    /// Solves the analytic reference of `prepared` and writes it to a file of this process in
    /// the temporary folder. The stored reference matrix is not kept.
    pub fn solve(prepared: &PreparedScene, progress: &dyn Progress) -> Result<ReferenceFile, LabError> {
        let start = Instant::now();
        let lab = Lab::new(prepared, &BackendSpec::parse("analytic")?, LabOptions::default(), progress)?;
        let seconds = start.elapsed().as_secs_f64();
        let reference = lab
            .reference()
            .ok_or_else(|| LabError::Invalid("the timed runs need a reference, and none was solved".into()))?;
        let note = ReferenceNote {
            method: reference.method().to_string(),
            certificate: reference.certificate().to_string(),
            seconds,
        };
        let path = std::env::temp_dir().join(format!("radiosity-bench-reference-{}.bin", std::process::id()));
        let bytes: Vec<u8> = reference.values().iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(&path, bytes).map_err(|e| LabError::write(&path, e))?;
        Ok(ReferenceFile { path, note })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// How the reference was solved.
    pub fn note(&self) -> &ReferenceNote {
        &self.note
    }
}

impl Drop for ReferenceFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// A reference written by [`ReferenceFile::solve`].
pub fn read_reference(path: &Path) -> Result<Vec<Real>, LabError> {
    let bytes = std::fs::read(path)
        .map_err(|e| LabError::Invalid(format!("cannot read the reference {}: {e}", path.display())))?;
    if bytes.len() % 8 != 0 {
        return Err(LabError::Invalid(format!(
            "{} is not a reference: its length is not a multiple of 8",
            path.display()
        )));
    }
    Ok(bytes.chunks_exact(8).map(|c| Real::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])).collect())
}
