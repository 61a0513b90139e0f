//! The frame of the files this crate writes for a cache (stored matrices, hierarchical
//! operators): a magic string and a format version, a postcard header whose last two fields
//! are the body's length and checksum (fixed-size, filled in once the body is written, so the
//! file is one buffer), then the body.

use serde::Serialize;
use serde::de::DeserializeOwned;
use xxhash_rust::xxh3::xxh3_64;

/// The body's length and checksum, the last two fields of a header.
pub(crate) type Sums = ([u8; 8], [u8; 8]);

/// A framed file: `magic`, `version` and `header` (whose [`Sums`] are written as zeros and
/// filled in), then what `body` appends, in one buffer of at least `capacity` bytes.
pub(crate) fn frame<H: Serialize>(
    magic: &str,
    version: u32,
    header: &H,
    capacity: usize,
    body: impl FnOnce(Vec<u8>) -> Vec<u8>,
) -> Vec<u8> {
    let mut out = Vec::with_capacity(capacity);
    out = postcard::to_extend(&(magic, version), out).expect("postcard encodes a string and a number");
    out = postcard::to_extend(header, out).expect("postcard encodes the header");
    let body_start = out.len();
    out = body(out);
    let body_len = (out.len() - body_start) as u64;
    let checksum = xxh3_64(&out[body_start..]);
    out[body_start - 16..body_start - 8].copy_from_slice(&body_len.to_le_bytes());
    out[body_start - 8..body_start].copy_from_slice(&checksum.to_le_bytes());
    out
}

/// The header and the body of a framed file, or why not, in words for a refusal: `what` names
/// the kind of file (`a stored form-factor matrix`) and `body` its content (`the entries`);
/// `sums` reads a header's [`Sums`].
pub(crate) fn unframe<'b, H: DeserializeOwned>(
    bytes: &'b [u8],
    (magic, version): (&str, u32),
    (what, body): (&str, &str),
    sums: impl Fn(&H) -> Sums,
) -> Result<(H, &'b [u8]), String> {
    let (found, rest): (&str, &[u8]) = postcard::take_from_bytes(bytes).map_err(|e| format!("not {what} ({e})"))?;
    if found != magic {
        return Err(format!("not {what} (wrong magic string)"));
    }
    let (found, rest): (u32, &[u8]) = postcard::take_from_bytes(rest).map_err(|e| format!("truncated header ({e})"))?;
    if found != version {
        return Err(format!("written in format version {found}, this build reads version {version}"));
    }
    let (header, content): (H, &[u8]) =
        postcard::take_from_bytes(rest).map_err(|e| format!("truncated header ({e})"))?;
    let (len, checksum) = sums(&header);
    let len = u64::from_le_bytes(len);
    if content.len() as u64 != len {
        return Err(format!(
            "{body} take {} bytes where the header promises {len} (truncated or padded file)",
            content.len()
        ));
    }
    if xxh3_64(content) != u64::from_le_bytes(checksum) {
        return Err(format!("{body} do not match their checksum (corrupted file)"));
    }
    Ok((header, content))
}
