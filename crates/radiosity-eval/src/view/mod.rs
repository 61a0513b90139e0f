//! Seeing a solved scene: smooth radiosity at patch corners ([`shading`]), a ray-cast picture
//! through a pinhole camera ([`render`]) framed by default to show a scene's inside ([`framing`]) written as PNG ([`png_image`]), and the scene as
//! binary glTF with its radiosity as vertex colours ([`gltf_export`]).

pub(crate) mod framing;
pub(crate) mod gltf_export;
pub(crate) mod png_image;
pub(crate) mod render;
pub(crate) mod shading;
