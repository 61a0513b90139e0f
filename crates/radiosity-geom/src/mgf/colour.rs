//! MGF colours (`cxy`, `cspec`, `cct`, `cmix`) as CIE XYZ chromaticities, and their
//! conversion to the linear RGB reflectivities and emissions of a scene.
//!
//! An MGF colour has no brightness of its own: it is a chromaticity, and the value of `rd` or
//! `ed` gives the luminance `Y`. A colour is kept here as CIE XYZ scaled to `Y = 1`.
//!
//! **To RGB.** CIE xyY → XYZ (`X = x Y / y`, `Z = (1 − x − y) Y / y`) → linear sRGB (Rec. 709
//! primaries, the standard D65 matrix of IEC 61966-2-1). MGF's neutral colour is the
//! equal-energy white E (`x = y = 1/3`), not D65, so each RGB channel is then divided by that
//! channel of E (a von Kries white balance in RGB): `cxy 0.333 0.333` comes out grey, with
//! every channel equal to the `rd` or `ed` value. Negative channels (chromaticities outside
//! the sRGB gamut) are clamped to 0.
//!
//! **Spectra.** `cspec` samples and `cct` black bodies are integrated against the CIE 1931 2°
//! colour-matching functions in the multi-lobe Gaussian fit of Wyman, Sloan and Shirley,
//! "Simple Analytic Approximations to the CIE XYZ Color Matching Functions", JCGT 2(2), 2013
//! (errors below about 1% of the peak, far below what a radiosity reflectivity needs), on a
//! 1 nm grid from 380 to 780 nm; `cspec` samples are interpolated linearly and are zero
//! outside their range. `cmix` mixes colours as MGF does: each weight is a luminance, so the
//! mix is the sum of the colours' XYZ, each scaled to `Y = weight`.

use radiosity_core::{Real, Spectrum};

/// A chromaticity as CIE XYZ with `Y = 1`, or black.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Colour {
    /// X / Y.
    pub x: Real,
    /// Z / Y.
    pub z: Real,
    /// 1, or 0 for black: what RenderPark makes of a chromaticity with `y ≤ 0` ("invalid
    /// color specification (Y<=0) … setting to black"), which scales every use to nothing.
    pub luminance: Real,
}

impl Default for Colour {
    /// MGF's default colour: the equal-energy white, `x = y = 1/3`.
    fn default() -> Self {
        Colour { x: 1.0, z: 1.0, luminance: 1.0 }
    }
}

/// XYZ to linear sRGB (D65), row by row.
const XYZ_TO_RGB: [[Real; 3]; 3] = [
    [3.240_454_2, -1.537_138_5, -0.498_531_4],
    [-0.969_266_0, 1.876_010_8, 0.041_556_0],
    [0.055_643_4, -0.204_025_9, 1.057_225_2],
];

impl Colour {
    /// The colour with chromaticity `(x, y)`, or `None` where that is not a chromaticity.
    pub fn from_xy(x: Real, y: Real) -> Option<Colour> {
        if !(x.is_finite() && y.is_finite() && x >= 0.0 && y > 0.0 && x + y <= 1.0 + 1e-9) {
            return None;
        }
        Some(Colour { x: x / y, z: (1.0 - x - y).max(0.0) / y, luminance: 1.0 })
    }

    /// The colour of XYZ tristimulus values, or `None` where `Y` is not positive.
    pub fn from_xyz([x, y, z]: [Real; 3]) -> Option<Colour> {
        (y > 0.0 && y.is_finite()).then(|| Colour { x: x.max(0.0) / y, z: z.max(0.0) / y, luminance: 1.0 })
    }

    /// Black: every `rd` or `ed` value of this colour gives nothing.
    pub const BLACK: Colour = Colour { x: 1.0, z: 1.0, luminance: 0.0 };

    /// The chromaticity `(x, y)`.
    pub fn xy(self) -> (Real, Real) {
        let sum = self.x + 1.0 + self.z;
        (self.x / sum, 1.0 / sum)
    }

    /// The colour of a spectrum sampled evenly from `min_nm` to `max_nm` (at least two samples).
    pub fn from_samples(min_nm: Real, max_nm: Real, samples: &[Real]) -> Option<Colour> {
        if samples.len() < 2 || max_nm.partial_cmp(&min_nm) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let step = (max_nm - min_nm) / (samples.len() - 1) as Real;
        Colour::from_xyz(integrate(|nm| {
            if nm < min_nm || nm > max_nm {
                return 0.0;
            }
            let t = (nm - min_nm) / step;
            let i = (t.floor() as usize).min(samples.len() - 2);
            let f = t - i as Real;
            samples[i] * (1.0 - f) + samples[i + 1] * f
        }))
    }

    /// The colour of a black body at `kelvin`.
    pub fn black_body(kelvin: Real) -> Option<Colour> {
        if !(kelvin > 0.0 && kelvin.is_finite()) {
            return None;
        }
        // Planck's law up to a constant factor, with c2 = hc/k in nm·K.
        const C2: Real = 1.438_777e7;
        Colour::from_xyz(integrate(|nm| 1.0 / (nm.powi(5) * ((C2 / (nm * kelvin)).exp_m1()))))
    }

    /// MGF's `cmix`: the sum of the colours, each with luminance its weight.
    pub fn mix(parts: &[(Real, Colour)]) -> Option<Colour> {
        let mut xyz = [0.0; 3];
        for &(w, c) in parts {
            let w = w * c.luminance;
            xyz[0] += w * c.x;
            xyz[1] += w;
            xyz[2] += w * c.z;
        }
        Colour::from_xyz(xyz)
    }

    /// Linear RGB with luminance factor `value` (the `rd` or `ed` value), white-balanced so
    /// that the equal-energy white gives `(value, value, value)`; negative channels are 0.
    pub fn rgb(self, value: Real) -> Spectrum {
        let xyz = [self.x, 1.0, self.z];
        let white = Colour::default();
        let white = [white.x, 1.0, white.z];
        let mut rgb = [0.0; 3];
        for (c, row) in XYZ_TO_RGB.iter().enumerate() {
            let dot = |v: [Real; 3]| row[0] * v[0] + row[1] * v[1] + row[2] * v[2];
            rgb[c] = (self.luminance * value * dot(xyz) / dot(white)).max(0.0);
        }
        Spectrum(rgb)
    }
}

/// `∫ f(λ) (x̄, ȳ, z̄)(λ) dλ` over 380–780 nm on a 1 nm grid.
fn integrate(f: impl Fn(Real) -> Real) -> [Real; 3] {
    let mut xyz = [0.0; 3];
    for nm in 380..=780 {
        let nm = nm as Real;
        let v = f(nm);
        let [x, y, z] = matching(nm);
        xyz[0] += v * x;
        xyz[1] += v * y;
        xyz[2] += v * z;
    }
    xyz
}

/// The CIE 1931 colour-matching functions at `nm`, in the fit of Wyman, Sloan and Shirley.
pub fn matching(nm: Real) -> [Real; 3] {
    let g = |mu: Real, below: Real, above: Real| {
        let t = (nm - mu) / if nm < mu { below } else { above };
        (-0.5 * t * t).exp()
    };
    let x = 1.056 * g(599.8, 37.9, 31.0) + 0.362 * g(442.0, 16.0, 26.7) - 0.065 * g(501.1, 20.4, 26.2);
    let y = 0.821 * g(568.8, 46.9, 40.5) + 0.286 * g(530.9, 16.3, 31.1);
    let z = 1.217 * g(437.0, 11.8, 36.0) + 0.681 * g(459.0, 26.0, 13.8);
    [x, y, z]
}
