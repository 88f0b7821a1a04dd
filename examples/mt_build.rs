//! Build and reduction time of the bunny's patch hierarchies, one thread and on rayon:
//! `cargo run --release --example mt_build [model] [--one]` (default `models/bunny.glb`;
//! `--one`: one thread only).

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
    let t = Instant::now();
    let built: Vec<MtHierarchy> = parts
        .iter()
        .map(|p| MtHierarchy::build(&p.positions, &p.triangles))
        .collect();
    let build = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let nodes: usize = built
        .into_iter()
        .map(|mut h| {
            h.reduce(DEFAULT_ARC_SIZE);
            h.node_count()
        })
        .sum();
    let reduce = t.elapsed().as_secs_f64();
    println!(
        "{path}: {n} triangles, {} patches, {nodes} nodes after reduction\n\
         one thread: build {build:.3} s, reduce {reduce:.3} s ({:.0} k triangles/s)",
        parts.len(),
        n as f64 / (build + reduce) / 1e3,
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
