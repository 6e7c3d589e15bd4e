//! Unit tests of `cond::error` (`src/cond/error.rs`).

use vstructc::cond::internals::*;
use vstructc::diag::Location;

#[test]
fn caret_under_the_offending_column() {
    assert_eq!(
        render_caret("connect if x = 1", 13..14),
        "connect if x = 1\n             ^"
    );
    assert_eq!(render_caret("copy if", 5..7), "copy if\n     ^~");
}

#[test]
fn caret_at_end_of_input() {
    assert_eq!(render_caret("set", 3..3), "set\n   ^");
    assert_eq!(render_caret("", 0..0), "\n^");
}

#[test]
fn caret_keeps_tabs_and_escapes_controls() {
    assert_eq!(render_caret("a\tb\r", 3..4), "a\tb\\r\n \t ^~");
    assert_eq!(render_caret("x\n  y z", 4..5), "  y z\n  ^");
}

#[test]
fn caret_counts_characters_not_bytes() {
    assert_eq!(render_caret("é = 1", 3..4), "é = 1\n  ^");
}

#[test]
fn long_lines_are_cut_to_a_window_around_the_span() {
    let text = format!("{}x == 1{}", "a".repeat(10_000), "b".repeat(10_000));
    let r = render_caret(&text, 10_000..10_006);
    let (line, carets) = r.split_once('\n').unwrap();
    assert_eq!(
        line,
        format!("…{}x == 1{}…", "a".repeat(200), "b".repeat(200))
    );
    assert_eq!(carets, format!("{}^~~~~~", " ".repeat(201)));
    // A span longer than the window is marked up to the window's end.
    let r = render_caret(&text, 0..20_006);
    let (line, carets) = r.split_once('\n').unwrap();
    assert_eq!(line, format!("{}…", "a".repeat(400)));
    assert_eq!(carets, format!("^{}", "~".repeat(199)));
    // Within the window nothing changes, and a newline ends the line as before.
    let text = format!("{}\n{} y", "c".repeat(150), "d".repeat(150));
    assert_eq!(
        render_caret(&text, 302..303),
        format!("{} y\n{}^", "d".repeat(150), " ".repeat(151))
    );
}

#[test]
fn locations_map_into_the_source() {
    let start = Location::new("PxrLayer.args", 10, 30);
    let loc = location_in(&start, "connect if x = 1", 13);
    assert_eq!((loc.line, loc.column), (10, 43));
    let loc = location_in(&start, "a\nbc", 3);
    assert_eq!((loc.line, loc.column), (11, 2));
    let unknown = location_in(&Location::file("f"), "abc", 2);
    assert_eq!((unknown.line, unknown.column), (0, 0));
}
