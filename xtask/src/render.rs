//! `cargo xtask render --scene SCENE --solver SOLVER --out IMAGE.png [--ff BACKEND] [--until RULES]
//! [--camera x,y,z:tx,ty,tz[:fov]] [--width W --height H]`: a picture of the solved radiosity.
//!
//! ## Camera
//!
//! A pinhole camera: an eye, a point it looks at, +y up (every built-in scene is y-up) and a
//! vertical field of view in degrees. Each built-in scene has a default chosen to show what
//! matters in it ([`Camera::default_for`]): the Cornell box from its published camera, looking
//! into the open front (inside the box when `front=true` closes it); the closed rooms
//! (`multi-cubes`, `office`, `furnace`) from inside, near a wall or corner, looking across; the
//! labyrinth, open to the sky, from above and in front, looking down at its middle. Any other
//! scene is seen from its +z side, slightly above, far enough back for its bounding sphere to
//! fit the frame. `--camera` overrides the default.
//!
//! ## Shading
//!
//! Primary rays go through the scene's BVH ([`radiosity_geom::Visibility::first_hit`]).
//! Radiosity is constant over a patch, but an image of constant patches shows the mesh rather
//! than the lighting, so the shading is smooth: each patch corner carries the radiosity of
//! [`crate::shading::vertex_radiosity`] (the area-weighted mean of the patches meeting there on
//! the same smooth surface), interpolated over the patch with the weights that reproduce the
//! hit point: barycentric on a triangle, bilinear on a quad in the quad's own `(s, t)`
//! parametrisation (the one `Patch::point_at` and the mesher's grids use), so a grid of quads
//! shades continuously, without the diagonal seams of splitting quads into triangles. A patch
//! seen from behind (it neither emits nor reflects on that side) is dark grey; a ray that
//! leaves the scene is black. Each pixel averages 2 × 2 stratified rays, for smooth edges;
//! every pixel is computed on its own, so the image is the same whatever the thread count.
//!
//! ## Tone mapping
//!
//! Radiosity is linear and has no natural display scale (emitters can be a hundred times
//! brighter than the walls they light), so the image is exposed to its content: the exposure
//! scales the 95th percentile of the luminance (Rec. 709 weights on linear RGB) of the pixels
//! that see a front face, one ray through each pixel centre, to 0.8. The few brightest pixels
//! (the emitters, mostly) then saturate, and everything else keeps its ratios, which is what a
//! radiosity picture is for. Each ray's exposed colour is clamped to `[0, 1]`, the rays of a
//! pixel averaged, and the mean encoded with the sRGB transfer curve into an 8-bit RGB PNG.

use crate::experiment::{Experiment, SolveArgs, check_output_file};
use crate::scene_report::{prepare, print_warnings};
use anyhow::{Context, Result, bail};
use radiosity_core::{Patch, PatchShape, Real, Scene, Vec3};
use radiosity_geom::spec::split_file_argument;
use rayon::prelude::*;
use std::path::PathBuf;
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
    /// field of view in degrees (default 45), in scene coordinates, y up.
    #[arg(long, value_name = "x,y,z:tx,ty,tz[:fov]")]
    camera: Option<String>,
    /// Image width in pixels, 1 to 8192.
    #[arg(long, value_name = "W", default_value_t = 640)]
    width: u32,
    /// Image height in pixels, 1 to 8192.
    #[arg(long, value_name = "H", default_value_t = 480)]
    height: u32,
}

/// The largest image side accepted.
const MAX_SIDE: u32 = 8192;
/// The field of view of a `--camera` without one, and of the default for scene files.
const DEFAULT_FOV: Real = 45.0;
/// The exposed luminance the 95th percentile of visible pixels is mapped to.
const PERCENTILE_TARGET: Real = 0.8;
/// The percentile of visible luminance that sets the exposure.
const PERCENTILE: Real = 0.95;
/// The linear display value of a patch seen from behind: dark grey (sRGB about 63).
const BACK_GREY: Real = 0.05;
/// Sub-pixel positions of the rays averaged into one pixel (2 × 2 stratified).
const SUBSAMPLES: [(Real, Real); 4] = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];

/// Runs `render`.
pub fn run(args: &Args) -> Result<()> {
    let start = Instant::now();
    // Every argument is checked before any geometry is built, so a typo fails at once.
    let (spec, _) = args.run.check()?;
    if !args.out.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        bail!("the output image must be a .png file, not '{}'", args.out.display());
    }
    check_output_file(&args.out)?;
    for (name, side) in [("width", args.width), ("height", args.height)] {
        if !(1..=MAX_SIDE).contains(&side) {
            bail!("--{name} {side} is out of range: an image side is 1 to {MAX_SIDE} pixels");
        }
    }
    let camera = args.camera.as_deref().map(Camera::parse).transpose()?;

    let prepared = prepare(&args.run.scene)?;
    print_warnings(&prepared.report());
    let scene = &prepared.loaded.scene;
    let aspect = Real::from(args.width) / Real::from(args.height);
    let camera = camera.unwrap_or_else(|| Camera::default_for(&args.run.scene, scene, aspect));
    let view = camera.view(args.width, args.height)?;
    let experiment = Experiment::new(&prepared, spec)?;
    let rgb = experiment.radiosity_rgb(&args.run.solver, &args.run.until)?;
    let corners = crate::shading::vertex_radiosity(scene, &rgb);

    let render_start = Instant::now();
    let tracer = Tracer { prepared: &prepared, corners: &corners, view };
    let exposure = tracer.exposure();
    let pixels = tracer.pixels(exposure);
    let render_seconds = render_start.elapsed().as_secs_f64();
    image::save_buffer_with_format(
        &args.out,
        &pixels,
        args.width,
        args.height,
        image::ExtendedColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .with_context(|| format!("cannot write '{}'", args.out.display()))?;
    println!(
        "wrote {}: {} × {} pixels, exposure {:.4e}, {:.2} s ({:.2} s rendering)",
        args.out.display(),
        args.width,
        args.height,
        exposure,
        start.elapsed().as_secs_f64(),
        render_seconds
    );
    Ok(())
}

/// A pinhole camera: eye, the point it looks at, and the vertical field of view in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Camera {
    eye: Vec3,
    target: Vec3,
    fov: Real,
}

impl Camera {
    /// Parses `x,y,z:tx,ty,tz[:fov]`.
    fn parse(arg: &str) -> Result<Camera> {
        let syntax =
            || format!("invalid camera '{arg}': expected x,y,z:tx,ty,tz[:fov], e.g. 278,273,-800:278,273,0:40");
        let point = |s: &str| -> Result<Vec3> {
            let v: Vec<Real> =
                s.split(',').map(|x| x.trim().parse::<Real>()).collect::<Result<_, _>>().ok().unwrap_or_default();
            match v[..] {
                [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(x, y, z)),
                _ => bail!(syntax()),
            }
        };
        let parts: Vec<&str> = arg.split(':').collect();
        let (eye, target, fov) = match parts[..] {
            [eye, target] => (point(eye)?, point(target)?, DEFAULT_FOV),
            [eye, target, fov] => {
                let fov: Real = fov.trim().parse().map_err(|_| anyhow::anyhow!(syntax()))?;
                (point(eye)?, point(target)?, fov)
            }
            _ => bail!(syntax()),
        };
        if !(fov > 0.0 && fov < 180.0) {
            bail!("invalid camera '{arg}': the field of view must lie strictly between 0 and 180 degrees");
        }
        if eye == target {
            bail!("invalid camera '{arg}': the eye and the point it looks at are the same");
        }
        Ok(Camera { eye, target, fov })
    }

    /// The default camera for scene argument `arg`, loaded as `scene`, for an image of aspect
    /// ratio `aspect` (width over height).
    fn default_for(arg: &str, scene: &Scene, aspect: Real) -> Camera {
        let (lo, hi) = scene.bounds();
        let builtin = if split_file_argument(arg).is_some() { "" } else { arg.split(':').next().unwrap_or_default() };
        let v = Vec3::new;
        match builtin {
            // The published camera (focal length 35 mm, 25 mm film: 39.3°), from in front of
            // the open side at z = 0, red wall (x ≈ 556) on the left. A closed box is seen
            // from just inside its front wall, high, looking down past the blocks.
            "cornell" if scene.objects().iter().any(|o| o == "front wall") => {
                Camera { eye: v(278.0, 440.0, 8.0), target: v(278.0, 180.0, 559.2), fov: 72.0 }
            }
            "cornell" => Camera { eye: v(278.0, 273.0, -800.0), target: v(278.0, 273.0, 0.0), fov: 39.3 },
            // Inside the closed cube [0, 4]³, against the front wall (z = 0) where two gaps of
            // the lattice cross (x = y = 1), looking up across the cubes to the ceiling light.
            "multi-cubes" => Camera { eye: v(1.0, 1.0, 0.05), target: v(3.0, 3.0, 4.0), fov: 80.0 },
            // Inside the room [0, 7.2] × [0, 2.7] × [0, 6], at eye height in the front left
            // corner, looking across the desks to the bookcases and filing cabinets.
            "office" => Camera { eye: v(0.3, 1.7, 0.3), target: v(5.0, 0.9, 5.0), fov: 70.0 },
            // The maze is open to the sky: from above its front edge, looking down at its middle.
            "labyrinth" => {
                let (c, size) = ((lo + hi) * 0.5, (hi - lo).max_element());
                Camera { eye: v(c.x, 0.8 * size, lo.z - 0.25 * size), target: v(c.x, 0.0, c.z), fov: 52.0 }
            }
            // Inside the closed cube (the unit cube times `scale`), near a top corner, looking
            // across to the opposite bottom corner (past the inner block, if any).
            "furnace" => {
                let size = (hi - lo).max_element();
                Camera { eye: lo + size * v(0.08, 0.85, 0.08), target: lo + size * v(0.75, 0.3, 0.75), fov: 75.0 }
            }
            // Anything else: from the +z side, 15° above, far enough for the bounding sphere
            // to fit the narrower of the two fields of view.
            _ => {
                let (c, radius) = ((lo + hi) * 0.5, (0.5 * (hi - lo).length()).max(Real::MIN_POSITIVE));
                let half_v = (DEFAULT_FOV * 0.5).to_radians();
                let half = half_v.min((half_v.tan() * aspect).atan());
                let distance = radius / half.sin();
                let up = 15f64.to_radians();
                Camera { eye: c + v(0.0, up.sin(), up.cos()) * distance, target: c, fov: DEFAULT_FOV }
            }
        }
    }

    /// The view through this camera for a `width × height` image.
    fn view(&self, width: u32, height: u32) -> Result<View> {
        let forward = (self.target - self.eye).normalize_or_zero();
        if forward == Vec3::ZERO {
            bail!("the camera's eye and the point it looks at are the same");
        }
        // +y up; looking straight up or down, -z is "up" on the image instead.
        let mut right = forward.cross(Vec3::Y);
        if right.length() < 1e-9 {
            right = forward.cross(Vec3::NEG_Z);
        }
        let right = right.normalize();
        let up = right.cross(forward);
        let half_h = (self.fov * 0.5).to_radians().tan();
        let half_w = half_h * Real::from(width) / Real::from(height);
        Ok(View { eye: self.eye, forward, right: right * half_w, up: up * half_h, width, height })
    }
}

/// A camera's rays for an image of a given size.
#[derive(Clone, Copy, Debug)]
struct View {
    eye: Vec3,
    forward: Vec3,
    /// The right vector scaled to half the image width at unit distance.
    right: Vec3,
    /// The up vector scaled to half the image height at unit distance.
    up: Vec3,
    width: u32,
    height: u32,
}

impl View {
    /// The direction of the ray through image position `(x, y)`, in pixels from the top left.
    fn direction(&self, x: Real, y: Real) -> Vec3 {
        let u = 2.0 * x / Real::from(self.width) - 1.0;
        let v = 1.0 - 2.0 * y / Real::from(self.height);
        self.forward + self.right * u + self.up * v
    }
}

/// What a ray sees.
enum Sample {
    /// Nothing: the ray leaves the scene.
    Miss,
    /// The back of a patch.
    Back,
    /// The front of a patch, with the interpolated radiosity there.
    Front([Real; 3]),
}

/// Traces primary rays and shades them.
struct Tracer<'a> {
    prepared: &'a crate::scene_report::PreparedScene,
    corners: &'a [Vec<[Real; 3]>],
    view: View,
}

impl Tracer<'_> {
    /// What the ray through image position `(x, y)` sees.
    fn trace(&self, x: Real, y: Real) -> Sample {
        let direction = self.view.direction(x, y);
        let Some(hit) = self.prepared.visibility.first_hit(self.view.eye, direction, None) else {
            return Sample::Miss;
        };
        if !hit.front {
            return Sample::Back;
        }
        let patch = &self.prepared.loaded.scene.patches()[hit.patch];
        let weights = corner_weights(patch, self.view.eye + direction * hit.t);
        let mut rgb = [0.0; 3];
        for (w, corner) in weights.iter().zip(&self.corners[hit.patch]) {
            for c in 0..3 {
                rgb[c] += w * corner[c];
            }
        }
        Sample::Front(rgb)
    }

    /// The exposure that maps the 95th percentile of the visible luminance, one ray through
    /// each pixel centre, to 0.8. When that percentile is zero the brightest pixel is used
    /// instead; with nothing lit at all, the exposure is 1.
    fn exposure(&self) -> Real {
        let (w, h) = (self.view.width, self.view.height);
        let mut luminance: Vec<Real> = (0..h)
            .into_par_iter()
            .flat_map_iter(|y| {
                (0..w).filter_map(move |x| match self.trace(Real::from(x) + 0.5, Real::from(y) + 0.5) {
                    Sample::Front(rgb) => Some(luminance_of(rgb)),
                    _ => None,
                })
            })
            .collect();
        if luminance.is_empty() {
            return 1.0;
        }
        let k = ((PERCENTILE * luminance.len() as Real).ceil() as usize).clamp(1, luminance.len()) - 1;
        let (_, &mut percentile, _) = luminance.select_nth_unstable_by(k, Real::total_cmp);
        let max = luminance.iter().copied().fold(0.0, Real::max);
        let reference = if percentile > 0.0 { percentile } else { max };
        if reference > 0.0 && reference.is_finite() { PERCENTILE_TARGET / reference } else { 1.0 }
    }

    /// The 8-bit sRGB pixels, row by row from the top, each the mean of its 2 × 2 rays.
    fn pixels(&self, exposure: Real) -> Vec<u8> {
        let (w, h) = (self.view.width as usize, self.view.height as usize);
        let mut pixels = vec![0u8; w * h * 3];
        pixels.par_chunks_mut(w * 3).enumerate().for_each(|(y, row)| {
            for (x, pixel) in row.chunks_exact_mut(3).enumerate() {
                let mut sum = [0.0; 3];
                for (dx, dy) in SUBSAMPLES {
                    let shown = match self.trace(x as Real + dx, y as Real + dy) {
                        Sample::Miss => [0.0; 3],
                        Sample::Back => [BACK_GREY; 3],
                        Sample::Front(rgb) => rgb.map(|c| (c * exposure).clamp(0.0, 1.0)),
                    };
                    for c in 0..3 {
                        sum[c] += shown[c];
                    }
                }
                for c in 0..3 {
                    pixel[c] = srgb_byte(sum[c] / SUBSAMPLES.len() as Real);
                }
            }
        });
        pixels
    }
}

/// Rec. 709 luminance of linear RGB.
fn luminance_of(rgb: [Real; 3]) -> Real {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// A linear value in `[0, 1]` encoded with the sRGB transfer curve, as a byte.
fn srgb_byte(linear: Real) -> u8 {
    let l = linear.clamp(0.0, 1.0);
    let encoded = if l <= 0.0031308 { 12.92 * l } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 };
    (encoded * 255.0).round() as u8
}

/// The weights of `patch`'s corners that reproduce the point `p` of its plane: barycentric on
/// a triangle, bilinear in the `(s, t)` of [`Patch::point_at`] on a quad. Points just outside
/// the patch (rays through its edges) get the weights of the nearest point of the patch.
fn corner_weights(patch: &Patch, p: Vec3) -> [Real; 4] {
    let v = patch.vertices();
    let n = patch.normal();
    // Twice the signed area of (a, b) seen from p, along the normal.
    let cross = |a: Vec3, b: Vec3| a.cross(b).dot(n);
    match patch.shape() {
        PatchShape::Triangle => {
            let w =
                [cross(v[1] - p, v[2] - p), cross(v[2] - p, v[0] - p), cross(v[0] - p, v[1] - p)].map(|w| w.max(0.0));
            let sum = w[0] + w[1] + w[2];
            if sum > 0.0 { [w[0] / sum, w[1] / sum, w[2] / sum, 0.0] } else { [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 0.0] }
        }
        PatchShape::Quad => {
            let (s, t) = inverse_bilinear(v[0], v[1], v[2], v[3], n, p);
            [(1.0 - s) * (1.0 - t), s * (1.0 - t), s * t, (1.0 - s) * t]
        }
    }
}

/// The `(s, t)` in the unit square with `p = (1 − t)((1 − s) a + s b) + t((1 − s) d + s c)`
/// for the planar convex quad `a b c d` of normal `n`, clamped to the square.
///
/// With `e = b − a`, `f = d − a`, `g = a − b + c − d` and `h = p − a`, `h = s (e + t g) + t f`;
/// crossing with `e + t g` (and projecting on `n`) leaves a quadratic in `t`, linear for a
/// parallelogram (`g = 0`); `s` then follows by projection on `e + t g`.
fn inverse_bilinear(a: Vec3, b: Vec3, c: Vec3, d: Vec3, n: Vec3, p: Vec3) -> (Real, Real) {
    let cross = |u: Vec3, v: Vec3| u.cross(v).dot(n);
    let (e, f, g, h) = (b - a, d - a, a - b + c - d, p - a);
    let k2 = cross(g, f);
    let k1 = cross(e, f) + cross(h, g);
    let k0 = cross(h, e);
    // k2 t² + k1 t + k0 = 0. cross(e, f) is about the quad's area, so the test is relative.
    let t = if k2.abs() <= 1e-12 * cross(e, f).abs() {
        if k1 != 0.0 { -k0 / k1 } else { 0.0 }
    } else {
        // The numerically stable pair of roots; keep the one nearer the unit interval.
        let q = -0.5 * (k1 + k1.signum() * (k1 * k1 - 4.0 * k2 * k0).max(0.0).sqrt());
        let roots = [q / k2, if q != 0.0 { k0 / q } else { q / k2 }];
        let outside = |t: Real| if t.is_finite() { (t - t.clamp(0.0, 1.0)).abs() } else { Real::INFINITY };
        if outside(roots[1]) < outside(roots[0]) { roots[1] } else { roots[0] }
    };
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let axis = e + g * t;
    let s = (h - f * t).dot(axis) / axis.length_squared();
    (if s.is_finite() { s.clamp(0.0, 1.0) } else { 0.0 }, t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use radiosity_core::{MaterialId, ObjectId};

    fn reproduce(patch: &Patch, s: Real, t: Real) {
        let p = patch.point_at(s, t);
        let w = corner_weights(patch, p);
        let back = patch.vertices().iter().zip(w).fold(Vec3::ZERO, |acc, (&v, w)| acc + v * w);
        assert!((back - p).length() < 1e-9 * patch.area().sqrt(), "{s} {t}: {back} against {p}");
        assert!((w.iter().sum::<Real>() - 1.0).abs() < 1e-12);
        assert!(w.iter().all(|&w| w >= 0.0));
    }

    #[test]
    fn corner_weights_reproduce_points_of_quads_and_triangles() {
        let (m, o) = (MaterialId(0), ObjectId(0));
        let trapezoid = Patch::quad(
            [Vec3::new(0.0, 0.0, 5.0), Vec3::new(4.0, 0.0, 5.0), Vec3::new(3.0, 1.0, 5.5), Vec3::new(0.5, 2.0, 6.0)],
            m,
            o,
        )
        .unwrap();
        let square = Patch::quad([Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y], m, o).unwrap();
        let triangle = Patch::triangle([Vec3::ZERO, Vec3::new(2.0, 0.0, 1.0), Vec3::new(0.0, 3.0, 0.0)], m, o).unwrap();
        for patch in [&trapezoid, &square, &triangle] {
            for i in 0..=6 {
                for j in 0..=6 {
                    reproduce(patch, i as Real / 6.0, j as Real / 6.0);
                }
            }
        }
        // On a quad, (s, t) itself comes back.
        let (s, t) = inverse_bilinear(
            trapezoid.vertices()[0],
            trapezoid.vertices()[1],
            trapezoid.vertices()[2],
            trapezoid.vertices()[3],
            trapezoid.normal(),
            trapezoid.point_at(0.3, 0.7),
        );
        assert!((s - 0.3).abs() < 1e-12 && (t - 0.7).abs() < 1e-12, "{s} {t}");
    }

    #[test]
    fn camera_syntax() {
        let c = Camera::parse("1,2,3:4,5,6").unwrap();
        assert_eq!((c.eye, c.target, c.fov), (Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0), DEFAULT_FOV));
        assert_eq!(Camera::parse("1,2,3:4,5,6:30").unwrap().fov, 30.0);
        for bad in ["1,2:4,5,6", "1,2,3", "a,b,c:4,5,6", "1,2,3:4,5,6:200", "1,2,3:1,2,3", "1,2,3:4,5,6:30:1", ""] {
            assert!(Camera::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn srgb_curve_ends() {
        assert_eq!((srgb_byte(0.0), srgb_byte(1.0), srgb_byte(2.0)), (0, 255, 255));
        // Mid grey: 0.2 linear is 0.4845 encoded.
        assert_eq!(srgb_byte(0.2), 124);
    }
}
