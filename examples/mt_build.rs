//! Build and reduction time of the bunny's patch hierarchies, one thread and on rayon:
//! `cargo run --release --example mt_build [model] [--one]` (default `models/bunny.glb`;
//! `--one`: one thread only). Prints fingerprints of the built and reduced hierarchies (equal
//! fingerprints: identical hierarchies), the triangles their cuts draw at a few errors, and the
//! one-thread phase's CPU time beside its wall time (the machine may be shared).

use std::time::Instant;

use patchwork::model::mesh::MeshPatch;
use patchwork::mt::{DEFAULT_ARC_SIZE, MtHierarchy};
use rayon::prelude::*;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let one_thread_only = args.iter().any(|a| a == "--one");
    let path = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .cloned()
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/models/bunny.glb").to_string());
    let patchwork::io::Model::Mesh(mut mesh) =
        patchwork::io::read(std::path::Path::new(&path)).expect("the model loads")
    else {
        panic!("{path} is not a triangle mesh");
    };
    let t = Instant::now();
    mesh.weld();
    let weld = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let parts: Vec<MeshPatch> =
        patchwork::prep::partition(&mesh, patchwork::prep::DEFAULT_PATCH_TRIANGLES);
    println!(
        "weld {:.3} s, partition {:.3} s",
        weld,
        t.elapsed().as_secs_f64()
    );
    let n: usize = parts.iter().map(|p| p.triangles.len()).sum();
    let cpu0 = thread_cpu_seconds();
    let t = Instant::now();
    let built: Vec<MtHierarchy> = parts
        .iter()
        .map(|p| MtHierarchy::build(&p.positions, &p.triangles))
        .collect();
    let build = t.elapsed().as_secs_f64();
    let built_hash = fingerprint(&built);
    let built_drawn = drawn_at(&built, &parts);
    let t = Instant::now();
    let reduced: Vec<MtHierarchy> = built
        .into_iter()
        .map(|mut h| {
            h.reduce(DEFAULT_ARC_SIZE);
            h
        })
        .collect();
    let reduce = t.elapsed().as_secs_f64();
    let cpu = thread_cpu_seconds().map(|c| c - cpu0.unwrap_or(0.0));
    let nodes: usize = reduced.iter().map(|h| h.node_count()).sum();
    let drawn = drawn_at(&reduced, &parts);
    println!(
        "hierarchy fingerprints: built {:016x}, reduced {:016x}; triangles drawn (ε/diagonal): {} \
         (built, unreduced: {})",
        built_hash,
        fingerprint(&reduced),
        drawn.join(", "),
        built_drawn.join(", ")
    );
    println!(
        "{path}: {n} triangles, {} patches, {nodes} nodes after reduction\n\
         one thread: build {build:.3} s, reduce {reduce:.3} s ({:.0} k triangles/s); CPU {}",
        parts.len(),
        n as f64 / (build + reduce) / 1e3,
        cpu.map_or("unknown".into(), |c| format!(
            "{c:.3} s ({:.0} k triangles/s)",
            n as f64 / c / 1e3
        )),
    );
    if one_thread_only {
        return;
    }
    let t = Instant::now();
    let mut par = parts.clone();
    par.par_iter_mut()
        .for_each(|p| p.build_hierarchy(DEFAULT_ARC_SIZE));
    let both = t.elapsed().as_secs_f64();
    println!(
        "rayon ({} threads): build + reduce {:.3} s ({:.0} k triangles/s)",
        rayon::current_num_threads(),
        both,
        n as f64 / both / 1e3
    );
}

/// What the hierarchies are worth: triangles drawn at a few errors (fractions of the model's
/// bounding-box diagonal).
fn drawn_at(hs: &[MtHierarchy], parts: &[MeshPatch]) -> Vec<String> {
    let (lo, hi) = patchwork::model::bounding_box(
        parts
            .iter()
            .flat_map(|p| p.positions.iter().map(|v| v.as_dvec3())),
    )
    .unwrap_or_default();
    let diagonal = lo.distance(hi);
    let mut cut = Vec::new();
    [1e-4, 1e-3, 5e-3, 1e-2, 2e-2]
        .iter()
        .map(|&f| {
            let n: usize = hs
                .iter()
                .map(|h| {
                    h.cut(f * diagonal, &mut cut);
                    cut.len()
                })
                .sum();
            format!("{n} at {f:e}")
        })
        .collect()
}

/// A hash of the hierarchies' stored fields (as the cache writes them): equal fingerprints,
/// identical hierarchies.
fn fingerprint(hs: &[MtHierarchy]) -> u64 {
    let refs: Vec<&MtHierarchy> = hs.iter().collect();
    let bytes = patchwork::io::mt_cache::encode(patchwork::io::mt_cache::CacheKey([0, 0]), &refs);
    patchwork::util::hash128(&bytes)[0]
}

/// CPU time of the calling thread (Linux: `/proc/thread-self/schedstat`), which a busy machine
/// inflates less than wall time.
fn thread_cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}
