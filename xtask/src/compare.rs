//! `cargo xtask compare`: compare solvers on a scene.
//!
//! Solvers and form factors are not implemented yet. Until they are, this command runs the
//! stage that exists, preparing the scene (meshing, BVH, analysis), and says so plainly,
//! rather than printing numbers it could not have computed.

use crate::scene_report::{prepare, print_warnings};
use anyhow::Result;

/// Arguments of `compare`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene: a built-in name with `:key=value` parameters, or a .gltf/.glb path.
    #[arg(long, default_value = "multi-cubes")]
    scene: String,
}

/// Runs `compare`.
pub fn run(args: &Args) -> Result<()> {
    let prepared = prepare(&args.scene)?;
    let r = prepared.report();
    print_warnings(&r);
    println!(
        "scene {}: {} patches, mean reflectivity {:.3}, {} emitters",
        r.scene, r.patches, r.mean_reflectivity, r.emitters
    );
    println!(
        "prepared in {:.1} ms (load {:.1} ms, BVH {:.1} ms over {} triangles, analysis {:.1} ms)",
        1e3 * (r.seconds.load + r.seconds.bvh + r.seconds.analysis),
        1e3 * r.seconds.load,
        1e3 * r.seconds.bvh,
        prepared.visibility.triangle_count(),
        1e3 * r.seconds.analysis
    );
    println!("left out: {}", if r.left_out.is_empty() { "nothing".to_string() } else { r.left_out.join("; ") });
    println!();
    println!("Form factors and solvers are not implemented yet, so nothing was compared.");
    println!("This command will run PR, Xu and their group-accelerated variants here and write");
    println!("convergence tables and plots under results/.");
    Ok(())
}
