//! `patchwork bench --flythrough`: the recorded camera path through the LOD frame loop; a CSV,
//! a plot and the summary. Exit code 1 when a frame had crack pixels.
//!
//! `patchwork bench --scale [FILE...]`: teapot grids from 10³ to 10⁶ patches and the files
//! given, each point measured by `drive::scale::run_point` in a child process of this binary
//! (the hidden `scale-point` command), so each point's resident peak is its own; a Markdown
//! table, and a CSV with `--csv`. Exit code 1 when a point failed. `--scale --shard I/N`
//! measures only the points of that shard (ids `grid#N`, `file#PATH`, assigned as
//! `check`'s cases are: `crate::shard`) and writes them for `patchwork merge`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use clap::Args;
use serde_json::json;

use patchwork::drive::flythrough::{FlythroughOptions, run as run_flythrough};
use patchwork::drive::scale::{
    DEFAULT_GRID_SIZES, ScaleOptions, ScalePoint, Source, run_point, sizes_within,
};
use patchwork::io::png;
use patchwork::lod::LodOptions;
use patchwork::render::Renderer;
use patchwork::report::flythrough::{TargetSummary, frames_csv, jump_table, plot};
use patchwork::report::scale as scale_report;
use patchwork::strips::Join;
use patchwork::view;

use super::{load_built, progress};
use crate::args::{
    BudgetArgs, PrimitivesArg, at_least, fov_y, lod_options, parse_size, pixel_error, positive_ms,
};
use crate::error::CliError;
use crate::out::{self, data, note};
use crate::shard;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Model file (.bpt, .step, .stp, .glb, .gltf, .obj, .ply, .stl): one for `--flythrough`,
    /// any number (after the grids) for `--scale`.
    files: Vec<PathBuf>,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    /// Run the fly-through: orbit, zoom in close, a sudden jump, then still.
    #[arg(long)]
    flythrough: bool,
    /// Run the scale sweep: N×N teapot grids (`--sizes`), then the files given.
    #[arg(long, conflicts_with = "flythrough")]
    scale: bool,
    /// `--scale`: grid sizes N (32·N² patches each).
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_GRID_SIZES)]
    sizes: Vec<usize>,
    /// `--scale`: leave out grids of more patches than this.
    #[arg(long, default_value_t = 2_000_000)]
    max_patches: usize,
    /// `--scale`: only the files, no teapot grids.
    #[arg(long)]
    no_grids: bool,
    /// Frames of the camera path (default 200 for `--flythrough`, 20 for `--scale`).
    #[arg(long)]
    frames: Option<usize>,
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
    /// `--flythrough`: orthographic views along the same path (zooming shrinks the image's
    /// height).
    #[arg(long, conflicts_with = "scale")]
    ortho: bool,
    /// Skip the per-frame crack measurement (it renders a reference; not timed either way).
    #[arg(long)]
    no_cracks: bool,
    /// Tessellate every placement of a part on its own (no sharing between instances; for
    /// comparison).
    #[arg(long)]
    no_instancing: bool,
    /// Draw each placement of an instanced part with GPU geometry of its own (world-space
    /// copies; tessellations still shared) instead of its part's shared mesh (for comparison).
    #[arg(long)]
    world_copies: bool,
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

    /// `--scale`: measure one shard of the points (grids and files): `I/N` (1-based) or
    /// `auto` / `auto/N` from the batch engine's environment, as `check --shard`; the shard's
    /// rows go to --out for `patchwork merge` (stdout holds the table). Points measured on
    /// different machines compare only as far as the machines do.
    #[arg(long, value_name = "I/N|auto[/N]", value_parser = shard::parse_spec, requires = "scale")]
    shard: Option<shard::ShardSpec>,
    /// With --shard: write the shard's points (JSON) to this file (temporary name, renamed).
    #[arg(short, long, requires = "shard")]
    out: Option<PathBuf>,
    /// Per-frame CSV (`--flythrough`, default flythrough.csv); the table as CSV (`--scale`,
    /// only when given).
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Plot of error and frame time over the frames.
    #[arg(long, default_value = "flythrough.png")]
    plot: PathBuf,
}

/// Bytes as MiB with the exact count.
fn mib(bytes: f64) -> String {
    format!("{:.2} MiB ({bytes:.0} bytes)", bytes / (1024.0 * 1024.0))
}

/// Whether every measured frame was crack-free (`--flythrough`) or every point was measured
/// (`--scale`).
pub fn run(args: &BenchArgs) -> Result<bool, CliError> {
    if args.scale {
        return run_scale(args);
    }
    if !args.flythrough {
        return Err(CliError::NoBenchmark);
    }
    let [file] = args.files.as_slice() else {
        return Err(CliError::FlythroughFiles(args.files.len()));
    };
    let fov_y = fov_y(args.fov)?;
    let pixel_error = pixel_error(args.pixel_error)?;
    let frames = at_least("--frames", args.frames.unwrap_or(200), 2)?;
    let budget = args.budget.validate()?;
    let target = args
        .target_ms
        .map(|t| positive_ms("--target-ms", t))
        .transpose()?;
    let scene = load_built(file, &args.cache)?;
    let mut renderer = Renderer::new()?;
    renderer.static_arcs = !args.upload_cuts;
    renderer.instances = !args.world_copies;
    renderer.primitives = args.primitives.primitives;
    if let Some(join) = args.strip_joins {
        renderer.strip_join = join;
    }
    note!("adapter: {}", renderer.gpu().describe());
    let opts = FlythroughOptions {
        frames,
        size: args.size,
        fov_y,
        ortho: args.ortho,
        lod: LodOptions {
            instancing: !args.no_instancing,
            ..lod_options(pixel_error, budget)
        },
        target,
        cracks: !args.no_cracks,
    };
    let pb = progress(frames, "frames");
    let (records, summary) = run_flythrough(&mut renderer, &scene, &opts, |_| pb.inc(1))?;
    pb.finish_and_clear();
    let csv = args
        .csv
        .clone()
        .unwrap_or_else(|| PathBuf::from("flythrough.csv"));
    png::write_text(&csv, &frames_csv(&records))?;
    png::write_rgba(
        &args.plot,
        &plot(&records, args.budget.budget_ms, summary.jump_frame),
    )?;
    let crack_free = summary.max_crack_pixels.is_none_or(|m| m == 0);
    let target = args
        .target_ms
        .and_then(|t| TargetSummary::of(&records).map(|s| (t, s)));
    out::emit(&json!({
        "file": file.display().to_string(),
        "patches": scene.patches.len(),
        "frames": records.len(),
        "size": [args.size.0, args.size.1],
        "budget_ms": args.budget.budget_ms,
        "pixel_error": pixel_error,
        "initial_tessellation_ms": summary.initial_ms,
        "initial_upload_ms": summary.initial_upload_ms,
        "initial_upload_bytes": summary.initial_upload_bytes,
        "frame_ms": { "p50": summary.p50_frame_ms, "p99": summary.p99_frame_ms },
        "cpu_ms": { "p50": summary.p50_cpu_ms, "p99": summary.p99_cpu_ms },
        "uploaded_bytes": {
            "mean": summary.mean_uploaded_bytes,
            "max": summary.max_uploaded_bytes,
        },
        "tessellation_ms_p99": summary.p99_tessellation_ms,
        "jump_frame": summary.jump_frame,
        "converge_ms": summary.converge_ms,
        "converge_frames": summary.converge_frames,
        "target": target.map(|(t, s)| json!({
            "target_ms": t,
            "mean_ms": s.mean_ms,
            "tail_mean_ms": s.tail_mean_ms,
            "tail_pixel_error": s.tail_pixel_error,
        })),
        "instancing": {
            "shared_patches": summary.instancing.shared_patches,
            "made": summary.instancing.made,
            "saved": summary.instancing.saved,
            "shared_meshes": summary.shared_meshes,
            "placed_patches": summary.placed_patches,
        },
        "resident_bytes": summary.resident_bytes,
        "lod_memory": {
            "state": summary.lod_memory.state,
            "current": summary.lod_memory.current,
            "cached": summary.lod_memory.cached,
            "shared": summary.lod_memory.shared,
            "cached_budgeted": summary.cached_bytes,
            "cache_budget": opts.lod.cache_bytes,
            "evicted": summary.evicted,
        },
        "crack_pixels": {
            "total": summary.total_crack_pixels,
            "max": summary.max_crack_pixels,
        },
        "crack_free": crack_free,
        "csv": csv.display().to_string(),
        "plot": args.plot.display().to_string(),
    }));
    data!(
        "fly-through of {} ({} patches), {} frames at {}x{}, budget {} ms, pixel error {}{}",
        file.display(),
        scene.patches.len(),
        records.len(),
        args.size.0,
        args.size.1,
        args.budget.budget_ms,
        pixel_error,
        args.target_ms
            .map_or(String::new(), |t| format!(", frame-rate target {t} ms"))
    );
    data!("initial tessellation      {:.1} ms", summary.initial_ms);
    data!(
        "initial upload            {:.1} ms, {}",
        summary.initial_upload_ms,
        mib(summary.initial_upload_bytes as f64)
    );
    data!(
        "frame time                p50 {:.2} ms, p99 {:.2} ms",
        summary.p50_frame_ms,
        summary.p99_frame_ms
    );
    data!(
        "CPU time per frame        p50 {:.2} ms, p99 {:.2} ms (frame less the GPU wait)",
        summary.p50_cpu_ms,
        summary.p99_cpu_ms
    );
    data!(
        "uploaded per frame        mean {}, max {}",
        mib(summary.mean_uploaded_bytes),
        mib(summary.max_uploaded_bytes as f64)
    );
    data!(
        "re-tessellation per frame p99 {:.2} ms (budget {} ms)",
        summary.p99_tessellation_ms,
        args.budget.budget_ms
    );
    match (summary.converge_ms, summary.converge_frames) {
        (Some(ms), Some(f)) => data!(
            "after the jump (frame {}) every visible patch is within the pixel error in {:.0} ms ({f} frames)",
            summary.jump_frame,
            ms
        ),
        _ => data!(
            "after the jump (frame {}) the visible patches never got within the pixel error",
            summary.jump_frame
        ),
    }
    data!(
        "from the jump, per frame (waiting: trimmed faces queued and left; ms/face: worker time per tessellation made; redone: made before at that level and dropped; reused: trimmed faces whose tessellation held the wanted level)"
    );
    for line in jump_table(&records, summary.jump_frame, 16).lines() {
        data!("  {line}");
    }
    if let Some((t, s)) = target {
        data!(
            "frame-rate target         {t} ms: achieved mean {:.2} ms (second half {:.2} ms at pixel error {:.2} on average)",
            s.mean_ms,
            s.tail_mean_ms,
            s.tail_pixel_error
        );
    }
    let inst = summary.instancing;
    if inst.shared_patches > 0 {
        data!(
            "instanced parts           {} of {} patches share a surface with another placement: {} tessellations made for them, {} saved",
            inst.shared_patches,
            scene.patches.len(),
            inst.made,
            inst.saved
        );
        data!(
            "instanced on the GPU      {} patches drawn as placements of {} shared meshes; resident geometry {}",
            summary.placed_patches,
            summary.shared_meshes,
            mib(summary.resident_bytes as f64)
        );
    }
    let m = summary.lod_memory;
    data!(
        "frame loop memory         {} (state {}, current {}, cached {}, shared {}); cached levels as budgeted {} of {}, {} evicted",
        mib(m.total() as f64),
        mib(m.state as f64),
        mib(m.current as f64),
        mib(m.cached as f64),
        mib(m.shared as f64),
        mib(summary.cached_bytes as f64),
        mib(opts.lod.cache_bytes as f64),
        summary.evicted
    );
    if let (Some(max), Some(total)) = (summary.max_crack_pixels, summary.total_crack_pixels) {
        data!("crack pixels              {total} in all, at most {max} in a frame");
    }
    data!("wrote {} and {}", csv.display(), args.plot.display());
    Ok(crack_free)
}

/// The id of a `bench --scale` point: `grid#N` for an N×N teapot grid, `file#PATH` (as given).
pub fn scale_case_id(source: &Source) -> String {
    match source {
        Source::Grid(n) => format!("grid#{n}"),
        Source::File(f) => format!("file#{}", f.display()),
    }
}

/// The line above the table (what every point was measured with).
pub fn scale_heading(frames: usize, size: (u32, u32), pixel_error: f64, budget_ms: f64) -> String {
    format!(
        "scale sweep: {frames} frames per point at {}x{}, pixel error {pixel_error}, budget {budget_ms} ms; each point in its own process",
        size.0, size.1
    )
}

/// `--scale`: every point (of the shard, with `--shard`) in a child process (`scale-point`),
/// then the table.
fn run_scale(args: &BenchArgs) -> Result<bool, CliError> {
    fov_y(args.fov)?;
    pixel_error(args.pixel_error)?;
    args.budget.validate()?;
    let frames = at_least("--frames", args.frames.unwrap_or(20), 2)?;
    let mut sources: Vec<Source> = Vec::new();
    if !args.no_grids {
        sources.extend(
            sizes_within(&args.sizes, args.max_patches)
                .into_iter()
                .map(Source::Grid),
        );
    }
    sources.extend(args.files.iter().cloned().map(Source::File));
    let all: Vec<String> = sources.iter().map(scale_case_id).collect();
    let shard = match args.shard {
        Some(spec) => {
            let (shard, from) = shard::resolve(spec, |v| std::env::var(v).ok())?;
            if let Some(variable) = from {
                note!("shard {shard} (from {variable})");
            }
            Some(shard)
        }
        None => None,
    };
    let mine: Vec<&Source> = sources
        .iter()
        .zip(&all)
        .filter(|(_, id)| shard.is_none_or(|s| shard::shard_of(id, s.total) == s.index))
        .map(|(source, _)| source)
        .collect();
    if let Some(shard) = shard {
        data!("shard {shard}: {} of {} points", mine.len(), all.len());
    }
    let exe = std::env::current_exe().map_err(|source| CliError::Io {
        path: PathBuf::from("patchwork"),
        source,
    })?;
    let work_dir = std::env::temp_dir().join(format!("patchwork-scale-{}", std::process::id()));
    std::fs::create_dir_all(&work_dir).map_err(|source| CliError::CreateDir {
        path: work_dir.clone(),
        source,
    })?;
    let pb = progress(mine.len(), "points");
    pb.enable_steady_tick(std::time::Duration::from_millis(500));
    let mut points = Vec::new();
    let mut cases = Vec::new();
    let mut failed = 0;
    for source in mine {
        pb.set_message(source.label());
        let point = measure_in_child(&exe, source, args, frames, &work_dir);
        pb.inc(1);
        let id = scale_case_id(source);
        match point {
            Ok(p) => {
                let row = scale_report::csv_row(&p);
                pb.suspend(|| note!("{row}"));
                cases.push(json!({ "id": id, "row": row }));
                points.push(p);
            }
            Err(e) => {
                pb.suspend(|| eprintln!("error: {e}"));
                cases.push(json!({ "id": id, "error": e.to_string() }));
                failed += 1;
            }
        }
    }
    pb.finish_and_clear();
    let _ = std::fs::remove_dir_all(&work_dir);
    data!(
        "{}",
        scale_heading(frames, args.size, args.pixel_error, args.budget.budget_ms)
    );
    crate::out::write(format_args!("{}", scale_report::markdown(&points)));
    if let Some(csv) = &args.csv {
        png::write_text(csv, &scale_report::csv(&points))?;
        data!("wrote {}", csv.display());
    }
    if let Some(shard) = shard {
        let value = json!({
            "format": shard::FORMAT,
            "shard": { "index": shard.index, "total": shard.total },
            "run": {
                "command": "bench-scale",
                "cases": all,
                "frames": frames,
                "size": [args.size.0, args.size.1],
                "pixel_error": args.pixel_error,
                "budget_ms": args.budget.budget_ms,
                "options": { "fov": args.fov },
            },
            "cases_total": all.len(),
            "cases_fingerprint": shard::fingerprint(all.iter().map(String::as_str)),
            "cases": cases,
        });
        if let Some(path) = &args.out {
            png::write_text(path, &format!("{value}\n"))?;
            note!("wrote {}", path.display());
        }
    }
    Ok(failed == 0)
}

/// Runs `scale-point` for `source` in a child process and reads its row back.
fn measure_in_child(
    exe: &Path,
    source: &Source,
    args: &BenchArgs,
    frames: usize,
    work_dir: &Path,
) -> Result<ScalePoint, CliError> {
    let mut cmd = Command::new(exe);
    cmd.arg("scale-point");
    match source {
        Source::Grid(n) => cmd.arg("--grid").arg(n.to_string()),
        Source::File(f) => cmd.arg("--file").arg(f),
    };
    cmd.arg("--frames")
        .arg(frames.to_string())
        .arg("--pixel-error")
        .arg(args.pixel_error.to_string())
        .arg("--size")
        .arg(format!("{}x{}", args.size.0, args.size.1))
        .arg("--fov")
        .arg(args.fov.to_string())
        .arg("--budget-ms")
        .arg(args.budget.budget_ms.to_string())
        .arg("--cache-mib")
        .arg(args.budget.cache_mib.to_string())
        .arg("--work-dir")
        .arg(work_dir)
        .stdin(Stdio::null())
        .stderr(Stdio::inherit());
    let failed = |reason: String| CliError::ScalePoint {
        point: source.label(),
        reason,
    };
    let out = cmd
        .output()
        .map_err(|e| failed(format!("cannot start {}: {e}", exe.display())))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let row = stdout
        .lines()
        .find_map(|l| l.strip_prefix(POINT_PREFIX))
        .ok_or_else(|| failed(format!("the child process gave no row ({})", out.status)))?;
    scale_report::parse_row(row).map_err(failed)
}

/// The line a `scale-point` child answers on.
const POINT_PREFIX: &str = "scale-point: ";

/// The hidden `scale-point` command: one point of `bench --scale`, measured in this process.
#[derive(Args, Debug)]
pub struct ScalePointArgs {
    /// An N×N teapot grid ...
    #[arg(long, conflicts_with = "file", required_unless_present = "file")]
    grid: Option<usize>,
    /// ... or a model file.
    #[arg(long)]
    file: Option<PathBuf>,
    #[arg(long, default_value_t = 20)]
    frames: usize,
    #[arg(long, default_value_t = view::DEFAULT_PIXEL_ERROR)]
    pixel_error: f64,
    #[arg(long, default_value = "1024x768", value_parser = parse_size)]
    size: (u32, u32),
    #[arg(long, default_value_t = view::DEFAULT_FOV_Y_DEG)]
    fov: f64,
    #[command(flatten)]
    budget: BudgetArgs,
    /// Where a grid's file is written.
    #[arg(long, default_value = ".")]
    work_dir: PathBuf,
}

/// Measures the point and prints its row on stdout (after [`POINT_PREFIX`]).
pub fn run_scale_point(args: &ScalePointArgs) -> Result<(), CliError> {
    let source = match (&args.file, args.grid) {
        (Some(f), _) => Source::File(f.clone()),
        (None, n) => Source::Grid(at_least("--grid", n.unwrap_or(0), 1)?),
    };
    let opts = ScaleOptions {
        frames: at_least("--frames", args.frames, 2)?,
        size: args.size,
        fov_y: fov_y(args.fov)?,
        lod: lod_options(pixel_error(args.pixel_error)?, args.budget.validate()?),
        work_dir: args.work_dir.clone(),
    };
    let mut renderer = Renderer::new()?;
    let run = run_point(&mut renderer, &source, &opts, |_| {})?;
    crate::out::outln!("{POINT_PREFIX}{}", scale_report::csv_row(&run.point));
    Ok(())
}
