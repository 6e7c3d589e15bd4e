//! Unit tests of `resolve::check` (`src/resolve/check.rs`).

use vstructc::resolve::check::*;

#[test]
fn element_names_count_as_their_array() {
    assert_eq!(without_index("colors[2]"), Some("colors"));
    assert_eq!(without_index("colors[]"), None);
    assert_eq!(without_index("colors[x]"), None);
    assert_eq!(without_index("colors"), None);
}
