//! A peer program's process times beside ours: RenderPark's solvers, run by the stochastic
//! section on the same MGF scene, on the same machine, in the same run.
//!
//! The user supplies a RenderPark executable ([`Peer`]: `--renderpark FILE` on the command
//! line, or the `RENDERPARK` setting, with its commit in `RENDERPARK_COMMIT` when known); the
//! project holds none and builds none. Each case of [`CASES`] runs it as
//! `rpk SCENE -raytracing-method none -radiance-method METHOD -iterations N -timings`
//! ([`PeerCase::args`]) and records what the operating system says the whole process cost:
//! wall seconds from spawn to exit, measured here, and the user and system CPU seconds of the
//! process and its children, as `times` (POSIX, `times(2)`) reports them once it has been
//! waited for ([`time_process`]). Without an executable the section says, in one sentence,
//! that it has no peer measurement and how to give one ([`NO_PEER`]).

use crate::error::LabError;
use crate::lab::timing::median;
use crate::reports::report_text::duration;
use radiosity_core::Real;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// The setting that names a RenderPark executable.
pub const VARIABLE: &str = "RENDERPARK";

/// The setting that names the commit it was built from (optional).
pub const COMMIT_VARIABLE: &str = "RENDERPARK_COMMIT";

/// What the section says when it was given no executable.
pub const NO_PEER: &str = "No peer measurement: RenderPark's times are measured only beside ours, so give a \
     RenderPark build you supply with `--renderpark FILE` or the RENDERPARK setting (its commit in RENDERPARK_COMMIT) \
     to have its solvers timed on the same scene in this run.";

/// A RenderPark executable supplied by the user.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Peer {
    /// The executable.
    pub executable: PathBuf,
    /// The commit it was built from, when known.
    pub commit: Option<String>,
}

impl Peer {
    /// The executable `path`, with the commit of `RENDERPARK_COMMIT` if set; an error when
    /// `path` is not a file.
    pub fn new(path: &Path) -> Result<Peer, LabError> {
        if !path.is_file() {
            return Err(LabError::Invalid(format!(
                "the RenderPark executable {} is not a file; give the path of a RenderPark build",
                path.display()
            )));
        }
        let commit = std::env::var(COMMIT_VARIABLE).ok().map(|c| c.trim().to_string()).filter(|c| !c.is_empty());
        Ok(Peer { executable: path.to_path_buf(), commit })
    }

    /// The executable `explicit` names, else the one the `RENDERPARK` setting names, else
    /// `None`.
    pub fn from_arg_or_env(explicit: Option<&Path>) -> Result<Option<Peer>, LabError> {
        let setting = std::env::var_os(VARIABLE).filter(|v| !v.is_empty()).map(PathBuf::from);
        explicit.map(Path::to_path_buf).or(setting).map(|p| Peer::new(&p)).transpose()
    }
}

/// One of RenderPark's solvers, as the peer runs it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PeerCase {
    /// `-radiance-method`.
    pub method: &'static str,
    /// `-iterations`.
    pub iterations: u32,
}

impl PeerCase {
    /// The arguments after the executable, on the scene file `scene`: no ray tracing pass,
    /// this radiance method for this many iterations, with RenderPark's own timings printed.
    pub fn args(&self, scene: &Path) -> Vec<String> {
        vec![
            scene.display().to_string(),
            "-raytracing-method".into(),
            "none".into(),
            "-radiance-method".into(),
            self.method.into(),
            "-iterations".into(),
            self.iterations.to_string(),
            "-timings".into(),
        ]
    }
}

/// The peer's cases: stochastic Jacobi for 20 iterations at its default rays per iteration
/// (about 111k rays in all on classroom). Its Galerkin radiosity is left out: on classroom it
/// takes minutes for a few iterations.
pub const CASES: [PeerCase; 1] = [PeerCase { method: "StochJacobi", iterations: 20 }];

/// What the operating system says one process cost.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProcessTimes {
    /// Wall seconds from spawn to exit.
    pub wall: Real,
    /// User CPU seconds of the process and its children.
    pub user: Real,
    /// System CPU seconds of the process and its children.
    pub system: Real,
}

/// Runs `program` with `args`, its output discarded, and returns its process times; an error
/// when it cannot start or exits unsuccessfully. The program runs under `sh`, which waits for
/// it and then prints its children's CPU times with the `times` builtin.
pub fn time_process(program: &Path, args: &[String]) -> Result<ProcessTimes, LabError> {
    let start = Instant::now();
    let output = Command::new("sh")
        .arg("-c")
        .arg("\"$0\" \"$@\" >/dev/null 2>&1; s=$?; times; exit $s")
        .arg(program)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| LabError::Invalid(format!("cannot run {} under sh: {e}", program.display())))?;
    let wall = start.elapsed().as_secs_f64();
    if !output.status.success() {
        return Err(LabError::Invalid(format!("{} {} failed ({})", program.display(), args.join(" "), output.status)));
    }
    // `times` prints the shell's own times, then its children's: `0m1.23s 0m0.04s`.
    let stdout = String::from_utf8_lossy(&output.stdout);
    let children = stdout.lines().rfind(|l| !l.trim().is_empty()).unwrap_or_default();
    let mut fields = children.split_whitespace().map(minutes_seconds);
    match (fields.next().flatten(), fields.next().flatten()) {
        (Some(user), Some(system)) => Ok(ProcessTimes { wall, user, system }),
        _ => Err(LabError::Invalid(format!("sh's `times` printed '{children}', not two CPU times"))),
    }
}

/// `1m2.5s` (as `times` prints) in seconds.
fn minutes_seconds(field: &str) -> Option<Real> {
    let (minutes, seconds) = field.strip_suffix('s')?.split_once('m')?;
    Some(minutes.parse::<Real>().ok()? * 60.0 + seconds.parse::<Real>().ok()?)
}

/// One case's runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PeerRun {
    /// `-radiance-method`.
    pub method: String,
    /// `-iterations`.
    pub iterations: u32,
    /// The command line, as run.
    pub command: String,
    /// Each run's process times.
    pub runs: Vec<ProcessTimes>,
}

impl PeerRun {
    /// The median of one figure over the runs.
    pub fn median(&self, figure: impl Fn(&ProcessTimes) -> Real) -> Real {
        median(&self.runs.iter().map(figure).collect::<Vec<_>>())
    }
}

/// Runs `case` of `peer` on `scene` once.
pub fn run_case(peer: &Peer, case: &PeerCase, scene: &Path) -> Result<ProcessTimes, LabError> {
    time_process(&peer.executable, &case.args(scene))
}

/// The command line of `case` on `scene`, as the report prints it.
pub fn command(peer: &Peer, case: &PeerCase, scene: &Path) -> String {
    format!("{} {}", peer.executable.display(), case.args(scene).join(" "))
}

/// The peer's figures, for `--json`: the executable and its commit, or `null` without one.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct PeerJson {
    /// The executable and its commit; `None` when none was given.
    pub peer: Option<Peer>,
    /// Why there is no measurement, when there is none.
    pub missing: Option<String>,
    /// One entry per case.
    pub cases: Vec<PeerRun>,
}

/// The peer's part of the section: a table of its cases' median process times, or why there
/// is none (`missing`, e.g. [`NO_PEER`]).
pub fn report(peer: Option<&Peer>, runs: &[PeerRun], missing: Option<&str>) -> (String, PeerJson) {
    let mut out = String::from("\n### RenderPark, side by side\n\n");
    let (Some(peer), None) = (peer, missing) else {
        let why = missing.unwrap_or(NO_PEER);
        let _ = writeln!(out, "{why}");
        return (out, PeerJson { peer: peer.cloned(), missing: Some(why.to_string()), cases: Vec::new() });
    };
    let json = PeerJson { peer: Some(peer.clone()), missing: None, cases: runs.to_vec() };
    let _ = writeln!(
        out,
        "The executable `{}` (commit {}), run in this section on the same scene and machine, one process per run; \
         process times from the operating system (wall from spawn to exit, CPU of the process and its children), \
         medians over the runs.\n",
        peer.executable.display(),
        peer.commit.as_deref().unwrap_or("not given: set RENDERPARK_COMMIT"),
    );
    out += "| method | iterations | runs | wall | user CPU | system CPU | command |\n|---|--:|--:|--:|--:|--:|---|\n";
    for run in runs {
        let _ = writeln!(
            out,
            "| `{}` | {} | {} | {} | {} | {} | `{}` |",
            run.method,
            run.iterations,
            run.runs.len(),
            duration(run.median(|t| t.wall)),
            duration(run.median(|t| t.user)),
            duration(run.median(|t| t.system)),
            run.command,
        );
    }
    (out, json)
}
