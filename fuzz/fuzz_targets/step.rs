//! The whole STEP reader: scanner, structure, truck's entity table and the geometry
//! conversion of every face.
//!
//! With `PATCHWORK_FUZZ_LAST=FILE` each input is written to FILE before it runs, so a crash
//! libFuzzer cannot record (a stack overflow under `-s none`) still leaves its input behind.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Some(last) = std::env::var_os("PATCHWORK_FUZZ_LAST") {
        let _ = std::fs::write(last, data);
    }
    let _ = patchwork::io::step::read(data, std::path::Path::new("fuzz.step"));
});
