//! The discrete radiosity system `B = E + diag(ρ) F B`, per channel, without the form factors.
//!
//! A [`LinearSystem`] holds what a solver needs besides the columns of `F`: the patch areas
//! (for reciprocity `F_ji = F_ij A_i / A_j`, selection and metrics), and reflectivity and
//! emission in the solved channels. Values are stored patch-major: the channels of patch `i`
//! are `i * channels .. (i + 1) * channels`.

use crate::error::CoreError;
use crate::math::Real;
use crate::scene::Scene;
use crate::spectrum::Channels;

/// Areas, reflectivities and emissions of the system to solve.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearSystem {
    channels: Channels,
    area: Vec<Real>,
    reflectivity: Vec<Real>,
    emission: Vec<Real>,
}

impl LinearSystem {
    /// The system of `scene` in the channels the scene needs ([`Scene::channels`]).
    pub fn from_scene(scene: &Scene) -> LinearSystem {
        let channels = scene.channels();
        let k = channels.count();
        let n = scene.len();
        let mut reflectivity = Vec::with_capacity(n * k);
        let mut emission = Vec::with_capacity(n * k);
        for i in 0..n {
            let (r, e) = (scene.reflectivity(i), scene.emission(i));
            for c in 0..k {
                reflectivity.push(r.channel(c));
                emission.push(e.channel(c));
            }
        }
        let area = scene.patches().iter().map(|p| p.area()).collect();
        LinearSystem { channels, area, reflectivity, emission }
    }

    /// A system from raw arrays (patch-major), validated like a scene.
    pub fn new(
        channels: Channels,
        area: Vec<Real>,
        reflectivity: Vec<Real>,
        emission: Vec<Real>,
    ) -> Result<LinearSystem, CoreError> {
        let n = area.len();
        if n == 0 {
            return Err(CoreError::EmptyScene);
        }
        let k = channels.count();
        for (what, v) in [("reflectivity", &reflectivity), ("emission", &emission)] {
            if v.len() != n * k {
                return Err(CoreError::SizeMismatch { what, expected: n * k, found: v.len() });
            }
        }
        if let Some((patch, &area)) = area.iter().enumerate().find(|(_, a)| !(a.is_finite() && **a > 0.0)) {
            return Err(CoreError::InvalidArea { patch, area });
        }
        for (idx, &value) in reflectivity.iter().enumerate() {
            if !(0.0..1.0).contains(&value) {
                return Err(CoreError::InvalidReflectivity { material: format!("patch {}", idx / k), value });
            }
        }
        for (idx, &value) in emission.iter().enumerate() {
            if !(value.is_finite() && value >= 0.0) {
                return Err(CoreError::InvalidEmission { material: format!("patch {}", idx / k), value });
            }
        }
        Ok(LinearSystem { channels, area, reflectivity, emission })
    }

    /// The number of patches.
    pub fn len(&self) -> usize {
        self.area.len()
    }

    /// Always false: a system has at least one patch.
    pub fn is_empty(&self) -> bool {
        self.area.is_empty()
    }

    /// The solved channels.
    pub fn channels(&self) -> Channels {
        self.channels
    }

    /// Patch areas.
    pub fn areas(&self) -> &[Real] {
        &self.area
    }

    /// Reflectivities, patch-major.
    pub fn reflectivities(&self) -> &[Real] {
        &self.reflectivity
    }

    /// Emissions, patch-major.
    pub fn emissions(&self) -> &[Real] {
        &self.emission
    }

    /// Reflectivity of patch `i` in channel `c`.
    pub fn rho(&self, i: usize, c: usize) -> Real {
        self.reflectivity[i * self.channels.count() + c]
    }

    /// Emission of patch `i` in channel `c`.
    pub fn e(&self, i: usize, c: usize) -> Real {
        self.emission[i * self.channels.count() + c]
    }
}
