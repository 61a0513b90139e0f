//! Fuzz target for the glTF loader: whatever the bytes, `gltf_input::load_slice` must return a
//! scene or a typed error, never panic.
//!
//! The loader tells binary from text glTF by the `glTF` magic, not by the file name, so the
//! bytes are fed twice:
//!
//! 1. as they are, named `fuzz.gltf`: text glTF, or binary glTF when they start with the magic
//!    (the `.glb` seeds), with the default parameters;
//! 2. when they are not binary glTF already, wrapped in a well-formed binary container named
//!    `fuzz.glb`: the bytes up to the first NUL are the JSON chunk and the bytes after it the
//!    BIN chunk, so mutations of the seeds' JSON also reach the binary path (and buffers
//!    without a URI, which read the BIN chunk). This load uses `size=0.5`, which cuts each
//!    triangle into at most four and so exercises subdivision without letting an input
//!    multiply its patches without bound.

#![no_main]

use libfuzzer_sys::fuzz_target;
use radiosity_geom::KeyValueParams;
use radiosity_geom::gltf_input::{self, PARAMS};
use std::path::Path;

/// Binary glTF version 2 holding `json` and, when given, a BIN chunk.
fn glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8], pad: u8) {
        let padded = data.len().next_multiple_of(4);
        out.extend_from_slice(&(padded as u32).to_le_bytes());
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        out.resize(out.len() + padded - data.len(), pad);
    }
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&[0; 4]);
    chunk(&mut out, b"JSON", json, b' ');
    if let Some(bin) = bin {
        chunk(&mut out, b"BIN\0", bin, 0);
    }
    let total = out.len() as u32;
    out[8..12].copy_from_slice(&total.to_le_bytes());
    out
}

fuzz_target!(|data: &[u8]| {
    let _ = gltf_input::load_slice(data, Path::new("fuzz.gltf"), &KeyValueParams::default());
    if !data.starts_with(b"glTF") {
        let (json, bin) = match data.iter().position(|&b| b == 0) {
            Some(nul) => (&data[..nul], Some(&data[nul + 1..])),
            None => (data, None),
        };
        let refined = KeyValueParams::parse("fuzz", ["size=0.5"], PARAMS).expect("size=0.5 is a valid parameter");
        let _ = gltf_input::load_slice(&glb(json, bin), Path::new("fuzz.glb"), &refined);
    }
});
