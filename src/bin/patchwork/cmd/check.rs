//! `patchwork check`: random views with fat borders off and on; crack and growth pixels per
//! view and in sum. Exit code 1 when fat borders leave a crack.

use std::path::{Path, PathBuf};

use clap::Args;
use serde_json::json;

use patchwork::check::{CheckOptions, run_check};
use patchwork::render::{FatBorders, Renderer};
use patchwork::view;

use super::{load_built, progress};
use crate::args::{PrimitivesArg, at_least, fov_y, parse_size, pixel_error};
use crate::error::CliError;
use crate::out::{data, note};

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Model files (`-` reads stdin, with --format); several: one block (one JSON object in
    /// an array) per file, exit code the worst.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    /// Number of random views.
    #[arg(long, default_value_t = 20)]
    views: usize,
    /// Seed of the random views.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Allowed screen-space error in pixels.
    #[arg(long, default_value_t = view::DEFAULT_PIXEL_ERROR)]
    pixel_error: f64,
    /// Image size of every view.
    #[arg(long, default_value = "512x384", value_parser = parse_size)]
    size: (u32, u32),
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = view::DEFAULT_FOV_Y_DEG)]
    fov: f64,
    /// Orthographic views (each as tall as the perspective view's at its target).
    #[arg(long)]
    ortho: bool,
    /// Write actual and crack-mask images of views with cracks or growth into this folder.
    #[arg(long)]
    save_failures: Option<PathBuf>,
    #[command(flatten)]
    primitives: PrimitivesArg,
    /// Stress tessellation: every border pulled back towards its patch as far as the pixel
    /// error allows, so that only fat borders of full width close the gaps.
    #[arg(long)]
    stress: bool,
    /// Also measure the fat borders drawn this much narrower (a mutation: 0.5 must crack).
    #[arg(long)]
    narrowed_width: Option<f64>,
}

/// Whether the check passed (no crack pixel with fat borders) for every file.
pub fn run(args: &CheckArgs) -> Result<bool, CliError> {
    let mut renderer = None;
    super::for_each_file(&args.files, |file| run_one(args, file, &mut renderer))
}

/// One file's check: printed as text, returned with its JSON object. The renderer is made
/// once, after the first file loads (a missing file is reported first).
fn run_one(
    args: &CheckArgs,
    file: &Path,
    renderer: &mut Option<Renderer>,
) -> Result<(bool, serde_json::Value), CliError> {
    let fov_y = fov_y(args.fov)?;
    let pixel_error = pixel_error(args.pixel_error)?;
    let views = at_least("--views", args.views, 1)?;
    let scene = load_built(file, &args.cache)?;
    let renderer = match renderer {
        Some(r) => r,
        None => {
            let mut r = Renderer::new()?;
            r.primitives = args.primitives.primitives;
            note!("adapter: {}", r.gpu().describe());
            renderer.insert(r)
        }
    };
    if let Some(dir) = &args.save_failures {
        std::fs::create_dir_all(dir).map_err(|source| CliError::Io {
            path: dir.clone(),
            source,
        })?;
    }
    let opts = CheckOptions {
        views,
        seed: args.seed,
        pixel_error,
        size: args.size,
        fov_y,
        ortho: args.ortho,
        save_failures: args.save_failures.clone(),
        stress: args.stress,
        narrowed_width: args.narrowed_width,
        ..CheckOptions::default()
    };
    let pb = progress(views, "views");
    let variants = opts.variants.clone();
    let header: Vec<String> = variants
        .iter()
        .map(|v| format!("cracks fb={:<3}", v.name()))
        .collect();
    data!(
        "{:>4}  {:>9}  {:>8}  {}  {:>10}",
        "view",
        "triangles",
        "ref grid",
        header.join("  "),
        "growth(6)"
    );
    let report = run_check(renderer, &scene, &opts, |r| {
        let cells: Vec<String> = r
            .counts
            .iter()
            .map(|(_, c)| format!("{:>13}", c.cracks()))
            .collect();
        let growth = r
            .counts
            .iter()
            .find(|(v, _)| *v == FatBorders::Six)
            .map(|(_, c)| c.growth)
            .unwrap_or(0);
        pb.suspend(|| {
            data!(
                "{:>4}  {:>9}  {:>8}  {}  {:>10}",
                r.index,
                r.stats.triangles,
                r.reference_grid,
                cells.join("  "),
                growth
            )
        });
        pb.inc(1);
    })?;
    pb.finish_and_clear();
    data!();
    data!(
        "summary over {} views at {} px pixel error, {}x{}:",
        views,
        pixel_error,
        args.size.0,
        args.size.1
    );
    for v in &variants {
        let t = report.total(*v);
        data!(
            "  fat borders {:<3}  crack pixels {:>7} (background {}, surface behind {}), growth pixels {} (max {} px out), of {} inside pixels",
            v.name(),
            t.cracks(),
            t.background,
            t.behind,
            t.growth,
            t.growth_max_px,
            t.inside
        );
    }
    if let Some(f) = args.narrowed_width {
        for v in variants.iter().filter(|v| **v != FatBorders::Off) {
            let t = report.total_narrowed(*v);
            data!(
                "  fat borders {:<3} × {f}  crack pixels {:>7} (background {}, surface behind {}), growth pixels {}",
                v.name(),
                t.cracks(),
                t.background,
                t.behind,
                t.growth
            );
        }
    }
    let ok = report.crack_free();
    let totals = |t: &patchwork::check::crack::CrackCounts| {
        json!({
            "cracks": t.cracks(),
            "background": t.background,
            "behind": t.behind,
            "growth": t.growth,
            "growth_max_px": t.growth_max_px,
            "inside": t.inside,
        })
    };
    let value = json!({
        "file": file.display().to_string(),
        "views": views,
        "pixel_error": pixel_error,
        "size": [args.size.0, args.size.1],
        "variants": variants.iter().map(|v| {
            let mut o = totals(&report.total(*v));
            o["fat_borders"] = json!(v.name());
            o
        }).collect::<Vec<_>>(),
        "narrowed": args.narrowed_width.map(|f| json!({
            "factor": f,
            "variants": variants.iter().filter(|v| **v != FatBorders::Off).map(|v| {
                let mut o = totals(&report.total_narrowed(*v));
                o["fat_borders"] = json!(v.name());
                o
            }).collect::<Vec<_>>(),
        })),
        "crack_free": ok,
    });
    data!(
        "{}",
        if ok {
            "OK: no crack pixel with fat borders"
        } else {
            "FAIL: crack pixels with fat borders"
        }
    );
    Ok((ok, value))
}
