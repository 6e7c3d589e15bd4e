//! Decoding the command line's PNG output for pixel checks (8-bit sRGB, RGB or RGBA).

/// A decoded image: rows top to bottom, three bytes per pixel.
pub struct Rgb8 {
    pub width: u32,
    pub height: u32,
    data: Vec<u8>,
}

impl Rgb8 {
    /// The pixel at column `x`, row `y`.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }
}

/// Decode `bytes`; panics (failing the test) on anything but an 8-bit RGB or RGBA PNG.
pub fn decode(bytes: &[u8]) -> Rgb8 {
    let reader = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = reader.read_info().expect("a PNG header");
    let mut buf = vec![0; reader.output_buffer_size().expect("a sane image size")];
    let info = reader.next_frame(&mut buf).expect("a PNG frame");
    assert_eq!(info.bit_depth, png::BitDepth::Eight, "8-bit samples");
    let channels = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        other => panic!("unexpected PNG colour type {other:?}"),
    };
    let data = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    Rgb8 {
        width: info.width,
        height: info.height,
        data,
    }
}
