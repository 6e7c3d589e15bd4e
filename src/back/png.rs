//! Image encoders for previews: 8-bit sRGB PNG through the `png` crate (values clamped to
//! [0, 1]; feature `png`, on by default), linear PFM (`PF`, little-endian f32, rows bottom to
//! top as the format requires) and linear OpenEXR through the `exr` crate (32-bit float `R`,
//! `G`, `B` channels, lossless ZIP compression in blocks of 16 scan lines; feature `exr`, on
//! by default).
//!
//! [`write_rows`] writes an image row by row as it is rendered, so a contact sheet of any
//! size is never held whole ([`crate::interp::preview::ContactSheet::render_rows`] hands
//! out the rows in the format's [`ImageFormat::order`]). [`Image::encode`] encodes an image
//! held in memory the same way.

use crate::raster::{Image, RowOrder};
use glam::Vec3;
use std::io::{self, Write};

/// The sRGB transfer function of one linear value, clamped to [0, 1].
#[cfg(any(feature = "png", feature = "testkit"))]
pub(crate) fn srgb_encode(x: f32) -> f32 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// One linear colour as 8-bit sRGB.
#[cfg(any(feature = "png", feature = "testkit"))]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn srgb8(c: Vec3) -> [u8; 3] {
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
    /// Linear OpenEXR: one part of scan lines, 32-bit float `R`, `G`, `B`, ZIP compressed.
    #[cfg(feature = "exr")]
    Exr,
}

impl ImageFormat {
    /// The order the format stores rows in: top down for PNG and EXR, bottom up for PFM.
    pub fn order(self) -> RowOrder {
        match self {
            #[cfg(feature = "png")]
            ImageFormat::Png => RowOrder::TopDown,
            ImageFormat::Pfm => RowOrder::BottomUp,
            #[cfg(feature = "exr")]
            ImageFormat::Exr => RowOrder::TopDown,
        }
    }

    /// Whether the format keeps linear values as they are (PFM, EXR) rather than encoding
    /// them for display (PNG).
    pub fn is_linear(self) -> bool {
        match self {
            #[cfg(feature = "png")]
            ImageFormat::Png => false,
            ImageFormat::Pfm => true,
            #[cfg(feature = "exr")]
            ImageFormat::Exr => true,
        }
    }
}

/// Where a [`RowSink`]'s rows go.
enum Target<'a> {
    /// Encoded row by row into bytes (PNG, PFM).
    Bytes {
        out: &'a mut dyn Write,
        format: ImageFormat,
    },
    /// Handed to an encoder that gathers them into blocks (EXR).
    #[cfg(feature = "exr")]
    Rows(&'a mut dyn FnMut(&[Vec3]) -> io::Result<()>),
}

/// Where [`write_rows`]'s producer puts the rows of the image, one at a time, in the format's
/// [`ImageFormat::order`].
pub struct RowSink<'a> {
    target: Target<'a>,
    width: usize,
    /// One encoded row.
    buf: Vec<u8>,
}

impl<'a> RowSink<'a> {
    fn new(out: &'a mut dyn Write, format: ImageFormat, width: usize) -> Self {
        let bytes_per_pixel = match format {
            #[cfg(feature = "png")]
            ImageFormat::Png => 3,
            _ => 12,
        };
        RowSink {
            target: Target::Bytes { out, format },
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
        let (out, format) = match &mut self.target {
            Target::Bytes { out, format } => (out, *format),
            #[cfg(feature = "exr")]
            Target::Rows(take) => return take(row),
        };
        self.buf.clear();
        match format {
            #[cfg(feature = "png")]
            ImageFormat::Png => {
                for p in row {
                    self.buf.extend_from_slice(&srgb8(*p));
                }
            }
            _ => {
                for p in row {
                    for c in p.to_array() {
                        self.buf.extend_from_slice(&c.to_le_bytes());
                    }
                }
            }
        }
        out.write_all(&self.buf)
    }
}

/// Write a `width × height` image in `format` on `out` as `produce` hands its rows to the
/// [`RowSink`]: only one row is held here, whatever the image's size. Fails if a side is 0
/// or (PNG) above 2³¹ − 1, if `produce` fails or gives a row of another width, or (PNG,
/// EXR) if it gives fewer rows than `height`.
///
/// EXR stores the table of its blocks' positions before the blocks, so the file is first
/// assembled in a temporary buffer (in memory up to 64 MiB, then in an
/// anonymous temporary file) and copied to `out` once complete: `out` receives nothing if the
/// image fails.
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
        #[cfg(feature = "exr")]
        ImageFormat::Exr => exr_image::write(&mut out, width, height, produce),
    }
}

/// How much of an EXR file [`write_rows`] assembles in memory before it moves to a
/// temporary file (64 MiB).
#[cfg(feature = "exr")]
const EXR_SPOOL_BYTES: usize = 64 << 20;

/// OpenEXR writing through the `exr` crate's block interface: rows are gathered into blocks
/// of scan lines, each block is compressed and written as soon as it is full.
#[cfg(feature = "exr")]
mod exr_image {
    use super::{RowSink, Target};
    use exr::block::writer::ChunksWriter;
    use exr::block::{BlockIndex, UncompressedBlock};
    use exr::compression::Compression;
    use exr::math::Vec2;
    use exr::meta::BlockDescription;
    use exr::meta::attribute::{ChannelDescription, LineOrder, SampleType};
    use exr::meta::header::{Header, LayerAttributes};
    use glam::Vec3;
    use smallvec::smallvec;
    use std::io::{self, Seek, Write};

    /// Lossless, and read by every OpenEXR reader.
    const COMPRESSION: Compression = Compression::ZIP16;

    /// The `exr` crate's error as an I/O error (its I/O errors unwrapped).
    fn io_error(e: exr::error::Error) -> io::Error {
        match e {
            exr::error::Error::Io(e) => e,
            e => io::Error::other(format!("EXR: {e}")),
        }
    }

    /// Write a `width × height` linear RGB EXR on `out` from the rows `produce` gives, top
    /// row first.
    pub(super) fn write(
        out: &mut dyn Write,
        width: usize,
        height: usize,
        produce: impl FnOnce(&mut RowSink<'_>) -> io::Result<()>,
    ) -> io::Result<()> {
        // Channels in the alphabetical order the format requires; `true`: linear values.
        let channels = smallvec![
            ChannelDescription::new("B", SampleType::F32, true),
            ChannelDescription::new("G", SampleType::F32, true),
            ChannelDescription::new("R", SampleType::F32, true),
        ];
        let header = Header::new("".into(), (width, height), channels)
            .with_encoding(
                COMPRESSION,
                BlockDescription::ScanLines,
                LineOrder::Increasing,
            )
            .with_attributes(LayerAttributes::default());
        let lines = COMPRESSION.scan_lines_per_block();
        let mut spool = tempfile::spooled_tempfile(super::EXR_SPOOL_BYTES);
        exr::block::write(
            io::BufWriter::new(&mut spool),
            smallvec![header],
            true,
            |meta, chunks| {
                let mut data: Vec<u8> = Vec::with_capacity(width * lines.min(height) * 12);
                let (mut y, mut block_rows) = (0usize, 0usize);
                let mut take = |row: &[Vec3]| -> io::Result<()> {
                    if y + block_rows >= height {
                        return Err(io::Error::new(
                            io::ErrorKind::InvalidInput,
                            format!("more than {height} rows in an image {height} high"),
                        ));
                    }
                    // One scan line: all of B, then G, then R, native-endian (the crate
                    // converts to little-endian when it compresses).
                    for c in [2, 1, 0] {
                        for p in row {
                            data.extend_from_slice(&p[c].to_ne_bytes());
                        }
                    }
                    block_rows += 1;
                    if block_rows == lines || y + block_rows == height {
                        let block = UncompressedBlock {
                            index: BlockIndex {
                                layer: 0,
                                pixel_position: Vec2(0, y),
                                pixel_size: Vec2(width, block_rows),
                                level: Vec2(0, 0),
                            },
                            data: std::mem::take(&mut data),
                        };
                        let chunk = block.compress_to_chunk(&meta.headers).map_err(io_error)?;
                        chunks.write_chunk(y / lines, chunk).map_err(io_error)?;
                        y += block_rows;
                        block_rows = 0;
                    }
                    Ok(())
                };
                let mut sink = RowSink {
                    target: Target::Rows(&mut take),
                    width,
                    buf: Vec::new(),
                };
                produce(&mut sink).map_err(exr::error::Error::Io)
            },
        )
        .map_err(io_error)?;
        spool.rewind()?;
        io::copy(&mut spool, out)?;
        out.flush()
    }
}

impl Image {
    /// The image encoded in `format`, in memory (for files and streams, [`write_rows`]
    /// writes rows as they are produced). Fails only when the encoder does (an error naming
    /// the format).
    pub fn encode(&self, format: ImageFormat) -> Result<Vec<u8>, crate::diag::Error> {
        use crate::diag::{Diagnostic, Error};
        let mut out = Vec::with_capacity(self.pixels.len() * 12 + 32);
        encode_image(self, format, &mut out).map_err(|e| {
            Error::Input(Box::new(Diagnostic::error(
                "IO002",
                format!("{format:?} encoding: {e}"),
            )))
        })?;
        Ok(out)
    }
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
