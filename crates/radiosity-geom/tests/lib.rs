//! Integration tests of radiosity-geom: meshing, built-in scenes, glTF input, visibility and
//! scene analysis, each in its own module.

mod analysis;
mod builtin_large;
mod gltf_input;
mod mesh;
mod scenes;
mod spatial_order;
mod visibility;
