//! The scene description: patches, the materials they use and the objects they came from.
//!
//! A [`Scene`] is validated on construction: it has at least one patch, every reflectivity is
//! in `[0, 1)` and every emission finite and non-negative, and every patch refers to an
//! existing material and object. Reflectivity and emission belong to materials; a patch reads
//! them through its [`MaterialId`](crate::MaterialId), so there is one source of truth per surface.

use crate::error::CoreError;
use crate::math::{Real, Vec3, bounding_diagonal};
use crate::patch::Patch;
use crate::spectrum::{Channels, Spectrum};

/// A diffuse material: what fraction of incident light a surface reflects, and what it emits.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name, for messages and provenance.
    pub name: String,
    /// Diffuse reflectivity per channel, in `[0, 1)`.
    pub reflectivity: Spectrum,
    /// Emitted radiosity per channel, at least 0.
    pub emission: Spectrum,
}

impl Material {
    /// A material with the given name, reflectivity and emission (validated by [`Scene::new`]).
    pub fn new(name: impl Into<String>, reflectivity: Spectrum, emission: Spectrum) -> Self {
        Material { name: name.into(), reflectivity, emission }
    }

    /// Checks that reflectivity lies in `[0, 1)` and emission is finite and non-negative.
    pub fn validate(&self) -> Result<(), CoreError> {
        for &value in &self.reflectivity.0 {
            if !(0.0..1.0).contains(&value) {
                return Err(CoreError::InvalidReflectivity { material: self.name.clone(), value });
            }
        }
        for &value in &self.emission.0 {
            if !(value.is_finite() && value >= 0.0) {
                return Err(CoreError::InvalidEmission { material: self.name.clone(), value });
            }
        }
        Ok(())
    }
}

/// Patches with their materials and object names.
#[derive(Clone, Debug)]
pub struct Scene {
    name: String,
    patches: Vec<Patch>,
    materials: Vec<Material>,
    objects: Vec<String>,
}

impl Scene {
    /// Builds and validates a scene.
    pub fn new(
        name: impl Into<String>,
        patches: Vec<Patch>,
        materials: Vec<Material>,
        objects: Vec<String>,
    ) -> Result<Scene, CoreError> {
        if patches.is_empty() {
            return Err(CoreError::EmptyScene);
        }
        for m in &materials {
            m.validate()?;
        }
        for (patch, p) in patches.iter().enumerate() {
            let references = [("material", p.material.0, materials.len()), ("object", p.object.0, objects.len())];
            for (what, index, count) in references {
                if index as usize >= count {
                    return Err(CoreError::DanglingReference { patch, what, index: index as usize, count });
                }
            }
        }
        Ok(Scene { name: name.into(), patches, materials, objects })
    }

    /// The scene's name (a built-in name with parameters, or a file name).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The bytes the scene holds on the heap: its patches, materials and object names.
    pub fn heap_bytes(&self) -> usize {
        self.patches.capacity() * size_of::<Patch>()
            + self.materials.capacity() * size_of::<Material>()
            + self.objects.iter().map(|o| o.capacity() + size_of::<String>()).sum::<usize>()
            + self.name.capacity()
    }

    /// The patches, indexed by patch id.
    pub fn patches(&self) -> &[Patch] {
        &self.patches
    }

    /// The number of patches.
    pub fn len(&self) -> usize {
        self.patches.len()
    }

    /// Always false: a scene has at least one patch.
    pub fn is_empty(&self) -> bool {
        self.patches.is_empty()
    }

    /// The materials, indexed by [`MaterialId`](crate::MaterialId).
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The object names, indexed by [`ObjectId`](crate::ObjectId).
    pub fn objects(&self) -> &[String] {
        &self.objects
    }

    /// The material of patch `i`.
    pub fn material_of(&self, i: usize) -> &Material {
        &self.materials[self.patches[i].material.0 as usize]
    }

    /// The name of the object patch `i` belongs to.
    pub fn object_of(&self, i: usize) -> &str {
        &self.objects[self.patches[i].object.0 as usize]
    }

    /// The reflectivity of patch `i`.
    pub fn reflectivity(&self, i: usize) -> Spectrum {
        self.material_of(i).reflectivity
    }

    /// The emission of patch `i`.
    pub fn emission(&self, i: usize) -> Spectrum {
        self.material_of(i).emission
    }

    /// The total surface area.
    pub fn total_area(&self) -> Real {
        self.patches.iter().map(Patch::area).sum()
    }

    /// The area-weighted mean reflectivity, averaged over the three channels.
    pub fn mean_reflectivity(&self) -> Real {
        let weighted: Real = self.patches.iter().enumerate().map(|(i, p)| p.area() * self.reflectivity(i).mean()).sum();
        weighted / self.total_area()
    }

    /// The largest reflectivity of any patch in any channel.
    pub fn max_reflectivity(&self) -> Real {
        (0..self.len()).map(|i| self.reflectivity(i).max()).fold(0.0, Real::max)
    }

    /// Indices of the patches that emit in at least one channel.
    pub fn emitters(&self) -> Vec<usize> {
        (0..self.len()).filter(|&i| self.emission(i).is_positive()).collect()
    }

    /// Grey when every material used by a patch is grey in both reflectivity and emission.
    pub fn channels(&self) -> Channels {
        let mut used = vec![false; self.materials.len()];
        for p in &self.patches {
            used[p.material.0 as usize] = true;
        }
        let grey =
            self.materials.iter().zip(used).all(|(m, u)| !u || (m.reflectivity.is_grey() && m.emission.is_grey()));
        if grey { Channels::Grey } else { Channels::Rgb }
    }

    /// Minimum and maximum corners of the axis-aligned bounding box.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(Real::INFINITY);
        let mut hi = Vec3::splat(Real::NEG_INFINITY);
        for v in self.patches.iter().flat_map(|p| p.vertices().iter()) {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
        (lo, hi)
    }

    /// The length of the bounding-box diagonal: the scene's scale for relative tolerances.
    pub fn diagonal(&self) -> Real {
        bounding_diagonal(self.patches.iter().flat_map(|p| p.vertices().iter().copied()))
    }
}
