//! Where a mesh's triangles go (issue 30, item 1): `cargo run --release --example
//! mt_breakdown [model] [--rel 5e-3,1e-2,2e-2]` (default `models/bunny.glb`). For every
//! error (a fraction of the bounding-box diagonal) it prints the triangles the patch
//! hierarchies' cuts draw, split into those with a corner on a patch border loop (the outer
//! border between patches), on a seam (a border inside the patch: vertices split by their
//! normals or UVs, an edge used once there), and interior ones; the same for the hierarchies
//! before arc collapse (`reduce`), for one hierarchy of the whole mesh (no patches), so
//! the cost of the partition, of the seams and of the reduction can be read apart, and for
//! the patches with their coarse groups as loading makes them (`prep::groups`: the units an
//! export at that tolerance draws).

use std::collections::HashSet;

use patchwork::model::PatchSurface;
use patchwork::model::mesh::{MeshPatch, border_loops};
use patchwork::mt::group::Unit;
use patchwork::mt::{DEFAULT_ARC_SIZE, MAX_MERGE_ERROR_RATIO, MtHierarchy};
use rayon::prelude::*;

#[derive(Default, Clone, Copy)]
struct Count {
    triangles: usize,
    on_border: usize,
    on_seam: usize,
    vertices: usize,
    border_vertices: usize,
    seam_vertices: usize,
}

/// The vertices on an edge used once (the loops of `model::mesh::border_loops`), and those of
/// them on the patch's own border loops (`borders`).
fn classify(triangles: &[[u32; 3]], borders: &[Vec<u32>]) -> (HashSet<u32>, HashSet<u32>) {
    let open = border_loops(triangles).into_iter().flatten().collect();
    let border = borders.iter().flatten().copied().collect();
    (open, border)
}

fn count(h: &MtHierarchy, open: &HashSet<u32>, border: &HashSet<u32>, eps: f64) -> Count {
    let mut cut = Vec::new();
    h.cut(eps, &mut cut);
    let mut c = Count {
        triangles: cut.len(),
        ..Count::default()
    };
    let mut alive = HashSet::new();
    for t in &cut {
        if t.iter().any(|v| border.contains(v)) {
            c.on_border += 1;
        } else if t.iter().any(|v| open.contains(v)) {
            c.on_seam += 1;
        }
        alive.extend(t.iter().copied());
    }
    c.vertices = alive.len();
    c.border_vertices = alive.iter().filter(|v| border.contains(v)).count();
    c.seam_vertices = alive
        .iter()
        .filter(|v| open.contains(v) && !border.contains(v))
        .count();
    c
}

fn add(a: Count, b: Count) -> Count {
    Count {
        triangles: a.triangles + b.triangles,
        on_border: a.on_border + b.on_border,
        on_seam: a.on_seam + b.on_seam,
        vertices: a.vertices + b.vertices,
        border_vertices: a.border_vertices + b.border_vertices,
        seam_vertices: a.seam_vertices + b.seam_vertices,
    }
}

fn show(label: &str, c: Count) {
    println!(
        "  {label:<28} {:>7} triangles: {:>6} at a border, {:>6} at a seam, {:>6} interior; \
         vertices {:>6} ({} border, {} seam)",
        c.triangles,
        c.on_border,
        c.on_seam,
        c.triangles - c.on_border - c.on_seam,
        c.vertices,
        c.border_vertices,
        c.seam_vertices
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let rels: Vec<f64> = args
        .iter()
        .position(|a| a == "--rel")
        .and_then(|i| args.get(i + 1))
        .map(|s| s.split(',').filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_else(|| vec![5e-3, 1e-2, 2e-2]);
    let path = args
        .iter()
        .enumerate()
        .find(|(i, a)| !a.starts_with("--") && (*i == 0 || args[i - 1] != "--rel"))
        .map(|(_, a)| a.clone())
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/models/bunny.glb").to_string());
    let patchwork::io::Model::Mesh(mut mesh) =
        patchwork::io::read(std::path::Path::new(&path)).expect("the model loads")
    else {
        panic!("{path} is not a triangle mesh");
    };
    mesh.weld();
    let parts: Vec<MeshPatch> =
        patchwork::prep::partition(&mesh, patchwork::prep::DEFAULT_PATCH_TRIANGLES);
    let classes: Vec<(HashSet<u32>, HashSet<u32>)> = parts
        .iter()
        .map(|p| classify(&p.triangles, &p.borders))
        .collect();
    let built: Vec<MtHierarchy> = parts
        .par_iter()
        .map(|p| MtHierarchy::build(&p.positions, &p.triangles))
        .collect();
    let reduced: Vec<MtHierarchy> = built
        .par_iter()
        .map(|h| {
            let mut h = h.clone();
            h.reduce_within(DEFAULT_ARC_SIZE, MAX_MERGE_ERROR_RATIO);
            h
        })
        .collect();
    let whole = MtHierarchy::build(&mesh.positions, &mesh.triangles);
    // The scene as loading makes it: patches and their coarse groups (`prep::groups`).
    let grouped = patchwork::prep::mesh_scene(
        mesh.clone(),
        patchwork::prep::DEFAULT_PATCH_TRIANGLES,
        DEFAULT_ARC_SIZE,
        patchwork::model::UpAxis::Y,
        true,
        &patchwork::prep::NoProgress,
    );
    let whole_class = classify(&mesh.triangles, &[]);
    let (lo, hi) = patchwork::model::bounding_box(mesh.positions.iter().map(|v| v.as_dvec3()))
        .unwrap_or_default();
    let diagonal = lo.distance(hi);
    let (open, border): (usize, usize) = classes
        .iter()
        .map(|(o, b)| (o.len(), b.len()))
        .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    println!(
        "{path}: {} triangles, {} vertices, {} patches; patch vertices on an \
         open edge {open}, of them on border loops {border}; whole mesh: {} vertices on an \
         open edge (seams)",
        mesh.triangles.len(),
        mesh.positions.len(),
        parts.len(),
        whole_class.0.len()
    );
    for rel in rels {
        let eps = rel * diagonal;
        println!("eps = {rel:e} x diagonal = {eps:.4e}");
        let sum = |hs: &[MtHierarchy]| {
            hs.iter()
                .zip(&classes)
                .map(|(h, (o, b))| count(h, o, b, eps))
                .fold(Count::default(), add)
        };
        show("patches, reduced", sum(&reduced));
        let arcs: usize = reduced.iter().map(|h| h.arc_count()).sum();
        let tris: usize = reduced.iter().map(|h| h.triangles.len()).sum();
        println!(
            "  (reduced: {arcs} arcs, {:.2} triangles per arc)",
            tris as f64 / arcs as f64
        );
        show("patches, built (no reduce)", sum(&built));
        let units = grouped.mesh_units(&mut |_| eps);
        let mut cut = Vec::new();
        let (mut tris, mut groups) = (0, [0usize; 3]);
        for &u in &units {
            let h = match u {
                Unit::Patch(p) => match &grouped.patches[p as usize].surface {
                    PatchSurface::Mesh(m) => &m.hierarchy,
                    _ => continue,
                },
                Unit::Group(g) => {
                    let g = &grouped.mesh_groups[g as usize];
                    groups[(g.level as usize).min(2)] += 1;
                    &g.patch.hierarchy
                }
            };
            h.cut(eps, &mut cut);
            tris += cut.len();
        }
        println!(
            "  {:<28} {tris:>7} triangles: {} units drawn ({} patches, {} level-1 groups, {} \
             level-2 groups)",
            "patches + groups",
            units.len(),
            units.len() - groups[1] - groups[2],
            groups[1],
            groups[2]
        );
        show(
            "whole mesh, one hierarchy",
            count(&whole, &whole_class.0, &whole_class.1, eps),
        );
    }
}
