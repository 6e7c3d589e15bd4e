//! Unit tests of `raster::font` (`src/raster/font.rs`).

use vstructc::raster::font::*;

/// The text as rows of `#` and `.` (one character per pixel).
fn art(l: &Label, width: usize) -> Vec<String> {
    (0..l.height())
        .map(|y| {
            (0..width)
                .map(|x| if l.ink(x, y) { '#' } else { '.' })
                .collect()
        })
        .collect()
}

#[test]
fn glyphs_are_drawn_at_their_place() {
    // "Hi" in a box 13 wide: 11 pixels of text centred, one column either side.
    let l = Label::fit("Hi", 13, 1);
    assert_eq!(
        art(&l, 13),
        [
            ".#...#...#...",
            ".#...#.......",
            ".#...#..##...",
            ".#####...#...",
            ".#...#...#...",
            ".#...#...#...",
            ".#...#..###..",
            ".............",
        ]
    );
    // Scale 2 doubles every pixel.
    let big = Label::fit("Hi", 26, 2);
    let small = art(&l, 13);
    let doubled: Vec<String> = small
        .iter()
        .flat_map(|r| {
            let d: String = r.chars().flat_map(|c| [c, c]).collect();
            [d.clone(), d]
        })
        .collect();
    assert_eq!(art(&big, 26), doubled);
}

#[test]
fn long_text_ends_with_an_ellipsis_inside_the_box() {
    // A box of 32 pixels holds 5 glyphs (5 × 6 − 1 = 29 pixels within a margin of 1).
    assert_eq!(Label::fit("abcde", 32, 1).glyphs().len(), 5);
    let cut = Label::fit("abcdefgh", 32, 1);
    assert_eq!(cut, Label::fit("abcd…", 32, 1));
    assert!((0..8).all(|y| !cut.ink(0, y) && !cut.ink(31, y)));
    // Other characters show as `?`; every glyph differs from every other.
    assert_eq!(Label::fit("é", 32, 1), Label::fit("?", 32, 1));
    for (a, ga) in GLYPHS.iter().enumerate() {
        for (b, gb) in GLYPHS.iter().enumerate().skip(a + 1) {
            assert_ne!(ga, gb, "glyphs {a} and {b}");
        }
    }
    // A box too narrow for one glyph draws nothing.
    assert!(Label::fit("abc", 4, 1).glyphs().is_empty());
}
