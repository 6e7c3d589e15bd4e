//! Unit tests of the grouping of human diagnostics (`src/bin/vstructc/cli/group.rs`).

use crate::group::*;
use vstructc::Diagnostic;

fn on(node: &str, message: &str) -> Diagnostic {
    Diagnostic::warning("VS013", message.replace("N", node)).with_node(node)
}

#[test]
fn a_handle_is_replaced_only_as_a_whole_name() {
    assert_eq!(
        shape("m0.fuzz: set on m0", "m0"),
        "<node>.fuzz: set on <node>"
    );
    assert_eq!(
        shape("m01.fuzz and am0 and m0_x", "m0"),
        "m01.fuzz and am0 and m0_x"
    );
    assert_eq!(shape("`aa`: aaa", "aa"), "`<node>`: aaa");
    assert_eq!(shape("/M/a.inputs:x", "/M/a"), "<node>.inputs:x");
    assert_eq!(shape("é m0é m0", "m0"), "é m0é <node>");
}

#[test]
fn thousands_are_separated() {
    assert_eq!(thousands(7), "7");
    assert_eq!(thousands(2000), "2,000");
    assert_eq!(thousands(1_234_567), "1,234,567");
}

#[test]
fn one_shape_on_many_nodes_is_one_entry_naming_the_first_few() {
    let ds: Vec<Diagnostic> = (0..5)
        .map(|i| on(&format!("m{i}"), "N.tint: not set"))
        .collect();
    let refs: Vec<&Diagnostic> = ds.iter().collect();
    let entries = group(&refs);
    assert_eq!(entries.len(), 1);
    assert_eq!(entries[0].count(), 5);
    assert_eq!(
        entries[0].diagnostic().message,
        "<node>.tint: not set on 5 nodes (m0, m1, m2, …)"
    );
    // The diagnostic printed keeps the first one's node, location and code.
    assert_eq!(entries[0].diagnostic().node.as_deref(), Some("m0"));
}

#[test]
fn other_differences_keep_entries_apart() {
    let ds = [
        on("a", "N.tint: not set"),
        on("b", "N.tint: not set from b2"),
        on("c", "N.tint: not set"),
        Diagnostic::info("VS013", "a.tint: not set").with_node("d"),
        Diagnostic::warning("VS013", "no node"),
        Diagnostic::warning("VS013", "no node"),
        // The same shape twice on one node (two places in it): its own entry.
        on("a", "N.tint: not set"),
        on("e", "N.tint: not set").with_note("more"),
    ];
    let refs: Vec<&Diagnostic> = ds.iter().collect();
    let entries = group(&refs);
    let sizes: Vec<usize> = entries.iter().map(|e| e.count()).collect();
    assert_eq!(sizes, [2, 1, 1, 1, 1, 1, 1]);
    assert_eq!(
        entries[0].diagnostic().message,
        "<node>.tint: not set on 2 nodes (a, c)"
    );
    // Alone, a message is printed as it is.
    assert_eq!(entries[1].diagnostic().message, "b.tint: not set from b2");
}
