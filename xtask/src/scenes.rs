//! `cargo xtask scenes [--json] [--explain SCENE]`: the built-in scenes, or one scene in detail.

use crate::experiment::prepare;
use anyhow::Result;
use radiosity_geom::SceneReport;
use radiosity_geom::builtin_scenes;

/// Arguments of `scenes`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Explain one scene (a built-in name with `:key=value` parameters, or a .gltf, .glb or
    /// .mgf path):
    /// its figures, every pipeline decision and the reason for it.
    #[arg(long, value_name = "SCENE")]
    explain: Option<String>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Runs `scenes`.
pub fn run(args: &Args) -> Result<()> {
    match &args.explain {
        Some(arg) => {
            let report = prepare(arg)?.report();
            if args.json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", explain_text(&report, arg));
            }
        }
        None => {
            let reports =
                builtin_scenes().iter().map(|s| prepare(s.name).map(|p| p.report())).collect::<Result<Vec<_>>>()?;
            if args.json {
                println!("{}", serde_json::to_string_pretty(&reports)?);
            } else {
                print!("{}", list_text(&reports));
            }
        }
    }
    Ok(())
}

fn list_text(reports: &[SceneReport]) -> String {
    let mut out = format!(
        "{:<12} {:>7} {:>7} {:>9} {:>8} {:<7} {}\n",
        "scene", "patches", "mean ρ", "emitters", "channels", "closed", "left out"
    );
    for (r, builtin) in reports.iter().zip(builtin_scenes()) {
        out += &format!(
            "{:<12} {:>7} {:>7.3} {:>9} {:>8} {:<7} {}\n",
            r.scene,
            r.patches,
            r.mean_reflectivity,
            r.emitters,
            r.channels,
            if r.closure.value == "closed" { "yes" } else { "no" },
            if r.left_out.is_empty() { "nothing".to_string() } else { r.left_out.join("; ") }
        );
        debug_assert_eq!(r.scene, builtin.name);
    }
    out += "\nParameters (NAME:key=value:...):\n";
    for b in builtin_scenes() {
        out += &format!("  {:<12} {}\n", b.name, b.summary);
        for p in b.params {
            out += &format!("  {:<12}   {:<16} {}\n", "", format!("{}={}", p.key, p.default), p.doc);
        }
    }
    out += "\nFiles: PATH.gltf or PATH.glb (glTF 2.0), or PATH.mgf (MGF 2.0, with :div=N for curved primitives);\n";
    out += "both take :size=F to cut patches to edges of at most F times the scene diagonal.\n";
    out += "Run `cargo xtask scenes --explain SCENE` for the reasons behind each decision.\n";
    out
}

fn explain_text(r: &SceneReport, arg: &str) -> String {
    let [lo, hi] = r.bounds;
    let mut out = format!("scene       {arg}\n");
    out += &format!("patches     {} ({} quads, {} triangles)\n", r.patches, r.quads, r.triangles);
    out += &format!("area        {:.6e}\n", r.total_area);
    out += &format!(
        "bounds      [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}]\n",
        lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
    );
    out += &format!("reflectivity mean {:.4} (area-weighted), max {:.4}\n\n", r.mean_reflectivity, r.max_reflectivity);
    out += "decisions\n";
    for (what, d) in
        [("occlusion", &r.occlusion), ("channels", &r.colour), ("emitters", &r.emission), ("closure", &r.closure)]
    {
        out += &format!("  {what:<10} {}\n  {:<10} because {}\n", d.value, "", d.reason);
    }
    let g = &r.geometry;
    out += &format!(
        "\ngeometry    {} hidden ({} pressed, {} enclosed, area {:.4e}), {} touching, {} overlapping ({} covered, {} \
         cut)\n",
        g.hidden,
        g.pressed,
        g.enclosed,
        g.hidden_area,
        g.touching,
        g.overlapping + g.covered + g.cut,
        g.covered,
        g.cut
    );
    out += &format!("  {:<10} because {}\n", "", g.reason);
    for e in &g.examples {
        out += &format!("  {e}\n");
    }
    out += "\nleft out\n";
    if r.left_out.is_empty() {
        out += "  nothing: this scene needs every stage\n";
    }
    for l in &r.left_out {
        out += &format!("  {l}\n");
    }
    if !r.warnings.is_empty() {
        out += "\nwarnings\n";
        for w in &r.warnings {
            out += &format!("  {w}\n");
        }
    }
    out += &format!(
        "\ntime        load {:.1} ms, BVH {:.1} ms, analysis {:.1} ms\n",
        1e3 * r.seconds.load,
        1e3 * r.seconds.bvh,
        1e3 * r.seconds.analysis
    );
    let per_patch = |b: usize| b as f64 / r.patches.max(1) as f64;
    out += &format!(
        "memory      scene {:.0} bytes a patch, BVH {:.0} bytes a patch (held after the set-up)\n",
        per_patch(r.memory.scene),
        per_patch(r.memory.bvh)
    );
    out
}
