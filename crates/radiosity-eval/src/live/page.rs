//! The page itself (`page.html`, served live) and the same page kept as one self-contained
//! file ([`write_page`]).

use crate::error::LabError;
use crate::live::feed::{Feed, point_json};
use serde_json::{Value, json};
use std::io::Write;

/// The page: hand-written HTML, CSS, WebGL2 and JavaScript.
const PAGE: &str = include_str!("page.html");
/// Where the kept page's data goes.
const DATA_MARK: &str = "<!--DATA-->";

/// The page as served: it reads the feed from the server that serves it.
pub(crate) fn live_page() -> &'static str {
    PAGE
}

/// Writes the page of `feed` as it stands to `out`, as one file that needs no server and no
/// network: the geometry once, each run's points and the radiosity at its kept moments, and
/// a slider over them.
pub fn write_page(out: &mut dyn Write, feed: &Feed) -> Result<(), LabError> {
    let state = feed.lock();
    let runs: Vec<Value> = state
        .runs
        .iter()
        .map(|run| {
            let kept: Vec<Value> = run
                .kept
                .iter()
                .map(|f| {
                    let bytes: Vec<u8> = f.values.iter().flat_map(|v| v.to_le_bytes()).collect();
                    json!({"point": point_json(&f.point), "exposure": f.exposure, "values": base64(&bytes)})
                })
                .collect();
            let points: Vec<Value> = run.points.iter().map(point_json).collect();
            json!({"points": points, "kept": kept, "end": run.end})
        })
        .collect();
    let data = json!({"meta": feed.scene.meta, "geometry": base64(&feed.scene.geometry), "runs": runs,
        "done": state.done});
    drop(state);
    // Inside a script element, `</` must not appear: JSON allows `<\/`.
    let text = data.to_string().replace("</", "<\\/");
    let script = format!("<script id=\"data\" type=\"application/json\">{text}</script>");
    let (head, tail) = PAGE.split_once(DATA_MARK).unwrap_or((PAGE, ""));
    let write = |e: std::io::Error| LabError::Invalid(format!("cannot write the page: {e}"));
    out.write_all(head.as_bytes()).map_err(write)?;
    out.write_all(script.as_bytes()).map_err(write)?;
    out.write_all(tail.as_bytes()).map_err(write)?;
    out.flush().map_err(write)
}

/// Standard base64 with padding (RFC 4648 §4).
pub(crate) fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn base64_is_rfc_4648() {
        // RFC 4648 §10's test vectors.
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(super::base64(plain.as_bytes()), coded);
        }
    }
}
