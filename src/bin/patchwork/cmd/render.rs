//! `patchwork render`: one view of a model to a PNG (and optionally its depth).

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use serde_json::json;

use patchwork::check::golden::{FlipScore, flip_score, sibling};
use patchwork::io::depth::DepthRange;
use patchwork::io::png;
use patchwork::render::{Primitives, RenderOptions, Renderer};
use patchwork::tessellate::{MeshStats, tessellate_scene};

use super::report_failures;
use crate::args::{CameraArgs, DrawArgs};
use crate::error::CliError;
use crate::out::{self, data, note};

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Model files (.bpt, .step, .stp, .iges, .glb, .gltf, .obj, .ply, .stl; `-` reads stdin,
    /// with --format); several are drawn as one scene, each file a top-level part.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    #[command(flatten)]
    parts: crate::args::PartArgs,
    /// Output PNG.
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    camera: CameraArgs,
    #[command(flatten)]
    draw: DrawArgs,
    #[command(flatten)]
    section: crate::args::SectionArgs,
    /// Also write linear view-space depth as a 16-bit PNG (0 = near plane, 65535 = far plane).
    #[arg(long)]
    depth_out: Option<PathBuf>,
    /// Compare the image with this reference PNG (FLIP, as the golden tests do): exit 1 when
    /// the mean FLIP error is above --ref-threshold, writing the FLIP map next to the output
    /// (`NAME-diff.png`). A missing reference is an error: copy a checked image there.
    #[arg(long = "ref", value_name = "IMG")]
    reference: Option<PathBuf>,
    /// Largest mean FLIP error (0 = identical, 1 = opposite) accepted with --ref.
    #[arg(long, default_value_t = 0.02, requires = "reference")]
    ref_threshold: f64,
}

/// Renders; `Ok(false)` when the image differs from `--ref` by more than the threshold.
pub fn run(args: &RenderArgs) -> Result<bool, CliError> {
    if !(args.ref_threshold.is_finite() && (0.0..=1.0).contains(&args.ref_threshold)) {
        return Err(CliError::OutOfRange {
            flag: "--ref-threshold",
            value: args.ref_threshold,
            range: "from 0 to 1 (mean FLIP error)",
        });
    }
    let sections = args.section.validate()?;
    // Read the reference first: a missing or unreadable one fails before any work.
    let reference = args.reference.as_deref().map(read_reference).transpose()?;
    // A mesh is drawn from its cached hierarchies, or else at full resolution (error 0):
    // building them would take longer than the image (`stats`, `check`, `bench` and `view`
    // fill the cache).
    let file = &super::shown(&args.files);
    let loaded = super::load_all(
        &args.files,
        &args
            .cache
            .options(patchwork::prep::Hierarchies::CachedOrOriginal),
    )?;
    if loaded.pending.is_some() {
        note!(
            "{}: no cached hierarchies: drawn at full resolution",
            file.display()
        );
    }
    let scene = args.parts.apply(loaded.scene, file)?;
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
    note!("adapter: {}", renderer.gpu().describe());
    let gpu = renderer.upload(&meshes);
    let opts = RenderOptions {
        sections,
        ..args.draw.options()
    };
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
    let image = frame.to_rgba_image();
    let comparison = match (&reference, &args.reference) {
        (Some(r), Some(path)) => Some(compare(path, r, &image, args)?),
        _ => None,
    };
    png::write_rgba(&args.output, &image)?;
    if let Some((depth_path, img)) = depth_image {
        png::write_gray16(depth_path, &img)?;
    }
    let s = MeshStats::of(&meshes);
    let (tess_ms, render_ms) = (t_tess.as_secs_f64() * 1e3, t_render.as_secs_f64() * 1e3);
    let passed = comparison.as_ref().is_none_or(|c| c.passed);
    out::emit(&json!({
        "output": args.output.display().to_string(),
        "depth": args.depth_out.as_ref().map(|p| p.display().to_string()),
        "size": [view.width, view.height],
        "patches": s.patches,
        "triangles": s.triangles,
        "border_vertices": s.border_vertices,
        "tessellation_ms": tess_ms,
        "render_ms": render_ms,
        "adapter": renderer.gpu().describe(),
        "reference": comparison.as_ref().map(|c| json!({
            "path": c.reference.display().to_string(),
            "flip_mean": c.score.mean,
            "flip_p99": c.score.p99,
            "flip_max": c.score.max,
            "threshold": args.ref_threshold,
            "passed": c.passed,
            "diff": c.diff.as_ref().map(|p| p.display().to_string()),
        })),
    }));
    data!(
        "{}: {} patches, {} triangles, {} border vertices; tessellation {tess_ms:.1} ms, render \
         {render_ms:.1} ms",
        args.output.display(),
        s.patches,
        s.triangles,
        s.border_vertices,
    );
    if let Some(c) = &comparison {
        data!(
            "{}: FLIP mean {:.4} (threshold {}), p99 {:.4}, max {:.4}: {}{}",
            c.reference.display(),
            c.score.mean,
            args.ref_threshold,
            c.score.p99,
            c.score.max,
            if c.passed { "same" } else { "DIFFERENT" },
            c.diff
                .as_ref()
                .map_or(String::new(), |d| format!("; wrote {}", d.display()))
        );
    }
    Ok(passed)
}

/// The outcome of `--ref`.
struct RefComparison {
    reference: PathBuf,
    score: FlipScore,
    passed: bool,
    /// The FLIP map, written when the images differ.
    diff: Option<PathBuf>,
}

fn read_reference(path: &Path) -> Result<image::RgbaImage, CliError> {
    Ok(image::open(path)
        .map_err(|e| CliError::Reference {
            path: path.to_owned(),
            reason: e.to_string(),
        })?
        .to_rgba8())
}

/// FLIP of `image` against the reference; the map is written beside the output when they
/// differ (a stale one from an earlier failure is removed when they match).
fn compare(
    path: &Path,
    reference: &image::RgbaImage,
    image: &image::RgbaImage,
    args: &RenderArgs,
) -> Result<RefComparison, CliError> {
    if reference.dimensions() != image.dimensions() {
        return Err(CliError::Reference {
            path: path.to_owned(),
            reason: format!(
                "it is {:?} pixels, the image {:?} (use --size)",
                reference.dimensions(),
                image.dimensions()
            ),
        });
    }
    let (score, map) = flip_score(reference, image);
    let passed = f64::from(score.mean) <= args.ref_threshold;
    let diff_path = sibling(&args.output, "diff");
    let diff = if passed {
        let _ = std::fs::remove_file(&diff_path);
        None
    } else {
        png::write_rgba(&diff_path, &map)?;
        Some(diff_path)
    };
    Ok(RefComparison {
        reference: path.to_owned(),
        score,
        passed,
        diff,
    })
}
