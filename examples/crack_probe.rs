//! Diagnoses the crack pixels of one random view of `patchwork check`: for every crack pixel,
//! the patches covering it (id and depth) in the drawn tessellation and in the reference, and
//! the tolerance and measured error of both meshes of the patch in front. A reference patch
//! whose error exceeds its tolerance reports cracks that are not there.
//!
//! `cargo run --release --example crack_probe -- FILE SEED VIEW` (512×384, 0.5 px, fat borders 6)

use patchwork::check::crack::{
    SENTINEL, check_render_options, classify, random_view, reference_meshes,
};
use patchwork::render::{FatBorders, RenderOptions, Renderer};
use patchwork::tessellate::{PatchMesh, tessellate_scene};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [file, seed, index] = args.as_slice() else {
        return Err("usage: crack_probe FILE SEED VIEW".into());
    };
    let scene = patchwork::io::load(std::path::Path::new(file))?;
    let size = (512, 384);
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
    let meshes = tessellate_scene(&scene, &view, pixel_error);
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
            "({x},{y}): drawn depth {:.4}, reference depth {:.4}",
            depth(&frame, i),
            depth(&ref_frame, i)
        );
        println!(
            "  drawn hits {:?}\n  reference hits {:?}",
            hits[k].0, hits[k].1
        );
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
