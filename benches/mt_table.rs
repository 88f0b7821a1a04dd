//! Table 1 of Holst & Schumann on the bunny (144 046 triangles), and meshopt in the same run.
//!
//! `cargo bench --bench mt_table` prints (and writes `target/mt_table.md`): per arc size
//! (none, 2, 5, 10, 20 by Holst's reduction, and 5 within `MAX_MERGE_ERROR_RATIO` as loaded
//! meshes are reduced) the arcs, triangles per arc, nodes, vertex-buffer MB, build and
//! reduction time; per viewing distance (1×, 2×, 4× the framing distance) the triangles a
//! ½-pixel cut draws, the cut time and the measured two-sided Hausdorff distance of the whole
//! cut to the original, relative to the largest patch ε of the view (every patch holds its own
//! ε, so the union holds the largest); and meshopt simplifying the whole mesh to the same triangle counts
//! as the unreduced and the loaded meshes' cuts: time, measured Hausdorff distance and our ratio to it. Distances are sampled at every vertex and triangle
//! centroid of both meshes (nearest triangle through a uniform grid).

use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;
use patchwork::geom::point_triangle_distance;
use patchwork::model::{PatchSurface, UpAxis};
use patchwork::tessellate::tessellate_scene;
use patchwork::view::View;

/// Nearest-triangle queries through a uniform grid of cells.
struct Grid {
    pos: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    lo: DVec3,
    cell: f64,
    dims: [i64; 3],
    cells: Vec<Vec<u32>>,
}

impl Grid {
    fn new(pos: &[DVec3], tris: &[[u32; 3]]) -> Grid {
        let lo = pos
            .iter()
            .fold(DVec3::splat(f64::INFINITY), |a, &p| a.min(p));
        let hi = pos
            .iter()
            .fold(DVec3::splat(f64::NEG_INFINITY), |a, &p| a.max(p));
        let cell = ((hi - lo).max_element() / 64.0).max(1e-12);
        let dims = ((hi - lo) / cell).floor().as_i64vec3() + 1;
        let dims = [dims.x, dims.y, dims.z];
        let mut cells = vec![Vec::new(); (dims[0] * dims[1] * dims[2]) as usize];
        for (t, tri) in tris.iter().enumerate() {
            let [a, b, c] = tri.map(|i| pos[i as usize]);
            let (tlo, thi) = (a.min(b).min(c), a.max(b).max(c));
            let (i0, i1) = (((tlo - lo) / cell).floor(), ((thi - lo) / cell).floor());
            for x in i0.x as i64..=i1.x as i64 {
                for y in i0.y as i64..=i1.y as i64 {
                    for z in i0.z as i64..=i1.z as i64 {
                        cells[((x * dims[1] + y) * dims[2] + z) as usize].push(t as u32);
                    }
                }
            }
        }
        Grid {
            pos: pos.to_vec(),
            tris: tris.to_vec(),
            lo,
            cell,
            dims,
            cells,
        }
    }

    fn distance(&self, p: DVec3) -> f64 {
        let c = ((p - self.lo) / self.cell).floor();
        let (cx, cy, cz) = (c.x as i64, c.y as i64, c.z as i64);
        let mut best = f64::INFINITY;
        for ring in 0..self.dims.iter().copied().max().unwrap_or(1) + 1 {
            // Every point of ring k is at least (k − 1) cells away.
            if (ring as f64 - 1.0) * self.cell > best {
                break;
            }
            for x in cx - ring..=cx + ring {
                for y in cy - ring..=cy + ring {
                    for z in cz - ring..=cz + ring {
                        let on_ring = (x - cx).abs() == ring
                            || (y - cy).abs() == ring
                            || (z - cz).abs() == ring;
                        if !on_ring
                            || x < 0
                            || y < 0
                            || z < 0
                            || x >= self.dims[0]
                            || y >= self.dims[1]
                            || z >= self.dims[2]
                        {
                            continue;
                        }
                        for &t in &self.cells[((x * self.dims[1] + y) * self.dims[2] + z) as usize]
                        {
                            let [a, b, c] = self.tris[t as usize].map(|i| self.pos[i as usize]);
                            best = best.min(point_triangle_distance(p, a, b, c));
                        }
                    }
                }
            }
        }
        best
    }

    /// Largest distance from the vertices and centroids of `tris` (over `pos`) to this grid's
    /// triangles.
    fn farthest(&self, pos: &[DVec3], tris: &[[u32; 3]]) -> f64 {
        use rayon::prelude::*;
        let used: std::collections::BTreeSet<u32> = tris.iter().flatten().copied().collect();
        let corners = used
            .par_iter()
            .map(|&v| self.distance(pos[v as usize]))
            .reduce(|| 0.0, f64::max);
        let centroids = tris
            .par_iter()
            .map(|t| self.distance(t.map(|i| pos[i as usize]).iter().sum::<DVec3>() / 3.0))
            .reduce(|| 0.0, f64::max);
        corners.max(centroids)
    }
}

fn hausdorff(original: &Grid, pos: &[DVec3], orig_tris: &[[u32; 3]], tris: &[[u32; 3]]) -> f64 {
    let other = Grid::new(pos, tris);
    original
        .farthest(pos, tris)
        .max(other.farthest(pos, orig_tris))
}

fn main() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/bunny.glb");
    let mut whole = patchwork::io::mesh::read_gltf(&path).expect("bunny loads");
    whole.weld();
    let n_orig = whole.triangles.len();
    let pos: Vec<DVec3> = whole.positions.iter().map(|p| p.as_dvec3()).collect();
    let original = Grid::new(&pos, &whole.triangles);

    let t = Instant::now();
    let scene = patchwork::prep::mesh_scene(
        whole.clone(),
        patchwork::prep::DEFAULT_PATCH_TRIANGLES,
        0.0,
        UpAxis::Y,
        false,
        &patchwork::prep::NoProgress,
    );
    let build = t.elapsed().as_secs_f64();
    let fov = 45f64.to_radians();
    let base = View::framing(&scene.bounds, scene.up.vector(), fov, (1024, 768));
    let dir = base.eye - base.target;
    let views: Vec<(f64, View)> = [1.0, 2.0, 4.0]
        .into_iter()
        .map(|k| {
            let eye = base.target + dir * k;
            (
                k,
                View::new(eye, base.target, base.up, fov, (1024, 768), &scene.bounds),
            )
        })
        .collect();
    let vertices: usize = scene
        .patches
        .iter()
        .map(|p| match &p.surface {
            PatchSurface::Mesh(m) => m.positions.len(),
            _ => 0,
        })
        .sum();
    // The renderer's static vertex: position, normal (f32), patch id, colour.
    let vb_mb = vertices as f64 * 32.0 / 1e6;

    let mut out = String::new();
    out.push_str(&format!(
        "bunny.glb: {n_orig} triangles, {} patches, {vertices} patch vertices ({vb_mb:.2} MB static vertex buffers, same for every arc size: half-edge collapses create no vertex); hierarchies built in {:.2} s on {} threads ({:.0} k triangles/s)\n\n",
        scene.patches.len(),
        build,
        rayon::current_num_threads(),
        n_orig as f64 / build / 1e3
    ));
    out.push_str("Per arc size: static index buffer (every triangle of the hierarchy, once), reduction time on 2 threads. Per distance: triangles a ½-px cut draws; cut extraction over all patches from scratch (scan of every triangle) and moved from the previous frame's cut (frame coherence: the camera 5 % farther; `ranges` = index ranges drawn after merging adjacent arcs); Hausdorff of the drawn cut ÷ the largest patch ε.\n\n| arc size | arcs | triangles / arc | nodes | index MB | reduce s | distance | triangles at ½ px | of full | scratch cut ms | moved cut ms | ranges | Hausdorff / largest ε |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let mut counts_fine = Vec::new();
    // Holst's reduction at every arc size, then what loaded meshes get (`build_hierarchy`:
    // arc size 5, merging only nodes whose errors are within `MAX_MERGE_ERROR_RATIO`).
    let holst = f64::INFINITY;
    let shipped = patchwork::mt::MAX_MERGE_ERROR_RATIO;
    for (target, ratio) in [
        (None, holst),
        (Some(2.0), holst),
        (Some(5.0), holst),
        (Some(10.0), holst),
        (Some(20.0), holst),
        (Some(patchwork::mt::DEFAULT_ARC_SIZE), shipped),
    ] {
        let mut s = scene.clone();
        let t = Instant::now();
        use rayon::prelude::*;
        s.patches.par_iter_mut().for_each(|p| {
            if let (PatchSurface::Mesh(m), Some(target)) = (&mut p.surface, target) {
                let mut copy = (**m).clone();
                copy.hierarchy.reduce_within(target, ratio);
                p.surface = PatchSurface::Mesh(Arc::new(copy));
            }
        });
        let reduce = t.elapsed().as_secs_f64();
        let (mut arcs, mut tris_in_arcs, mut nodes) = (0usize, 0usize, 0usize);
        let mut hierarchies = Vec::new();
        for p in &s.patches {
            if let PatchSurface::Mesh(m) = &p.surface {
                arcs += m.hierarchy.arc_count();
                tris_in_arcs += m.hierarchy.triangles.len();
                nodes += m.hierarchy.node_count();
                hierarchies.push((m.clone(), p.bounds));
            }
        }
        let index_mb = tris_in_arcs as f64 * 12.0 / 1e6;
        for (k, view) in &views {
            // From scratch: every patch scans its triangles.
            let mut cut = Vec::new();
            let t = Instant::now();
            for (m, bounds) in &hierarchies {
                m.hierarchy.cut(view.eps_obj(bounds, 0.5), &mut cut);
            }
            let cut_ms = t.elapsed().as_secs_f64() * 1e3;
            // Moved: from the cut of a view 5 % nearer (the previous frame of a slow
            // dolly), applying only the nodes in between.
            let near = View::new(
                base.target + dir * (k / 1.05),
                base.target,
                base.up,
                fov,
                (1024, 768),
                &s.bounds,
            );
            let mut states: Vec<_> = hierarchies
                .iter()
                .map(|(m, b)| {
                    let mut st = m.hierarchy.finest_cut();
                    m.hierarchy.move_cut(&mut st, near.eps_obj(b, 0.5));
                    st
                })
                .collect();
            let mut ranges = Vec::new();
            let mut range_count = 0;
            let t = Instant::now();
            for ((m, bounds), st) in hierarchies.iter().zip(states.iter_mut()) {
                m.hierarchy.move_cut(st, view.eps_obj(bounds, 0.5));
                m.hierarchy.cut_ranges(st, &mut ranges);
                range_count += ranges.len();
            }
            let moved_ms = t.elapsed().as_secs_f64() * 1e3;
            let meshes = tessellate_scene(&s, view, 0.5);
            let drawn: Vec<[u32; 3]> = meshes
                .iter()
                .zip(&s.patches)
                .flat_map(|(m, p)| {
                    let PatchSurface::Mesh(mp) = &p.surface else {
                        unreachable!("a mesh scene")
                    };
                    m.triangles
                        .iter()
                        .map(|t| t.map(|i| mp.source_vertices[i as usize]))
                        .collect::<Vec<_>>()
                })
                .collect();
            let eps_max = meshes.iter().map(|m| m.eps_target).fold(0.0, f64::max);
            let h = hausdorff(&original, &pos, &whole.triangles, &drawn);
            if target.is_none() || ratio == shipped {
                counts_fine.push((target.is_some(), *k, drawn.len(), eps_max, h));
            }
            out.push_str(&format!(
                "| {} | {arcs} | {:.2} | {nodes} | {index_mb:.2} | {reduce:.2} | {k}× | {} | {:.1} % | {cut_ms:.1} | {moved_ms:.2} | {range_count} | {:.3} |\n",
                match target {
                    None => "none".to_string(),
                    Some(t) if ratio == shipped => format!("{t} within {ratio}× (loaded meshes)"),
                    Some(t) => t.to_string(),
                },
                tris_in_arcs as f64 / arcs as f64,
                drawn.len(),
                100.0 * drawn.len() as f64 / n_orig as f64,
                h / eps_max
            ));
            eprint!(".");
        }
    }
    // meshopt: the whole mesh to the same triangle counts.
    out.push_str("\nmeshopt 0.7 `simplify` of the whole mesh to the triangle counts of our ½-px cuts (unreduced, and as loaded meshes are reduced):\n\n| hierarchy | distance | triangles | ours: Hausdorff | meshopt ms | meshopt triangles | meshopt Hausdorff | ours ÷ meshopt | meshopt throughput |\n|---|---|---|---|---|---|---|---|---|\n");
    let bytes: &[u8] = bytemuck::cast_slice(&whole.positions);
    let adapter = meshopt::VertexDataAdapter::new(bytes, 12, 0).expect("positions");
    let indices: Vec<u32> = whole.triangles.iter().flatten().copied().collect();
    for (reduced, k, count, _eps, ours) in counts_fine {
        let t = Instant::now();
        let simplified = meshopt::simplify(
            &indices,
            &adapter,
            count * 3,
            1.0,
            meshopt::SimplifyOptions::None,
            None,
        );
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let tris: Vec<[u32; 3]> = simplified
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let h = hausdorff(&original, &pos, &whole.triangles, &tris);
        out.push_str(&format!(
            "| {} | {k}× | {count} | {ours:.3e} | {ms:.1} | {} | {h:.3e} | {:.2} | {:.2} M triangles/s |\n",
            if reduced { "as loaded" } else { "unreduced" },
            tris.len(),
            ours / h,
            n_orig as f64 / (ms / 1e3) / 1e6
        ));
    }
    eprintln!();
    println!("{out}");
    let target = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/mt_table.md");
    if let Err(e) = std::fs::write(&target, &out) {
        eprintln!("cannot write {}: {e}", target.display());
    }
}
