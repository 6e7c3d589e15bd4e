//! Unit tests of `limits` (`src/limits.rs`).

use vstructc::diag::Location;
use vstructc::limits::*;

#[test]
fn every_limit_reads_its_own_field() {
    let limits = Limits {
        definition_file_bytes: 1,
        network_file_bytes: 2,
        nodes: 3,
        connections_per_input: 4,
        params_per_node: 5,
        expr_terms: 6,
        expr_depth: 7,
        preview_pixels: 8,
    };
    let all = [
        Limit::DefinitionFileBytes,
        Limit::NetworkFileBytes,
        Limit::Nodes,
        Limit::ConnectionsPerInput,
        Limit::ParamsPerNode,
        Limit::ExprTerms,
        Limit::ExprDepth,
        Limit::PreviewPixels,
    ];
    for (k, limit) in all.into_iter().enumerate() {
        assert_eq!(limits.max(limit), k as u64 + 1, "{limit}");
        assert!(limits.check(limit, k as u64 + 1).is_ok());
        assert!(limits.check(limit, k as u64 + 2).is_err());
    }
}

#[test]
fn the_message_names_the_limit_value_and_maximum() {
    let e = Limits::default()
        .check(Limit::ExprTerms, 5_000_000)
        .unwrap_err()
        .at(Location::new("big.args", 3, 7));
    assert_eq!(
        e.to_string(),
        "5000000 terms exceed the limit expr_terms = 4194304"
    );
    let d = e.to_diagnostic();
    assert_eq!(d.code, "LM001");
    assert_eq!(d.render_human().lines().nth(1), Some("  --> big.args:3:7"));
}
