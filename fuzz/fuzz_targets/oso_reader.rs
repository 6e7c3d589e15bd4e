//! The `.oso` reader on arbitrary bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use vstructc::Diagnostics;
use vstructc::front::oso::parse_oso;

fuzz_target!(|data: &[u8]| {
    let mut diags = Diagnostics::new();
    let _ = parse_oso(data, "fuzz.oso", &mut diags);
});
