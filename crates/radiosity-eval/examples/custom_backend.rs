//! A form-factor backend of one's own under the built-in solvers, registered as `point-disc` and
//! run through the lab as the built-ins are, with the report, CSV and plots of `cargo xtask compare`.
//!
//! `cargo run --release -p radiosity-eval --example custom_backend -- --out DIR [--scene SCENE] [--ff point-disc:disc=2]`
//!
//! Centroid-to-centroid point-to-disc form factors `F_ij ≈ A_j cos θ_i cos θ_j / (π r² + k A_j)`
//! (Wallace, Elmquist & Haines 1989; `k` is `disc`), without visibility: on occluded scenes the
//! solvers are measured on a different, unphysical system.

use radiosity_core::{ColumnSource, Real, Scene, Vec3};
use radiosity_eval::{Lab, LabOptions, NoProgress};
use radiosity_ff::FormFactorBackend as Backend;
use radiosity_ff::{BackendArgument, BackendParams, BackendRegistry, BuildObserver, FfError, FormFactorInput};
use radiosity_geom::{KeyValueParams, ParamDoc, PreparedScene};
use radiosity_solvers::{SolverRegistry, StopRules};
use std::{error::Error, path::Path};

/// Point-to-disc form factors between patch centroids (position, normal, area), no visibility.
pub struct CentroidDisc(Vec<(Vec3, Vec3, Real)>, Real);

impl CentroidDisc {
    /// The scene's patches, with discs of `disc` times their area.
    pub fn new(scene: &Scene, disc: Real) -> CentroidDisc {
        CentroidDisc(scene.patches().iter().map(|p| (p.centroid(), p.normal(), p.area())).collect(), disc)
    }
}

impl ColumnSource for CentroidDisc {
    fn patch_count(&self) -> usize {
        self.0.len()
    }

    fn fill_column(&self, j: usize, column: &mut [Real]) {
        let (cj, nj, aj) = self.0[j];
        for (i, (f, &(ci, ni, _))) in column.iter_mut().zip(&self.0).enumerate() {
            let d = cj - ci;
            let (r2, cos_i, cos_j) = (d.length_squared(), ni.dot(d), -nj.dot(d));
            let visible = i != j && cos_i > 0.0 && cos_j > 0.0;
            *f = if visible { aj * cos_i * cos_j / (r2 * (std::f64::consts::PI * r2 + self.1 * aj)) } else { 0.0 };
        }
    }
}

impl Backend for CentroidDisc {} // Every capability's default: no exact rows, no figures.

/// The parameters of `point-disc`: `k`, the receiver's disc area over its patch's.
#[derive(Clone, Copy, Debug)]
pub struct PointDisc(pub Real);

impl BackendArgument for PointDisc {
    fn canonical(&self) -> String {
        format!("point-disc:disc={}", self.0)
    }

    fn build<'a>(&self, input: FormFactorInput<'a>, _: &dyn BuildObserver) -> Result<Box<dyn Backend + 'a>, FfError> {
        Ok(Box::new(CentroidDisc::new(input.scene, self.0)))
    }
}

impl BackendParams for PointDisc {
    const NAME: &'static str = "point-disc";
    const HELP: &'static str = "point-to-disc form factors between centroids, without visibility";
    const PARAMS: &'static [ParamDoc] = &[ParamDoc { key: "disc", default: "1", doc: "k of the kernel, in (0, 16]" }];

    fn from_params(p: &KeyValueParams) -> Result<Self, FfError> {
        Ok(PointDisc(p.real("disc", 1.0, |k| k > 0.0 && k <= 16.0, "a multiple in (0, 16]")?))
    }
}

/// The built-in backends and `point-disc`.
pub fn backends() -> BackendRegistry {
    let mut registry = BackendRegistry::builtin();
    registry.register::<PointDisc>();
    registry
}

/// Runs `pr`, `xu` and `xu-g30-m480` on `scene` over the backend `ff` names (`point-disc`, a
/// built-in, or `matrix:of=point-disc`), writes the report into `out` and gives its summary.
pub fn compare(scene: &str, ff: &str, out: &Path) -> Result<String, Box<dyn Error>> {
    let (spec, scene) = (backends().parse(ff)?, PreparedScene::load(scene)?);
    let lab = Lab::new(&scene, &spec, LabOptions::default(), &NoProgress)?;
    let solvers = ["pr", "xu", "xu-g30-m480"].map(|s| SolverRegistry::builtin().build(s)).into_iter();
    let comparison = lab.compare(solvers.collect::<Result<_, _>>()?, &StopRules::parse("columns=2n")?, &NoProgress)?;
    comparison.write(out)?;
    Ok(comparison.summary())
}

/// The value after `flag` among the arguments, or `default`.
pub fn argument(flag: &str, default: &str) -> String {
    let args: Vec<String> = std::env::args().collect();
    args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1).cloned()).unwrap_or(default.into())
}

fn main() -> Result<(), Box<dyn Error>> {
    let out = argument("--out", "results/custom-backend");
    print!("{}", compare(&argument("--scene", "cornell"), &argument("--ff", "point-disc"), Path::new(&out))?);
    println!("wrote {out} (report.md, convergence.csv and plots)");
    Ok(())
}
