//! A form-factor backend of one's own under the built-in solvers: centroid-to-centroid point
//! form factors without visibility, with the same report, CSV and plots as `cargo xtask compare`.
//!
//! `cargo run --release -p radiosity-eval --example custom_backend -- --out DIR [--scene SCENE]`
//!
//! The kernel is the point-to-disc approximation `F_ij ≈ A_j cos θ_i cos θ_j / (π r² + A_j)`
//! (Wallace, Elmquist & Haines 1989), bounded where patches nearly touch; it sees through
//! walls, so on occluded scenes it measures the solvers on a different, unphysical system.

use radiosity_core::{ColumnSource, Real, Scene, Vec3};
use radiosity_eval::{Lab, LabOptions, NoProgress};
use radiosity_geom::PreparedScene;
use radiosity_solvers::{SolverRegistry, StopRules};
use std::error::Error;
use std::path::{Path, PathBuf};

/// Point-to-disc form factors between patch centroids, no visibility.
pub struct CentroidDisc {
    centroid: Vec<Vec3>,
    normal: Vec<Vec3>,
    area: Vec<Real>,
}

impl CentroidDisc {
    /// The scene's centroids, normals and areas.
    pub fn new(scene: &Scene) -> CentroidDisc {
        let patches = scene.patches();
        CentroidDisc {
            centroid: patches.iter().map(|p| p.centroid()).collect(),
            normal: patches.iter().map(|p| p.normal()).collect(),
            area: patches.iter().map(|p| p.area()).collect(),
        }
    }
}

impl ColumnSource for CentroidDisc {
    fn patch_count(&self) -> usize {
        self.area.len()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        for (i, f) in column.iter_mut().enumerate() {
            let d = self.centroid[j] - self.centroid[i];
            let r2 = d.length_squared();
            let cos_i = self.normal[i].dot(d);
            let cos_j = -self.normal[j].dot(d);
            *f = if i == j || cos_i <= 0.0 || cos_j <= 0.0 {
                0.0
            } else {
                self.area[j] * cos_i * cos_j / (r2 * (std::f64::consts::PI * r2 + self.area[j]))
            };
        }
    }
}

/// Runs `pr`, `xu` and `xu-g30-m480` on `scene` with these form factors, writes the report
/// into `out` and gives the summary table.
pub fn compare(scene: &str, out: &Path) -> Result<String, Box<dyn Error>> {
    let scene = PreparedScene::load(scene)?;
    let source = Box::new(CentroidDisc::new(scene.scene()));
    let lab = Lab::with_source(&scene, "centroid-disc", source, false, LabOptions::default(), &NoProgress)?;
    let registry = SolverRegistry::builtin();
    let solvers = ["pr", "xu", "xu-g30-m480"].iter().map(|s| registry.build(s)).collect::<Result<Vec<_>, _>>()?;
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
    let out = PathBuf::from(argument("--out").unwrap_or_else(|| "results/custom-backend".into()));
    let scene = argument("--scene").unwrap_or_else(|| "cornell".into());
    print!("{}", compare(&scene, &out)?);
    println!("wrote {} (report.md, convergence.csv and plots)", out.display());
    Ok(())
}
