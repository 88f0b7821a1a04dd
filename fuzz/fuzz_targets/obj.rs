//! The OBJ reader and the drawable check.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("fuzz.obj");
    if let Ok(mesh) = patchwork::io::mesh::parse_obj(data, path) {
        let _ = patchwork::io::mesh::check_drawable(path, &mesh);
    }
});
