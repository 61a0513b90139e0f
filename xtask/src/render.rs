//! `cargo xtask render --scene SCENE --solver SOLVER --out IMAGE.png [--ff BACKEND] [--until RULES]
//! [--reference KIND] [--camera x,y,z:tx,ty,tz[:fov]] [--width W --height H]`: a picture of the
//! solved radiosity (no reference is computed unless `--solver reference`, an `rms=` rule or
//! `--reference` asks for one).
//!
//! The picture is [`radiosity_eval::render`]'s: a pinhole camera (each built-in scene's preset,
//! kept with the scene in radiosity-geom, or `--camera`) ray-casting the scene's BVH, smooth
//! shading from the radiosity at patch corners, exposure to the 95th percentile of the visible
//! luminance and the sRGB curve.
//! This command checks its arguments before any geometry is built, solves the scene, and
//! writes the PNG.

use crate::experiment::{SolveArgs, check_output_file, prepare, solved_rgb, start_camera};
use anyhow::{Result, bail};
use radiosity_core::Real;
use radiosity_eval::{MAX_SIDE, RenderParams, render};
use std::path::PathBuf;

/// A coordinate as `--camera` takes it, to four significant digits.
fn sig(x: Real) -> String {
    radiosity_eval::round_significant(x, 4)
}
use std::time::Instant;

/// Arguments of `render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    run: SolveArgs,
    /// The PNG image to write.
    #[arg(long, value_name = "IMAGE.png")]
    out: PathBuf,
    /// The camera: eye `x,y,z`, the point it looks at `tx,ty,tz` and optionally the vertical
    /// field of view in degrees (default 45), in scene coordinates, with the scene's up axis up
    /// on the image (+y for built-in and glTF scenes, +z for MGF unless the luminaires say
    /// otherwise; printed). Default: a built-in scene's preset, or for a file a view from
    /// inside its enclosure where there is one, else from outside.
    #[arg(long, value_name = "x,y,z:tx,ty,tz[:fov]")]
    camera: Option<String>,
    /// Image width in pixels, 1 to 8192.
    #[arg(long, value_name = "W", default_value_t = 640)]
    width: u32,
    /// Image height in pixels, 1 to 8192.
    #[arg(long, value_name = "H", default_value_t = 480)]
    height: u32,
}

/// Runs `render`.
pub fn run(args: &Args) -> Result<()> {
    let start = Instant::now();
    // Every argument is checked before any geometry is built, so a typo fails at once.
    let (spec, solver, rules, kind) = args.run.check()?;
    if !args.out.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        bail!("the output image must be a .png file, not '{}'", args.out.display());
    }
    check_output_file(&args.out)?;
    for (name, side) in [("width", args.width), ("height", args.height)] {
        if !(1..=MAX_SIDE).contains(&side) {
            bail!("--{name} {side} is out of range: an image side is 1 to {MAX_SIDE} pixels");
        }
    }
    let camera = args.camera.as_deref().map(str::parse::<radiosity_eval::Camera>).transpose()?;

    let prepared = prepare(&args.run.scene)?;
    let scene = &prepared.loaded.scene;
    let aspect = Real::from(args.width) / Real::from(args.height);
    let (camera, how, why) = start_camera(&args.run.scene, &prepared, camera, aspect)?;
    let (e, t) = (camera.eye(), camera.target());
    eprintln!(
        "camera {},{},{}:{},{},{}:{} ({how}; up {why})",
        sig(e.x),
        sig(e.y),
        sig(e.z),
        sig(t.x),
        sig(t.y),
        sig(t.z),
        sig(camera.fov())
    );
    let (rgb, _) = solved_rgb(&args.run, &prepared, &spec, solver, &rules, kind)?;

    let render_start = Instant::now();
    let params = RenderParams { camera, width: args.width, height: args.height };
    let image = render(scene, &prepared.visibility_for("a render")?, &rgb, &params)?;
    let render_seconds = render_start.elapsed().as_secs_f64();
    image.save(&args.out)?;
    println!(
        "wrote {}: {} × {} pixels, exposure {:.4e}, {:.2} s ({:.2} s rendering)",
        args.out.display(),
        args.width,
        args.height,
        image.exposure,
        start.elapsed().as_secs_f64(),
        render_seconds
    );
    Ok(())
}
