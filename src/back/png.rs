//! Image encoders for previews: 8-bit sRGB PNG through the `png` crate (values clamped to
//! [0, 1]; feature `png`, on by default) and linear PFM (`PF`, little-endian f32, rows bottom to top as the format
//! requires).
//!
//! [`write_rows`] writes an image row by row as it is rendered, so a contact sheet of any
//! size is never held whole ([`crate::interp::preview::ContactSheet::render_rows`] hands
//! out the rows in the format's [`ImageFormat::order`]). [`encode_png`] and [`encode_pfm`]
//! encode an image held in memory the same way.

use crate::raster::{Image, RowOrder};
use glam::Vec3;
use std::io::{self, Write};

/// The sRGB transfer function of one linear value, clamped to [0, 1].
pub(crate) fn srgb_encode(x: f32) -> f32 {
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

/// The preview file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit sRGB PNG (values clamped to [0, 1]).
    #[cfg(feature = "png")]
    Png,
    /// Linear little-endian PFM (`PF`, scale −1).
    Pfm,
}

impl ImageFormat {
    /// The order the format stores rows in: top down for PNG, bottom up for PFM.
    pub fn order(self) -> RowOrder {
        match self {
            #[cfg(feature = "png")]
            ImageFormat::Png => RowOrder::TopDown,
            ImageFormat::Pfm => RowOrder::BottomUp,
        }
    }
}

/// Where [`write_rows`]'s producer puts the rows of the image, one at a time, in the format's
/// [`ImageFormat::order`].
pub struct RowSink<'a> {
    out: &'a mut dyn Write,
    format: ImageFormat,
    width: usize,
    /// One encoded row.
    buf: Vec<u8>,
}

impl<'a> RowSink<'a> {
    fn new(out: &'a mut dyn Write, format: ImageFormat, width: usize) -> Self {
        let bytes_per_pixel = match format {
            #[cfg(feature = "png")]
            ImageFormat::Png => 3,
            ImageFormat::Pfm => 12,
        };
        RowSink {
            out,
            format,
            width,
            buf: Vec::with_capacity(width * bytes_per_pixel),
        }
    }

    /// Write the next row (`width` pixels).
    pub fn write_row(&mut self, row: &[Vec3]) -> io::Result<()> {
        if row.len() != self.width {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "a row of {} pixels in an image {} wide",
                    row.len(),
                    self.width
                ),
            ));
        }
        self.buf.clear();
        match self.format {
            #[cfg(feature = "png")]
            ImageFormat::Png => {
                for p in row {
                    self.buf.extend_from_slice(&srgb8(*p));
                }
            }
            ImageFormat::Pfm => {
                for p in row {
                    for c in p.to_array() {
                        self.buf.extend_from_slice(&c.to_le_bytes());
                    }
                }
            }
        }
        self.out.write_all(&self.buf)
    }
}

/// Write a `width × height` image in `format` on `out` as `produce` hands its rows to the
/// [`RowSink`]: only one row is held here, whatever the image's size. Fails if a side is 0
/// or (PNG) above 2³¹ − 1, if `produce` fails or gives a row of another width, or (PNG) if
/// it gives fewer rows than `height`.
///
/// ```
/// # #[cfg(feature = "png")] {
/// use vstructc::back::png::{ImageFormat, write_rows};
/// use glam::Vec3;
/// let mut png = Vec::new();
/// write_rows(ImageFormat::Png, &mut png, 2, 3, |rows| {
///     (0..3).try_for_each(|_| rows.write_row(&[Vec3::ONE, Vec3::ZERO]))
/// })
/// .unwrap();
/// assert_eq!(&png[1..4], b"PNG");
/// # }
/// ```
pub fn write_rows<W: Write>(
    format: ImageFormat,
    mut out: W,
    width: usize,
    height: usize,
    produce: impl FnOnce(&mut RowSink<'_>) -> io::Result<()>,
) -> io::Result<()> {
    let bad_size = || {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("an image of {width}×{height} pixels cannot be written"),
        )
    };
    if width == 0 || height == 0 {
        return Err(bad_size());
    }
    match format {
        ImageFormat::Pfm => {
            write!(out, "PF\n{width} {height}\n-1.0\n")?;
            produce(&mut RowSink::new(&mut out, format, width))?;
            out.flush()
        }
        #[cfg(feature = "png")]
        ImageFormat::Png => {
            let side = |n: usize| u32::try_from(n).ok().filter(|&n| n < 1 << 31);
            let (Some(w), Some(h)) = (side(width), side(height)) else {
                return Err(bad_size());
            };
            let mut encoder = png::Encoder::new(out, w, h);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_compression(png::Compression::Balanced);
            encoder.set_filter(png::Filter::Adaptive);
            let mut writer = encoder.write_header().map_err(io::Error::other)?;
            let mut stream = writer.stream_writer().map_err(io::Error::other)?;
            produce(&mut RowSink::new(&mut stream, format, width))?;
            stream.finish().map_err(io::Error::other)?;
            writer.finish().map_err(io::Error::other)
        }
    }
}

/// Encode `img` as an 8-bit sRGB PNG.
#[cfg(feature = "png")]
pub fn encode_png(img: &Image) -> Result<Vec<u8>, crate::diag::Error> {
    use crate::diag::{Diagnostic, Error};
    let mut out = Vec::new();
    encode_image(img, ImageFormat::Png, &mut out)
        .map_err(|e| Error::Input(Box::new(Diagnostic::error("IO002", format!("PNG: {e}")))))?;
    Ok(out)
}

/// Encode `img` as a linear little-endian PFM (`PF`, scale −1, rows bottom to top).
pub fn encode_pfm(img: &Image) -> Vec<u8> {
    let mut out = Vec::with_capacity(img.pixels.len() * 12 + 32);
    // Writing to a vector fails only for an empty image, whose header is still written.
    if encode_image(img, ImageFormat::Pfm, &mut out).is_err() {
        out = format!("PF\n{} {}\n-1.0\n", img.width, img.height).into_bytes();
    }
    out
}

/// Write `img` in `format` on `out`.
pub(crate) fn encode_image(
    img: &Image,
    format: ImageFormat,
    out: &mut dyn Write,
) -> io::Result<()> {
    write_rows(format, out, img.width, img.height, |sink| {
        let rows = img.pixels.chunks(img.width.max(1));
        match format.order() {
            RowOrder::TopDown => rows.into_iter().try_for_each(|r| sink.write_row(r)),
            RowOrder::BottomUp => rows.rev().try_for_each(|r| sink.write_row(r)),
        }
    })
}
