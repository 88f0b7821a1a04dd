//! The `.bpt` reader: any bytes give patches or a `LoadError`, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = patchwork::io::bpt::parse(data, std::path::Path::new("fuzz.bpt"));
});
