//! Unit tests of the command line's source snippets (`src/bin/vstructc/cli/snippet.rs`).

use crate::snippet::*;
use std::sync::Arc;

#[test]
fn window_marks_the_column_and_cuts_long_lines() {
    let (s, r) = window("abc def", 5, 3);
    assert_eq!((s.as_str(), r), ("abc def", 4..7));
    let (s, r) = window("abc", 4, 1);
    assert_eq!((s.as_str(), r), ("abc", 3..3));
    let (s, r) = window("\t\tx = 1", 3, 1);
    assert_eq!((s.as_str(), r), ("        x = 1", 8..9));
    let long = "x".repeat(10 * LINE_CONTEXT);
    let (s, r) = window(&long, 5 * LINE_CONTEXT as u32, 1);
    assert!(s.chars().count() <= 2 * LINE_CONTEXT + 3);
    assert!(s.starts_with('…') && s.ends_with('…'));
    assert_eq!(&s[r], "x");
}

#[test]
fn lines_are_found_without_their_line_ending() {
    let s = Source::new(Arc::from("a\r\nb\n"));
    assert_eq!(s.line(1), Some("a"));
    assert_eq!(s.line(2), Some("b"));
    assert_eq!(s.line(3), Some(""));
    assert_eq!(s.line(4), None);
    assert_eq!(s.line(0), None);
    assert_eq!(Source::new(Arc::from("x")).line(1), Some("x"));
}

#[test]
fn auto_colours_a_terminal_unless_no_color_is_set() {
    use std::ffi::OsStr;
    let auto = ColorChoice::Auto;
    assert!(auto.colours(None, true));
    assert!(auto.colours(Some(OsStr::new("")), true));
    assert!(!auto.colours(Some(OsStr::new("1")), true));
    assert!(!auto.colours(None, false));
    assert!(ColorChoice::Always.colours(Some(OsStr::new("1")), false));
    assert!(!ColorChoice::Never.colours(None, true));
}

#[test]
fn escapes_are_removed() {
    assert_eq!(without_escapes("\x1b[1m\x1b[94m|\x1b[0m"), "|");
}
