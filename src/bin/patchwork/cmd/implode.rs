//! `patchwork implode`: parts (or patches) flying together or apart — numbered PNGs, a GIF,
//! `frames.csv` (`patchwork::report::implode`) and an MP4 through `ffmpeg` when it is on the
//! PATH. Exit code 1 when `--check` finds a frame that fails.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use clap::Args;
use serde_json::json;

use patchwork::view::View;

use patchwork::anim::{Explosion, GroupBy};
use patchwork::drive::implode::{
    AnimOptions, frames_pass, growth_within_bound, run as run_animation,
};
use patchwork::io::{atomic, png};
use patchwork::render::Renderer;
use patchwork::report::implode::{CrackSummary, FrameTimes, write_frames_csv};

use super::{load_built, progress};
use crate::args::{BudgetArgs, CameraArgs, DrawArgs, at_least, distance, lod_options};
use crate::error::CliError;
use crate::out::{self, data, note};

#[derive(Args, Debug)]
pub struct ImplodeArgs {
    /// Model file (.bpt, .step, .stp, .glb, .gltf, .obj, .ply, .stl).
    file: PathBuf,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    #[command(flatten)]
    parts: crate::args::PartArgs,
    /// Output folder (created if missing): frame-0000.png, …, implode.gif (explode.gif), and
    /// frames.csv with every frame's figures.
    #[arg(short, long)]
    output: PathBuf,
    /// Number of frames.
    #[arg(long, default_value_t = 48)]
    frames: usize,
    /// Explode (assembled → apart) instead of implode (apart → assembled).
    #[arg(long)]
    explode: bool,
    /// What moves as one: parts (each placed part of an assembly) or patches.
    #[arg(long, default_value = "parts")]
    by: GroupBy,
    /// Flight distance at full explosion, × the model's radius.
    #[arg(long, default_value_t = 1.0)]
    distance: f64,
    /// Frames per second of the GIF and MP4.
    #[arg(long, default_value_t = 24)]
    fps: u32,
    #[command(flatten)]
    budget: BudgetArgs,
    /// Write no GIF.
    #[arg(long)]
    no_gif: bool,
    /// Write no MP4 even when ffmpeg is found.
    #[arg(long)]
    no_mp4: bool,
    /// Count crack and growth pixels in every frame (against the moved watertight reference).
    #[arg(long)]
    check: bool,
    /// With --check: write check images and crack masks of frames with cracks or growth here.
    #[arg(long, requires = "check")]
    save_failures: Option<PathBuf>,
    /// Frame the whole flight (every exploded position in view) instead of the assembled
    /// model (whose parts then fly in from beyond the image's edges).
    #[arg(long)]
    frame_flight: bool,
    #[command(flatten)]
    camera: CameraArgs,
    #[command(flatten)]
    draw: DrawArgs,
    #[command(flatten)]
    section: crate::args::SectionArgs,
}

/// The output folder, refused when it is named like one of the files written into it.
fn output_folder(dir: &Path) -> Result<&Path, CliError> {
    const FILES: [&str; 6] = ["gif", "png", "mp4", "csv", "jpg", "jpeg"];
    match dir
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
    {
        Some(e) if FILES.contains(&e.as_str()) && !dir.is_dir() => Err(CliError::OutputNotFolder {
            path: dir.to_owned(),
            extension: e,
            suggestion: dir.with_extension(""),
        }),
        _ => Ok(dir),
    }
}

fn create_dir(dir: &Path) -> Result<(), CliError> {
    std::fs::create_dir_all(dir).map_err(|source| CliError::CreateDir {
        path: dir.to_owned(),
        source,
    })
}

/// The name of frame `k`.
fn frame_name(k: usize) -> String {
    format!("frame-{k:04}.png")
}

/// Whether `name` is one of ours: `frame-` + at least four digits + `.png`.
fn is_frame_name(name: &str) -> bool {
    name.strip_prefix("frame-")
        .and_then(|r| r.strip_suffix(".png"))
        .is_some_and(|d| d.len() >= 4 && d.bytes().all(|b| b.is_ascii_digit()))
}

/// How many `frame-NNNN.png` are in `dir`, checked to be `frame-0000.png` … in a row.
fn frames_in(dir: &Path) -> Result<usize, CliError> {
    let io = |source| CliError::Io {
        path: dir.to_owned(),
        source,
    };
    let mut count = 0;
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let name = entry.map_err(io)?.file_name();
        count += usize::from(is_frame_name(&name.to_string_lossy()));
    }
    let in_a_row = (0..count).all(|k| dir.join(frame_name(k)).is_file());
    Ok(if in_a_row { count } else { 0 })
}

/// Whether the frames passed (always, without `--check`).
pub fn run(args: &ImplodeArgs) -> Result<bool, CliError> {
    let frames = at_least("--frames", args.frames, 1)?;
    let distance = distance(args.distance)?;
    at_least("--fps", args.fps as usize, 1)?;
    let fps = args.fps;
    let budget = args.budget.validate()?;
    let sections = args.section.validate()?;
    output_folder(&args.output)?;
    let scene = args
        .parts
        .apply(load_built(&args.file, &args.cache)?, &args.file)?;
    // Frame the assembled model (or the whole flight); near and far always hold the flight.
    let explosion = Explosion::new(&scene, args.by, distance);
    let mut flight = scene.clone();
    flight.bounds = explosion.bounds(&scene);
    let camera = args.camera.validate()?;
    let framed = camera.view(if args.frame_flight { &flight } else { &scene })?;
    let view = View::new(
        framed.eye,
        framed.target,
        framed.up,
        framed.fov_y,
        (framed.width, framed.height),
        &flight.bounds,
    )
    .with_projection(framed.projection, &flight.bounds);
    create_dir(&args.output)?;
    let mut renderer = Renderer::new()?;
    renderer.primitives = args.draw.primitives.primitives;
    note!("adapter: {}", renderer.gpu().describe());
    let opts = AnimOptions {
        frames,
        explode: args.explode,
        by: args.by,
        distance,
        lod: lod_options(camera.pixel_error, budget),
        render: patchwork::render::RenderOptions {
            sections,
            ..args.draw.options()
        },
        check: args.check,
        save_failures: args.save_failures.clone(),
    };
    if let Some(dir) = &args.save_failures {
        create_dir(dir)?;
    }
    let name = if args.explode { "explode" } else { "implode" };
    // Everything is written into a fresh folder beside the output and moved in only when the
    // whole set is written: a failed or interrupted run leaves the previous output as it was,
    // and a shorter run removes the previous run's extra frames.
    let stage =
        atomic::TempDir::beside(&args.output.join(name)).map_err(|source| CliError::CreateDir {
            path: args.output.clone(),
            source,
        })?;
    let mut gif = if args.no_gif {
        None
    } else {
        let delay = (1000 / fps).max(10);
        Some(png::GifWriter::create(
            &stage.path().join(format!("{name}.gif")),
            delay,
        )?)
    };
    let pb = progress(frames, "frames");
    let mut write_error: Option<CliError> = None;
    let records = run_animation(&mut renderer, &scene, &view, &opts, |r, frame| {
        if write_error.is_some() {
            // The run has failed: stop writing (the frames still render; the loop has no exit).
            pb.inc(1);
            return Ok(());
        }
        let img = frame.to_rgba_image();
        let path = stage.path().join(frame_name(r.frame));
        let written = png::write_rgba(&path, &img)
            .and_then(|()| gif.as_mut().map_or(Ok(()), |g| g.add(&img)));
        if let Err(e) = written {
            write_error = Some(e.into());
        }
        pb.inc(1);
        Ok(())
    })?;
    pb.finish_and_clear();
    if let Some(e) = write_error {
        return Err(e);
    }
    if records.len() != frames {
        return Err(CliError::ShortRun {
            frames,
            made: records.len(),
        });
    }
    if let Some(g) = gif {
        g.finish()?;
    }
    let mp4 = if args.no_mp4 {
        None
    } else {
        write_mp4(stage.path(), name, fps)?
    };
    write_frames_csv(&stage.path().join("frames.csv"), &records)?;
    let moved = stage
        .move_into(&args.output, is_frame_name)
        .map_err(|source| CliError::Io {
            path: args.output.clone(),
            source,
        })?;
    let in_folder = frames_in(&args.output)?;
    if in_folder != frames || moved.iter().filter(|n| is_frame_name(n)).count() != frames {
        return Err(CliError::ShortRun {
            frames,
            made: in_folder,
        });
    }
    let mp4 = mp4.map(|p| args.output.join(p.file_name().unwrap_or_default()));
    let times = FrameTimes::of(&records);
    data!(
        "{name} of {} by {:?}: {} groups, {} frames at {}x{} — {:.1} frames per second (mean {:.1} ms, p50 {:.1} ms, max {:.1} ms per frame: frame loop, upload, draw; PNG writing not counted)",
        args.file.display(),
        args.by,
        explosion.groups,
        times.frames,
        view.width,
        view.height,
        times.per_second,
        times.mean_ms,
        times.p50_ms,
        times.max_ms
    );
    data!(
        "wrote {}/frame-0000.png … frame-{:04}.png{}{}",
        args.output.display(),
        records.len().saturating_sub(1),
        if args.no_gif {
            String::new()
        } else {
            format!(", {name}.gif")
        },
        mp4.as_ref()
            .map_or(String::new(), |p| format!(", {}", p.display()))
    );
    let pe = camera.pixel_error;
    let checked = args.check.then(|| {
        (
            CrackSummary::of(&records),
            frames_pass(&records, args.by, explosion.groups, pe),
        )
    });
    out::emit(&json!({
        "file": args.file.display().to_string(),
        "output": args.output.display().to_string(),
        "by": format!("{:?}", args.by).to_lowercase(),
        "groups": explosion.groups,
        "frames": times.frames,
        "size": [view.width, view.height],
        "frames_per_second": times.per_second,
        "frame_ms": { "mean": times.mean_ms, "p50": times.p50_ms, "max": times.max_ms },
        "gif": (!args.no_gif).then(|| format!("{name}.gif")),
        "mp4": mp4.as_ref().map(|p| p.display().to_string()),
        "check": checked.as_ref().map(|(c, ok)| json!({
            "crack_pixels": c.cracks,
            "frames_with_cracks": c.frames_with_cracks,
            "last_frame_cracks": c.last,
            "most_growth": c.most_growth,
            "worst_growth_px": c.worst_growth_px,
            "passed": ok,
        })),
    }));
    let Some((c, ok)) = checked else {
        return Ok(true);
    };
    let bound = records
        .iter()
        .find_map(|r| r.cracks)
        .map_or(String::new(), |first| {
            growth_within_bound(&first, args.by, explosion.groups, pe).0
        });
    data!(
        "crack pixels: {} in all frames, {} frames with any, {} in the last frame; growth at most {} pixels a frame, at most {} px out (bound {bound})",
        c.cracks,
        c.frames_with_cracks,
        c.last,
        c.most_growth,
        c.worst_growth_px,
    );
    if !ok {
        note!(
            "check failed: {}",
            match args.by {
                GroupBy::Parts =>
                    "moving parts must be crack-free in every frame, growth within the bound",
                GroupBy::Patches =>
                    "the assembled frame must be crack-free, growth within the bound in every frame",
            }
        );
    }
    Ok(ok)
}

/// Encodes `dir/frame-%04d.png` as `dir/NAME.mp4` (ffmpeg's default MP4 encoder, via a
/// temporary name) when an `ffmpeg` binary is on the PATH; says so and returns `None` when
/// there is none.
fn write_mp4(dir: &Path, name: &str, fps: u32) -> Result<Option<PathBuf>, CliError> {
    let found = Command::new("ffmpeg")
        .arg("-version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !found {
        note!("note: no ffmpeg on the PATH, so no MP4 (the PNGs and the GIF are written)");
        return Ok(None);
    }
    let out = dir.join(format!("{name}.mp4"));
    let tmp = dir.join(format!(".{name}.{}.tmp.mp4", std::process::id()));
    let status = Command::new("ffmpeg")
        .args(["-y", "-loglevel", "error", "-framerate"])
        .arg(fps.to_string())
        .arg("-i")
        .arg(dir.join("frame-%04d.png"))
        .args([
            "-vf",
            "pad=ceil(iw/2)*2:ceil(ih/2)*2",
            "-pix_fmt",
            "yuv420p",
        ])
        .arg(&tmp)
        .status()
        .map_err(CliError::FfmpegStart)?;
    if !status.success() {
        let _ = std::fs::remove_file(&tmp);
        return Err(CliError::FfmpegFailed {
            status,
            dir: dir.to_owned(),
        });
    }
    std::fs::rename(&tmp, &out).map_err(|source| CliError::Io {
        path: out.clone(),
        source,
    })?;
    Ok(Some(out))
}
