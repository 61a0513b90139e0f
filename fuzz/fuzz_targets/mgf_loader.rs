//! Fuzz target for the MGF loader: whatever the bytes, `mgf::load_slice_limited` must return a
//! scene or a typed error, never panic, hang or exhaust memory.
//!
//! The bytes up to the first NUL are the file `fuzz.mgf`; the bytes after it are `part.mgf`,
//! which `fuzz.mgf` may include (`i part.mgf`), as may `part.mgf` itself or `fuzz.mgf` (both
//! are in the map of files in memory, so include cycles are reachable too). Files are loaded
//! with the default parameters and, when that succeeds, again cut to `size=0.5`. The limits are
//! a hundredth of the defaults or less, so that a file at the limits loads well within the
//! fuzzer's timeout: the checks are the same code, at other numbers.

#![no_main]

use libfuzzer_sys::fuzz_target;
use radiosity_geom::KeyValueParams;
use radiosity_geom::mgf::{self, Limits, PARAMS};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A hundredth of the default limits (or less), the include depth as it is.
const LIMITS: Limits = Limits { instances: 10_000, patches: 40_000, work: 1 << 20, include_depth: 32 };

fuzz_target!(|data: &[u8]| {
    let (root, part) = match data.iter().position(|&b| b == 0) {
        Some(nul) => (&data[..nul], &data[nul + 1..]),
        None => (data, &[][..]),
    };
    let includes =
        BTreeMap::from([(PathBuf::from("fuzz.mgf"), root.to_vec()), (PathBuf::from("part.mgf"), part.to_vec())]);
    let name = Path::new("fuzz.mgf");
    if mgf::load_slice_limited(root, name, &includes, &KeyValueParams::default(), &LIMITS).is_ok() {
        let sized = KeyValueParams::parse("fuzz", ["size=0.5"], PARAMS).expect("size=0.5 is a valid parameter");
        let _ = mgf::load_slice_limited(root, name, &includes, &sized, &LIMITS);
    }
});
