//! Every output reads back: a structure-aware fuzzed network (see `common`) is read from RIB,
//! resolved, and written as RIB and as JSON; vstructc's own readers must accept both outputs
//! (no error diagnostic), whatever values resolution stored (huge `set` constants, copies).
#![no_main]

mod common;

use common::{Net, REGISTRY};
use libfuzzer_sys::fuzz_target;
use vstructc::back::json::write_json;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::json::parse_json;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{Diagnostics, Severity};

fn read_rib(text: &[u8], registry: &Registry) -> Result<vstructc::network::Network, String> {
    let mut diags = Diagnostics::new();
    let net = parse_rib(
        text,
        "fuzz.rib",
        registry,
        &RibOptions::default(),
        &mut diags,
    )
    .map_err(|e| e.to_string())?;
    no_errors(&diags)?;
    Ok(net)
}

fn no_errors(diags: &Diagnostics) -> Result<(), String> {
    match diags.iter().find(|d| d.severity == Severity::Error) {
        Some(d) => Err(d.to_string()),
        None => Ok(()),
    }
}

fuzz_target!(|net: Net| {
    let registry: &Registry = &REGISTRY;
    let text = net.rib();
    let Ok(mut network) = read_rib(text.as_bytes(), registry) else {
        return;
    };
    let options = ResolveOptions {
        conditions: !net.no_conditions,
        ..ResolveOptions::default()
    };
    let _ = resolve(&mut network, registry, &options);

    let rib = write_rib_to_vec(text.as_bytes(), &network, registry).expect("RIB writes");
    if let Err(e) = read_rib(&rib, registry) {
        panic!(
            "written RIB does not read back: {e}\n{}",
            String::from_utf8_lossy(&rib)
        );
    }

    // A network with nodes but no material has no JSON form; the writer says so.
    let Ok(json) = write_json(&network) else {
        return;
    };
    let mut diags = Diagnostics::new();
    let back = parse_json(json.as_bytes(), "fuzz.json", registry, &mut diags);
    if let Err(e) = back
        .map_err(|e| e.to_string())
        .and_then(|_| no_errors(&diags))
    {
        panic!("written JSON does not read back: {e}\n{json}");
    }
});
