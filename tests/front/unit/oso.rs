//! Unit tests of `front::oso` (`src/front/oso.rs`).

use vstructc::ArraySpec;
use vstructc::front::oso::*;

#[test]
fn unescape_handles_c_escapes() {
    assert_eq!(unescape(br#"a\\\"b"#), "a\\\"b");
    assert_eq!(unescape(br"x\ny\t"), "x\ny\t");
    assert_eq!(unescape(br"\101\60"), "A0");
    assert_eq!(unescape(br"\q"), "\\q");
    assert_eq!(unescape(br"end\"), "end\\");
}

#[test]
fn array_lengths() {
    assert_eq!(array_spec("3", false), Some(ArraySpec::Fixed(3)));
    assert_eq!(array_spec("-1", false), Some(ArraySpec::Dynamic));
    assert_eq!(array_spec("0", false), None);
    assert_eq!(array_spec("2.0", true), None);
}

#[test]
fn options_split_into_pairs() {
    assert_eq!(
        parse_options("opt1:v1|opt2"),
        vec![("opt1".into(), "v1".into()), ("opt2".into(), "opt2".into())]
    );
}
