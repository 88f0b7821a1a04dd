//! Times building the MT hierarchies of a mesh's patches (one thread, for profiling):
//! `cargo run --release --example mt_build -- models/bunny.glb`.
fn main() {
    let path = std::env::args().nth(1).unwrap_or("models/bunny.glb".into());
    let mut mesh = patchwork::io::mesh::read_gltf(std::path::Path::new(&path)).expect("loads");
    mesh.weld();
    let mut parts = patchwork::prep::partition(&mesh, patchwork::prep::DEFAULT_PATCH_TRIANGLES);
    let t = std::time::Instant::now();
    for p in parts.iter_mut() {
        p.build_hierarchy(0.0);
    }
    let build = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    for p in parts.iter_mut() {
        p.hierarchy.reduce(patchwork::mt::DEFAULT_ARC_SIZE);
    }
    let reduce = t.elapsed().as_secs_f64();
    println!(
        "{} triangles: build {build:.2} s ({:.0} k triangles/s, one thread), reduce to {} per arc {reduce:.2} s",
        mesh.triangles.len(),
        mesh.triangles.len() as f64 / build / 1e3,
        patchwork::mt::DEFAULT_ARC_SIZE
    );
}
