//! Labels of a contact sheet: a band under each row of balls with each ball's name, which
//! leaves the balls' pixels as they are; different names draw differently; a name too long
//! for its cell is cut within the cell.

use crate::uniform_materials::coated_ir;
use glam::Vec3;
use vstructc::interp::Material;
use vstructc::interp::preview::{Ball, ContactSheet, PreviewOptions, RowOrder};

const SIZE: usize = 64;
const BACKGROUND: Vec3 = Vec3::splat(0.05);

/// A sheet of one ball per label (all the same material), rendered top row first: width,
/// height, label rows and pixels.
fn sheet(m: &Material, size: usize, labels: &[Option<&str>]) -> (usize, usize, usize, Vec<Vec3>) {
    let balls = labels
        .iter()
        .map(|l| Ball {
            material: m,
            options: PreviewOptions {
                size,
                ..PreviewOptions::default()
            },
            label: l.map(str::to_string),
        })
        .collect();
    let sheet = ContactSheet::new(balls, BACKGROUND).expect("a valid sheet");
    let mut px = Vec::new();
    sheet
        .render_rows(RowOrder::TopDown, &|_| {}, |row| {
            px.extend_from_slice(row);
            Ok::<(), ()>(())
        })
        .unwrap();
    // Bottom-up order hands out the same rows, reversed.
    let mut up = Vec::new();
    sheet
        .render_rows(RowOrder::BottomUp, &|_| {}, |row| {
            up.push(row.to_vec());
            Ok::<(), ()>(())
        })
        .unwrap();
    up.reverse();
    assert!(
        up.concat() == px,
        "bottom-up rows are the top-down rows reversed"
    );
    assert_eq!(px.len(), sheet.width() * sheet.height());
    (sheet.width(), sheet.height(), sheet.label_rows(), px)
}

/// The pixels of cell column `c` in rows `rows` of a sheet `w` wide.
fn cell(px: &[Vec3], w: usize, c: usize, rows: std::ops::Range<usize>) -> Vec<Vec3> {
    rows.flat_map(|y| px[y * w + c * SIZE..y * w + (c + 1) * SIZE].to_vec())
        .collect()
}

#[test]
fn labels_change_only_the_band_under_the_balls() {
    let m = Material::new(&coated_ir()).expect("compiles");
    let (w, h, band, plain) = sheet(&m, SIZE, &[None, None]);
    assert_eq!((w, h, band), (2 * SIZE, SIZE, 0));
    let (lw, lh, band, labelled) = sheet(&m, SIZE, &[Some("red"), Some("blue")]);
    assert!(band > 0);
    assert_eq!((lw, lh), (2 * SIZE, SIZE + band));
    // The balls are the same pixels; the band is the background and the text.
    assert!(labelled[..SIZE * w] == plain[..], "ball pixels changed");
    for c in 0..2 {
        let text = cell(&labelled, w, c, SIZE..SIZE + band);
        let ink = text.iter().filter(|&&p| p != BACKGROUND).count();
        assert!(ink > 10, "cell {c}: {ink} text pixels");
        assert!(
            text.iter()
                .all(|&p| p == BACKGROUND || p == Vec3::splat(0.8))
        );
    }
    // A ball without a label has a blank band.
    let (_, _, _, half) = sheet(&m, SIZE, &[Some("red"), None]);
    assert!(
        cell(&half, w, 1, SIZE..SIZE + band)
            .iter()
            .all(|&p| p == BACKGROUND)
    );
    assert!(cell(&half, w, 0, 0..SIZE + band) == cell(&labelled, w, 0, 0..SIZE + band));
    // Balls below 32 pixels, too small for a readable name, get no band.
    let small = 31;
    let (_, sh, band, _) = sheet(&m, small, &[Some("red"), Some("blue")]);
    assert_eq!((sh, band), (small, 0));
}

#[test]
fn different_names_draw_different_labels() {
    let m = Material::new(&coated_ir()).expect("compiles");
    let (w, _, band, a) = sheet(&m, SIZE, &[Some("red"), Some("same")]);
    let (_, _, _, b) = sheet(&m, SIZE, &[Some("rod"), Some("same")]);
    let label = |px: &[Vec3], c| cell(px, w, c, SIZE..SIZE + band);
    assert!(
        label(&a, 0) != label(&b, 0),
        "`red` and `rod` draw the same"
    );
    assert!(label(&a, 1) == label(&b, 1));
}

#[test]
fn a_long_name_is_cut_with_an_ellipsis_inside_its_cell() {
    let m = Material::new(&coated_ir()).expect("compiles");
    let long = "a_material_name_far_longer_than_its_ball";
    let (w, _, band, px) = sheet(&m, SIZE, &[Some(long), None]);
    let text = |px: &[Vec3]| cell(px, w, 0, SIZE..SIZE + band);
    // The neighbour's band stays blank: nothing spills over.
    assert!(
        cell(&px, w, 1, SIZE..SIZE + band)
            .iter()
            .all(|&p| p == BACKGROUND)
    );
    // Nor does the text reach the cell's edges.
    for y in SIZE..SIZE + band {
        assert_eq!(px[y * w], BACKGROUND);
        assert_eq!(px[y * w + SIZE - 1], BACKGROUND);
    }
    // The band is that of a prefix of the name followed by `…` (longer prefixes are cut
    // the same way), and not that of the prefix alone.
    let k = (1..long.len())
        .find(|&k| {
            let short = format!("{}…", &long[..k]);
            text(&sheet(&m, SIZE, &[Some(&short), None]).3) == text(&px)
        })
        .expect("the cut name is a prefix and `…`");
    assert!(k >= 5, "only {k} characters kept in a {SIZE}-pixel cell");
    assert!(text(&sheet(&m, SIZE, &[Some(&long[..k]), None]).3) != text(&px));
}

#[test]
fn labels_are_dark_on_a_light_background() {
    let m = Material::new(&coated_ir()).expect("compiles");
    let options = PreviewOptions {
        size: SIZE,
        ..PreviewOptions::default()
    }
    .furnace();
    let ball = Ball {
        material: &m,
        options: options.clone(),
        label: Some("white".into()),
    };
    let sheet = ContactSheet::new(vec![ball.clone(), ball], options.env).unwrap();
    let mut band = Vec::new();
    let mut row = 0;
    sheet
        .render_rows(RowOrder::TopDown, &|_| {}, |r| {
            if row >= SIZE {
                band.extend_from_slice(r);
            }
            row += 1;
            Ok::<(), ()>(())
        })
        .unwrap();
    assert_eq!(options.env, Vec3::ONE);
    assert!(band.contains(&Vec3::ZERO), "no black text");
    assert!(band.iter().all(|&p| p == Vec3::ZERO || p == Vec3::ONE));
}
