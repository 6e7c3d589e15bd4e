//! The `.args` reader on arbitrary bytes: any input gives `Ok` or a positioned error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use vstructc::Diagnostics;
use vstructc::front::args::parse_args;

fuzz_target!(|data: &[u8]| {
    let mut diags = Diagnostics::new();
    let _ = parse_args(data, "fuzz.args", "Fuzz", &mut diags);
});
