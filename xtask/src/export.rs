//! `cargo xtask export --scene SCENE --solver SOLVER --out SOLVED.glb [--ff BACKEND]
//! [--until RULES] [--reference KIND]`: writes the solved scene as binary glTF 2.0, its
//! radiosity as vertex colours, for any glTF viewer (docs/cli.md); no reference is computed
//! unless `--solver reference`, an `rms=` rule or `--reference` asks for one.
//!
//! The file is [`radiosity_eval::export_glb`]'s: one primitive per material, unlit white
//! materials carrying each surface's reflectivity and emission in their extras (so the file
//! loads back as the same system with `--scene SOLVED.glb`), and colours tone mapped to the
//! 99th percentile of the vertex luminance. This command checks its arguments before any
//! geometry is built, solves the scene, and writes the file. Only `.glb` is written; a
//! `.gltf` output is refused with a message saying so.

use crate::experiment::{SolveArgs, check_output_file, prepare, solved_rgb};
use anyhow::{Result, bail};
use radiosity_eval::{ExportInfo, export_glb};
use std::path::{Path, PathBuf};

/// Arguments of `export`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    run: SolveArgs,
    /// The binary glTF file to write (.glb).
    #[arg(long, value_name = "SOLVED.glb")]
    out: PathBuf,
}

/// Runs `export`.
pub fn run(args: &Args) -> Result<()> {
    // Every argument is checked before any geometry is built, so a typo fails at once.
    check_output(&args.out)?;
    check_output_file(&args.out)?;
    let (spec, solver, rules, kind) = args.run.check()?;
    let prepared = prepare(&args.run.scene)?;
    let (rgb, ff) = solved_rgb(&args.run, &prepared, &spec, solver, &rules, kind)?;
    if let Some(i) = rgb.iter().position(|b| b.iter().any(|c| !c.is_finite())) {
        bail!("{} left a radiosity that is not finite at patch {i}, so there is nothing to export", args.run.solver);
    }
    let scene = &prepared.loaded.scene;
    let about = ExportInfo { scene: args.run.scene.clone(), solver: args.run.solver.clone(), ff };
    let glb = export_glb(scene, &rgb, &about)?;
    glb.save(&args.out)?;
    println!(
        "{}: {} patches, {} vertices, {} triangles, exposure {:.6e} (radiosity = colour × exposure)",
        args.out.display(),
        scene.len(),
        glb.vertices,
        glb.triangles,
        glb.exposure
    );
    Ok(())
}

/// Refuses an output that is not `.glb`.
fn check_output(out: &Path) -> Result<()> {
    let extension = out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("glb") => Ok(()),
        Some("gltf") => {
            bail!("export writes binary glTF only; name the output {} instead", out.with_extension("glb").display())
        }
        _ => bail!("the output {} must end in .glb (export writes binary glTF)", out.display()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_other_than_glb_are_refused() {
        assert!(check_output(Path::new("a/b.GLB")).is_ok());
        let e = check_output(Path::new("a/b.gltf")).unwrap_err().to_string();
        assert!(e.contains("binary glTF only") && e.contains("b.glb"), "{e}");
        assert!(check_output(Path::new("b.png")).unwrap_err().to_string().contains(".glb"));
        assert!(check_output(Path::new("b")).is_err());
    }
}
