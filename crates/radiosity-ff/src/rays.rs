//! The rays form-factor backends trace: shadow-ray segments between two patches and rays to
//! their first hit. A leaf module, so that a backend can record its rays
//! ([`crate::traced`]) without the listing and the backend importing each other.

use radiosity_core::Vec3;

/// A shadow-ray segment: `p` on patch `from` to `q` on patch `to`, both patches ignored as
/// occluders ([`radiosity_geom::Visibility::unoccluded_between`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowSegment {
    /// The start, a point of patch `from`.
    pub p: Vec3,
    /// The patch `p` lies on.
    pub from: usize,
    /// The end, a point of patch `to`.
    pub q: Vec3,
    /// The patch `q` lies on.
    pub to: usize,
}

/// A ray traced to its first hit, ignoring patch `skip` (the shooter it leaves from;
/// [`radiosity_geom::Visibility::first_hit`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitRay {
    /// Where the ray starts.
    pub origin: Vec3,
    /// Its direction (not normalised).
    pub direction: Vec3,
    /// The patch it leaves from.
    pub skip: usize,
}

/// The rays of one or more columns.
#[derive(Clone, Debug, PartialEq)]
pub enum TracedRays {
    /// Occlusion queries on segments (`analytic`).
    Segments(Vec<ShadowSegment>),
    /// First-hit queries on rays (`hemicube`, `montecarlo`).
    Rays(Vec<HitRay>),
}

impl TracedRays {
    /// The number of rays.
    pub fn len(&self) -> usize {
        match self {
            TracedRays::Segments(s) => s.len(),
            TracedRays::Rays(r) => r.len(),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Removes every ray, keeping the kind and the allocation.
    pub fn clear(&mut self) {
        match self {
            TracedRays::Segments(s) => s.clear(),
            TracedRays::Rays(r) => r.clear(),
        }
    }
}
