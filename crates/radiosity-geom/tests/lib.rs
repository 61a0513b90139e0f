//! Integration tests of radiosity-geom: meshing, built-in scenes, glTF input, visibility and
//! scene analysis, each in its own module.

mod analysis;
mod builtin_large;
mod coplanar;
mod gltf_input;
mod hidden;
mod mesh;
mod mgf_input;
mod office_storeys;
mod scenes;
mod spatial_order;
mod visibility;

use radiosity_geom::{GeomError, LoadedScene, load_scene};

/// A file in `test_data/`.
fn fixture(name: &str) -> String {
    format!("{}/test_data/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Loads a scene argument that must load.
fn load(arg: &str) -> LoadedScene {
    load_scene(arg).unwrap_or_else(|e| panic!("{arg} should load: {e}"))
}

/// Loads a scene argument that must fail, with its error and message.
fn load_err(arg: &str) -> (GeomError, String) {
    match load_scene(arg) {
        Ok(_) => panic!("{arg} should fail to load"),
        Err(e) => {
            let message = e.to_string();
            (e, message)
        }
    }
}
