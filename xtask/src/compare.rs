//! `cargo xtask compare`: compare solvers on a scene.
//!
//! The comparison is not implemented yet: the paper's solvers (overshooting, group and
//! group-accelerated) are still to come. Until then this command prepares the scene
//! (meshing, BVH, analysis), says so plainly rather than printing numbers it could not have
//! computed, and points to `cargo xtask solve`, which runs one point solver.

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
    println!("The comparison is not implemented yet, so nothing was compared. This command will run");
    println!("PR, Xu and their group-accelerated variants here and write convergence tables and plots");
    println!("under results/. Until then one point solver runs at a time, against a reference:");
    println!("  cargo xtask solve --scene {} --solver pr --until columns=2n", args.scene);
    Ok(())
}
