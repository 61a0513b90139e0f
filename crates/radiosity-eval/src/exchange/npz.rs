//! NumPy's `.npz`: a zip archive of `.npy` arrays, stored without compression. `F` is written
//! under the keys `scipy.sparse.save_npz` uses for a `csc_array` (`format`, `shape`, `data`,
//! `indices`, `indptr`, `_is_array`), so `scipy.sparse.load_npz` reads it back, and the
//! patches' `area` (`n`), `emission` and `reflectivity` (`n × k`) beside it, which `numpy.load`
//! reads. Values are little-endian `f64` (`F`'s `f32` entries widened exactly), indices `i64`.
//!
//! The `.npy` header follows NEP 1 (format version 1.0, the header padded to a multiple of 64
//! bytes); the archive is plain zip without zip64, so each array and the whole file stay
//! below 4 GiB (larger systems are refused with an error: Matrix Market has no such limit).

use crate::exchange::sparse_columns::SparseColumns;
use radiosity_core::LinearSystem;
use std::io::{self, Write};

/// One array: its `.npy` `descr`, shape and little-endian bytes.
struct Array {
    name: &'static str,
    descr: &'static str,
    shape: Vec<usize>,
    bytes: Vec<u8>,
}

impl Array {
    fn reals(name: &'static str, shape: Vec<usize>, values: impl IntoIterator<Item = f64>) -> Array {
        Array { name, descr: "<f8", shape, bytes: values.into_iter().flat_map(f64::to_le_bytes).collect() }
    }

    fn integers(name: &'static str, values: &[u64]) -> Array {
        let bytes = values.iter().flat_map(|&v| (v as i64).to_le_bytes()).collect();
        Array { name, descr: "<i8", shape: vec![values.len()], bytes }
    }

    /// The `.npy` file: magic, version 1.0, header, data.
    fn npy(&self) -> Vec<u8> {
        let shape = match self.shape.as_slice() {
            [] => "()".to_string(),
            [n] => format!("({n},)"),
            dims => format!("({})", dims.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")),
        };
        let mut header = format!("{{'descr': '{}', 'fortran_order': False, 'shape': {shape}, }}", self.descr);
        // Magic (6), version (2) and length (2) before it; padded with spaces to a multiple of
        // 64 bytes, ending in a newline.
        let unpadded = 10 + header.len() + 1;
        header.push_str(&" ".repeat(unpadded.next_multiple_of(64) - unpadded));
        header.push('\n');
        let mut npy = Vec::with_capacity(10 + header.len() + self.bytes.len());
        npy.extend_from_slice(b"\x93NUMPY\x01\x00");
        npy.extend_from_slice(&(header.len() as u16).to_le_bytes());
        npy.extend_from_slice(header.as_bytes());
        npy.extend_from_slice(&self.bytes);
        npy
    }
}

/// Writes `f` and the patches of `system` as an `.npz` archive (module documentation).
pub fn write_system(out: &mut impl Write, f: &SparseColumns, system: &LinearSystem) -> io::Result<()> {
    let (n, k) = (system.len(), system.channels().count());
    let arrays = [
        Array { name: "format", descr: "|S3", shape: vec![], bytes: b"csc".to_vec() },
        Array { name: "_is_array", descr: "|b1", shape: vec![], bytes: vec![1] },
        Array::integers("shape", &[f.n as u64, f.n as u64]),
        Array::reals("data", vec![f.nonzeros()], f.values.iter().copied()),
        Array::integers("indices", &f.indices),
        Array::integers("indptr", &f.indptr),
        Array::reals("area", vec![n], system.areas().iter().copied()),
        Array::reals("emission", vec![n, k], system.emissions().iter().copied()),
        Array::reals("reflectivity", vec![n, k], system.reflectivities().iter().copied()),
    ];
    let mut zip = StoredZip::default();
    for array in &arrays {
        zip.add(out, &format!("{}.npy", array.name), &array.npy())?;
    }
    zip.finish(out)
}

/// A zip archive written as it goes, every entry stored (no compression).
#[derive(Default)]
struct StoredZip {
    /// Bytes written so far.
    offset: u64,
    /// The central directory's records.
    directory: Vec<u8>,
    entries: u16,
}

/// 1980-01-01, the earliest date zip can say (every entry carries it).
const DOS_DATE: u16 = (1 << 5) | 1;

/// `value` as a zip field of 32 bits, or an error saying why the archive cannot hold it.
fn field(value: u64, what: &str) -> io::Result<u32> {
    u32::try_from(value).map_err(|_| {
        io::Error::other(format!(
            "the system's {what} passes 4 GiB, beyond plain zip: write it as Matrix Market (.mtx)"
        ))
    })
}

impl StoredZip {
    fn add(&mut self, out: &mut impl Write, name: &str, data: &[u8]) -> io::Result<()> {
        let crc = crc32fast::hash(data);
        let size = field(data.len() as u64, name)?;
        let offset = field(self.offset, "archive")?;
        // The fields both headers share, from "version needed" to the name's length.
        let mut common = Vec::new();
        for v in [20u16, 0, 0, 0, DOS_DATE] {
            common.extend_from_slice(&v.to_le_bytes());
        }
        for v in [crc, size, size] {
            common.extend_from_slice(&v.to_le_bytes());
        }
        common.extend_from_slice(&(name.len() as u16).to_le_bytes());
        common.extend_from_slice(&0u16.to_le_bytes());
        let mut local = 0x0403_4b50u32.to_le_bytes().to_vec();
        local.extend_from_slice(&common);
        local.extend_from_slice(name.as_bytes());
        out.write_all(&local)?;
        out.write_all(data)?;
        self.offset += (local.len() + data.len()) as u64;
        // Central record: signature, "version made by", the shared fields, then comment
        // length, disk, internal and external attributes and the local header's offset.
        self.directory.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
        self.directory.extend_from_slice(&20u16.to_le_bytes());
        self.directory.extend_from_slice(&common);
        for v in [0u16, 0, 0] {
            self.directory.extend_from_slice(&v.to_le_bytes());
        }
        self.directory.extend_from_slice(&0u32.to_le_bytes());
        self.directory.extend_from_slice(&offset.to_le_bytes());
        self.directory.extend_from_slice(name.as_bytes());
        self.entries += 1;
        Ok(())
    }

    fn finish(self, out: &mut impl Write) -> io::Result<()> {
        let start = field(self.offset, "archive")?;
        let size = field(self.directory.len() as u64, "archive")?;
        out.write_all(&self.directory)?;
        let mut end = 0x0605_4b50u32.to_le_bytes().to_vec();
        for v in [0u16, 0, self.entries, self.entries] {
            end.extend_from_slice(&v.to_le_bytes());
        }
        for v in [size, start] {
            end.extend_from_slice(&v.to_le_bytes());
        }
        end.extend_from_slice(&0u16.to_le_bytes());
        out.write_all(&end)
    }
}
