//! Tests: gltf_input.
