//! The hierarchical operator's accuracy against its cost, one point per setting: each
//! operator built afresh (never read from a cache), its shadow rays and build seconds, and
//! e_rms between its exact solution and the analytic system's, written as `curve.csv` and as
//! one log–log plot of e_rms against shadow rays (`curve.png`), a curve per series.
//!
//! `cargo run --release -p radiosity-eval --example refinement_curve -- [--scene SCENE]
//! [--out DIR]`
//!
//! Defaults: `office` (10,990 patches), `target/refinement-curve`. The analytic system's exact
//! solution is the stored matrix's, solved once and cached in `RADIOSITY_CACHE_DIR` (default
//! `target/ff-cache`), as `cargo xtask ff --against analytic` caches it. The series are those of
//! docs/hierarchical.md ([`SERIES`]): the sequential test at two values of `trust` over
//! `shadows`, and every ray (`trust=4096`, as before the test) over `rays`.

use radiosity_core::{LinearSystem, Real};
use radiosity_eval::{
    AxisScale, Cache, Curve, Lab, LabOptions, NoProgress, OperatorDistanceParams, PlotSpec, ReferenceKind,
    operator_distance, write_png,
};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use std::error::Error;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The series drawn: a name and the settings of `hierarchical` along it, each with the
/// defaults for the rest.
pub const SERIES: &[(&str, &[&str])] = &[
    ("trust=1.5 over shadows", &["shadows=0.05", "shadows=0.04", "shadows=0.03", "shadows=0.025", "shadows=0.02"]),
    ("trust=1 over shadows", &["trust=1:shadows=0.05", "trust=1:shadows=0.03", "trust=1:shadows=0.02"]),
    (
        "every ray (trust=4096) over rays, shadows=0.05",
        &[
            "trust=4096:shadows=0.05:rays=10",
            "trust=4096:shadows=0.05:rays=12",
            "trust=4096:shadows=0.05:rays=14",
            "trust=4096:shadows=0.05:rays=16",
        ],
    ),
];

/// One point of the curve.
#[derive(Clone, Debug)]
pub struct Point {
    /// The series it belongs to.
    pub series: String,
    /// The backend's canonical argument.
    pub backend: String,
    /// Shadow rays of far links.
    pub rays: Real,
    /// Far and near links.
    pub links: Real,
    /// Seconds to build the operator.
    pub seconds: Real,
    /// e_rms between the operator's exact solution and the analytic system's.
    pub e_rms: Real,
}

/// Builds every setting of `series` on `scene`, writes `curve.csv` and `curve.png` into `out`,
/// and returns the points. The analytic solution is cached in `cache`.
pub fn curve(scene: &str, series: &[(&str, &[&str])], cache: &Cache, out: &Path) -> Result<Vec<Point>, Box<dyn Error>> {
    let prepared = PreparedScene::load(scene)?;
    let analytic = BackendSpec::parse("analytic")?;
    let options = LabOptions::default()
        .with_cache(Some(cache.clone()))
        .with_reference(ReferenceKind::Matrix)
        .with_residuals(false);
    let star =
        Lab::new(&prepared, &analytic, options, &NoProgress)?.reference().ok_or("no reference")?.values().to_vec();
    let truth = radiosity_eval::backend(&prepared, &analytic, None, &NoProgress)?;
    let system = LinearSystem::from_scene(prepared.scene());
    let mut points = Vec::new();
    for (name, settings) in series {
        for setting in *settings {
            let spec = BackendSpec::parse(&format!("hierarchical:{setting}"))?;
            let built = radiosity_eval::backend(&prepared, &spec, None, &NoProgress)?;
            let figures = built.figures().ok_or("the hierarchical operator reports its figures")?;
            let count = |label: &str| figures.count(label).unwrap_or(0.0);
            let params = OperatorDistanceParams { rows: 1, ..OperatorDistanceParams::default() };
            let distance = operator_distance(&system, &built, &truth, Some(&star), params)?;
            let point = Point {
                series: name.to_string(),
                backend: spec.canonical(),
                rays: count("shadow rays"),
                links: count("far links") + count("near links"),
                seconds: figures.seconds,
                e_rms: distance.solution_e_rms.ok_or("no e_rms between the solutions")?,
            };
            eprintln!("{}: {} rays, {:.2} s, e_rms {:.3e}", point.backend, point.rays, point.seconds, point.e_rms);
            points.push(point);
        }
    }
    std::fs::create_dir_all(out)?;
    let mut csv = String::from("series,backend,shadow_rays,links,build_seconds,e_rms\n");
    for p in &points {
        writeln!(csv, "{},{},{},{},{:.3},{:.4e}", p.series, p.backend, p.rays, p.links, p.seconds, p.e_rms)?;
    }
    std::fs::write(out.join("curve.csv"), csv)?;
    let curves: Vec<Curve> = series
        .iter()
        .map(|(name, _)| {
            let mut along: Vec<(Real, Real)> =
                points.iter().filter(|p| p.series == *name).map(|p| (p.rays, p.e_rms)).collect();
            along.sort_by(|a, b| a.0.total_cmp(&b.0));
            Curve::new(*name, along)
        })
        .collect();
    let mut spec = PlotSpec::new(format!("hierarchical operator on {scene}: e_rms against its cost"), "shadow rays");
    spec.x_scale = AxisScale::Log;
    spec.notes
        .push("e_rms between the operator's exact solution and the analytic system's; one point per setting".into());
    write_png(&curves, &spec, std::fs::File::create(out.join("curve.png"))?)?;
    Ok(points)
}

/// The value after `flag` among the arguments, if given.
fn argument(flag: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1).cloned())
}

fn main() -> Result<(), Box<dyn Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let scene = argument("--scene").unwrap_or_else(|| "office".into());
    let out = argument("--out").map_or_else(|| root.join("target/refinement-curve"), PathBuf::from);
    let cache = Cache::from_env(root.join("target/ff-cache"));
    let points = curve(&scene, SERIES, &cache, &out)?;
    println!("{:<72} {:>12} {:>10} {:>9} {:>10}", "backend", "shadow rays", "links", "build s", "e_rms");
    for p in &points {
        println!("{:<72} {:>12} {:>10} {:>9.2} {:>10.3e}", p.backend, p.rays, p.links, p.seconds, p.e_rms);
    }
    println!("wrote {} and curve.png", out.join("curve.csv").display());
    Ok(())
}
