//! `patchwork bench --flythrough`: the recorded camera path through the LOD frame loop; a CSV,
//! a plot and the summary. Exit code 1 when a frame had crack pixels.

use std::path::PathBuf;

use clap::Args;

use patchwork::drive::flythrough::{FlythroughOptions, run as run_flythrough};
use patchwork::io::png;
use patchwork::render::Renderer;
use patchwork::report::flythrough::{TargetSummary, frames_csv, plot};
use patchwork::strips::Join;
use patchwork::view;

use super::{load_built, progress};
use crate::args::{
    BudgetArgs, PrimitivesArg, at_least, fov_y, lod_options, parse_size, pixel_error, positive_ms,
};
use crate::error::CliError;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Model file (.bpt, .step, .stp, .glb, .gltf, .obj, .ply).
    file: PathBuf,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    /// Run the fly-through: orbit, zoom in close, a sudden jump, then still.
    #[arg(long)]
    flythrough: bool,
    /// Frames of the camera path.
    #[arg(long, default_value_t = 200)]
    frames: usize,
    #[command(flatten)]
    budget: BudgetArgs,
    /// Frame-rate target mode: choose the pixel error per frame to fit this frame time (ms).
    #[arg(long)]
    target_ms: Option<f64>,
    /// Pixel error asked for (the finest one in frame-rate target mode).
    #[arg(long, default_value_t = view::DEFAULT_PIXEL_ERROR)]
    pixel_error: f64,
    /// Image size.
    #[arg(long, default_value = "1024x768", value_parser = parse_size)]
    size: (u32, u32),
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = view::DEFAULT_FOV_Y_DEG)]
    fov: f64,
    /// Skip the per-frame crack measurement (it renders a reference; not timed either way).
    #[arg(long)]
    no_cracks: bool,
    /// Mesh patches: upload every new cut's triangles instead of drawing index ranges of
    /// static per-patch buffers (for comparison).
    #[arg(long)]
    upload_cuts: bool,
    #[command(flatten)]
    primitives: PrimitivesArg,
    /// How strips are joined: `restart` (primitive restart) or `degenerate` (zero-area
    /// windows); default: restart, degenerate on wgpu's GL backend.
    #[arg(long)]
    strip_joins: Option<Join>,

    /// Per-frame CSV.
    #[arg(long, default_value = "flythrough.csv")]
    csv: PathBuf,
    /// Plot of error and frame time over the frames.
    #[arg(long, default_value = "flythrough.png")]
    plot: PathBuf,
}

/// Whether every measured frame was crack-free.
pub fn run(args: &BenchArgs) -> Result<bool, CliError> {
    if !args.flythrough {
        return Err(CliError::NoBenchmark);
    }
    let fov_y = fov_y(args.fov)?;
    let pixel_error = pixel_error(args.pixel_error)?;
    let frames = at_least("--frames", args.frames, 2)?;
    let budget = args.budget.validate()?;
    let target = args
        .target_ms
        .map(|t| positive_ms("--target-ms", t))
        .transpose()?;
    let scene = load_built(&args.file, &args.cache)?;
    let mut renderer = Renderer::new()?;
    renderer.static_arcs = !args.upload_cuts;
    renderer.primitives = args.primitives.primitives;
    if let Some(join) = args.strip_joins {
        renderer.strip_join = join;
    }
    eprintln!("adapter: {}", renderer.gpu().describe());
    let opts = FlythroughOptions {
        frames,
        size: args.size,
        fov_y,
        lod: lod_options(pixel_error, budget),
        target,
        cracks: !args.no_cracks,
    };
    let pb = progress(frames, "frames");
    let (records, summary) = run_flythrough(&mut renderer, &scene, &opts, |_| pb.inc(1))?;
    pb.finish_and_clear();
    png::write_text(&args.csv, &frames_csv(&records))?;
    png::write_rgba(
        &args.plot,
        &plot(&records, args.budget.budget_ms, summary.jump_frame),
    )?;
    println!(
        "fly-through of {} ({} patches), {} frames at {}x{}, budget {} ms, pixel error {}{}",
        args.file.display(),
        scene.patches.len(),
        records.len(),
        args.size.0,
        args.size.1,
        args.budget.budget_ms,
        pixel_error,
        args.target_ms
            .map_or(String::new(), |t| format!(", frame-rate target {t} ms"))
    );
    println!("initial tessellation      {:.1} ms", summary.initial_ms);
    println!(
        "initial upload            {:.1} ms",
        summary.initial_upload_ms
    );
    println!(
        "frame time                p50 {:.2} ms, p99 {:.2} ms",
        summary.p50_frame_ms, summary.p99_frame_ms
    );
    println!(
        "re-tessellation per frame p99 {:.2} ms (budget {} ms)",
        summary.p99_tessellation_ms, args.budget.budget_ms
    );
    match (summary.converge_ms, summary.converge_frames) {
        (Some(ms), Some(f)) => println!(
            "after the jump (frame {}) every visible patch is within the pixel error in {:.0} ms ({f} frames)",
            summary.jump_frame, ms
        ),
        _ => println!(
            "after the jump (frame {}) the visible patches never got within the pixel error",
            summary.jump_frame
        ),
    }
    if let (Some(t), Some(s)) = (args.target_ms, TargetSummary::of(&records)) {
        println!(
            "frame-rate target         {t} ms: achieved mean {:.2} ms (second half {:.2} ms at pixel error {:.2} on average)",
            s.mean_ms, s.tail_mean_ms, s.tail_pixel_error
        );
    }
    let crack_free = summary.max_crack_pixels.is_none_or(|m| m == 0);
    if let (Some(max), Some(total)) = (summary.max_crack_pixels, summary.total_crack_pixels) {
        println!("crack pixels              {total} in all, at most {max} in a frame");
    }
    println!("wrote {} and {}", args.csv.display(), args.plot.display());
    Ok(crack_free)
}
