//! RGB spectra for reflectivity, emission and radiosity, and the choice of solved channels.
//!
//! Every scene is described in RGB. A scene whose materials are all grey (the three channels
//! equal) is solved as one channel: the answer is the same and costs a third. [`Channels`]
//! records that choice; [`Spectrum::channel`] reads a channel under it.

use crate::math::Real;
use std::ops::{Add, AddAssign, Mul};

/// An RGB triple of non-negative values (reflectivity, emission or radiosity).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spectrum(pub [Real; 3]);

impl Spectrum {
    /// Black: all channels zero.
    pub const ZERO: Spectrum = Spectrum([0.0; 3]);

    /// A spectrum with the three given channels.
    pub const fn rgb(r: Real, g: Real, b: Real) -> Self {
        Spectrum([r, g, b])
    }

    /// A grey spectrum: every channel equal to `v`.
    pub const fn grey(v: Real) -> Self {
        Spectrum([v, v, v])
    }

    /// The value of channel `c` (0 = red, 1 = green, 2 = blue).
    ///
    /// Under [`Channels::Grey`] there is only channel 0, and it reads red, which equals the
    /// others for a grey spectrum.
    pub fn channel(&self, c: usize) -> Real {
        self.0[c]
    }

    /// The mean over the three channels.
    pub fn mean(&self) -> Real {
        (self.0[0] + self.0[1] + self.0[2]) / 3.0
    }

    /// The largest channel.
    pub fn max(&self) -> Real {
        self.0[0].max(self.0[1]).max(self.0[2])
    }

    /// The smallest channel.
    pub fn min(&self) -> Real {
        self.0[0].min(self.0[1]).min(self.0[2])
    }

    /// True when the three channels are exactly equal.
    pub fn is_grey(&self) -> bool {
        self.0[0] == self.0[1] && self.0[1] == self.0[2]
    }

    /// True when no channel is NaN or infinite.
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }

    /// True when any channel is strictly positive.
    pub fn is_positive(&self) -> bool {
        self.0.iter().any(|&v| v > 0.0)
    }
}

impl Add for Spectrum {
    type Output = Spectrum;
    fn add(self, o: Spectrum) -> Spectrum {
        Spectrum([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
}

impl AddAssign for Spectrum {
    fn add_assign(&mut self, o: Spectrum) {
        *self = *self + o;
    }
}

impl Mul<Real> for Spectrum {
    type Output = Spectrum;
    fn mul(self, s: Real) -> Spectrum {
        Spectrum(self.0.map(|v| v * s))
    }
}

impl Mul for Spectrum {
    type Output = Spectrum;
    fn mul(self, o: Spectrum) -> Spectrum {
        Spectrum([self.0[0] * o.0[0], self.0[1] * o.0[1], self.0[2] * o.0[2]])
    }
}

/// Which channels a system is solved in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channels {
    /// One channel: every material is grey.
    Grey,
    /// Red, green and blue.
    Rgb,
}

impl Channels {
    /// The number of solved channels (1 or 3).
    pub fn count(self) -> usize {
        match self {
            Channels::Grey => 1,
            Channels::Rgb => 3,
        }
    }
}
