//! Typed indices into a scene's tables: the material and the object a patch refers to.
//!
//! They live apart from [`crate::Scene`] and [`crate::Patch`] so that both can name them
//! without importing each other.

/// Index of a material in [`Scene::materials`](crate::Scene::materials).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct MaterialId(pub u32);

/// Index of an object name in [`Scene::objects`](crate::Scene::objects).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ObjectId(pub u32);
