//! Timing a form-factor backend of one's own beside the built-in analytic one with the bench's
//! library functions: columns per second over the bench's seeded sample of columns, and the
//! wall time from the backend's setup to e_rms 1e-1, 1e-2 and 1e-3 for `xu` over each, with
//! the time spent measuring e_rms taken out (`cargo xtask bench` does the same from scene
//! load, each case in a process of its own).
//!
//! `cargo run --release -p radiosity-eval --example time_backend -- [--scene SCENE]`
//!
//! The backend of one's own is `custom_backend`'s centroid-to-centroid point form factors,
//! which see through walls: each backend is measured against the reference of its own system.

#[allow(dead_code)]
#[path = "custom_backend.rs"]
pub mod custom_backend;

use radiosity_core::ColumnSource;
use radiosity_eval::bench::e2e::{EndToEndReport, time_to_accuracy_over};
use radiosity_eval::bench::report_text::{duration, sig};
use radiosity_eval::bench::{columns, e2e};
use radiosity_eval::{Lab, LabOptions, NoProgress};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::SolverRegistry;
use std::error::Error;
use std::fmt::Write as _;
use std::time::Instant;

/// One backend's figures.
pub struct Timing {
    /// The backend's name.
    pub backend: String,
    /// Columns per second, in parallel over the global pool.
    pub columns_per_second: f64,
    /// `xu`'s run to e_rms 1e-3 (or 60 s).
    pub run: EndToEndReport,
}

/// Times `source` (named `name`), set up after `start`: `xu` over it from `start` against
/// `lab`'s reference (a lab of the same source, set up before `start`), then its columns per
/// second, computed afresh (what the run left in the source's memory forgotten first).
fn time(
    prepared: &PreparedScene,
    name: &str,
    source: &dyn ColumnSource,
    lab: &Lab<'_>,
    start: Instant,
) -> Result<Timing, Box<dyn Error>> {
    let star = lab.reference().ok_or("the lab has no reference")?.values();
    let mut xu = SolverRegistry::builtin().build("xu")?;
    let run = time_to_accuracy_over(prepared, start, 0.0, xu.as_mut(), source, star, 60.0)?;
    source.reset_memory();
    let sample = columns::sample(source.patch_count(), 50, columns::SAMPLE_SEED);
    // One pass: a second would find the first's visible fractions recorded.
    let seconds = columns::time_parallel(source, &sample, 0.0);
    Ok(Timing { backend: name.to_string(), columns_per_second: sample.len() as f64 / seconds, run })
}

/// Times the analytic backend and the centroid-disc one on `scene`; gives both and a table.
pub fn measure(scene: &str) -> Result<(Vec<Timing>, String), Box<dyn Error>> {
    let prepared = PreparedScene::load(scene)?;
    let analytic = BackendSpec::parse("analytic")?;
    // The references are solved before the clocks start.
    let lab = Lab::new(&prepared, &analytic, LabOptions::default(), &NoProgress)?;
    let start = Instant::now();
    let built_in = radiosity_eval::fresh_backend(&prepared, &analytic, &NoProgress)?;
    let mut timings = vec![time(&prepared, "analytic", &built_in, &lab, start)?];
    let source = Box::new(custom_backend::CentroidDisc::new(prepared.scene(), 1.0));
    let lab = Lab::with_source(&prepared, "centroid-disc", source, false, LabOptions::default(), &NoProgress)?;
    let start = Instant::now();
    let own = custom_backend::CentroidDisc::new(prepared.scene(), 1.0);
    timings.push(time(&prepared, "centroid-disc", &own, &lab, start)?);

    let mut table = String::from("| backend | columns/s | xu to 1e-1 | to 1e-2 | to 1e-3 | columns |\n");
    table += "|---|--:|--:|--:|--:|--:|\n";
    for t in &timings {
        let to = |k: usize| t.run.reached.get(k).map_or("not reached".to_string(), |r| duration(r.seconds));
        let _ = writeln!(
            table,
            "| `{}` | {} | {} | {} | {} | {} |",
            t.backend,
            sig(t.columns_per_second, 3),
            to(0),
            to(1),
            to(2),
            t.run.columns
        );
    }
    let _ = writeln!(table, "\nThresholds: {:?}; the times include each backend's setup.", e2e::THRESHOLDS);
    Ok((timings, table))
}

fn main() -> Result<(), Box<dyn Error>> {
    let scene = custom_backend::argument("--scene", "cornell");
    print!("{}", measure(&scene)?.1);
    Ok(())
}
