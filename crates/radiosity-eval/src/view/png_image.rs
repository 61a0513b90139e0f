//! 8-bit RGB PNG files, for plots and renders, with the `png` crate (the `image` crate's
//! encoder without its decoders and colour management, which cost most of a cold build).

use crate::error::EvalError;
use std::io::Write;

/// Encodes `pixels` (RGB, row by row from the top, `width × height × 3` bytes) as PNG into `out`.
pub fn write_rgb8(out: impl Write, pixels: &[u8], width: u32, height: u32) -> Result<(), EvalError> {
    let expected = width as usize * height as usize * 3;
    if pixels.len() != expected {
        return Err(EvalError::SizeMismatch { what: "the pixel buffer", expected, found: pixels.len() });
    }
    let mut encoder = png::Encoder::new(out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| EvalError::Image(e.to_string()))?;
    writer.write_image_data(pixels).map_err(|e| EvalError::Image(e.to_string()))?;
    writer.finish().map_err(|e| EvalError::Image(e.to_string()))
}

/// An 8-bit RGB image read back from a PNG file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rgb8 {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGB bytes, row by row from the top.
    pub pixels: Vec<u8>,
}

impl Rgb8 {
    /// Decodes an 8-bit RGB or RGBA PNG (alpha dropped).
    pub fn decode(bytes: &[u8]) -> Result<Rgb8, EvalError> {
        let bad = |e: png::DecodingError| EvalError::Image(e.to_string());
        let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().map_err(bad)?;
        let mut buffer = vec![0; reader.output_buffer_size().unwrap_or(0)];
        let info = reader.next_frame(&mut buffer).map_err(bad)?;
        let channels = match (info.color_type, info.bit_depth) {
            (png::ColorType::Rgb, png::BitDepth::Eight) => 3,
            (png::ColorType::Rgba, png::BitDepth::Eight) => 4,
            (c, d) => return Err(EvalError::Image(format!("expected 8-bit RGB, found {c:?} at {d:?}"))),
        };
        let pixels = buffer[..info.buffer_size()].chunks_exact(channels).flat_map(|p| [p[0], p[1], p[2]]).collect();
        Ok(Rgb8 { width: info.width, height: info.height, pixels })
    }

    /// The pixel at column `x`, row `y`.
    pub fn get(&self, x: u32, y: u32) -> [u8; 3] {
        let at = 3 * (y as usize * self.width as usize + x as usize);
        [self.pixels[at], self.pixels[at + 1], self.pixels[at + 2]]
    }

    /// Every pixel with its column and row, row by row.
    pub fn enumerate(&self) -> impl Iterator<Item = (u32, u32, [u8; 3])> + '_ {
        let w = self.width.max(1);
        self.pixels.chunks_exact(3).enumerate().map(move |(k, p)| (k as u32 % w, k as u32 / w, [p[0], p[1], p[2]]))
    }
}
