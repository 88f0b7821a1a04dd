//! The IGES 5.3 reader: sections, directory, parameters and the face conversion. Any bytes
//! give a model or a `LoadError`, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = patchwork::io::iges::read(data, std::path::Path::new("fuzz.iges"));
});
