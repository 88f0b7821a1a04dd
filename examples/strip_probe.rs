//! Quick look at tunneling strips on the whole bunny vs meshopt (the full table is
//! `cargo bench --bench strips`). `cargo run --release --example strip_probe [max_len]`.
use std::time::Instant;

use patchwork::strips::{decode, same_triangles, tunnel};

fn main() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/bunny.glb");
    let mut m = patchwork::io::mesh::read_gltf(&path).expect("bunny loads");
    m.weld();
    let max_len: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(75);
    for greedy in [true, false] {
        let opts = tunnel::TunnelOptions {
            max_len,
            greedy_start: greedy,
            swap_aware: std::env::args().nth(2).is_none(),
            ..Default::default()
        };
        let t = Instant::now();
        let mut s = tunnel::TunnelStrips::build(&m.triangles, opts);
        let el = t.elapsed().as_secs_f64();
        let idx = s.to_indices();
        let ok = same_triangles(&decode(&idx.indices), &m.triangles);
        println!(
            "greedy {greedy}: {} tris, {} strips, {} swaps, {:.3} idx/tri, {:.2} s, tunnels {:?}, covers {ok}",
            idx.triangles,
            idx.strips,
            s.swap_count(),
            idx.indices_per_triangle(),
            el,
            s.stats
        );
    }
    let flat: Vec<u32> = m.triangles.iter().flatten().copied().collect();
    let n = m.positions.len();
    let st = meshopt::stripify(&flat, n, u32::MAX).expect("stripify");
    println!(
        "meshopt original order: {:.3} idx/tri, {} strips",
        st.len() as f64 / m.triangles.len() as f64,
        st.iter().filter(|&&i| i == u32::MAX).count() + 1
    );
    let opt = meshopt::optimize_vertex_cache_strip(&flat, n);
    let st = meshopt::stripify(&opt, n, u32::MAX).expect("stripify");
    println!(
        "meshopt after optimize_vertex_cache_strip: {:.3} idx/tri, {} strips",
        st.len() as f64 / m.triangles.len() as f64,
        st.iter().filter(|&&i| i == u32::MAX).count() + 1
    );
    let opt = meshopt::optimize_vertex_cache(&flat, n);
    let st = meshopt::stripify(&opt, n, u32::MAX).expect("stripify");
    println!(
        "meshopt after optimize_vertex_cache: {:.3} idx/tri, {} strips",
        st.len() as f64 / m.triangles.len() as f64,
        st.iter().filter(|&&i| i == u32::MAX).count() + 1
    );
}
