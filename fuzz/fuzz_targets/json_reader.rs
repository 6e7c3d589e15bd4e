//! The JSON network reader on arbitrary bytes, with the embedded definitions supplying types;
//! a network that reads is resolved and written back as JSON, which must read again.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::sync::LazyLock;
use vstructc::back::json::write_json;
use vstructc::front::json::parse_json;
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{Diagnostics, Severity};

static REGISTRY: LazyLock<Registry> = LazyLock::new(Registry::embedded);

fuzz_target!(|data: &[u8]| {
    let registry: &Registry = &REGISTRY;
    let mut diags = Diagnostics::new();
    let Ok(mut net) = parse_json(data, "fuzz.json", registry, &mut diags) else {
        return;
    };
    if diags.iter().any(|d| d.severity == Severity::Error) {
        return;
    }
    let _ = resolve(&mut net, registry, &ResolveOptions::default());
    // A network with nodes but no material has no JSON form; the writer says so.
    let Ok(json) = write_json(&net) else {
        return;
    };
    let mut again = Diagnostics::new();
    let back = parse_json(json.as_bytes(), "fuzz.json", registry, &mut again);
    assert!(
        back.is_ok() && again.iter().all(|d| d.severity != Severity::Error),
        "written JSON does not read back: {:?}\n{json}",
        back.err()
            .map(|e| e.to_string())
            .or_else(|| again.iter().next().map(|d| d.to_string()))
    );
});
