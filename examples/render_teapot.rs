//! The library in a few lines: load a model, frame it, tessellate every patch for the view,
//! render with fat borders and write a PNG.
//!
//! `cargo run --release --example render_teapot -- out.png`

use std::path::PathBuf;

use patchwork::render::{RenderOptions, Renderer};
use patchwork::tessellate::{MeshStats, tessellate_scene};
use patchwork::view::{DEFAULT_FOV_Y_DEG, DEFAULT_PIXEL_ERROR, View};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .map_or_else(|| PathBuf::from("teapot.png"), PathBuf::from);
    let model = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("models/teapot.bpt");
    let scene = patchwork::prep::load(&model)?;
    let view = View::framing(
        &scene.bounds,
        scene.up.vector(),
        DEFAULT_FOV_Y_DEG.to_radians(),
        (800, 600),
    );
    let meshes = tessellate_scene(&scene, &view, DEFAULT_PIXEL_ERROR);
    let stats = MeshStats::of(&meshes);
    println!(
        "{} patches, {} triangles, ε {:.2e}..{:.2e}, worst measured error {:.2} ε",
        stats.patches, stats.triangles, stats.eps_min, stats.eps_max, stats.worst_error_ratio
    );
    let mut renderer = Renderer::new()?;
    let gpu = renderer.upload(&meshes);
    let frame = renderer.render(
        &gpu,
        &view,
        &RenderOptions {
            msaa: 4,
            ..Default::default()
        },
    )?;
    patchwork::io::png::write_rgba(&out, &frame.to_rgba_image())?;
    println!("wrote {} on {}", out.display(), renderer.gpu().describe());
    Ok(())
}
