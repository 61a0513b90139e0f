//! A solver of one's own beside the built-in ones: damped Jacobi, compared with `pr` and `xu`
//! on the Cornell box, with the same report, CSV and plots as `cargo xtask compare`.
//!
//! `cargo run --release -p radiosity-eval --example custom_solver -- --out DIR [--scene SCENE]`

use radiosity_core::Real;
use radiosity_eval::{Lab, LabOptions, NoProgress};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::{Problem, Record, Solver, SolverError, SolverRegistry, State, StepKind, StopRules};
use std::error::Error;
use std::path::{Path, PathBuf};

/// Damped Jacobi: every sweep sets `B ← (1 − ω) B + ω (E + ρ F B_old)`, one patch a step,
/// gathering along rows of F (one row costs what a column costs).
struct DampedJacobi {
    omega: Real,
    old: Vec<Real>,
    row: Vec<Real>,
    next: usize,
}

impl Solver for DampedJacobi {
    fn name(&self) -> String {
        format!("damped-jacobi-{}", self.omega)
    }

    fn init(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        (self.old, self.row, self.next) = (state.radiosity.clone(), vec![0.0; problem.n()], 0);
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let (i, k, system) = (self.next, problem.channels(), problem.system());
        problem.row(i, &mut self.row);
        for c in 0..k {
            let gathered: Real = self.row.iter().enumerate().map(|(j, f)| f * self.old[j * k + c]).sum();
            let b = state.radiosity[i * k + c];
            let updated = (1.0 - self.omega) * b + self.omega * (system.e(i, c) + system.rho(i, c) * gathered);
            state.unshot[i * k + c] = updated - b;
            state.radiosity[i * k + c] = updated;
        }
        self.next = (self.next + 1) % problem.n();
        if self.next == 0 {
            self.old.copy_from_slice(&state.radiosity);
        }
        Ok(Record::new())
    }

    fn residual_power(&self, _problem: &Problem<'_>, _state: &State) -> Option<Real> {
        None
    }

    fn step_kind(&self) -> StepKind {
        StepKind::Gather
    }
}

/// Compares damped Jacobi with `pr` and `xu` on `scene`, writes the report into `out` and
/// gives the summary table.
pub fn compare(scene: &str, out: &Path) -> Result<String, Box<dyn Error>> {
    let scene = PreparedScene::load(scene)?;
    let lab = Lab::new(&scene, &BackendSpec::parse("analytic")?, LabOptions::default(), &NoProgress)?;
    let registry = SolverRegistry::builtin();
    let mine = DampedJacobi { omega: 0.9, old: Vec::new(), row: Vec::new(), next: 0 };
    let solvers: Vec<Box<dyn Solver>> = vec![registry.build("pr")?, registry.build("xu")?, Box::new(mine)];
    let comparison = lab.compare(solvers, &StopRules::parse("columns=2n")?, &NoProgress)?;
    comparison.write(out)?;
    Ok(comparison.summary())
}

/// The value after `flag` among the arguments, if given.
pub fn argument(flag: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1).cloned())
}

fn main() -> Result<(), Box<dyn Error>> {
    let out = PathBuf::from(argument("--out").unwrap_or_else(|| "results/custom-solver".into()));
    let scene = argument("--scene").unwrap_or_else(|| "cornell".into());
    print!("{}", compare(&scene, &out)?);
    println!("wrote {} (report.md, convergence.csv and plots)", out.display());
    Ok(())
}
