//! Our ISO 10303-21 scanner and the product-structure analysis on what it accepts.
#![no_main]
use libfuzzer_sys::fuzz_target;
use patchwork::io::step::{p21, structure};

fuzz_target!(|data: &[u8]| {
    if let Ok(file) = p21::parse_bytes(data) {
        let _ = structure::analyse(&file);
    }
});
