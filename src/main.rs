//! `patchwork` command line: render, stats, check.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::{Args, Parser, Subcommand};
use glam::DVec3;
use indicatif::{ProgressBar, ProgressStyle};

use patchwork::check::{CheckOptions, run_check};
use patchwork::io::{self, png};
use patchwork::model::Scene;
use patchwork::render::{FatBorders, Primitives, RenderOptions, Renderer, Shading};
use patchwork::tessellate::{MeshStats, tessellate_scene};
use patchwork::view::{self, View};

#[derive(Parser, Debug)]
#[command(
    name = "patchwork",
    version,
    about = "Crack-free rendering of multi-patch surfaces with fat borders"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a model to a PNG (headless; software rasterizers are fine).
    Render(RenderArgs),
    /// Tessellate for a view and print patches, triangles, border vertices, ε range, time.
    Stats(StatsArgs),
    /// Render random views with fat borders off and on and count crack and growth pixels.
    Check(CheckArgs),
    /// Write the tessellation as binary glTF (.glb): one mesh per part, one node per placement.
    Export(ExportArgs),
    /// Benchmarks: `--flythrough` drives a recorded camera path through the LOD frame loop.
    Bench(BenchArgs),
    /// Interactive viewer (needs a display; `xvfb-run -a` gives a virtual one).
    View(ViewArgs),
    /// Animate parts (or patches) flying together (or apart): numbered PNGs, an animated GIF,
    /// and an MP4 when `ffmpeg` is on the PATH.
    Implode(ImplodeArgs),
}

#[derive(Args, Debug)]
struct ImplodeArgs {
    /// Model file (.bpt, .step, .stp, .glb, .gltf, .obj, .ply).
    file: PathBuf,
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
    by: patchwork::anim::GroupBy,
    /// Flight distance at full explosion, × the model's radius.
    #[arg(long, default_value_t = 1.0)]
    distance: f64,
    /// Frames per second of the GIF and MP4.
    #[arg(long, default_value_t = 24)]
    fps: u32,
    /// Re-tessellation time budget per frame, milliseconds.
    #[arg(long, default_value_t = 40.0)]
    budget_ms: f64,
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
    #[command(flatten)]
    camera: CameraArgs,
    #[command(flatten)]
    draw: DrawArgs,
}

#[derive(Args, Debug)]
struct ViewArgs {
    /// Model file (.bpt, .step, .stp, .glb, .gltf, .obj, .ply).
    file: PathBuf,
    /// Window size.
    #[arg(long, default_value = "1024x768", value_parser = parse_size)]
    size: (u32, u32),
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = view::DEFAULT_FOV_Y_DEG)]
    fov: f64,
    /// Pixel error at start (`+`/`-` change it).
    #[arg(long, default_value_t = view::DEFAULT_PIXEL_ERROR)]
    pixel_error: f64,
    /// Re-tessellation time budget per frame, milliseconds.
    #[arg(long, default_value_t = 40.0)]
    budget_ms: f64,
    /// Scripted run: draw this many frames, then exit.
    #[arg(long)]
    frames: Option<usize>,
    /// With --frames: write the last frame here.
    #[arg(long, requires = "frames")]
    screenshot: Option<PathBuf>,
    /// With --frames: keys pressed one per frame from the first, comma-separated
    /// (e.g. `h,+` or `b,b,w`; names: characters, left, right, up, down, pageup, pagedown,
    /// space).
    #[arg(long, requires = "frames", value_delimiter = ',')]
    keys: Vec<String>,
    /// Play an implosion/explosion loop (space pauses and resumes).
    #[arg(long)]
    implode: bool,
    /// With --implode: parts or patches move.
    #[arg(long, default_value = "parts", requires = "implode")]
    by: patchwork::anim::GroupBy,
    /// With --implode: flight distance, × the model's radius.
    #[arg(long, default_value_t = 1.0, requires = "implode")]
    distance: f64,
    /// With --implode: frames per implosion.
    #[arg(long, default_value_t = 60, requires = "implode")]
    implode_frames: usize,
    /// Surface primitives: `auto` (lists for tessellated patches, multiresolution strips for
    /// mesh patches: fastest measured), `list` (indexed triangles), `strips` (static triangle
    /// strips by tunneling; per arc for mesh patches), `mts` (mesh patches: multiresolution
    /// strips at each cut) or `repair` (mesh patches: strips repaired by tunneling as the cut
    /// moves).
    #[arg(long, default_value = "auto")]
    primitives: Primitives,
}

#[derive(Args, Debug)]
struct BenchArgs {
    /// Model file (.bpt, .step, .stp, .glb, .gltf, .obj, .ply).
    file: PathBuf,
    /// Run the fly-through: orbit, zoom in close, a sudden jump, then still.
    #[arg(long)]
    flythrough: bool,
    /// Frames of the camera path.
    #[arg(long, default_value_t = 200)]
    frames: usize,
    /// Re-tessellation time budget per frame, milliseconds.
    #[arg(long, default_value_t = 40.0)]
    budget_ms: f64,
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
    /// Surface primitives: `auto` (lists for tessellated patches, multiresolution strips for
    /// mesh patches: fastest measured), `list` (indexed triangles), `strips` (static triangle
    /// strips by tunneling; per arc for mesh patches), `mts` (mesh patches: multiresolution
    /// strips at each cut) or `repair` (mesh patches: strips repaired by tunneling as the cut
    /// moves).
    #[arg(long, default_value = "auto")]
    primitives: Primitives,
    /// How strips are joined: `restart` (primitive restart) or `degenerate` (zero-area
    /// windows); default: restart, degenerate on wgpu's GL backend.
    #[arg(long)]
    strip_joins: Option<patchwork::strips::Join>,

    /// Per-frame CSV.
    #[arg(long, default_value = "flythrough.csv")]
    csv: PathBuf,
    /// Plot of error and frame time over the frames.
    #[arg(long, default_value = "flythrough.png")]
    plot: PathBuf,
}

#[derive(Args, Debug)]
struct ExportArgs {
    /// Model file (.bpt, .step, .stp, .glb, .gltf, .obj, .ply).
    file: PathBuf,
    /// Output .glb file.
    #[arg(short, long)]
    output: PathBuf,
    /// Tessellate for the default view at this screen-space error (pixels, 1024x768).
    #[arg(long, default_value_t = view::DEFAULT_PIXEL_ERROR, conflicts_with = "tolerance")]
    pixel_error: f64,
    /// Tessellate to this absolute tolerance instead (model units: millimetres for STEP).
    #[arg(long)]
    tolerance: Option<f64>,
}

#[derive(Args, Debug, Clone)]
struct CameraArgs {
    /// Image size in pixels.
    #[arg(long, default_value = "1024x768", value_parser = parse_size)]
    size: (u32, u32),
    /// Eye position (default: frames the model's bounding sphere from a three-quarter view).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    eye: Option<DVec3>,
    /// Point looked at (default: the model's centre).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    target: Option<DVec3>,
    /// Up vector (default 0,1,0; for z-up formats such as .bpt, 0,0,1).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    up: Option<DVec3>,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = view::DEFAULT_FOV_Y_DEG)]
    fov: f64,
    /// Allowed screen-space error in pixels (ε per patch follows from it).
    #[arg(long, default_value_t = view::DEFAULT_PIXEL_ERROR)]
    pixel_error: f64,
}

/// How images are drawn (shared by `render` and `implode`).
#[derive(Args, Debug, Clone, Copy)]
struct DrawArgs {
    /// lit, flat or ids.
    #[arg(long, default_value = "lit")]
    shading: Shading,
    /// Background colour R,G,B (0–255).
    #[arg(long, default_value = "255,255,255", value_parser = parse_rgb)]
    background: [u8; 3],
    /// Fat-border variant: off, 6, 4 or 2 displaced vertices per border vertex.
    #[arg(long, default_value = "6")]
    fat_borders: FatBorders,
    /// Samples per pixel: 1 or 4.
    #[arg(long, default_value_t = 4, value_parser = parse_msaa)]
    msaa: u32,
    /// Surface primitives: `auto` (lists for tessellated patches, multiresolution strips for
    /// mesh patches: fastest measured), `list` (indexed triangles), `strips` (static triangle
    /// strips by tunneling; per arc for mesh patches), `mts` (mesh patches: multiresolution
    /// strips at each cut) or `repair` (mesh patches: strips repaired by tunneling as the cut
    /// moves).
    #[arg(long, default_value = "auto")]
    primitives: Primitives,
}

impl DrawArgs {
    fn options(&self) -> RenderOptions {
        RenderOptions {
            shading: self.shading,
            background: self.background,
            fat_borders: self.fat_borders,
            msaa: self.msaa,
            depth: false,
            ..RenderOptions::default()
        }
    }
}

#[derive(Args, Debug)]
struct RenderArgs {
    /// Model file (.bpt, .step, .stp, .glb, .gltf, .obj, .ply).
    file: PathBuf,
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

#[derive(Args, Debug)]
struct StatsArgs {
    file: PathBuf,
    #[command(flatten)]
    camera: CameraArgs,
    /// Print the placed solids / shells (instances): part, occurrence, shell, world bounding box.
    #[arg(long)]
    parts: bool,
    /// How many of the worst trimmed faces to name (error measured against the trimmed face).
    #[arg(long, default_value_t = 5)]
    faces: usize,
}

#[derive(Args, Debug)]
struct CheckArgs {
    file: PathBuf,
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
    /// Write actual and crack-mask images of views with cracks or growth into this folder.
    #[arg(long)]
    save_failures: Option<PathBuf>,
    /// Surface primitives: `auto` (lists for tessellated patches, multiresolution strips for
    /// mesh patches: fastest measured), `list` (indexed triangles), `strips` (static triangle
    /// strips by tunneling; per arc for mesh patches), `mts` (mesh patches: multiresolution
    /// strips at each cut) or `repair` (mesh patches: strips repaired by tunneling as the cut
    /// moves).
    #[arg(long, default_value = "auto")]
    primitives: Primitives,
    /// Stress tessellation: every border pulled back towards its patch as far as the pixel
    /// error allows, so that only fat borders of full width close the gaps.
    #[arg(long)]
    stress: bool,
    /// Also measure the fat borders drawn this much narrower (a mutation: 0.5 must crack).
    #[arg(long)]
    narrowed_width: Option<f64>,
}

fn parse_triple<T: std::str::FromStr>(s: &str, what: &str) -> Result<[T; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected {what} as three comma-separated numbers, got {s:?}"
        ));
    }
    let mut out = Vec::with_capacity(3);
    for p in parts {
        out.push(
            p.parse::<T>()
                .map_err(|_| format!("{p:?} is not a valid {what} component"))?,
        );
    }
    out.try_into()
        .map_err(|_| format!("expected three numbers, got {s:?}"))
}

fn parse_vec3(s: &str) -> Result<DVec3, String> {
    let [x, y, z] = parse_triple::<f64>(s, "X,Y,Z")?;
    let v = DVec3::new(x, y, z);
    if !v.is_finite() {
        return Err(format!("{s:?} is not finite"));
    }
    Ok(v)
}

fn parse_rgb(s: &str) -> Result<[u8; 3], String> {
    parse_triple::<u8>(s, "R,G,B (0-255)")
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got {s:?}"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in {s:?}"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in {s:?}"))?;
    if w == 0 || h == 0 {
        return Err(format!("image size must be at least 1x1, got {w}x{h}"));
    }
    Ok((w, h))
}

fn parse_msaa(s: &str) -> Result<u32, String> {
    match s {
        "1" => Ok(1),
        "4" => Ok(4),
        _ => Err(format!("MSAA must be 1 or 4, got {s:?}")),
    }
}

/// Any error the CLI reports; the message already names the file.
type CliError = Box<dyn std::error::Error>;

fn check_pixel_error(px: f64) -> Result<(), CliError> {
    if !(px.is_finite() && px > 0.0) {
        return Err(format!("--pixel-error must be a positive number of pixels, got {px}").into());
    }
    Ok(())
}

fn check_fov(fov: f64) -> Result<(), CliError> {
    if !(fov.is_finite() && fov > 0.5 && fov < 179.0) {
        return Err(format!("--fov must be between 0.5 and 179 degrees, got {fov}").into());
    }
    Ok(())
}

fn make_view(scene: &Scene, cam: &CameraArgs) -> Result<View, CliError> {
    check_fov(cam.fov)?;
    check_pixel_error(cam.pixel_error)?;
    let fov = cam.fov.to_radians();
    let up = cam.up.unwrap_or_else(|| scene.up.vector());
    if up.length() < 1e-12 {
        return Err("--up must not be the zero vector".into());
    }
    let target = cam.target.unwrap_or(scene.bounds.center);
    let view = match cam.eye {
        Some(eye) => {
            if eye.distance(target) < 1e-12 {
                return Err("--eye and --target must differ".into());
            }
            if (target - eye).cross(up).length() < 1e-9 * (target - eye).length() * up.length() {
                return Err("--up must not be parallel to the viewing direction".into());
            }
            View::new(eye, target, up, fov, cam.size, &scene.bounds)
        }
        None => {
            let mut v = View::framing(&scene.bounds, up, fov, cam.size);
            let shift = target - v.target;
            v.eye += shift;
            v.target = target;
            View::new(v.eye, v.target, up, fov, cam.size, &scene.bounds)
        }
    };
    Ok(view)
}

/// Loads a model and tells the user (stderr) what was left out and why.
fn load(path: &Path) -> Result<Scene, CliError> {
    let scene = io::load(path)?;
    for w in &scene.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    if !scene.skipped.is_empty() {
        eprintln!(
            "warning: {}: {} face(s) skipped:",
            path.display(),
            scene.skipped.len()
        );
        for s in &scene.skipped {
            eprintln!("  face #{}: {}", s.face, s.reason);
        }
    }
    Ok(scene)
}

/// Reports patches whose tessellation failed (their faces are not drawn in this frame).
fn report_failures(meshes: &[patchwork::tessellate::PatchMesh]) {
    let failed: Vec<&str> = meshes.iter().filter_map(|m| m.failure.as_deref()).collect();
    if !failed.is_empty() {
        eprintln!(
            "warning: {} patch(es) could not be tessellated:",
            failed.len()
        );
        for f in failed.iter().take(10) {
            eprintln!("  {f}");
        }
    }
}

fn cmd_render(args: &RenderArgs) -> Result<(), CliError> {
    let scene = load(&args.file)?;
    let view = make_view(&scene, &args.camera)?;
    let t0 = Instant::now();
    let meshes = tessellate_scene(&scene, &view, args.camera.pixel_error);
    let t_tess = t0.elapsed();
    report_failures(&meshes);
    let mut renderer = Renderer::new()?;
    renderer.primitives = args.draw.primitives;
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
            let depth = d.depth.unwrap_or_default();
            let (near, far) = (view.near, view.far);
            let img = image::ImageBuffer::from_fn(view.width, view.height, |x, y| {
                let z = depth[(y * view.width + x) as usize] as f64;
                let t = if z.is_finite() {
                    ((z - near) / (far - near)).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                image::Luma([(t * 65535.0).round() as u16])
            });
            Some((path, img))
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

fn cmd_implode(args: &ImplodeArgs) -> Result<bool, CliError> {
    use patchwork::anim::{AnimOptions, Explosion, run};
    use patchwork::lod::LodOptions;
    if args.frames == 0 {
        return Err("--frames must be at least 1".into());
    }
    if !(args.distance.is_finite() && args.distance >= 0.0) {
        return Err(format!("--distance must be a number ≥ 0, not {}", args.distance).into());
    }
    if args.fps == 0 {
        return Err("--fps must be at least 1".into());
    }
    if !(args.budget_ms.is_finite() && args.budget_ms > 0.0) {
        return Err(format!(
            "--budget-ms must be a positive number, not {}",
            args.budget_ms
        )
        .into());
    }
    let scene = load(&args.file)?;
    // Frame the whole flight: the view holds every frame.
    let explosion = Explosion::new(&scene, args.by, args.distance);
    let mut framing = scene.clone();
    framing.bounds = explosion.bounds(&scene);
    let view = make_view(&framing, &args.camera)?;
    std::fs::create_dir_all(&args.output)
        .map_err(|e| format!("{}: cannot create the folder: {e}", args.output.display()))?;
    let mut renderer = Renderer::new()?;
    renderer.primitives = args.draw.primitives;
    eprintln!("adapter: {}", renderer.gpu().describe());
    let opts = AnimOptions {
        frames: args.frames,
        explode: args.explode,
        by: args.by,
        distance: args.distance,
        lod: LodOptions {
            pixel_error: args.camera.pixel_error,
            budget: std::time::Duration::from_secs_f64(args.budget_ms / 1e3),
            ..LodOptions::default()
        },
        render: args.draw.options(),
        check: args.check,
        save_failures: args.save_failures.clone(),
    };
    if let Some(dir) = &args.save_failures {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("{}: cannot create the folder: {e}", dir.display()))?;
    }
    let name = if args.explode { "explode" } else { "implode" };
    let mut gif = if args.no_gif {
        None
    } else {
        let delay = (1000 / args.fps).max(10);
        Some(png::GifWriter::create(
            &args.output.join(format!("{name}.gif")),
            delay,
        )?)
    };
    let pb = ProgressBar::new(args.frames as u64);
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} frames {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut write_error: Option<CliError> = None;
    let records = run(&mut renderer, &scene, &view, &opts, |r, frame| {
        let img = frame.to_rgba_image();
        let path = args.output.join(format!("frame-{:04}.png", r.frame));
        let written = png::write_rgba(&path, &img)
            .and_then(|()| gif.as_mut().map_or(Ok(()), |g| g.add(&img)));
        if let Err(e) = written
            && write_error.is_none()
        {
            write_error = Some(e.into());
        }
        pb.inc(1);
        Ok(())
    })?;
    pb.finish_and_clear();
    if let Some(e) = write_error {
        return Err(e);
    }
    if let Some(g) = gif {
        g.finish()?;
    }
    let mp4 = if args.no_mp4 {
        None
    } else {
        write_mp4(&args.output, name, args.fps)?
    };
    let mut csv = String::from(
        "frame,amount,frame_ms,tessellation_ms,retessellated,triangles,max_error_px,crack_pixels,growth_pixels,growth_max_px\n",
    );
    for r in &records {
        let (cracks, growth, growth_max) =
            r.cracks
                .map_or((String::new(), String::new(), String::new()), |c| {
                    (
                        c.cracks().to_string(),
                        c.growth.to_string(),
                        c.growth_max_px.to_string(),
                    )
                });
        csv.push_str(&format!(
            "{},{:.4},{:.3},{:.3},{},{},{:.3},{cracks},{growth},{growth_max}\n",
            r.frame,
            r.amount,
            r.frame_ms,
            r.tessellation_ms,
            r.retessellated,
            r.triangles,
            r.max_error_px
        ));
    }
    png::write_text(&args.output.join("frames.csv"), &csv)?;
    let n = records.len() as f64;
    let total_ms: f64 = records.iter().map(|r| r.frame_ms).sum();
    let mut ms: Vec<f64> = records.iter().map(|r| r.frame_ms).collect();
    ms.sort_by(f64::total_cmp);
    println!(
        "{name} of {} by {:?}: {} groups, {} frames at {}x{} — {:.1} frames per second (mean {:.1} ms, p50 {:.1} ms, max {:.1} ms per frame: frame loop, upload, draw; PNG writing not counted)",
        args.file.display(),
        args.by,
        explosion.groups,
        records.len(),
        view.width,
        view.height,
        1e3 * n / total_ms.max(1e-9),
        total_ms / n,
        ms[ms.len() / 2],
        ms[ms.len() - 1]
    );
    println!(
        "wrote {}/frame-0000.png … frame-{:04}.png{}{}",
        args.output.display(),
        records.len() - 1,
        if args.no_gif {
            String::new()
        } else {
            format!(", {name}.gif")
        },
        mp4.map_or(String::new(), |p| format!(", {}", p.display()))
    );
    let mut ok = true;
    if args.check {
        use patchwork::anim::{frames_pass, growth_within_bound};
        let counts: Vec<_> = records.iter().filter_map(|r| r.cracks).collect();
        let cracks: usize = counts.iter().map(|c| c.cracks()).sum();
        let worst = counts.iter().map(|c| c.growth_max_px).max().unwrap_or(0);
        let most = counts.iter().map(|c| c.growth).max().unwrap_or(0);
        let last = counts.last().map_or(0, |c| c.cracks());
        let pe = args.camera.pixel_error;
        let bound = counts.first().map_or(String::new(), |c| {
            growth_within_bound(c, args.by, explosion.groups, pe).0
        });
        println!(
            "crack pixels: {cracks} in all frames, {} frames with any, {last} in the last frame; growth at most {most} pixels a frame, at most {worst} px out (bound {bound})",
            counts.iter().filter(|c| c.cracks() > 0).count(),
        );
        ok = frames_pass(&records, args.by, explosion.groups, pe);
        if !ok {
            eprintln!(
                "check failed: {}",
                match args.by {
                    patchwork::anim::GroupBy::Parts =>
                        "moving parts must be crack-free in every frame, growth within the bound",
                    patchwork::anim::GroupBy::Patches =>
                        "the assembled frame must be crack-free, growth within the bound in every frame",
                }
            );
        }
    }
    Ok(ok)
}

/// Encodes `dir/frame-%04d.png` as `dir/NAME.mp4` (ffmpeg's default MP4 encoder, via a temporary name) when an
/// `ffmpeg` binary is on the PATH; says so and returns `None` when there is none.
fn write_mp4(dir: &Path, name: &str, fps: u32) -> Result<Option<PathBuf>, CliError> {
    let found = std::process::Command::new("ffmpeg")
        .arg("-version")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !found {
        eprintln!("note: no ffmpeg on the PATH, so no MP4 (the PNGs and the GIF are written)");
        return Ok(None);
    }
    let out = dir.join(format!("{name}.mp4"));
    let tmp = dir.join(format!(".{name}.{}.tmp.mp4", std::process::id()));
    let status = std::process::Command::new("ffmpeg")
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
        .map_err(|e| format!("ffmpeg: {e}"))?;
    if !status.success() {
        let _ = std::fs::remove_file(&tmp);
        return Err(format!(
            "ffmpeg failed ({status}); the PNGs are in {}",
            dir.display()
        )
        .into());
    }
    std::fs::rename(&tmp, &out).map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(Some(out))
}

fn cmd_export(args: &ExportArgs) -> Result<(), CliError> {
    use patchwork::io::gltf_out::{ExportMesh, ExportNode, ExportScene, write_glb};
    use patchwork::tessellate::{PatchMesh, Tessellators};
    let scene = load(&args.file)?;
    if let Some(t) = args.tolerance
        && !(t.is_finite() && t > 0.0)
    {
        return Err(format!("--tolerance must be a positive number, not {t}").into());
    }
    let view = View::framing(
        &scene.bounds,
        scene.up.vector(),
        view::DEFAULT_FOV_Y_DEG.to_radians(),
        (1024, 768),
    );
    // One node per placed solid / shell (the scene's instances); one mesh per shell (or part,
    // outside STEP), shared by the placements of that shell.
    let mesh_key = |i: &patchwork::model::Instance| (i.part, i.shell);
    let mut meshes = Vec::new();
    let mut mesh_of = std::collections::HashMap::new();
    let mut nodes = Vec::new();
    let mut t = Tessellators::new();
    for (index, inst) in scene.instances.iter().enumerate() {
        let patches: Vec<&patchwork::model::Patch> = scene
            .patches
            .iter()
            .filter(|p| p.instance as usize == index)
            .collect();
        if patches.is_empty() {
            continue;
        }
        let part_name = scene
            .parts
            .get(inst.part as usize)
            .map(|p| p.name.clone())
            .unwrap_or_default();
        let mesh = match mesh_of.get(&mesh_key(inst)) {
            Some(&m) => m,
            None => {
                let mut mesh = ExportMesh {
                    name: part_name.clone(),
                    ..ExportMesh::default()
                };
                for p in &patches {
                    // The finest ε any placement of the face asks for, in its own units.
                    let eps = match args.tolerance {
                        Some(tol) => tol / p.scale(),
                        None => scene
                            .patches
                            .iter()
                            .filter(|q| q.part == p.part && same_surface(q, p))
                            .map(|q| view.eps_obj(&q.bounds, args.pixel_error) / q.scale())
                            .fold(f64::INFINITY, f64::min),
                    };
                    let local = patchwork::model::Patch {
                        transform: glam::DMat4::IDENTITY,
                        ..(*p).clone()
                    };
                    let mut m = PatchMesh::default();
                    t.patch(&local, eps, &mut m);
                    let base = mesh.positions.len() as u32;
                    mesh.positions
                        .extend(m.positions.iter().map(|v| v.to_array()));
                    mesh.normals.extend(m.normals.iter().map(|v| v.to_array()));
                    mesh.indices
                        .extend(m.triangles.iter().flatten().map(|i| base + i));
                    if mesh.color.is_none() {
                        mesh.color = p.color.map(|c| [c[0], c[1], c[2], 1.0]);
                    }
                }
                mesh_of.insert(mesh_key(inst), meshes.len());
                meshes.push(mesh);
                meshes.len() - 1
            }
        };
        let name = match (inst.name.is_empty(), inst.shell) {
            (false, _) => format!("{part_name} {}", inst.name),
            (true, Some(shell)) => format!("{part_name} shell #{shell} {index}"),
            (true, None) => format!("{part_name} {index}"),
        };
        nodes.push(ExportNode {
            name,
            mesh,
            matrix: inst.transform.as_mat4().to_cols_array(),
        });
    }
    let doc = ExportScene {
        meshes,
        nodes,
        generator: format!("patchwork {}", env!("CARGO_PKG_VERSION")),
    };
    check_pixel_error(args.pixel_error)?;
    let stats = write_glb(&args.output, &doc)?;
    eprintln!(
        "{}: {} meshes, {} nodes, {} triangles, {} bytes",
        args.output.display(),
        stats.meshes,
        stats.nodes,
        stats.triangles,
        stats.bytes
    );
    Ok(())
}

/// Whether two patches draw the same surface (the same face placed twice).
fn same_surface(a: &patchwork::model::Patch, b: &patchwork::model::Patch) -> bool {
    use patchwork::model::PatchSurface;
    match (&a.surface, &b.surface) {
        (PatchSurface::Trimmed(x), PatchSurface::Trimmed(y)) => std::sync::Arc::ptr_eq(x, y),
        _ => a.id == b.id,
    }
}

fn cmd_stats(args: &StatsArgs) -> Result<(), CliError> {
    let scene = load(&args.file)?;
    let view = make_view(&scene, &args.camera)?;
    // Warm-up run (thread pool start), then the timed one.
    let _ = tessellate_scene(&scene, &view, args.camera.pixel_error);
    let t0 = Instant::now();
    let meshes = tessellate_scene(&scene, &view, args.camera.pixel_error);
    let dt = t0.elapsed();
    let s = MeshStats::of(&meshes);
    println!("file              {}", args.file.display());
    println!("patches           {}", s.patches);
    println!("triangles         {}", s.triangles);
    println!("vertices          {}", s.vertices);
    println!("border vertices   {}", s.border_vertices);
    println!("pixel error       {} px", args.camera.pixel_error);
    println!(
        "eps range         {:.3e} .. {:.3e} (object units)",
        s.eps_min, s.eps_max
    );
    println!(
        "worst error/eps   {:.3} (the tessellator's own samples)",
        s.worst_error_ratio
    );
    let faces = patchwork::check::fidelity::measure_meshes(&scene, &meshes);
    if !faces.is_empty() {
        let samples: usize = faces.iter().map(|f| f.1.samples).sum();
        let outside: usize = faces.iter().map(|f| f.1.outside).sum();
        let face_samples: usize = faces.iter().map(|f| f.1.face_samples).sum();
        let uncovered: usize = faces.iter().map(|f| f.1.uncovered).sum();
        println!(
            "trimmed error/eps {:.3} (against the trimmed faces, {samples} samples; {outside} \
             outside their trim by more than eps; {face_samples} face samples, {uncovered} \
             farther than eps from the mesh)",
            faces[0].1.ratio()
        );
        for (patch, f) in faces.iter().take(args.faces) {
            println!(
                "  face #{:<8} {:<9} error/eps {:>7.3}  outside {:>5}  missing/eps {:>7.3}  \
                 patch {patch}",
                f.face,
                f.surface,
                f.ratio(),
                f.outside,
                f.missing / f.eps.max(f64::MIN_POSITIVE)
            );
        }
    }
    println!(
        "placed solids     {} ({} parts)",
        scene.instances.len(),
        scene.parts.len()
    );
    if !scene.skipped.is_empty() {
        println!("skipped faces     {}", scene.skipped.len());
        for f in scene.skipped.iter().take(10) {
            println!("  face #{}: {}", f.face, f.reason);
        }
        if scene.skipped.len() > 10 {
            println!("  …");
        }
    }
    println!(
        "tessellation      {:.2} ms ({} threads)",
        dt.as_secs_f64() * 1e3,
        rayon::current_num_threads()
    );
    println!(
        "eye               {:.3},{:.3},{:.3}",
        view.eye.x, view.eye.y, view.eye.z
    );
    if args.parts {
        print_parts(&scene, &meshes);
    }
    Ok(())
}

/// The placed solids / shells: index, part, occurrence path, shell, translation, world box
/// (of the tessellation).
fn print_parts(scene: &Scene, meshes: &[patchwork::tessellate::PatchMesh]) {
    let mut boxes: Vec<Option<(glam::DVec3, glam::DVec3)>> = vec![None; scene.instances.len()];
    for (p, m) in scene.patches.iter().zip(meshes) {
        let Some(b) = patchwork::model::bounding_box(m.positions.iter().map(|v| v.as_dvec3()))
        else {
            continue;
        };
        if let Some(slot) = boxes.get_mut(p.instance as usize) {
            *slot = Some(match *slot {
                Some((lo, hi)) => (lo.min(b.0), hi.max(b.1)),
                None => b,
            });
        }
    }
    println!("instances         (index, part, occurrence, shell, translation, world box)");
    for (i, inst) in scene.instances.iter().enumerate() {
        let part = scene
            .parts
            .get(inst.part as usize)
            .map_or("", |p| p.name.as_str());
        let t = inst.transform.w_axis;
        let shell = inst.shell.map_or(String::from("-"), |s| format!("#{s}"));
        let bbox = boxes[i].map_or(String::from("(no faces)"), |(lo, hi)| {
            format!(
                "[{:.3}, {:.3}, {:.3}] .. [{:.3}, {:.3}, {:.3}]",
                lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
            )
        });
        println!(
            "  {i:>4}  {part:<24} {:<24} {shell:<8} ({:.3}, {:.3}, {:.3})  {bbox}",
            if inst.name.is_empty() {
                "-"
            } else {
                &inst.name
            },
            t.x,
            t.y,
            t.z
        );
    }
}

fn cmd_check(args: &CheckArgs) -> Result<bool, CliError> {
    check_fov(args.fov)?;
    check_pixel_error(args.pixel_error)?;
    if args.views == 0 {
        return Err("--views must be at least 1".into());
    }
    let scene = load(&args.file)?;
    let mut renderer = Renderer::new()?;
    renderer.primitives = args.primitives;
    eprintln!("adapter: {}", renderer.gpu().describe());
    if let Some(dir) = &args.save_failures {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let opts = CheckOptions {
        views: args.views,
        seed: args.seed,
        pixel_error: args.pixel_error,
        size: args.size,
        fov_y: args.fov.to_radians(),
        save_failures: args.save_failures.clone(),
        stress: args.stress,
        narrowed_width: args.narrowed_width,
        ..CheckOptions::default()
    };
    let pb = ProgressBar::new(args.views as u64);
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} views {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let variants = opts.variants.clone();
    let header: Vec<String> = variants
        .iter()
        .map(|v| format!("cracks fb={:<3}", v.name()))
        .collect();
    println!(
        "{:>4}  {:>9}  {:>8}  {}  {:>10}",
        "view",
        "triangles",
        "ref grid",
        header.join("  "),
        "growth(6)"
    );
    let report = run_check(&mut renderer, &scene, &opts, |r| {
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
            println!(
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
    println!();
    println!(
        "summary over {} views at {} px pixel error, {}x{}:",
        args.views, args.pixel_error, args.size.0, args.size.1
    );
    for v in &variants {
        let t = report.total(*v);
        println!(
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
            println!(
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
    println!(
        "{}",
        if ok {
            "OK: no crack pixel with fat borders"
        } else {
            "FAIL: crack pixels with fat borders"
        }
    );
    Ok(ok)
}

fn cmd_bench(args: &BenchArgs) -> Result<bool, CliError> {
    use patchwork::lod::LodOptions;
    use patchwork::lod::flythrough::{FlythroughOptions, FrameRecord, plot, run};
    if !args.flythrough {
        return Err("say which benchmark: --flythrough".into());
    }
    check_fov(args.fov)?;
    check_pixel_error(args.pixel_error)?;
    if args.frames < 2 {
        return Err("--frames must be at least 2".into());
    }
    if !(args.budget_ms.is_finite() && args.budget_ms > 0.0) {
        return Err(format!(
            "--budget-ms must be a positive number, not {}",
            args.budget_ms
        )
        .into());
    }
    if let Some(t) = args.target_ms
        && !(t.is_finite() && t > 0.0)
    {
        return Err(format!("--target-ms must be a positive number, not {t}").into());
    }
    let scene = load(&args.file)?;
    let mut renderer = Renderer::new()?;
    renderer.static_arcs = !args.upload_cuts;
    renderer.primitives = args.primitives;
    if let Some(join) = args.strip_joins {
        renderer.strip_join = join;
    }
    eprintln!("adapter: {}", renderer.gpu().describe());
    let opts = FlythroughOptions {
        frames: args.frames,
        size: args.size,
        fov_y: args.fov.to_radians(),
        lod: LodOptions {
            pixel_error: args.pixel_error,
            budget: std::time::Duration::from_secs_f64(args.budget_ms / 1e3),
            ..LodOptions::default()
        },
        target: args
            .target_ms
            .map(|t| std::time::Duration::from_secs_f64(t / 1e3)),
        cracks: !args.no_cracks,
    };
    let pb = ProgressBar::new(args.frames as u64);
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} frames {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let (records, summary) = run(&mut renderer, &scene, &opts, |_| pb.inc(1))?;
    pb.finish_and_clear();
    let mut csv = String::from(FrameRecord::CSV_HEADER);
    csv.push('\n');
    for r in &records {
        csv.push_str(&r.csv_row());
        csv.push('\n');
    }
    png::write_text(&args.csv, &csv)?;
    png::write_rgba(
        &args.plot,
        &plot(&records, args.budget_ms, summary.jump_frame),
    )?;
    let frames = records.len();
    println!(
        "fly-through of {} ({} patches), {frames} frames at {}x{}, budget {} ms, pixel error {}{}",
        args.file.display(),
        scene.patches.len(),
        args.size.0,
        args.size.1,
        args.budget_ms,
        args.pixel_error,
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
        summary.p99_tessellation_ms, args.budget_ms
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
    if let Some(t) = args.target_ms {
        let mean: f64 = records.iter().map(|r| r.frame_ms).sum::<f64>() / frames as f64;
        let tail = &records[frames / 2..];
        let tail_mean = tail.iter().map(|r| r.frame_ms).sum::<f64>() / tail.len() as f64;
        let pe = tail.iter().map(|r| r.pixel_error).sum::<f64>() / tail.len() as f64;
        println!(
            "frame-rate target         {t} ms: achieved mean {mean:.2} ms (second half {tail_mean:.2} ms at pixel error {pe:.2} on average)"
        );
    }
    let crack_free = summary.max_crack_pixels.is_none_or(|m| m == 0);
    if let (Some(max), Some(total)) = (summary.max_crack_pixels, summary.total_crack_pixels) {
        println!("crack pixels              {total} in all, at most {max} in a frame");
    }
    println!("wrote {} and {}", args.csv.display(), args.plot.display());
    Ok(crack_free)
}

fn cmd_view(args: &ViewArgs) -> Result<(), CliError> {
    use patchwork::viewer::{ViewerOptions, run};
    check_fov(args.fov)?;
    check_pixel_error(args.pixel_error)?;
    if !(args.budget_ms.is_finite() && args.budget_ms > 0.0) {
        return Err(format!(
            "--budget-ms must be a positive number, not {}",
            args.budget_ms
        )
        .into());
    }
    if args.frames == Some(0) {
        return Err("--frames must be at least 1".into());
    }
    if !(args.distance.is_finite() && args.distance >= 0.0) {
        return Err(format!("--distance must be a number ≥ 0, not {}", args.distance).into());
    }
    if let Some(k) = args
        .keys
        .iter()
        .find(|k| patchwork::viewer::script_key(k).is_none())
    {
        return Err(format!("--keys: unknown key {k:?}").into());
    }
    if let Some(n) = args.frames
        && args.keys.len() > n
    {
        return Err(format!("--keys: {} keys for {n} frames", args.keys.len()).into());
    }
    let scene = load(&args.file)?;
    let title = args.file.file_name().map_or_else(
        || "patchwork".into(),
        |n| format!("patchwork — {}", n.to_string_lossy()),
    );
    let report = run(
        scene,
        ViewerOptions {
            title,
            size: args.size,
            fov_y: args.fov.to_radians(),
            lod: patchwork::lod::LodOptions {
                pixel_error: args.pixel_error,
                budget: std::time::Duration::from_secs_f64(args.budget_ms / 1e3),
                ..patchwork::lod::LodOptions::default()
            },
            frames: args.frames,
            screenshot: args.screenshot.clone(),
            keys: args.keys.clone(),
            implode: args.implode.then_some(patchwork::viewer::ViewerAnimation {
                by: args.by,
                distance: args.distance,
                frames: args.implode_frames.max(2),
            }),
            primitives: args.primitives,
        },
    )?;
    eprintln!(
        "{} frames ({} presented), {:.1} ms per frame on average",
        report.frames, report.presented, report.mean_frame_ms
    );
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Render(a) => cmd_render(a).map(|()| true),
        Command::Stats(a) => cmd_stats(a).map(|()| true),
        Command::Check(a) => cmd_check(a),
        Command::Export(a) => cmd_export(a).map(|()| true),
        Command::Bench(a) => cmd_bench(a),
        Command::View(a) => cmd_view(a).map(|()| true),
        Command::Implode(a) => cmd_implode(a),
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
