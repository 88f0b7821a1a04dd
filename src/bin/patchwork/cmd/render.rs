//! `patchwork render`: one view of a model to a PNG (and optionally its depth).

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use patchwork::io::depth::DepthRange;
use patchwork::io::png;
use patchwork::render::{Primitives, RenderOptions, Renderer};
use patchwork::tessellate::{MeshStats, tessellate_scene};

use super::{load, report_failures};
use crate::args::{CameraArgs, DrawArgs};
use crate::error::CliError;

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Model file (.bpt, .step, .stp, .glb, .gltf, .obj, .ply, .stl).
    file: PathBuf,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    /// Output PNG.
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    camera: CameraArgs,
    #[command(flatten)]
    draw: DrawArgs,
    /// Also write linear view-space depth as a 16-bit PNG (0 = near plane, 65535 = far plane).
    #[arg(long)]
    depth_out: Option<PathBuf>,
}

pub fn run(args: &RenderArgs) -> Result<(), CliError> {
    // A mesh is drawn from its cached hierarchies, or else at full resolution (error 0):
    // building them would take longer than the image (`stats`, `check`, `bench` and `view`
    // fill the cache).
    let loaded = load(
        &args.file,
        &args
            .cache
            .options(patchwork::prep::Hierarchies::CachedOrOriginal),
    )?;
    if loaded.pending.is_some() {
        eprintln!(
            "{}: no cached hierarchies: drawn at full resolution",
            args.file.display()
        );
    }
    let scene = loaded.scene;
    let camera = args.camera.validate()?;
    let view = camera.view(&scene)?;
    let t0 = Instant::now();
    let meshes = tessellate_scene(&scene, &view, camera.pixel_error);
    let t_tess = t0.elapsed();
    report_failures(&meshes);
    let mut renderer = Renderer::new()?;
    // One still image: strips cost more to build than they save in a single draw (bunny:
    // 0.33 s of CPU with lists, 0.7–0.84 s with multiresolution strips), so `auto` is lists.
    renderer.primitives = match args.draw.primitives.primitives {
        Primitives::Auto => Primitives::List,
        p => p,
    };
    eprintln!("adapter: {}", renderer.gpu().describe());
    let gpu = renderer.upload(&meshes);
    let opts = args.draw.options();
    let t1 = Instant::now();
    let frame = renderer.render(&gpu, &view, &opts)?;
    let t_render = t1.elapsed();
    // Render everything first, then write: a failure leaves no output at all.
    let depth_image = match &args.depth_out {
        Some(path) => {
            let d = renderer.render(
                &gpu,
                &view,
                &RenderOptions {
                    depth: true,
                    msaa: 1,
                    ..opts
                },
            )?;
            let range = DepthRange {
                near: view.near,
                far: view.far,
            };
            let depth = d.depth.unwrap_or_default();
            Some((path, range.encode(&depth, view.width, view.height)?))
        }
        None => None,
    };
    png::write_rgba(&args.output, &frame.to_rgba_image())?;
    if let Some((depth_path, img)) = depth_image {
        png::write_gray16(depth_path, &img)?;
    }
    let s = MeshStats::of(&meshes);
    eprintln!(
        "{}: {} patches, {} triangles, {} border vertices; tessellation {:.1} ms, render {:.1} ms",
        args.output.display(),
        s.patches,
        s.triangles,
        s.border_vertices,
        t_tess.as_secs_f64() * 1e3,
        t_render.as_secs_f64() * 1e3
    );
    Ok(())
}
