//! Bounded rendering: `render` of many materials streams the contact sheet row by row, so
//! its memory does not grow with the number of balls; the preview size limit lives in the
//! library (`PreviewOptions::validate`), which the command line reports.

use crate::scratch;
use std::fmt::Write as _;
use std::path::Path;
use vstructc::interp::preview::{ContactSheet, PreviewError, PreviewOptions, render_ball};

/// `n` PxrSurface materials (handles `m0`…), each a little different.
fn materials(n: usize) -> String {
    let mut rib = String::new();
    for i in 0..n {
        let _ = writeln!(
            rib,
            "Bxdf \"PxrSurface\" \"m{i}\" \"color diffuseColor\" [{} 0.5 {}] \
             \"float specularRoughness\" [{}]",
            (i % 7) as f32 / 7.0,
            (i % 5) as f32 / 5.0,
            (i % 9) as f32 / 9.0
        );
    }
    rib
}

/// Exit status and peak resident set size (KiB) of `vstructc args` (see
/// `crate::timed_vstructc` for why it runs under `/usr/bin/time`).
fn run_measured(name: &str, args: &[&str]) -> (Option<i32>, u64, String) {
    let err = scratch(&format!("{name}.stderr"), "");
    let report = err.with_extension("usage");
    let status = crate::timed_vstructc(args, &report)
        .stdout(std::process::Stdio::null())
        .stderr(std::fs::File::create(&err).expect("stderr file"))
        .status()
        .expect("/usr/bin/time runs");
    let stderr = std::fs::read_to_string(&err).unwrap_or_default();
    (
        status.code(),
        crate::read_usage(&report).max_rss_kib,
        stderr,
    )
}

fn render_sheet(name: &str, n: usize, size: usize, format: &str) -> (Option<i32>, u64, String) {
    let input = scratch(&format!("{name}.rib"), materials(n));
    let output = input.with_extension(format);
    let size = size.to_string();
    let (status, rss, stderr) = run_measured(
        name,
        &[
            "render",
            &input.display().to_string(),
            "--size",
            &size,
            "--batched",
            "-o",
            &output.display().to_string(),
        ],
    );
    (status, rss, stderr)
}

/// Pixels (RGB, top row first) of a PFM written by vstructc.
fn read_pfm(path: &Path) -> (usize, usize, Vec<[f32; 3]>) {
    let bytes = std::fs::read(path).expect("the PFM was written");
    let mut fields = bytes.splitn(4, |&b| b == b'\n');
    assert_eq!(fields.next(), Some(&b"PF"[..]));
    let dims = String::from_utf8_lossy(fields.next().expect("dims")).into_owned();
    let (w, h) = dims.split_once(' ').expect("w h");
    let (w, h): (usize, usize) = (w.parse().unwrap(), h.parse().unwrap());
    assert_eq!(fields.next(), Some(&b"-1.0"[..]));
    let data = fields.next().expect("pixels");
    assert_eq!(data.len(), w * h * 12);
    let mut px: Vec<[f32; 3]> = data
        .chunks(12)
        .map(|c| {
            std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap()))
        })
        .collect();
    // Rows are stored bottom to top.
    let rows: Vec<Vec<[f32; 3]>> = px.chunks(w).rev().map(<[_]>::to_vec).collect();
    px = rows.concat();
    (w, h, px)
}

/// 1,000 materials: one contact sheet, in memory far below what holding every ball (and
/// the sheet) took (1,000 × 64² balls and a 2048² sheet: 100 MB before; ~35 MB now).
#[test]
fn many_materials_render_in_bounded_memory() {
    let (status, rss_kib, stderr) = render_sheet("many1000", 1000, 64, "png");
    assert_eq!(status, Some(0), "{stderr}");
    let whole_sheet_kib = (32 * 64) * (32 * 64) * 12 / 1024;
    assert!(
        rss_kib < 80 * 1024 && rss_kib < whole_sheet_kib * 2,
        "peak RSS {rss_kib} KiB (the sheet alone is {whole_sheet_kib} KiB)"
    );
}

/// 64 materials at a large size (8 × 384 = a 3072² sheet, 113 MB as f32 RGB; at 2048 px
/// the same streaming holds, but the test stays fast): memory stays far below one copy of
/// the sheet.
#[test]
fn large_balls_render_in_bounded_memory() {
    let (status, rss_kib, stderr) = render_sheet("many64", 64, 384, "pfm");
    assert_eq!(status, Some(0), "{stderr}");
    let whole_sheet_kib = 3072 * 3072 * 12 / 1024;
    assert!(
        rss_kib < 80 * 1024 && rss_kib < whole_sheet_kib / 2,
        "peak RSS {rss_kib} KiB (the sheet alone is {whole_sheet_kib} KiB)"
    );
}

/// The streamed sheet is the balls rendered one by one, in row-major order, with empty
/// cells in the background colour, in PFM, whose rows are written bottom first.
fn sheet_is_balls_side_by_side(input: &Path, names: &[&str], size: usize) {
    let sheet_path = input.with_extension("pfm");
    let render = |extra: &[&str], out: &Path| {
        let mut args = vec![
            "render".to_string(),
            input.display().to_string(),
            "--size".into(),
            size.to_string(),
            "-o".into(),
            out.display().to_string(),
        ];
        args.extend(extra.iter().map(|s| s.to_string()));
        let o = crate::run(&args);
        assert_eq!(o.status, Some(0), "{}", o.stderr);
    };
    render(&[], &sheet_path);
    let (w, h, sheet) = read_pfm(&sheet_path);
    let columns = (names.len() as f64).sqrt().ceil() as usize;
    let rows = names.len().div_ceil(columns);
    assert_eq!((w, h), (columns * size, rows * size));
    for (k, name) in names.iter().enumerate() {
        let one = input.with_extension(format!("{name}.pfm"));
        render(&["--material", name], &one);
        let (bw, bh, ball) = read_pfm(&one);
        assert_eq!((bw, bh), (size, size));
        let (cx, cy) = ((k % columns) * size, (k / columns) * size);
        for y in 0..size {
            for x in 0..size {
                assert_eq!(
                    sheet[(cy + y) * w + cx + x],
                    ball[y * size + x],
                    "ball {name} at {x},{y}"
                );
            }
        }
    }
    let background = [0.05f32; 3];
    for k in names.len()..columns * rows {
        let (cx, cy) = ((k % columns) * size, (k / columns) * size);
        for y in cy..cy + size {
            assert!(
                sheet[y * w + cx..y * w + cx + size]
                    .iter()
                    .all(|p| *p == background)
            );
        }
    }
}

/// Five balls (3 columns, 2 rows, one empty cell) of 600 pixels: a ball row (1800 × 600)
/// is more than one band of `ContactSheet::BAND_PIXELS`, so bands split a ball row too.
#[test]
fn the_streamed_sheet_is_the_balls_side_by_side() {
    let size = 600;
    assert!(3 * size * size > vstructc::interp::preview::ContactSheet::BAND_PIXELS);
    let input = scratch("sheet5.rib", materials(5));
    sheet_is_balls_side_by_side(&input, &["m0", "m1", "m2", "m3", "m4"], size);
}

/// Materials of different structures side by side (plain, coated, textured, layered,
/// chained): a worker's working memory serves balls of different materials.
#[test]
fn a_sheet_of_different_materials_is_the_balls_side_by_side() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut rib = Vec::new();
    for file in [
        "tests/data/render/coated.rib",
        "tests/data/render/textured.rib",
        "examples/layered.rib",
        "examples/chain.rib",
        "tests/data/render/two.rib",
    ] {
        rib.extend(std::fs::read(root.join(file)).expect("a repository file"));
    }
    let input = scratch("mixed_sheet.rib", rib);
    let names = ["coated", "textured", "surface", "car", "white", "red"];
    sheet_is_balls_side_by_side(&input, &names, 40);
}

/// The library refuses a size beyond its limit with an error naming the limit and the
/// value; the command line reports that error as a usage error (exit 2).
#[test]
fn preview_size_is_validated_by_the_library() {
    let big = PreviewOptions {
        size: 100_000,
        ..PreviewOptions::default()
    };
    let err = big.validate().expect_err("too large");
    let PreviewError::TooLarge { size, exceeded } = &err else {
        panic!("{err:?}")
    };
    assert_eq!(*size, 100_000);
    assert_eq!(exceeded.limit, vstructc::limits::Limit::PreviewPixels);
    assert_eq!(
        err.to_string(),
        "preview size 100000: 10000000000 pixels exceed the limit preview_pixels = 67108864"
    );
    // The bound is the caller's: a smaller one refuses a size the default allows.
    let strict = PreviewOptions {
        size: 64,
        limits: vstructc::limits::Limits {
            preview_pixels: 63 * 63,
            ..Default::default()
        },
        ..PreviewOptions::default()
    };
    assert!(matches!(
        strict.validate(),
        Err(PreviewError::TooLarge { size: 64, .. })
    ));
    let zero = PreviewOptions {
        size: 0,
        ..PreviewOptions::default()
    };
    assert!(matches!(zero.validate(), Err(PreviewError::ZeroSize)));
    assert!(matches!(
        ContactSheet::new(Vec::new(), glam::Vec3::ZERO),
        Err(PreviewError::SheetBalls { .. })
    ));
    let _ = render_ball; // `render_ball` validates too (tests/materials/render_regression.rs renders).

    let input = scratch("size_limit.rib", materials(2));
    for (size, message) in [
        (
            "100000",
            "error: preview size 100000: 10000000000 pixels exceed the limit preview_pixels",
        ),
        (
            "0",
            "error: preview size 0: a ball needs at least one pixel",
        ),
    ] {
        let o = crate::run(&[
            "render".into(),
            input.display().to_string(),
            "--size".into(),
            size.into(),
            "-o".into(),
            input.with_extension("png").display().to_string(),
        ]);
        assert_eq!(o.status, Some(2), "{}", o.stderr);
        assert!(o.stderr.contains(message), "{}", o.stderr);
    }
}

/// `width × height` EXR bytes from `rows` rows given by `row(y)`, as `write_rows` writes them.
fn exr_rows(
    width: usize,
    height: usize,
    rows: usize,
    row: impl Fn(usize) -> Vec<glam::Vec3>,
) -> (std::io::Result<()>, Vec<u8>) {
    use vstructc::back::png::{ImageFormat, write_rows};
    let mut out = Vec::new();
    let r = write_rows(ImageFormat::Exr, &mut out, width, height, |sink| {
        (0..rows).try_for_each(|y| sink.write_row(&row(y)))
    });
    (r, out)
}

/// EXR keeps every f32 as it is, special values included (the file is read back with the
/// `exr` crate); an image given too few or too many rows is an error and nothing reaches
/// the output.
#[test]
fn exr_keeps_every_value_and_writes_nothing_on_a_short_or_long_image() {
    use exr::image::FlatSamples;
    use exr::prelude::{ReadChannels as _, ReadLayers as _};
    let specials = [
        0.0,
        -0.0,
        1e-40, // subnormal
        -1.5,
        0.5,
        65504.5,
        1e30,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::from_bits(0x7fc0_1234), // a NaN with a payload
    ];
    let (w, h) = (specials.len(), 37); // 37 rows: two full blocks of 16 and a short one
    let value = |x: usize, y: usize, c: usize| {
        if y.is_multiple_of(2) {
            specials[(x + c) % specials.len()]
        } else {
            (y * 1000 + x * 10 + c) as f32 / 7.0
        }
    };
    let row = |y: usize| -> Vec<glam::Vec3> {
        (0..w)
            .map(|x| glam::Vec3::new(value(x, y, 0), value(x, y, 1), value(x, y, 2)))
            .collect()
    };
    let (r, bytes) = exr_rows(w, h, h, row);
    r.unwrap();
    let image = exr::image::read::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .unwrap();
    let layer = image.layer_data;
    assert_eq!((layer.size.0, layer.size.1), (w, h));
    for (channel, c) in layer.channel_data.list.iter().zip([2, 1, 0]) {
        let FlatSamples::F32(samples) = &channel.sample_data else {
            panic!("channel {} is not f32", channel.name);
        };
        for y in 0..h {
            for x in 0..w {
                assert_eq!(
                    samples[y * w + x].to_bits(),
                    value(x, y, c).to_bits(),
                    "channel {} at {x},{y}",
                    channel.name
                );
            }
        }
    }
    for rows in [0, 16, h - 1, h + 1] {
        let (r, bytes) = exr_rows(w, h, rows, row);
        assert!(r.is_err(), "{rows} rows of {h}");
        assert!(
            bytes.is_empty(),
            "{rows} rows of {h}: {} bytes written",
            bytes.len()
        );
    }
}
