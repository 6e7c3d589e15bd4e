//! Images shared by the preview renderer ([`crate::interp::preview`]) and the image writers
//! ([`crate::back::png`]): a linear RGB image held in memory and the order rows are written
//! in.

use glam::Vec3;

// The label font: public under `testkit` for its unit tests.
testkit_mods!(font);

/// A linear RGB image, rows top to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width × height` pixels, row-major, top row first.
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// An image filled with one colour.
    pub fn filled(width: usize, height: usize, c: Vec3) -> Image {
        Image {
            width,
            height,
            pixels: vec![c; width * height],
        }
    }

    /// The pixel at column `x`, row `y` (row 0 at the top).
    pub fn at(&self, x: usize, y: usize) -> Vec3 {
        self.pixels[y * self.width + x]
    }
}

/// The order in which [`crate::interp::preview::ContactSheet::render_rows`] hands out pixel rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowOrder {
    /// Top row first (PNG).
    TopDown,
    /// Bottom row first (PFM).
    BottomUp,
}
