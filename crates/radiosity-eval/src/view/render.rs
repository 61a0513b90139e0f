//! Pictures of a solved scene: a pinhole camera ray-casts the scene's BVH, radiosity is shaded
//! smoothly over each patch, and the image is exposed to its content and tone mapped to 8-bit
//! sRGB.
//!
//! ## Camera
//!
//! A pinhole camera ([`Camera`]): an eye, a point it looks at, an up direction (+y, as every
//! built-in scene, unless [`Camera::with_up`] sets the scene's own, [`crate::up_axis`]) and a
//! vertical field of view in degrees; written `x,y,z:tx,ty,tz[:fov]`
//! ([`Camera::from_str`](std::str::FromStr::from_str)), 45° when the field of view is left
//! out. Each built-in scene has a preset chosen to show what matters in it, kept beside the
//! scene in `radiosity_geom::scenes` ([`radiosity_geom::CameraPreset`]) and made the default by
//! [`Camera::default_for`]: the Cornell box from its published camera, looking into the open
//! front (inside the box when `front=true` closes it); the closed rooms (`multi-cubes`,
//! `office`, `furnace`) from inside, near a wall or corner, looking across; the labyrinth, open
//! to the sky, from above and in front, looking down at its middle. A scene file is framed by
//! [`crate::default_view`]: from inside its enclosure where there is one, else from outside
//! (module `framing`).
//!
//! ## Shading
//!
//! Primary rays go through the scene's BVH ([`radiosity_geom::Visibility::first_hit`]).
//! Radiosity is constant over a patch, but an image of constant patches shows the mesh rather
//! than the lighting, so the shading is smooth: each patch corner carries the radiosity of
//! [`vertex_radiosity`] (the area-weighted mean of the patches meeting there on the same
//! smooth surface), interpolated over the patch with the weights that reproduce the hit
//! point ([`corner_weights`]): barycentric on a triangle, bilinear on a quad in the quad's own
//! `(s, t)` parametrisation (the one `Patch::point_at` and the mesher's grids use), so a grid
//! of quads shades continuously, without the diagonal seams of splitting quads into
//! triangles. A patch seen from behind (it neither emits nor
//! reflects on that side) is dark grey; a ray that leaves the scene is black. Each pixel
//! averages 2 × 2 stratified rays, for smooth edges; every pixel is computed on its own, so
//! the image is the same whatever the thread count.
//!
//! ## Tone mapping
//!
//! Radiosity is linear and has no natural display scale (emitters can be a hundred times
//! brighter than the walls they light), so the image is exposed to its content: the exposure
//! scales the 95th percentile of the luminance (Rec. 709 weights on linear RGB) of the pixels
//! that see a front face, one ray through each pixel centre, to 0.8. The few brightest pixels
//! (the emitters, mostly) then saturate, and everything else keeps its ratios, which is what a
//! radiosity picture is for. Each ray's exposed colour is clamped to `[0, 1]`, the rays of a
//! pixel averaged, and the mean encoded with the sRGB transfer curve ([`srgb_byte`], IEC
//! 61966-2-1) into 8-bit RGB, written as PNG by [`Image::write_png`].
//!
//! ```no_run
//! use radiosity_eval::{Camera, RenderParams, render};
//!
//! let spec = radiosity_geom::SceneSpec::parse("cornell:res=4").unwrap();
//! let scene = spec.load().unwrap().scene;
//! let visibility = radiosity_geom::Visibility::new(&scene);
//! let rgb: Vec<[f64; 3]> = (0..scene.len()).map(|i| scene.emission(i).0).collect();
//! let camera = Camera::default_for(&spec, &scene, 4.0 / 3.0);
//! let image = render(&scene, &visibility, &rgb, &RenderParams::new(camera)).unwrap();
//! image.save("cornell.png".as_ref()).unwrap();
//! ```

use crate::error::EvalError;
use crate::view::shading::vertex_radiosity;
use radiosity_core::{Patch, PatchShape, Real, Scene, Vec3};
use radiosity_geom::{CameraPreset, SceneSpec, Visibility};
use rayon::prelude::*;
use std::io::Write;
use std::path::Path;
use std::str::FromStr;

/// The largest image side accepted, in pixels.
pub const MAX_SIDE: u32 = 8192;
/// The field of view of a camera written without one, and of the default for scene files.
pub const DEFAULT_FOV: Real = 45.0;
/// The exposed luminance the 95th percentile of visible pixels is mapped to.
const PERCENTILE_TARGET: Real = 0.8;
/// The percentile of visible luminance that sets the exposure.
const PERCENTILE: Real = 0.95;
/// The linear display value of a patch seen from behind: dark grey (sRGB about 63).
const BACK_GREY: Real = 0.05;
/// Sub-pixel positions of the rays averaged into one pixel (2 × 2 stratified).
const SUBSAMPLES: [(Real, Real); 4] = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];
/// The reason given for a camera string that does not parse.
const CAMERA_SYNTAX: &str = "expected x,y,z:tx,ty,tz[:fov], e.g. 278,273,-800:278,273,0:40";

/// A pinhole camera: eye, the point it looks at, and the vertical field of view in degrees,
/// with +y up on the image (−z when looking straight up or down).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    eye: Vec3,
    target: Vec3,
    fov: Real,
    up: Vec3,
}

impl Camera {
    /// A camera at `eye` looking at `target` with a vertical field of view of `fov` degrees.
    /// Refused unless every coordinate is finite, the field of view lies strictly between 0
    /// and 180 degrees, and the eye is not the target.
    pub fn new(eye: Vec3, target: Vec3, fov: Real) -> Result<Camera, EvalError> {
        let fail = |reason| {
            let camera = format!("{},{},{}:{},{},{}:{fov}", eye.x, eye.y, eye.z, target.x, target.y, target.z);
            Err(EvalError::InvalidCamera { camera, reason })
        };
        if !(eye.is_finite() && target.is_finite()) {
            return fail("its coordinates must be finite");
        }
        Self::checked(eye, target, fov).map_or_else(fail, Ok)
    }

    /// The camera, or the reason it is refused (for finite coordinates).
    fn checked(eye: Vec3, target: Vec3, fov: Real) -> Result<Camera, &'static str> {
        if !(fov > 0.0 && fov < 180.0) {
            return Err("the field of view must lie strictly between 0 and 180 degrees");
        }
        if eye == target {
            return Err("the eye and the point it looks at are the same");
        }
        Ok(Camera { eye, target, fov, up: Vec3::Y })
    }

    /// The same camera with `up` up on the image (+y unless set; a scene's up axis,
    /// [`crate::up_axis`]); a zero or non-finite `up` leaves it as it was.
    pub fn with_up(self, up: Vec3) -> Camera {
        let up = up.normalize_or_zero();
        if up == Vec3::ZERO || !up.is_finite() { self } else { Camera { up, ..self } }
    }

    /// The direction that is up on the image.
    pub fn up(&self) -> Vec3 {
        self.up
    }

    /// Where the camera is.
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The point it looks at.
    pub fn target(&self) -> Vec3 {
        self.target
    }

    /// The vertical field of view, in degrees.
    pub fn fov(&self) -> Real {
        self.fov
    }

    /// The default camera for the scene `spec` names (a built-in scene with its parameters, or
    /// a file), loaded as `scene`, for an image of aspect ratio `aspect` (width over height):
    /// the built-in scene's camera preset ([`radiosity_geom::BuiltinScene::camera`]), or for
    /// any other scene a view from its +z side that fits its bounding sphere.
    pub fn default_for(spec: &SceneSpec, scene: &Scene, aspect: Real) -> Camera {
        let preset = spec.builtin().and_then(|s| s.camera(scene));
        if let Some(CameraPreset { eye, target, fov }) = preset {
            return Camera { eye, target, fov, up: Vec3::Y };
        }
        // Anything else: from the +z side, 15° above, far enough for the bounding sphere to
        // fit the narrower of the two fields of view.
        let (lo, hi) = scene.bounds();
        let (c, radius) = ((lo + hi) * 0.5, (0.5 * (hi - lo).length()).max(Real::MIN_POSITIVE));
        let half_v = (DEFAULT_FOV * 0.5).to_radians();
        let half = half_v.min((half_v.tan() * aspect).atan());
        let distance = radius / half.sin();
        let up = 15f64.to_radians();
        Camera { eye: c + Vec3::new(0.0, up.sin(), up.cos()) * distance, target: c, fov: DEFAULT_FOV, up: Vec3::Y }
    }

    /// The share of a coarse `width × height` grid of rays through this camera that see the
    /// front of a patch: how much of a picture would show lit surfaces rather than the black
    /// beyond the scene or the backs of its walls.
    pub fn front_share(&self, visibility: &Visibility, width: u32, height: u32) -> Real {
        let Ok(view) = self.view(width.max(1), height.max(1)) else { return 0.0 };
        let mut front = 0usize;
        for y in 0..view.height {
            for x in 0..view.width {
                let d = view.direction(Real::from(x) + 0.5, Real::from(y) + 0.5);
                front += usize::from(visibility.first_hit(view.eye, d, None).is_some_and(|h| h.front));
            }
        }
        front as Real / Real::from(view.width * view.height)
    }

    /// The view through this camera for a `width × height` image.
    fn view(&self, width: u32, height: u32) -> Result<View, EvalError> {
        let forward = (self.target - self.eye).normalize_or_zero();
        if forward == Vec3::ZERO || !forward.is_finite() {
            return Err(EvalError::InvalidCamera {
                camera: format!("{}:{}:{}", self.eye, self.target, self.fov),
                reason: "the eye and the point it looks at are the same",
            });
        }
        // The camera's up; looking straight along it, the next axis round is "up" instead.
        let mut right = forward.cross(self.up);
        if right.length() < 1e-9 {
            right = forward.cross(-Vec3::new(self.up.z, self.up.x, self.up.y));
        }
        let right = right.normalize();
        let up = right.cross(forward);
        let half_h = (self.fov * 0.5).to_radians().tan();
        let half_w = half_h * Real::from(width) / Real::from(height);
        Ok(View { eye: self.eye, forward, right: right * half_w, up: up * half_h, width, height })
    }
}

impl FromStr for Camera {
    type Err = EvalError;

    /// Parses `x,y,z:tx,ty,tz[:fov]`: the eye, the point it looks at and optionally the
    /// vertical field of view in degrees ([`DEFAULT_FOV`] without one).
    fn from_str(arg: &str) -> Result<Camera, EvalError> {
        let fail = |reason| EvalError::InvalidCamera { camera: arg.to_string(), reason };
        let point = |s: &str| -> Result<Vec3, EvalError> {
            let v: Vec<Real> =
                s.split(',').map(|x| x.trim().parse::<Real>()).collect::<Result<_, _>>().ok().unwrap_or_default();
            match v[..] {
                [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(x, y, z)),
                _ => Err(fail(CAMERA_SYNTAX)),
            }
        };
        let parts: Vec<&str> = arg.split(':').collect();
        let (eye, target, fov) = match parts[..] {
            [eye, target] => (point(eye)?, point(target)?, DEFAULT_FOV),
            [eye, target, fov] => {
                let fov: Real = fov.trim().parse().map_err(|_| fail(CAMERA_SYNTAX))?;
                (point(eye)?, point(target)?, fov)
            }
            _ => return Err(fail(CAMERA_SYNTAX)),
        };
        Camera::checked(eye, target, fov).map_err(fail)
    }
}

/// What to render: the camera and the image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderParams {
    /// The camera.
    pub camera: Camera,
    /// Image width in pixels, 1 to [`MAX_SIDE`].
    pub width: u32,
    /// Image height in pixels, 1 to [`MAX_SIDE`].
    pub height: u32,
}

impl RenderParams {
    /// A 640 × 480 picture through `camera`; change the size with struct update syntax.
    pub fn new(camera: Camera) -> RenderParams {
        RenderParams { camera, width: 640, height: 480 }
    }

    /// Checks that both sides lie in `1..=MAX_SIDE`.
    pub fn validate(&self) -> Result<(), EvalError> {
        for (name, side) in [("width", self.width), ("height", self.height)] {
            if !(1..=MAX_SIDE).contains(&side) {
                return Err(EvalError::InvalidParameter {
                    name,
                    value: side.to_string(),
                    reason: "an image side is 1 to 8192 pixels",
                });
            }
        }
        Ok(())
    }
}

/// A rendered picture: 8-bit sRGB pixels, row by row from the top, three bytes per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` RGB8 pixels, row by row from the top.
    pub pixels: Vec<u8>,
    /// The factor applied to linear radiosity before clamping to `[0, 1]`.
    pub exposure: Real,
}

impl Image {
    /// Writes the image as PNG to `out`.
    pub fn write_png(&self, out: impl Write) -> Result<(), EvalError> {
        crate::view::png_image::write_rgb8(out, &self.pixels, self.width, self.height)
    }

    /// Writes the image as PNG to the file `path`, creating or replacing it.
    pub fn save(&self, path: &Path) -> Result<(), EvalError> {
        let write_error = |e: std::io::Error| EvalError::Write { path: path.to_path_buf(), message: e.to_string() };
        let mut out = std::io::BufWriter::new(std::fs::File::create(path).map_err(write_error)?);
        self.write_png(&mut out)?;
        out.flush().map_err(write_error)
    }
}

/// Renders `scene`, whose BVH is `visibility`, lit by the per-patch RGB radiosity `rgb`, as
/// the module documentation describes. Refused when the sizes are out of range, `rgb` does not
/// have one finite triple per patch, or `visibility` was not built over `scene`.
pub fn render(
    scene: &Scene,
    visibility: &Visibility,
    rgb: &[[Real; 3]],
    params: &RenderParams,
) -> Result<Image, EvalError> {
    params.validate()?;
    if let Some(patch) = rgb.iter().position(|b| b.iter().any(|c| !c.is_finite())) {
        return Err(EvalError::NonFiniteRadiosity { patch });
    }
    let triangles: usize = scene.patches().iter().map(|p| p.vertices().len() - 2).sum();
    if visibility.triangle_count() != triangles {
        return Err(EvalError::SizeMismatch {
            what: "the BVH's triangles (it was built over another scene)",
            expected: triangles,
            found: visibility.triangle_count(),
        });
    }
    let corners = vertex_radiosity(scene, rgb)?;
    let view = params.camera.view(params.width, params.height)?;
    let tracer = Tracer { scene, visibility, corners: &corners, view };
    let exposure = ExposureProbe::through(scene, visibility, view).exposure(&|i, v| corners[i][v]);
    let pixels = tracer.pixels(exposure);
    Ok(Image { width: params.width, height: params.height, pixels, exposure })
}

/// Where the rays through the pixel centres of an image land on the fronts of patches: what
/// the exposure of [`render`] reads. Kept, it sets the exposure of any radiosity of the same
/// scene seen through the same camera without casting a ray again (the live page of
/// [`crate::live`] re-exposes every update this way).
#[derive(Clone, Debug)]
pub struct ExposureProbe {
    /// Each front hit: the patch and its corners' weights at the hit point.
    hits: Vec<(usize, [Real; 4])>,
}

impl ExposureProbe {
    /// The probe of a `width × height` image of `scene` through `camera`.
    pub fn new(
        scene: &Scene,
        visibility: &Visibility,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<ExposureProbe, EvalError> {
        RenderParams { camera: *camera, width, height }.validate()?;
        Ok(ExposureProbe::through(scene, visibility, camera.view(width, height)?))
    }

    fn through(scene: &Scene, visibility: &Visibility, view: View) -> ExposureProbe {
        let hits = (0..view.height)
            .into_par_iter()
            .flat_map_iter(|y| {
                (0..view.width).filter_map(move |x| {
                    let direction = view.direction(Real::from(x) + 0.5, Real::from(y) + 0.5);
                    let hit = visibility.first_hit(view.eye, direction, None).filter(|h| h.front)?;
                    let patch = scene.patches().get(hit.patch)?;
                    Some((hit.patch, corner_weights(patch, view.eye + direction * hit.t)))
                })
            })
            .collect();
        ExposureProbe { hits }
    }

    /// The exposure that maps the 95th percentile of the visible luminance, one ray through
    /// each pixel centre, to 0.8, for the radiosity `corner(i, v)` at corner `v` of patch `i`.
    /// When that percentile is zero the brightest pixel is used instead; with nothing lit at
    /// all, the exposure is 1.
    pub fn exposure(&self, corner: &(dyn Fn(usize, usize) -> [Real; 3] + Sync)) -> Real {
        let mut luminance: Vec<Real> = self
            .hits
            .par_iter()
            .map(|&(patch, weights)| {
                let mut rgb = [0.0; 3];
                for (v, w) in weights.iter().enumerate().filter(|(_, w)| **w != 0.0) {
                    let value = corner(patch, v);
                    for c in 0..3 {
                        rgb[c] += w * value[c];
                    }
                }
                luminance_of(rgb)
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
    scene: &'a Scene,
    visibility: &'a Visibility,
    corners: &'a [Vec<[Real; 3]>],
    view: View,
}

impl Tracer<'_> {
    /// What the ray through image position `(x, y)` sees.
    fn trace(&self, x: Real, y: Real) -> Sample {
        let direction = self.view.direction(x, y);
        let Some(hit) = self.visibility.first_hit(self.view.eye, direction, None) else {
            return Sample::Miss;
        };
        if !hit.front {
            return Sample::Back;
        }
        let (Some(patch), Some(corners)) = (self.scene.patches().get(hit.patch), self.corners.get(hit.patch)) else {
            return Sample::Miss;
        };
        let weights = corner_weights(patch, self.view.eye + direction * hit.t);
        let mut rgb = [0.0; 3];
        for (w, corner) in weights.iter().zip(corners) {
            for c in 0..3 {
                rgb[c] += w * corner[c];
            }
        }
        Sample::Front(rgb)
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

/// A linear value in `[0, 1]` encoded with the sRGB transfer curve, as a byte (values
/// outside `[0, 1]` are clamped first).
pub fn srgb_byte(linear: Real) -> u8 {
    let l = linear.clamp(0.0, 1.0);
    let encoded = if l <= 0.0031308 { 12.92 * l } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 };
    (encoded * 255.0).round() as u8
}

/// The weights of `patch`'s corners that reproduce the point `p` of its plane: barycentric on
/// a triangle, bilinear in the `(s, t)` of [`Patch::point_at`] on a quad. Points just outside
/// the patch (rays through its edges) get the weights of the nearest point of the patch. The
/// weights are non-negative, sum to 1, and a quad's are `[(1 − s)(1 − t), s (1 − t), s t,
/// (1 − s) t]`; a triangle's fourth weight is 0.
pub fn corner_weights(patch: &Patch, p: Vec3) -> [Real; 4] {
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
