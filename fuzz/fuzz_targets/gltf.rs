//! The glTF / GLB reader (relative buffer URIs point into a folder that does not exist).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("/nonexistent-patchwork-fuzz/fuzz.gltf");
    if let Ok(mesh) = patchwork::io::mesh::parse_gltf(data, path) {
        let _ = patchwork::io::mesh::check_drawable(path, &mesh);
    }
});
