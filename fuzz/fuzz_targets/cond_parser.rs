//! The `vstructConditionalExpr` parser on arbitrary text, with and without every extension.
#![no_main]

use libfuzzer_sys::fuzz_target;
use vstructc::cond::Extensions;
use vstructc::cond::internals::parse_statement;

fuzz_target!(|text: &str| {
    let _ = parse_statement(text, &Extensions::default());
    if let Ok(all) = Extensions::from_names(&["all".to_string()]) {
        let _ = parse_statement(text, &all);
    }
});
