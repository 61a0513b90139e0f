//! `cargo xtask validate --scene SCENE [--samples N] [--seed S] [--json]`: path-traces each
//! object's mean radiosity and sets it beside the discrete reference solution at increasing
//! mesh resolution ([`radiosity_eval::validate()`]), which tells the error of discretization
//! from the error of solvers.
//!
//! The text output is one block per object (its path-traced mean ± standard error, then per
//! resolution its patches, its discrete mean and the difference in standard errors and in
//! percent), one value for grey scenes and red, green and blue otherwise, and a summary of
//! the resolutions. `--json` prints the [`Validation`] instead.

use crate::bars::Bars;
use crate::experiment::cache;
use anyhow::Result;
use radiosity_core::Real;
use radiosity_eval::DEFAULT_SAMPLES_PER_OBJECT;
use radiosity_eval::round_significant;
use radiosity_eval::{DiscreteMean, ObjectValidation};
use radiosity_eval::{PathTraceParams, ValidateParams, Validation, validate};
use radiosity_ff::BackendSpec;
use radiosity_geom::SceneSpec;

/// Arguments of `validate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene: a built-in name with `:key=value` parameters, or a .gltf, .glb or .mgf path
    /// (files need `size` above 0 to be refined).
    #[arg(long, value_name = "SCENE")]
    scene: String,
    /// Paths traced per object.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_SAMPLES_PER_OBJECT)]
    samples: u64,
    /// Seed of the path tracer.
    #[arg(long, value_name = "S", default_value_t = 0)]
    seed: u64,
    /// How many times the mesh is refined beyond the given scene.
    #[arg(long, value_name = "K", default_value_t = 2)]
    refinements: usize,
    /// No refined scene has more patches than this.
    #[arg(long, value_name = "N", default_value_t = 6000)]
    max_patches: usize,
    /// The form-factor backend of the discrete system, with `:key=value` parameters.
    #[arg(long = "ff", value_name = "BACKEND", default_value = "analytic", long_help = crate::experiment::backend_help())]
    ff: String,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
}

/// Runs `validate`.
pub fn run(args: &Args) -> Result<()> {
    let backend = BackendSpec::parse(&args.ff)?;
    let params = ValidateParams::default()
        .with_path_trace(PathTraceParams::default().with_samples(args.samples).with_seed(args.seed))
        .with_refinements(args.refinements)
        .with_max_patches(args.max_patches)
        .with_backend(backend)
        .with_cache(Some(cache()));
    let validation = validate(&SceneSpec::parse(&args.scene)?, &params, &Bars::new())?;
    if args.json {
        println!("{}", serde_json::to_string(&validation)?);
    } else {
        print!("{}", report(&validation));
    }
    Ok(())
}

/// A value with 4 significant digits.
fn value(v: Real) -> String {
    round_significant(v, 4)
}

/// A signed difference in standard errors.
fn sigmas(s: Real) -> String {
    if s.is_finite() { format!("{s:+.1}σ") } else { "(σ = 0)".to_string() }
}

/// A signed difference in percent.
fn percent(p: Real) -> String {
    if p.is_finite() { format!("{p:+.2}%") } else { "(of 0)".to_string() }
}

/// The channels shown: one for grey scenes, red, green and blue otherwise.
fn channels(v: &Validation) -> &'static [(usize, &'static str)] {
    if v.grey { &[(0, "radiosity")] } else { &[(0, "red"), (1, "green"), (2, "blue")] }
}

/// The text report.
fn report(v: &Validation) -> String {
    let mut out = String::new();
    let resolutions: Vec<String> =
        v.resolutions.iter().map(|r| format!("{} ({} patches)", r.scene, r.patches)).collect();
    let varied = v.varied.as_deref().map(|s| format!(", {s}")).unwrap_or_default();
    let objects = match v.objects.len() {
        1 => "1 object".to_string(),
        n => format!("{n} objects"),
    };
    out += &format!("scene        {}: {objects}{varied}\n", v.scene);
    out += &format!("resolutions  {}\n", resolutions.join(", "));
    if let Some(note) = &v.note {
        out += &format!("note         {note}\n");
    }
    let t = &v.path_trace;
    out += &format!(
        "path traced  on {}: {} paths per object (seed {}), {} rays, {:.2} s",
        t.scene, t.samples_per_object, t.seed, t.rays, t.seconds
    );
    if t.truncated > 0 {
        out += &format!(", {} paths cut at the bounce cap (biased low)", t.truncated);
    }
    out += "\n";
    let width = v.resolutions.iter().map(|r| r.scene.len()).max().unwrap_or(0).max("path traced".len());
    for o in &v.objects {
        out += &object_block(v, o, width);
    }
    out += "\n";
    out += &format!(
        "{:width$}  {:>7}  {:>10}  {:>8}  {:>8}  reference\n",
        "resolution", "patches", "difference", "noise", "seconds"
    );
    for r in &v.resolutions {
        out += &format!(
            "{:width$}  {:>7}  {:>9.3}%  {:>7.3}%  {:>8.2}  {}\n",
            r.scene,
            r.patches,
            100.0 * r.difference,
            100.0 * r.noise,
            r.seconds,
            r.reference
        );
    }
    out += "difference: Σ area·|discrete − path traced| / Σ area·path traced over objects and channels; noise: the same \
            sum over standard errors\n";
    out
}

/// One object's block: the path-traced mean, then each resolution's discrete mean.
fn object_block(v: &Validation, o: &ObjectValidation, width: usize) -> String {
    const CELL: usize = 24;
    let left_out: Vec<String> =
        o.discrete.iter().filter(|d| d.left_out > 0).map(|d| format!("{} at {}", d.left_out, d.scene)).collect();
    let left_out = match left_out.is_empty() {
        true => String::new(),
        false => format!("; patches left out as hidden, radiosity = emission: {}", left_out.join(", ")),
    };
    let mut out = format!("\n{} (area {}{left_out})\n", o.name, value(o.area));
    out += &format!("  {:width$}  {:>7}", "", "patches");
    for (_, name) in channels(v) {
        out += &format!("  {name:CELL$}");
    }
    out = out.trim_end().to_string() + "\n";
    out += &format!("  {:width$}  {:>7}", "path traced", "");
    for &(c, _) in channels(v) {
        out += &format!("  {:CELL$}", format!("{} ± {}", value(o.path_traced[c]), value(o.stderr[c])));
    }
    out = out.trim_end().to_string() + "\n";
    for d in &o.discrete {
        out += &discrete_row(v, d, width, CELL);
    }
    out
}

fn discrete_row(v: &Validation, d: &DiscreteMean, width: usize, cell: usize) -> String {
    let mut out = format!("  {:width$}  {:>7}", d.scene, d.patches);
    for &(c, _) in channels(v) {
        let text = format!("{} {} {}", value(d.mean[c]), percent(d.percent[c]), sigmas(d.sigmas[c]));
        out += &format!("  {text:cell$}");
    }
    out.trim_end().to_string() + "\n"
}
