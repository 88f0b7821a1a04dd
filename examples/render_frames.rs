//! Renders the teapot's default view N times with one fat-border variant and MSAA setting:
//! a fixed workload for `benches/frame_callgrind.sh`, which counts instructions per frame
//! (repeatable on a shared 2-core machine, where wall-clock frame times vary by ±30 %).
//!
//! `cargo run --release --example render_frames -- 6 1 10` (variant off|6|4|2, MSAA, frames)

use std::path::Path;

use patchwork::render::{FatBorders, RenderOptions, Renderer};
use patchwork::tessellate::tessellate_scene;
use patchwork::view::{DEFAULT_FOV_Y_DEG, DEFAULT_PIXEL_ERROR, View};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [variant, msaa, frames] = args.as_slice() else {
        return Err("usage: render_frames off|6|4|2 MSAA FRAMES".into());
    };
    let variant: FatBorders = variant.parse()?;
    let msaa: u32 = msaa.parse()?;
    let frames: usize = frames.parse()?;
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/teapot.bpt");
    let scene = patchwork::prep::load(&model)?;
    let fov = DEFAULT_FOV_Y_DEG.to_radians();
    let view = View::framing(&scene.bounds, scene.up.vector(), fov, (1024, 768));
    let meshes = tessellate_scene(&scene, &view, DEFAULT_PIXEL_ERROR);
    let mut renderer = Renderer::new()?;
    let gpu = renderer.upload(&meshes);
    let opts = RenderOptions {
        fat_borders: variant,
        msaa,
        ..RenderOptions::default()
    };
    // One warm-up frame compiles the pipelines; the script subtracts runs of different length.
    renderer.render(&gpu, &view, &opts)?;
    for _ in 0..frames {
        renderer.render(&gpu, &view, &opts)?;
    }
    Ok(())
}
