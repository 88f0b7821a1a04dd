//! The whole STEP reader: scanner, structure, truck's entity table and the geometry
//! conversion of every face.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = patchwork::io::step::read(data, std::path::Path::new("fuzz.step"));
});
