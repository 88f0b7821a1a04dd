//! Diagnoses the crack pixels of one random view of `patchwork check`: for every crack pixel,
//! the patches covering it (id and depth) in the drawn tessellation and in the reference, and
//! the tolerance and measured error of both meshes of the patch in front. A reference patch
//! whose error exceeds its tolerance reports cracks that are not there.
//!
//! `cargo run --release --example crack_probe -- FILE SEED VIEW [stress] [WxH]` (512×384,
//! 0.5 px, fat borders 6; `stress`: the crack check's stress tessellation).

use patchwork::check::crack::{
    SENTINEL, check_render_options, classify, random_view, reference_meshes,
};
use patchwork::render::{FatBorders, RenderOptions, Renderer};
use patchwork::tessellate::{PatchMesh, tessellate_scene};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [file, seed, index, rest @ ..] = args.as_slice() else {
        return Err("usage: crack_probe FILE SEED VIEW [stress] [WxH]".into());
    };
    let stress = rest.iter().any(|a| a == "stress");
    let size = match rest.iter().find_map(|a| a.split_once('x')) {
        Some((w, h)) => (w.parse()?, h.parse()?),
        None => (512, 384),
    };
    let scene = patchwork::prep::load(std::path::Path::new(file))?;
    let view = random_view(
        &scene,
        seed.parse()?,
        index.parse()?,
        size,
        45f64.to_radians(),
    );
    let pixel_error = 0.5;
    let mut renderer = Renderer::new()?;
    let drawn = check_render_options(FatBorders::Six);
    let plain = RenderOptions {
        fat_borders: FatBorders::Off,
        ..drawn
    };
    let (reference, _) = reference_meshes(&scene, &view, pixel_error);
    let meshes = if stress {
        patchwork::check::stress::stress_tessellation(&scene, &view, pixel_error)
    } else {
        tessellate_scene(&scene, &view, pixel_error)
    };
    let ref_frame = renderer.render(&renderer.upload(&reference), &view, &plain)?;
    let frame = renderer.render(&renderer.upload(&meshes), &view, &drawn)?;
    let (counts, mask) = classify(&ref_frame, &frame, &view, pixel_error, SENTINEL)?;
    println!("{counts:?}");
    let cracks: Vec<usize> = mask
        .enumerate_pixels()
        .filter(|(_, _, p)| p.0[0] == 255 && p.0[2] == 0)
        .map(|(x, y, _)| (y * size.0 + x) as usize)
        .collect();
    // Depth of every patch alone at the crack pixels.
    let mut hits = vec![(Vec::new(), Vec::new()); cracks.len()];
    for (m, r) in meshes.iter().zip(&reference) {
        let one = renderer.render(&renderer.upload(std::slice::from_ref(m)), &view, &drawn)?;
        let one_ref = renderer.render(&renderer.upload(std::slice::from_ref(r)), &view, &plain)?;
        for (k, &i) in cracks.iter().enumerate() {
            let (drawn_hits, ref_hits) = &mut hits[k];
            for (frame, list) in [(&one, drawn_hits), (&one_ref, ref_hits)] {
                let d = frame.depth.as_ref().map_or(f32::INFINITY, |d| d[i]);
                if d.is_finite() {
                    list.push((m.patch_id, d));
                }
            }
        }
    }
    let depth =
        |f: &patchwork::render::Frame, i: usize| f.depth.as_ref().map_or(f32::NAN, |d| d[i]);
    let describe = |m: &PatchMesh| {
        format!(
            "ε {:.4}, error {:.4}, {} triangles",
            m.eps_target,
            m.error,
            m.triangles.len()
        )
    };
    for (k, &i) in cracks.iter().enumerate() {
        let (x, y) = (i % size.0 as usize, i / size.0 as usize);
        println!(
            "({x},{y}): drawn depth {:.4}, reference depth {:.4}, pixel {:.4}",
            depth(&frame, i),
            depth(&ref_frame, i),
            view.pixel_size_at(depth(&ref_frame, i) as f64)
        );
        for dy in -2i64..=2 {
            let row: Vec<String> = (-2i64..=2)
                .map(|dx| {
                    let j = (y as i64 + dy) as usize * size.0 as usize + (x as i64 + dx) as usize;
                    format!("{:.4}/{:.4}", depth(&ref_frame, j), depth(&frame, j))
                })
                .collect();
            println!("    {}", row.join("  "));
        }
        println!(
            "  drawn hits {:?}\n  reference hits {:?}",
            hits[k].0, hits[k].1
        );
        // Border polylines near the pixel: distance (px) of the pixel centre to each patch's
        // projected border, its ε in pixels there and the border's turn at the nearest vertex.
        let c = (x as f64 + 0.5, y as f64 + 0.5);
        for m in &meshes {
            let mut best = (f64::INFINITY, 0.0, 0.0);
            for ring in &m.borders {
                let n = ring.len();
                for j in 0..n {
                    let at = |o: usize| m.positions[ring[(j + o) % n] as usize].as_dvec3();
                    let (Some(a), Some(b)) = (view.project(at(0)), view.project(at(1))) else {
                        continue;
                    };
                    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
                    let l2 = (dx * dx + dy * dy).max(1e-12);
                    let t = (((c.0 - a.0) * dx + (c.1 - a.1) * dy) / l2).clamp(0.0, 1.0);
                    let d = ((a.0 + t * dx - c.0).powi(2) + (a.1 + t * dy - c.1).powi(2)).sqrt();
                    if d < best.0 {
                        let (s0, s1) =
                            ((at(0) - at(n - 1)).normalize(), (at(1) - at(0)).normalize());
                        let turn = s0.dot(s1).clamp(-1.0, 1.0).acos().to_degrees();
                        best = (d, m.eps_border() / view.pixel_size_at(a.2), turn);
                    }
                }
            }
            if best.0 < 1.0 {
                // The CPU twin of this patch's 6-vertex fat border: does a triangle cover c?
                let g = patchwork::render::BorderGeometry::of(std::slice::from_ref(m));
                let viewer = view.viewer().as_vec4();
                let mut inside = 0;
                for tri in g.triangles(patchwork::render::FatBorders::Six, viewer) {
                    let q: Vec<(f64, f64)> = tri
                        .iter()
                        .filter_map(|p| view.project(p.as_dvec3()))
                        .map(|p| (p.0, p.1))
                        .collect();
                    let near = q.iter().any(|p| (p.0 - c.0).hypot(p.1 - c.1) < 0.7);
                    if near && q.len() == 3 {
                        println!("      tri {q:.3?}");
                    }
                    if q.len() == 3 {
                        let side = |a: (f64, f64), b: (f64, f64)| {
                            (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
                        };
                        let s = [side(q[0], q[1]), side(q[1], q[2]), side(q[2], q[0])];
                        if s.iter().all(|v| *v >= 0.0) || s.iter().all(|v| *v <= 0.0) {
                            inside += 1;
                            println!("    covered by fat-border triangle {q:?}");
                        }
                    }
                }
                println!(
                    "    {inside} fat-border triangles of patch {} cover it",
                    m.patch_id
                );
                for ring in &m.borders {
                    for (j, &v) in ring.iter().enumerate() {
                        let p = view.project(m.positions[v as usize].as_dvec3());
                        if let Some(p) = p
                            && (p.0 - c.0).abs() < 2.0
                            && (p.1 - c.1).abs() < 2.0
                        {
                            println!(
                                "      ring vertex {j} (#{v}) at ({:.3}, {:.3}) depth {:.4}",
                                p.0, p.1, p.2
                            );
                        }
                    }
                }
            }
            if best.0 < 3.0 {
                println!(
                    "  patch {} border {:.3} px away, ε {:.3} px, turn {:.0}° at its vertex",
                    m.patch_id, best.0, best.1, best.2
                );
            }
        }
        if let Some(&(id, _)) = hits[k].1.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
            let find = |ms: &[PatchMesh]| ms.iter().find(|m| m.patch_id == id).map(describe);
            println!(
                "  patch {id}: drawn {:?}; reference {:?}",
                find(&meshes),
                find(&reference)
            );
        }
    }
    Ok(())
}
