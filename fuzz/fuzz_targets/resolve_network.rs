//! Resolution on structure-aware fuzzed networks (see `common`: up to 1,024 nodes, fan-in up
//! to 64, long conditional chains): the network is written as RIB, read back, resolved (with
//! or without conditions), and written out. Resolving the same network twice must give
//! identical bytes (determinism).
#![no_main]

mod common;

use common::{Net, REGISTRY};
use libfuzzer_sys::fuzz_target;
use vstructc::Diagnostics;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};

fn resolved(text: &[u8], options: &ResolveOptions) -> Option<Vec<u8>> {
    let registry: &Registry = &REGISTRY;
    let mut diags = Diagnostics::new();
    let mut net = parse_rib(
        text,
        "fuzz.rib",
        registry,
        &RibOptions::default(),
        &mut diags,
    )
    .ok()?;
    let _ = resolve(&mut net, registry, options);
    write_rib_to_vec(text, &net, registry).ok()
}

fuzz_target!(|net: Net| {
    let text = net.rib();
    let options = ResolveOptions {
        conditions: !net.no_conditions,
        ..ResolveOptions::default()
    };
    let first = resolved(text.as_bytes(), &options);
    let second = resolved(text.as_bytes(), &options);
    assert_eq!(first, second, "resolution is not deterministic");
});
