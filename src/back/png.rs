//! Image encoders for previews (spec closures.md §1.6): 8-bit sRGB PNG through the `image`
//! crate (values clamped to [0, 1]) and linear PFM (`PF`, little-endian f32, rows bottom to
//! top as the format requires).

use crate::diag::{Diagnostic, Error};
use crate::interp::preview::Image;
use glam::Vec3;

/// The sRGB transfer function of one linear value, clamped to [0, 1].
pub fn srgb_encode(x: f32) -> f32 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// One linear colour as 8-bit sRGB.
pub fn srgb8(c: Vec3) -> [u8; 3] {
    c.to_array()
        .map(|x| (srgb_encode(x) * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8)
}

/// Encode `img` as an 8-bit sRGB PNG.
pub fn encode_png(img: &Image) -> Result<Vec<u8>, Error> {
    let mut rgb = Vec::with_capacity(img.pixels.len() * 3);
    for p in &img.pixels {
        rgb.extend_from_slice(&srgb8(*p));
    }
    let (w, h) = (
        u32::try_from(img.width).map_err(|_| too_large(img))?,
        u32::try_from(img.height).map_err(|_| too_large(img))?,
    );
    let buf = image::RgbImage::from_raw(w, h, rgb).ok_or_else(|| too_large(img))?;
    let mut out = std::io::Cursor::new(Vec::new());
    buf.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| Error::Input(Box::new(Diagnostic::error("IO002", format!("PNG: {e}")))))?;
    Ok(out.into_inner())
}

fn too_large(img: &Image) -> Error {
    Error::Usage(format!(
        "image of {}×{} pixels cannot be encoded",
        img.width, img.height
    ))
}

/// Encode `img` as a linear little-endian PFM (`PF`, scale −1, rows bottom to top).
pub fn encode_pfm(img: &Image) -> Vec<u8> {
    let mut out = format!("PF\n{} {}\n-1.0\n", img.width, img.height).into_bytes();
    out.reserve(img.pixels.len() * 12);
    for row in img.pixels.chunks(img.width.max(1)).rev() {
        for p in row {
            for c in p.to_array() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    out
}
