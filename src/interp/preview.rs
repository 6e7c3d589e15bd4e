//! Material preview images: a deterministic, sampling-free render of
//! a unit sphere under one directional light and a uniform environment.
//!
//! * Pixels: an `N × N` image covers `[−1.1, 1.1]²`; pixel `(i, j)` (row 0 at the top) is
//!   shaded at its centre `x = −1.1 + 2.2 (i + ½)/N`, `y = 1.1 − 2.2 (j + ½)/N`. Pixels with
//!   `x² + y² < 1` lie on the sphere; the others show the environment.
//! * On the sphere: `N = (x, y, √(1 − x² − y²))`, `V = (0, 0, 1)`,
//!   `T = normalize((0, 1, 0) × N)` (`(1, 0, 0)` when `|N_y| > 0.999`). The program's
//!   globals: `P = N` (a unit sphere at the origin), `u = ½ + atan2(N_x, N_z)/2π`,
//!   `v = ½ + asin(N_y)/π` (vstructc's choice; the spec names none).
//! * Radiance: `eval(L_light).f_cos ⊙ E_light + env ⊙ (albedo().reflect + albedo().transmit)
//!   + emission() + transparency() ⊙ env`; defaults `L_light = normalize(1, 1, 1)`,
//!   `E_light = π`, `env = 0.05`. Furnace mode: no light, `env = 1`.
//! * AOV of one lobe: the same formula restricted to that lobe (its weighted response and
//!   its albedo `A_k`), without emission and transparency.
//!
//! Rows are independent; [`render_ball`] shades them in parallel with rayon (or serially),
//! with the scalar or the batched interpreter. The scalar path shades one pixel at a time;
//! for a material the uniform-material prepare covers (constant registers, one frame, a
//! batched kernel per leaf) it prepares each pixel with it at one lane, which writes the
//! leaves' view terms straight into their kernels instead of building lobe records
//! (`sample` and `lobes` are not needed here); other materials, and AOVs, take the prepare that builds lobe records
//! (one that does not pack lobes; [`PreviewOptions::general_prepare`] forces its
//! general form).
//!
//! Memory is bounded whatever the number of materials: [`ContactSheet`] renders a grid of
//! balls a band of pixel rows at a time (at most [`ContactSheet::BAND_PIXELS`] pixels, never
//! a whole ball or sheet) and hands each finished row to the caller, who streams it to a file
//! ([`crate::back::png::write_rows`]). Sizes are checked here, not only by the command line:
//! a ball has at most [`Limits::preview_pixels`] pixels ([`PreviewOptions::limits`]) and a
//! sheet's sides are at most [`ContactSheet::MAX_SIDE`] ([`PreviewError`] names the limit and the
//! value).

use super::material::{Material, Prepared, PreparedBatch, Scratch, ShadingBatch, ShadingPoint};
use super::math::Rgb;
use crate::limits::{Limit, LimitExceeded, Limits};
use crate::raster::font::{GLYPH_H, Label};
use glam::{Vec2, Vec3};
#[cfg(feature = "parallel")]
use rayon::prelude::*;

pub use crate::raster::{Image, RowOrder};
use std::f32::consts::{PI, TAU};

/// Lanes of the batched preview path.
pub(crate) const PREVIEW_LANES: usize = 16;

/// Preview settings outside what can be rendered.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PreviewError {
    /// [`PreviewOptions::size`] is 0.
    #[error("preview size 0: a ball needs at least one pixel")]
    ZeroSize,
    /// A ball of `size × size` pixels is above [`Limits::preview_pixels`].
    #[error("preview size {size}: {exceeded}")]
    TooLarge {
        /// The size asked for.
        size: usize,
        /// The limit, the ball's pixel count and the maximum.
        exceeded: LimitExceeded,
    },
    /// A contact sheet would be wider or taller than [`ContactSheet::MAX_SIDE`].
    #[error(
        "a contact sheet of {count} balls of {size} pixels would be {width}×{height} pixels; \
         a side is limited to {max}"
    )]
    SheetSide {
        /// Number of balls.
        count: usize,
        /// Side of one ball.
        size: usize,
        /// Sheet width.
        width: usize,
        /// Sheet height.
        height: usize,
        /// [`ContactSheet::MAX_SIDE`].
        max: usize,
    },
    /// A contact sheet needs at least one ball, all of one size.
    #[error("a contact sheet needs at least one ball, all of one size (sizes: {sizes:?})")]
    SheetBalls {
        /// The distinct sizes of the balls given (empty: no ball).
        sizes: Vec<usize>,
    },
}

/// What the preview shows.
#[derive(Debug, Clone, PartialEq)]
pub struct PreviewOptions {
    /// Image side in pixels (default 256).
    pub size: usize,
    /// Direction toward the light (normalised when used).
    pub light_dir: Vec3,
    /// Light irradiance `E_light` (RGB).
    pub light: Rgb,
    /// Uniform environment radiance (also the background).
    pub env: Rgb,
    /// Only this lobe's contribution (index into [`Material::leaves`]).
    pub aov_leaf: Option<usize>,
    /// Packed external inputs (see [`Material::input_layout`]); missing slots take their
    /// fallbacks.
    pub inputs: Vec<f32>,
    /// Use the batched interpreter (16 points at a time).
    pub batched: bool,
    /// One point at a time, prepare every pixel with the general prepare (lobe records)
    /// even when the material qualifies for the uniform-material prepare (constant
    /// registers, one frame, a batched kernel per leaf), which the scalar path otherwise
    /// uses at one lane. For comparisons; the two agree to relative 1e-5.
    pub general_prepare: bool,
    /// Shade rows in parallel (rayon's global pool); ignored without the `parallel`
    /// feature.
    pub parallel: bool,
    /// Bounds; a ball has at most [`Limits::preview_pixels`] pixels.
    pub limits: Limits,
}

impl Default for PreviewOptions {
    fn default() -> Self {
        PreviewOptions {
            size: 256,
            light_dir: Vec3::ONE.normalize(),
            light: Vec3::splat(PI),
            env: Vec3::splat(0.05),
            aov_leaf: None,
            inputs: Vec::new(),
            batched: false,
            general_prepare: false,
            parallel: true,
            limits: Limits::default(),
        }
    }
}

impl PreviewOptions {
    /// Check what a render needs of these options: a side of at least one pixel, and a ball
    /// of at most [`Limits::preview_pixels`] pixels (8192 × 8192 by default).
    ///
    /// ```
    /// use vstructc::interp::preview::{PreviewError, PreviewOptions};
    /// use vstructc::limits::Limit;
    /// let big = PreviewOptions { size: 100_000, ..PreviewOptions::default() };
    /// let Err(PreviewError::TooLarge { size, exceeded }) = big.validate() else { panic!() };
    /// assert_eq!((size, exceeded.limit, exceeded.value), (100_000, Limit::PreviewPixels, 10_000_000_000));
    /// assert!(PreviewOptions::default().validate().is_ok());
    /// ```
    pub fn validate(&self) -> Result<(), PreviewError> {
        if self.size == 0 {
            return Err(PreviewError::ZeroSize);
        }
        let pixels = (self.size as u64).saturating_mul(self.size as u64);
        self.limits
            .check(Limit::PreviewPixels, pixels)
            .map_err(|exceeded| PreviewError::TooLarge {
                size: self.size,
                exceeded,
            })
    }

    /// White-furnace settings: no light, `env = 1`.
    pub fn furnace(mut self) -> Self {
        self.light = Vec3::ZERO;
        self.env = Vec3::ONE;
        self
    }
}

/// The geometry of the sphere pixel at `(x, y)` (on the sphere: a column of
/// [`sphere_span`]): normal, tangent, globals (`uv` only when `with_uv`: it costs an `atan2`
/// and an `asin`, and a program that reads no global ignores it).
fn sphere_point(x: f32, y: f32, with_uv: bool) -> ShadingPoint<'static> {
    let (n, t) = sphere_frame(x, y);
    let uv = if with_uv { sphere_uv(n) } else { Vec2::ZERO };
    ShadingPoint::new(n, t, Vec3::Z)
        .with_position(n)
        .with_uv(uv)
}

/// True when the pixel centre `(x, y)` lies on the sphere.
#[inline(always)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn on_sphere(x: f32, y: f32) -> bool {
    x * x + y * y < 1.0
}

/// The sphere's normal and tangent at `(x, y)` (on the sphere). Branch-free, so that the
/// batched path's loop over lanes vectorises.
#[inline(always)]
fn sphere_frame(x: f32, y: f32) -> (Vec3, Vec3) {
    let n = Vec3::new(x, y, (1.0 - (x * x + y * y)).sqrt());
    // `normalize((0, 1, 0) × N)` written out: the cross product is `(N_z, 0, −N_x)`, and
    // its squared length sums the same terms in the same order, so the bits are those of
    // `cross` and `normalize` (but for the sign of `T_y`'s zero), in straight-line
    // arithmetic that vectorises across a batch.
    let r = 1.0 / (n.z * n.z + n.x * n.x).sqrt();
    let t = Vec3::new(n.z * r, 0.0, -n.x * r);
    let t = if n.y.abs() > 0.999 { Vec3::X } else { t };
    (n, t)
}

/// The sphere's surface parameters at normal `n`.
fn sphere_uv(n: Vec3) -> Vec2 {
    Vec2::new(
        0.5 + n.x.atan2(n.z) / TAU,
        0.5 + n.y.clamp(-1.0, 1.0).asin() / PI,
    )
}

/// The columns of row `j` whose pixel centres lie on the sphere: one run, since the test
/// is `x² < 1 − y²` and `x` grows with the column. The run's ends are guessed from the
/// circle's edge and settled with [`on_sphere`] itself, so it holds exactly the columns that
/// test accepts, and the other columns cost nothing (testing each was a division per pixel).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn sphere_span(j: usize, size: usize) -> std::ops::Range<usize> {
    let (_, y) = pixel_xy(0, j, size);
    let on = |i: usize| on_sphere(pixel_xy(i, j, size).0, y);
    // A run that is not empty holds the column nearest `x = 0` (one of the middle two).
    let mid = size / 2;
    let centre = match (on(mid), mid > 0 && on(mid - 1)) {
        (true, _) => mid,
        (false, true) => mid - 1,
        (false, false) => return 0..0,
    };
    let half = (1.0 - y * y).max(0.0).sqrt();
    let edge = ((1.1 - half) * size as f32 / 2.2).clamp(0.0, centre as f32) as usize;
    let mut lo = edge;
    while lo > 0 && on(lo - 1) {
        lo -= 1;
    }
    while !on(lo) {
        lo += 1;
    }
    let mut hi = (size - edge).max(centre + 1);
    while hi < size && on(hi) {
        hi += 1;
    }
    while !on(hi - 1) {
        hi -= 1;
    }
    lo..hi
}

/// Pixel centre of column `i` / row `j` in an image of side `size`.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn pixel_xy(i: usize, j: usize, size: usize) -> (f32, f32) {
    let s = size as f32;
    (
        -1.1 + 2.2 * (i as f32 + 0.5) / s,
        1.1 - 2.2 * (j as f32 + 0.5) / s,
    )
}

/// Render the material ball. `progress` is called with the number of rows finished so far
/// (from worker threads, in any order). Fails if the options do not pass
/// [`PreviewOptions::validate`]. The whole image is in memory: for many balls or large sizes
/// use [`ContactSheet`], which streams rows.
pub fn render_ball(
    material: &Material,
    opts: &PreviewOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Image, PreviewError> {
    opts.validate()?;
    let size = opts.size;
    let mut img = Image::filled(size, size, opts.env);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let row = |st: &mut RowState, (j, out): (usize, &mut [Rgb])| {
        st.shade(material, opts, j, out);
        progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
    };
    #[cfg(feature = "parallel")]
    if opts.parallel {
        img.pixels
            .par_chunks_mut(size)
            .enumerate()
            .for_each_init(RowState::default, row);
        return Ok(img);
    }
    let mut st = RowState::default();
    img.pixels
        .chunks_mut(size)
        .enumerate()
        .for_each(|r| row(&mut st, r));
    Ok(img)
}

/// Per-worker working memory of the row shaders: working memory per worker, not per row (a
/// 16-lane batch is ~120 KB, and building one per row cost a quarter of a batched preview).
/// The batches are made on first use, so one state serves balls of different materials.
#[derive(Default)]
struct RowState {
    scratch: Scratch,
    prep: Option<Prepared>,
    /// The batched path's lanes.
    batch: Option<Box<PreparedBatch<PREVIEW_LANES>>>,
    /// The scalar path's one lane, for a material the uniform-material prepare covers.
    lane: Option<Box<PreparedBatch<1>>>,
}

impl RowState {
    /// Shade row `j` of the ball of `material` into `out` (pixels off the sphere are left
    /// as they are), with the path the options and the material call for.
    fn shade(&mut self, material: &Material, opts: &PreviewOptions, j: usize, out: &mut [Rgb]) {
        let one_lane = !opts.batched
            && !opts.general_prepare
            && opts.aov_leaf.is_none()
            && material.prepares_lanes();
        let scratch = &mut self.scratch;
        if opts.batched {
            let batch = self
                .batch
                .get_or_insert_with(PreparedBatch::<PREVIEW_LANES>::new_boxed);
            shade_row_lanes(material, opts, j, out, scratch, batch);
        } else if one_lane {
            let lane = self.lane.get_or_insert_with(PreparedBatch::<1>::new_boxed);
            shade_row_lanes(material, opts, j, out, scratch, lane);
        } else {
            let prep = self.prep.get_or_insert_with(Prepared::new);
            shade_row_with(material, opts, j, out, scratch, prep);
        }
    }
}

/// A sphere pixel's radiance: the light through `direct` (`eval(L_light).f_cos`), the
/// uniform environment through the albedo, emission, and the environment seen through
/// transparency.
#[inline(always)]
fn radiance(opts: &PreviewOptions, direct: Rgb, albedo: Rgb, emission: Rgb, tau: Rgb) -> Rgb {
    direct * opts.light + opts.env * albedo + emission + tau * opts.env
}

testkit_pub! {
    /// Shade row `j` one point at a time with the prepare that builds lobe records
    /// ([`Material::prepare_unpacked_into`], or its general form with
    /// [`PreviewOptions::general_prepare`]).
    fn shade_row(material: &Material, opts: &PreviewOptions, j: usize, out: &mut [Rgb]) {
        let (mut scratch, mut prep) = (Scratch::default(), Prepared::new());
        shade_row_with(material, opts, j, out, &mut scratch, &mut prep);
    }
}

/// [`shade_row`] with caller-owned working memory.
fn shade_row_with(
    material: &Material,
    opts: &PreviewOptions,
    j: usize,
    out: &mut [Rgb],
    scratch: &mut Scratch,
    prep: &mut Prepared,
) {
    let size = out.len();
    let l = opts.light_dir.normalize_or(Vec3::Z);
    let with_uv = !material.is_uniform();
    let span = sphere_span(j, size);
    for (i, px) in span.clone().zip(&mut out[span]) {
        let (x, y) = pixel_xy(i, j, size);
        let p = sphere_point(x, y, with_uv).with_inputs(&opts.inputs);
        // One eval follows each prepare: planning lobe packs would not pay for itself.
        if opts.general_prepare {
            material.prepare_general_into(&p, scratch, prep);
        } else {
            material.prepare_unpacked_into(&p, scratch, prep);
        }
        let direct = if opts.light == Vec3::ZERO {
            Vec3::ZERO
        } else {
            match opts.aov_leaf {
                None => prep.eval_f_cos(l),
                Some(leaf) => prep
                    .lobes()
                    .iter()
                    .position(|a| a.leaf as usize == leaf)
                    .map_or(Vec3::ZERO, |k| prep.eval_lobe(k, l).f_cos),
            }
        };
        *px = match opts.aov_leaf {
            None => radiance(
                opts,
                direct,
                prep.albedo().total(),
                prep.emission(),
                prep.transparency(),
            ),
            Some(leaf) => {
                let a = prep
                    .lobes()
                    .iter()
                    .find(|a| a.leaf as usize == leaf)
                    .map_or(Vec3::ZERO, |a| a.albedo.total());
                direct * opts.light + opts.env * a
            }
        };
    }
}

/// Shade row `j` with the batched interpreter (AOVs fall back to the scalar path).
#[cfg(feature = "testkit")]
pub fn shade_row_batched(material: &Material, opts: &PreviewOptions, j: usize, out: &mut [Rgb]) {
    let mut scratch = Scratch::default();
    let mut batch = PreparedBatch::<PREVIEW_LANES>::new_boxed();
    shade_row_lanes(material, opts, j, out, &mut scratch, &mut batch);
}

/// Shade row `j` `W` pixels at a time with caller-owned working memory (the batched path
/// at [`PREVIEW_LANES`], the scalar path of a uniform material at one lane).
fn shade_row_lanes<const W: usize>(
    material: &Material,
    opts: &PreviewOptions,
    j: usize,
    out: &mut [Rgb],
    scratch: &mut Scratch,
    batch: &mut PreparedBatch<W>,
) {
    if opts.aov_leaf.is_some() {
        return shade_row(material, opts, j, out);
    }
    let size = out.len();
    let l = opts.light_dir.normalize_or(Vec3::Z);
    let with_uv = !material.is_uniform();
    let mut pts = ShadingBatch::<W>::new([Vec3::Z; W], [Vec3::X; W], [Vec3::Z; W]);
    pts.inputs = [&opts.inputs[..]; W];
    let (_, y) = pixel_xy(0, j, size);
    // The row's run of sphere columns, `W` consecutive columns a batch: the lanes' geometry
    // is computed in one loop (no per-pixel `ShadingPoint`), and the results go to one
    // contiguous stretch of the row.
    let span = sphere_span(j, size);
    for start in span.clone().step_by(W) {
        let n = (span.end - start).min(W);
        // A partial batch repeats its last point (every lane must be a real point).
        let xs: [f32; W] = std::array::from_fn(|k| pixel_xy(start + k.min(n - 1), j, size).0);
        for (k, &x) in xs.iter().enumerate() {
            let (nk, tk) = sphere_frame(x, y);
            pts.n[k] = nk;
            pts.t[k] = tk;
            pts.p[k] = nk;
        }
        if with_uv {
            for (uv, &n) in pts.uv.iter_mut().zip(&pts.n) {
                *uv = sphere_uv(n);
            }
        }
        material.prepare_batch_f_cos_into(&pts, scratch, batch);
        let direct: [Rgb; W] = if opts.light == Vec3::ZERO {
            [Vec3::ZERO; W]
        } else {
            batch.eval_f_cos(&[l; W])
        };
        // All lanes in one loop (it vectorises), then the real ones to their pixels.
        let rgb: [Rgb; W] = std::array::from_fn(|k| {
            let (a, e, t) = (batch.albedo(k), batch.emission(k), batch.transparency(k));
            radiance(opts, direct[k], a, e, t)
        });
        out[start..start + n].copy_from_slice(&rgb[..n]);
    }
}

/// One ball of a [`ContactSheet`]: a material and how to show it.
#[derive(Debug, Clone)]
pub struct Ball<'m> {
    /// The material.
    pub material: &'m Material,
    /// Its preview options (every ball of a sheet has the same [`PreviewOptions::size`]).
    pub options: PreviewOptions,
    /// Text written under the ball (the material's name), or none. A sheet where some ball
    /// has a label gives every cell a label band ([`ContactSheet`]).
    pub label: Option<String>,
}

/// The smallest ball side, in pixels, that gets a label: below it a name would be a few
/// letters at most.
const LABEL_MIN_SIZE: usize = 32;

/// The labels of a sheet: where they sit and how they look.
#[derive(Debug, Clone)]
struct Labels {
    /// One per ball (`None`: no label under this ball).
    text: Vec<Option<Label>>,
    /// Rows of the band under each ball row.
    rows: usize,
    /// Rows above the text in the band.
    top: usize,
    /// The colour of the text.
    ink: Rgb,
}

impl Labels {
    /// The labels of `balls` of side `size` over `background`; `None` when no ball has a
    /// label or the balls are too small for one.
    fn new(balls: &[Ball<'_>], size: usize, background: Rgb) -> Option<Labels> {
        if size < LABEL_MIN_SIZE || balls.iter().all(|b| b.label.is_none()) {
            return None;
        }
        let scale = (size / 128).max(1);
        let text: Vec<Option<Label>> = balls
            .iter()
            .map(|b| b.label.as_deref().map(|t| Label::fit(t, size, scale)))
            .collect();
        // Dark text on a light background, light text on a dark one.
        let light = background.x + background.y + background.z > 1.5;
        Some(Labels {
            text,
            rows: (GLYPH_H + 4) * scale,
            top: 2 * scale,
            ink: if light { Vec3::ZERO } else { Vec3::splat(0.8) },
        })
    }
}

/// Balls of equal size in a grid of `⌈√n⌉` columns, row-major in the given order, empty
/// cells in a background colour; rendered a band of pixel rows at a time, so its memory is
/// at most [`ContactSheet::BAND_PIXELS`] pixels (and at least one pixel row) whatever the
/// number of balls.
///
/// **Labels.** When some ball has a [`Ball::label`] and balls are at least 32 pixels, each row of balls is followed by a band of
/// `12 × max(1, ⌊size / 128⌋)` rows in the background colour, where each label is written
/// centred under its ball in a 5 × 8 bitmap font scaled by `max(1, ⌊size / 128⌋)`: light text
/// (linear 0.8) on a dark background, black on a light one. A label wider than its ball
/// (less a margin) is cut and ends with `…`; characters outside printable ASCII show as `?`.
/// Ball pixels are the same with or without labels.
///
/// ```
/// use vstructc::interp::preview::{ContactSheet, PreviewError};
/// use glam::Vec3;
/// // Sides are checked before anything is rendered.
/// let none = ContactSheet::new(Vec::new(), Vec3::ZERO);
/// assert!(matches!(none, Err(PreviewError::SheetBalls { .. })));
/// # let _ = ContactSheet::MAX_SIDE;
/// ```
#[derive(Debug, Clone)]
pub struct ContactSheet<'m> {
    balls: Vec<Ball<'m>>,
    background: Rgb,
    size: usize,
    columns: usize,
    rows: usize,
    labels: Option<Labels>,
}

impl<'m> ContactSheet<'m> {
    /// The largest side, in pixels, of a contact sheet: the PNG format's limit (2³¹ − 1).
    pub const MAX_SIDE: usize = (1 << 31) - 1;

    /// The most pixels a contact sheet holds at once (one band of rows, 12 MB of RGB).
    pub const BAND_PIXELS: usize = 1 << 20;

    /// A sheet of `balls`, empty cells filled with `background`, labelled if some ball has
    /// a label. Fails if there is no ball, if the balls' sizes differ or fail
    /// [`PreviewOptions::validate`], or if a side of the sheet would exceed
    /// [`ContactSheet::MAX_SIDE`].
    pub fn new(balls: Vec<Ball<'m>>, background: Rgb) -> Result<Self, PreviewError> {
        let mut sizes: Vec<usize> = balls.iter().map(|b| b.options.size).collect();
        sizes.sort_unstable();
        sizes.dedup();
        let [size] = sizes[..] else {
            return Err(PreviewError::SheetBalls { sizes });
        };
        for b in &balls {
            b.options.validate()?;
        }
        let count = balls.len();
        let columns = (count as f64).sqrt().ceil().max(1.0) as usize;
        let rows = count.div_ceil(columns);
        let labels = Labels::new(&balls, size, background);
        let cell_height = size + labels.as_ref().map_or(0, |l| l.rows);
        let (width, height) = (
            columns.saturating_mul(size),
            rows.saturating_mul(cell_height),
        );
        if width > ContactSheet::MAX_SIDE || height > ContactSheet::MAX_SIDE {
            return Err(PreviewError::SheetSide {
                count,
                size,
                width,
                height,
                max: ContactSheet::MAX_SIDE,
            });
        }
        Ok(ContactSheet {
            balls,
            background,
            size,
            columns,
            rows,
            labels,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.columns * self.size
    }

    /// Height in pixels (with the label bands, if any).
    pub fn height(&self) -> usize {
        self.rows * (self.size + self.label_rows())
    }

    /// Rows of the label band under each row of balls (0 without labels).
    pub fn label_rows(&self) -> usize {
        self.labels.as_ref().map_or(0, |l| l.rows)
    }

    /// Number of columns of balls.
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// Render the sheet and hand each pixel row (`width()` pixels) to `emit`, in `order`.
    /// `progress` is called with the number of rows handed out so far. Stops at `emit`'s
    /// first error. Bands of rows are shaded in parallel when the first ball's options ask
    /// for it ([`PreviewOptions::parallel`]).
    pub fn render_rows<E>(
        &self,
        order: RowOrder,
        progress: &dyn Fn(usize),
        mut emit: impl FnMut(&[Rgb]) -> Result<(), E>,
    ) -> Result<(), E> {
        let width = self.width();
        let band_rows = (ContactSheet::BAND_PIXELS / width).clamp(1, self.size);
        let mut band = Vec::with_capacity(band_rows * width);
        let mut done = 0;
        let mut ball_rows: Vec<usize> = (0..self.rows).collect();
        if order == RowOrder::BottomUp {
            ball_rows.reverse();
        }
        let mut label_row = vec![self.background; width];
        let mut label_rows = |r: usize,
                              done: &mut usize,
                              emit: &mut dyn FnMut(&[Rgb]) -> Result<(), E>|
         -> Result<(), E> {
            let mut js: Vec<usize> = (0..self.label_rows()).collect();
            if order == RowOrder::BottomUp {
                js.reverse();
            }
            for j in js {
                self.draw_label_row(r, j, &mut label_row);
                emit(&label_row)?;
                *done += 1;
                progress(*done);
            }
            Ok(())
        };
        for r in ball_rows {
            if order == RowOrder::BottomUp {
                label_rows(r, &mut done, &mut emit)?;
            }
            let mut starts: Vec<usize> = (0..self.size).step_by(band_rows).collect();
            if order == RowOrder::BottomUp {
                starts.reverse();
            }
            for j0 in starts {
                let j1 = (j0 + band_rows).min(self.size);
                band.clear();
                band.resize((j1 - j0) * width, self.background);
                self.shade_band(r, j0, &mut band);
                let mut rows: Vec<&[Rgb]> = band.chunks(width).collect();
                if order == RowOrder::BottomUp {
                    rows.reverse();
                }
                for row in rows {
                    emit(row)?;
                    done += 1;
                    progress(done);
                }
            }
            if order == RowOrder::TopDown {
                label_rows(r, &mut done, &mut emit)?;
            }
        }
        Ok(())
    }

    /// Row `j` of the label band under ball row `r`: the background, and the labels' ink.
    fn draw_label_row(&self, r: usize, j: usize, row: &mut [Rgb]) {
        row.fill(self.background);
        let Some(labels) = &self.labels else {
            return;
        };
        for c in 0..self.columns {
            let label = labels
                .text
                .get(r * self.columns + c)
                .and_then(Option::as_ref);
            let Some(label) = label else {
                continue;
            };
            let Some(y) = j.checked_sub(labels.top).filter(|&y| y < label.height()) else {
                continue;
            };
            let cell = &mut row[c * self.size..(c + 1) * self.size];
            for (x, p) in cell.iter_mut().enumerate() {
                if label.ink(x, y) {
                    *p = labels.ink;
                }
            }
        }
    }

    /// Shade rows `j0..` of ball row `r` into `band` (whole sheet rows, filled with the
    /// background): one task per ball and pixel row.
    fn shade_band(&self, r: usize, j0: usize, band: &mut [Rgb]) {
        let cell = |st: &mut RowState, (idx, out): (usize, &mut [Rgb])| {
            let (j, c) = (j0 + idx / self.columns, idx % self.columns);
            if let Some(ball) = self.balls.get(r * self.columns + c) {
                out.fill(ball.options.env);
                st.shade(ball.material, &ball.options, j, out);
            }
        };
        #[cfg(feature = "parallel")]
        if self.balls[0].options.parallel {
            band.par_chunks_mut(self.size)
                .enumerate()
                .for_each_init(RowState::default, cell);
            return;
        }
        let mut st = RowState::default();
        band.chunks_mut(self.size)
            .enumerate()
            .for_each(|x| cell(&mut st, x));
    }
}
