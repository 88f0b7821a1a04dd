//! Build speed of the MT hierarchies (issue 30 item 4):
//! `cargo bench --bench mt_build [-- [--rounds N] FILE...]` (default `models/bunny.glb`,
//! `alien.glb`, `cakeBirthday.glb` and a generated bumpy torus of 48 000 triangles). For each
//! mesh, welded and partitioned as the loader does, it times build + reduce of every patch's
//! hierarchy (`MeshPatch::build_hierarchy`, what loading runs) on rayon and on one thread, best
//! of `--rounds` (default 3), in triangles per second, and beside it meshopt 0.7's one-level
//! `simplify` of the whole mesh to half its triangles in the same run, so the ratio can be
//! read. It also prints the triangles the reduced cuts draw at 0.5, 1 and 2 % of the
//! bounding-box diagonal (what the speed must not cost), the thread CPU time of the one-thread
//! run (less inflated than wall time on a shared machine) and a fingerprint of the hierarchies
//! (equal: identical hierarchies, so an exact speed-up shows as such). Writes `mt_build.md` in
//! the target directory.

use std::fmt::Write as _;
use std::time::Instant;

use patchwork::model::mesh::{MeshPatch, TriMesh};
use patchwork::mt::DEFAULT_ARC_SIZE;
use rayon::prelude::*;

/// Each timing is the best of this many runs.
const ROUNDS: usize = 3;

/// Errors (fractions of the diagonal) at which the cuts' triangles are counted.
const RELATIVE_ERRORS: [f64; 3] = [5e-3, 1e-2, 2e-2];

fn main() {
    // `--rounds N`: timings are the best of N runs; other `--` flags (cargo bench's `--bench`)
    // are ignored.
    let (mut files, mut rounds) = (Vec::new(), ROUNDS);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--rounds" {
            rounds = args.next().and_then(|n| n.parse().ok()).unwrap_or(ROUNDS);
        } else if !a.starts_with("--") {
            files.push(a);
        }
    }
    let default = files.is_empty();
    if default {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/models");
        files = vec![
            format!("{dir}/bunny.glb"),
            format!("{dir}/alien.glb"),
            format!("{dir}/cakeBirthday.glb"),
        ];
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "MT build + reduce (arc size {DEFAULT_ARC_SIZE}), best of {rounds}; rayon on {} threads\n\n\
         | mesh | triangles | patches | rayon s | rayon M tri/s | one thread s | one thread M tri/s | one thread CPU s | meshopt simplify M tri/s | triangles at 0.5 / 1 / 2 % diag | fingerprint |\n\
         |---|---|---|---|---|---|---|---|---|---|---|",
        rayon::current_num_threads()
    );
    let mut meshes: Vec<(String, TriMesh)> = files
        .iter()
        .map(|path| {
            let patchwork::io::Model::Mesh(mesh) =
                patchwork::io::read(std::path::Path::new(path)).expect("the model loads")
            else {
                panic!("{path} is not a triangle mesh");
            };
            let name = std::path::Path::new(path)
                .file_name()
                .map_or(path.clone(), |f| f.to_string_lossy().into_owned());
            (name, mesh)
        })
        .collect();
    if default {
        meshes.push(("bumpy torus (generated)".into(), bumpy_torus(240, 100)));
    }
    for (name, mut mesh) in meshes {
        mesh.weld();
        let parts: Vec<MeshPatch> =
            patchwork::prep::partition(&mesh, patchwork::prep::DEFAULT_PATCH_TRIANGLES);
        let n: usize = parts.iter().map(|p| p.triangles.len()).sum();
        let mut rayon_s = f64::INFINITY;
        let mut built = Vec::new();
        for _ in 0..rounds {
            let mut par = parts.clone();
            let t = Instant::now();
            par.par_iter_mut()
                .for_each(|p| p.build_hierarchy(DEFAULT_ARC_SIZE));
            rayon_s = rayon_s.min(t.elapsed().as_secs_f64());
            built = par;
        }
        let (mut one_s, mut one_cpu) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..rounds {
            let mut seq = parts.clone();
            let cpu = thread_cpu_seconds();
            let t = Instant::now();
            seq.iter_mut()
                .for_each(|p| p.build_hierarchy(DEFAULT_ARC_SIZE));
            one_s = one_s.min(t.elapsed().as_secs_f64());
            if let (Some(a), Some(b)) = (cpu, thread_cpu_seconds()) {
                one_cpu = one_cpu.min(b - a);
            }
        }
        // meshopt: one level, the whole mesh to half its triangles.
        let bytes: &[u8] = bytemuck::cast_slice(&mesh.positions);
        let adapter = meshopt::VertexDataAdapter::new(bytes, 12, 0).expect("positions");
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let mut meshopt_s = f64::INFINITY;
        for _ in 0..rounds {
            let t = Instant::now();
            let s = meshopt::simplify(
                &indices,
                &adapter,
                indices.len() / 2,
                1.0,
                meshopt::SimplifyOptions::None,
                None,
            );
            meshopt_s = meshopt_s.min(t.elapsed().as_secs_f64());
            assert!(!s.is_empty());
        }
        let (lo, hi) = patchwork::model::bounding_box(
            parts
                .iter()
                .flat_map(|p| p.positions.iter().map(|v| v.as_dvec3())),
        )
        .unwrap_or_default();
        let diagonal = lo.distance(hi);
        let mut cut = Vec::new();
        let drawn: Vec<String> = RELATIVE_ERRORS
            .iter()
            .map(|&f| {
                built
                    .iter()
                    .map(|p| {
                        p.hierarchy.cut(f * diagonal, &mut cut);
                        cut.len()
                    })
                    .sum::<usize>()
                    .to_string()
            })
            .collect();
        let _ = writeln!(
            out,
            "| {name} | {n} | {} | {rayon_s:.3} | {:.3} | {one_s:.3} | {:.3} | {} | {:.2} | {} | {:016x} |",
            parts.len(),
            n as f64 / rayon_s / 1e6,
            n as f64 / one_s / 1e6,
            if one_cpu.is_finite() {
                format!("{one_cpu:.3}")
            } else {
                "unknown".into()
            },
            mesh.triangles.len() as f64 / meshopt_s / 1e6,
            drawn.join(" / "),
            fingerprint(&built),
        );
        eprint!(".");
    }
    eprintln!();
    println!("{out}");
    let dir = std::env::var_os("CARGO_TARGET_DIR").map_or_else(
        || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target"),
        std::path::PathBuf::from,
    );
    let target = dir.join("mt_build.md");
    if let Err(e) = std::fs::write(&target, &out) {
        eprintln!("could not write {}: {e}", target.display());
    }
}

/// A torus (radii 1 and 0.35) with bumps on its tube, `u` × `v` quads split in two: a
/// second, curved closed mesh of a size between the bunny's and the small glTF files'.
fn bumpy_torus(u: u32, v: u32) -> TriMesh {
    use std::f32::consts::TAU;
    let mut positions = Vec::new();
    for i in 0..u {
        for j in 0..v {
            let (a, b) = (TAU * i as f32 / u as f32, TAU * j as f32 / v as f32);
            let r = 0.35 * (1.0 + 0.15 * (7.0 * a).sin() * (5.0 * b).sin());
            let ring = 1.0 + r * b.cos();
            positions.push(glam::Vec3::new(ring * a.cos(), ring * a.sin(), r * b.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % u) * v + (j % v);
    let mut triangles = Vec::new();
    for i in 0..u {
        for j in 0..v {
            let (p, q, r, s) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.push([p, q, r]);
            triangles.push([p, r, s]);
        }
    }
    TriMesh {
        positions,
        triangles,
        ..TriMesh::default()
    }
}

/// A hash of the hierarchies as the cache writes them: equal fingerprints, identical
/// hierarchies (a speed-up that keeps them is exact).
fn fingerprint(parts: &[MeshPatch]) -> u64 {
    let refs: Vec<&patchwork::mt::MtHierarchy> = parts.iter().map(|p| &p.hierarchy).collect();
    let bytes = patchwork::io::mt_cache::encode(patchwork::io::mt_cache::CacheKey([0, 0]), &refs);
    patchwork::util::hash128(&bytes)[0]
}

/// CPU time of the calling thread (Linux: `/proc/thread-self/schedstat`).
fn thread_cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}
