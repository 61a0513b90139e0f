//! Where each built-in scene is best seen from: its camera preset, plain data (eye, target,
//! vertical field of view) that a renderer builds its camera from. Every built-in scene is
//! y-up, so a preset needs no up vector.

use radiosity_core::{Real, Vec3};

/// A pinhole camera preset: the eye, the point it looks at and the vertical field of view in
/// degrees, +y up on the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPreset {
    /// Where the camera is.
    pub eye: Vec3,
    /// The point it looks at.
    pub target: Vec3,
    /// The vertical field of view, in degrees.
    pub fov: Real,
}
