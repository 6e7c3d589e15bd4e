//! Image regression (spec closures.md §5.9): previews of every recipe at its definition's
//! defaults (the embedded definitions) and of the golden network of vstruct.md §12 (the
//! RenderMan for Maya export in `../shared/fixtures`), against PFM references in
//! `tests/data/render/reference/`. vstructc generated the references and each was reviewed
//! as a picture when it was made. A preview passes when its per-pixel RMS difference from
//! the reference is at most 1e-4 of the reference's mean; the MaterialX test suite's metric
//! (the per-channel RMS of the 8-bit sRGB images, summed, over 3·255) is printed for
//! information.
//!
//! `VSTRUCTC_BLESS=1 cargo test --test materials render_regression` rewrites the references, with a
//! PNG of each beside them in `target/render-regression/` to review. A missing reference
//! fails.

use crate::common;
use crate::common::pfm;

use pfm::{Pfm, read_pfm};
use std::path::PathBuf;
use vstructc::back::png::{ImageFormat, srgb8};
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::interp::Material;
use vstructc::interp::preview::{Image, PreviewOptions, render_ball};
use vstructc::ir::MaterialIr;
use vstructc::lower::network::{lower_terminal, terminals};
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{Diagnostics, Severity};

/// Small enough to keep the suite fast, large enough to show every lobe's highlight.
const SIZE: usize = 64;
/// §5.9's bound on the RMS difference, relative to the reference's mean.
const RMS_BOUND: f64 = 1e-4;

fn reference_path(name: &str) -> PathBuf {
    common::repo_dir()
        .join("tests/data/render/reference")
        .join(format!("{name}.pfm"))
}

fn render(ir: &MaterialIr) -> Image {
    let m = Material::new(ir).expect("the lowered IR compiles");
    let opts = PreviewOptions {
        size: SIZE,
        ..PreviewOptions::default()
    };
    render_ball(&m, &opts, &|_| {}).expect("valid preview options")
}

/// The golden network, resolved and lowered as in tests/lower/network.rs (its one external
/// input at its fallback).
fn golden_network(fixtures: &std::path::Path) -> MaterialIr {
    let surface = common::repo_dir().join("args/PxrLayerSurface.args");
    let registry = common::golden_registry(fixtures, &surface);
    let name = "pxrLayerSurface.0001.rib";
    let bytes = std::fs::read(fixtures.join(common::GOLDEN_RIB)).expect("fixture RIB");
    let mut diags = Diagnostics::new();
    let mut net =
        parse_rib(&bytes, name, &registry, &RibOptions::default(), &mut diags).expect("parses");
    diags.extend(resolve(&mut net, &registry, &ResolveOptions::default()).diagnostics);
    let (handle, node) = terminals(&net, None).expect("terminals")[0].clone();
    let ir = lower_terminal(&net, &registry, node, &handle, &mut diags).expect("lowers");
    assert!(
        !diags.iter().any(|d| d.severity == Severity::Error),
        "{diags:#?}"
    );
    ir
}

/// Per-pixel RMS difference over every channel, relative to the reference's mean.
fn relative_rms(image: &Image, reference: &Pfm) -> f64 {
    let n = (3 * reference.px.len()) as f64;
    let mean: f64 = reference
        .px
        .iter()
        .flatten()
        .map(|&c| f64::from(c))
        .sum::<f64>()
        / n;
    let squares: f64 = image
        .pixels
        .iter()
        .zip(&reference.px)
        .flat_map(|(a, b)| (0..3).map(move |c| f64::from(a[c] - b[c]).powi(2)))
        .sum();
    (squares / n).sqrt() / mean
}

/// The MaterialX test suite's image metric: per-channel RMS of the 8-bit sRGB images,
/// summed over the channels, divided by 3·255.
fn materialx_metric(image: &Image, reference: &Pfm) -> f64 {
    let mut squares = [0.0f64; 3];
    for (a, b) in image.pixels.iter().zip(&reference.px) {
        let (a, b) = (srgb8(*a), srgb8(glam::Vec3::from(*b)));
        for c in 0..3 {
            squares[c] += (f64::from(a[c]) - f64::from(b[c])).powi(2);
        }
    }
    let n = image.pixels.len() as f64;
    squares.iter().map(|s| (s / n).sqrt()).sum::<f64>() / (3.0 * 255.0)
}

fn blessing() -> bool {
    std::env::var("VSTRUCTC_BLESS").is_ok_and(|v| v == "1")
}

/// Writes `image` as the reference `name`, with a PNG to review.
fn bless(name: &str, image: &Image) {
    let path = reference_path(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, image.encode(ImageFormat::Pfm).unwrap()).unwrap();
    let review = common::repo_dir().join("target/render-regression");
    std::fs::create_dir_all(&review).unwrap();
    let png = image.encode(ImageFormat::Png).expect("encodes");
    std::fs::write(review.join(format!("{name}.png")), png).unwrap();
}

/// Compares `image` with the reference `name`; returns a failure message, if any.
fn check(name: &str, image: &Image) -> Option<String> {
    if blessing() {
        bless(name, image);
    }
    let path = reference_path(name);
    let Ok(bytes) = std::fs::read(&path) else {
        return Some(format!(
            "{name}: no reference at {path:?} (VSTRUCTC_BLESS=1 writes it; review it first)"
        ));
    };
    let reference = read_pfm(&bytes);
    if (reference.w, reference.h) != (image.width, image.height) {
        return Some(format!(
            "{name}: reference is {}×{}",
            reference.w, reference.h
        ));
    }
    let rms = relative_rms(image, &reference);
    let metric = materialx_metric(image, &reference);
    eprintln!("{name}: relative RMS {rms:.2e}, MaterialX metric {metric:.2e}");
    (rms > RMS_BOUND).then(|| format!("{name}: relative RMS {rms:.3e} > {RMS_BOUND:e}"))
}

#[test]
fn recipes_at_defaults_match_their_references() {
    let failures: Vec<String> = common::RECIPES
        .iter()
        .filter_map(|shader| check(shader, &render(&common::recipe_at_defaults(shader))))
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn golden_network_matches_its_reference() {
    let fixtures = fixtures_or_skip!();
    let image = render(&golden_network(&fixtures));
    if let Some(failure) = check("golden_network", &image) {
        panic!("{failure}");
    }
}

/// The bound is tight enough to see a small change: one pixel's channel moved by 5 % of the
/// image's mean over a 64² preview is an RMS of about 5e-4 of the mean.
#[test]
fn the_comparison_sees_a_small_change() {
    let image = render(&common::recipe_at_defaults("PxrSurface"));
    let as_pfm = |img: &Image| read_pfm(&img.encode(ImageFormat::Pfm).unwrap());
    let reference = as_pfm(&image);
    assert_eq!(relative_rms(&image, &reference), 0.0);
    let mean = reference.px.iter().flatten().sum::<f32>() / (3 * reference.px.len()) as f32;
    let mut changed = image.clone();
    let centre = SIZE / 2 * SIZE + SIZE / 2;
    changed.pixels[centre].x += 0.05 * mean;
    assert!(relative_rms(&changed, &reference) > RMS_BOUND);
}
