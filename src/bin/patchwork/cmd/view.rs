//! `patchwork view`: the interactive viewer (`patchwork::viewer`), or a scripted run of it.

use std::path::PathBuf;

use clap::Args;

use patchwork::anim::GroupBy;
use patchwork::viewer::{ViewerAnimation, ViewerOptions, script_input};

use crate::args::{
    BudgetArgs, CameraArgs, EdgesArg, PrimitivesArg, at_least, distance, lod_options,
};
use crate::error::CliError;
use crate::out::{data, note};

#[derive(Args, Debug)]
#[command(after_help = patchwork::viewer::CONTROLS)]
pub struct ViewArgs {
    /// Model files (.bpt, .step, .stp, .iges, .glb, .gltf, .obj, .ply, .stl; `-` reads stdin,
    /// with --format); several are drawn as one scene, each file a top-level part.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    #[command(flatten)]
    parts: crate::args::PartArgs,
    /// The starting camera, window size (--size) and pixel error (`+`/`-` change it).
    #[command(flatten)]
    camera: CameraArgs,
    #[command(flatten)]
    budget: BudgetArgs,
    /// Scripted run: draw this many frames, then exit.
    #[arg(long)]
    frames: Option<usize>,
    /// With --frames: write the last frame here.
    #[arg(long, requires = "frames")]
    screenshot: Option<PathBuf>,
    /// With --frames: keys pressed one per frame from the first, comma-separated
    /// (e.g. `h,+` or `b,b,w`; names: characters, left, right, up, down, pageup, pagedown,
    /// space; the part panel: `click:X:Y` a click at a window pixel, `part:N` instance N
    /// shown / hidden, `explode:F` the explode slider at F in [0, 1]).
    #[arg(long, requires = "frames", value_delimiter = ',')]
    keys: Vec<String>,
    /// Play an implosion/explosion loop (space pauses and resumes).
    #[arg(long)]
    implode: bool,
    /// With --implode: parts or patches move.
    #[arg(long, default_value = "parts", requires = "implode")]
    by: GroupBy,
    /// With --implode: flight distance, × the model's radius.
    #[arg(long, default_value_t = 1.0, requires = "implode")]
    distance: f64,
    /// With --implode: frames per implosion.
    #[arg(long, default_value_t = 60, requires = "implode")]
    implode_frames: usize,
    #[command(flatten)]
    primitives: PrimitivesArg,
    #[command(flatten)]
    section: crate::args::SectionArgs,
    /// The edges drawn at the start (`e` cycles off / feature / all).
    #[command(flatten)]
    edges: EdgesArg,
}

pub fn run(args: &ViewArgs) -> Result<(), CliError> {
    let camera = args.camera.validate()?;
    let budget = args.budget.validate()?;
    let frames = args
        .frames
        .map(|n| at_least("--frames", n, 1))
        .transpose()?;
    let distance = distance(args.distance)?;
    let sections = args.section.validate()?;
    if let Some(k) = args.keys.iter().find(|k| script_input(k).is_none()) {
        return Err(CliError::UnknownKey { key: k.clone() });
    }
    if let Some(n) = frames
        && args.keys.len() > n
    {
        return Err(CliError::TooManyKeys {
            keys: args.keys.len(),
            frames: n,
        });
    }
    // A mesh shows at once at full resolution (or from the cached hierarchies); its
    // hierarchies are built on a background thread, written to the cache, and the viewer
    // swaps in the scene that has them. Several files are merged with their hierarchies
    // built first.
    let file = super::shown(&args.files);
    let hierarchies = if args.files.len() > 1 {
        patchwork::prep::Hierarchies::Build
    } else {
        patchwork::prep::Hierarchies::CachedOrOriginal
    };
    let loaded = super::load_all(&args.files, &args.cache.options(hierarchies))?;
    let scene = args.parts.apply(loaded.scene, &file)?;
    let upgrade = loaded.pending.map(|pending| {
        let (tx, rx) = std::sync::mpsc::channel();
        let (start, file) = (scene.clone(), file.clone());
        std::thread::spawn(move || {
            let t = std::time::Instant::now();
            let built = pending.build(&start, &patchwork::prep::NoProgress);
            for w in &built.warnings {
                note!("warning: {}: {w}", file.display());
            }
            note!(
                "{}: hierarchies built in {:.2} s",
                file.display(),
                t.elapsed().as_secs_f64()
            );
            // The viewer may have closed meanwhile: nobody to tell.
            let _ = tx.send(built.scene);
        });
        rx
    });
    let title = file.file_name().map_or_else(
        || "patchwork".into(),
        |n| format!("patchwork — {}", n.to_string_lossy()),
    );
    let report = patchwork::viewer::run_upgrading(
        scene,
        ViewerOptions {
            title,
            size: camera.size,
            fov_y: camera.fov_y,
            framing: camera.framing,
            eye: camera.eye,
            target: camera.target,
            up: camera.up,
            lod: lod_options(camera.pixel_error, budget),
            frames,
            screenshot: args.screenshot.clone(),
            keys: args.keys.clone(),
            implode: args.implode.then_some(ViewerAnimation {
                by: args.by,
                distance,
                frames: args.implode_frames.max(2),
            }),
            primitives: args.primitives.primitives,
            sections,
            edges: args.edges.edges,
            notify: |m| note!("{m}"),
            picked: |m| data!("{m}"),
        },
        upgrade,
    )?;
    note!(
        "{} frames ({} presented), {:.1} ms per frame on average",
        report.frames,
        report.presented,
        report.mean_frame_ms
    );
    Ok(())
}
