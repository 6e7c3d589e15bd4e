//! The RIB reader on arbitrary bytes, with the embedded definitions supplying types; a
//! network that reads is written back, which must not fail either.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::sync::LazyLock;
use vstructc::Diagnostics;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::registry::Registry;

static REGISTRY: LazyLock<Registry> = LazyLock::new(Registry::embedded);

fuzz_target!(|data: &[u8]| {
    let mut diags = Diagnostics::new();
    let registry: &Registry = &REGISTRY;
    if let Ok(net) = parse_rib(
        data,
        "fuzz.rib",
        registry,
        &RibOptions::default(),
        &mut diags,
    ) {
        let _ = write_rib_to_vec(data, &net, registry);
    }
});
