//! `patchwork stats`: tessellate for a view and print the figures (and the worst faces, the
//! placed solids).

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use glam::DVec3;

use serde_json::{Value, json};

use patchwork::check::fidelity::{FaceFidelity, measure_meshes_with};
use patchwork::model::{Scene, UpAxis, bounding_box};
use patchwork::tessellate::{MeshStats, PatchMesh, tessellate_scene, tessellate_scene_tolerance};
use patchwork::view::{Projection, View};

use super::load_built;
use crate::args::{Camera, CameraArgs};
use crate::error::CliError;
use crate::out::{self, data};

#[derive(Args, Debug)]
pub struct StatsArgs {
    /// Model files (`-` reads stdin, with --format); several: one block (one JSON object in
    /// an array) per file.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    #[command(flatten)]
    camera: CameraArgs,
    /// Print the placed solids / shells (instances): part, occurrence, shell, world bounding box
    /// (the names --only and --hide take).
    #[arg(long, visible_alias = "list-parts")]
    parts: bool,
    /// How many of the worst trimmed faces to name (error measured against the trimmed face).
    #[arg(long, default_value_t = 5)]
    faces: usize,
    /// Tessellate every face to this absolute tolerance instead of the view's pixel error
    /// (model units: millimetres for STEP), as `export --tolerance` does: the figures then
    /// speak of the same mesh an exporter writes (tools/occt_fidelity.py --stats compares them
    /// with Open CASCADE's judgement of that mesh).
    #[arg(long)]
    tolerance: Option<f64>,
    /// What pixel X,Y (column, row from the top left) of `render`'s image at the same camera
    /// flags shows: part, face (STEP / IGES entity id), surface type and the 3-D point under
    /// the pixel's centre (`nothing` over the background); repeated, also the distance from
    /// the pick before. A pixel outside the image is an error.
    #[arg(
        long,
        value_name = "X,Y",
        value_parser = super::pick::parse_pixel,
        allow_hyphen_values = true
    )]
    pick: Vec<(i64, i64)>,
}

pub fn run(args: &StatsArgs) -> Result<bool, CliError> {
    super::for_each_file(&args.files, |file| Ok((true, run_one(args, file)?)))
}

/// One file's figures: printed as text, returned as JSON.
fn run_one(args: &StatsArgs, file: &Path) -> Result<Value, CliError> {
    let t_load = Instant::now();
    let scene = load_built(file, &args.cache)?;
    let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
    let camera = args.camera.validate()?;
    let view = camera.view(&scene)?;
    let tolerance = match args.tolerance {
        Some(t) if !(t.is_finite() && t > 0.0) => {
            return Err(CliError::NotPositive {
                flag: "--tolerance",
                value: t,
            });
        }
        t => t,
    };
    let run = || match tolerance {
        Some(t) => tessellate_scene_tolerance(&scene, t),
        None => tessellate_scene(&scene, &view, camera.pixel_error),
    };
    // The thread pool started before the timed run (a whole warm-up tessellation cost a
    // large board seconds, as long as the run it timed).
    rayon::broadcast(|_| ());
    let t0 = Instant::now();
    let meshes = run();
    let dt = t0.elapsed();
    let s = MeshStats::of(&meshes);
    let faces = measure_meshes_with(&scene, &meshes, &super::Bar::default());
    let mut report = json_report(
        args, file, &scene, &view, &camera, &s, &faces, &meshes, load_ms, dt,
    );
    // `--pick`: printed after the figures (what `render` draws: the view's tessellation,
    // whatever --tolerance asked here).
    let picks = || -> Result<Option<Value>, CliError> {
        if args.pick.is_empty() {
            return Ok(None);
        }
        let drawn;
        let shown = match tolerance {
            Some(_) => {
                drawn = tessellate_scene(&scene, &view, camera.pixel_error);
                &drawn
            }
            None => &meshes,
        };
        super::pick::run(&scene, shown, &view, &args.pick).map(Some)
    };
    if out::json() {
        if let Some(p) = picks()? {
            report["picks"] = p;
        }
        return Ok(report);
    }
    data!("file              {}", file.display());
    data!("load              {load_ms:.0} ms");
    let (lo, hi) = scene.bbox;
    let unit = scene.unit.unwrap_or("model units (the format states none)");
    data!(
        "bounding box      [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}] {unit}",
        lo.x,
        lo.y,
        lo.z,
        hi.x,
        hi.y,
        hi.z
    );
    let (c, size) = ((lo + hi) * 0.5, hi - lo);
    data!("centre            {:.4}, {:.4}, {:.4}", c.x, c.y, c.z);
    data!(
        "size              {:.4} x {:.4} x {:.4} (diagonal {:.4})",
        size.x,
        size.y,
        size.z,
        scene.bbox_diagonal()
    );
    data!("up axis           {}", up_name(scene.up));
    data!("patches           {}", s.patches);
    data!("triangles         {}", s.triangles);
    data!("vertices          {}", s.vertices);
    data!("border vertices   {}", s.border_vertices);
    match tolerance {
        Some(t) => data!("tolerance         {t} {unit} (every face; --tolerance)"),
        None => data!("pixel error       {} px", camera.pixel_error),
    }
    data!(
        "eps range         {:.3e} .. {:.3e} (object units)",
        s.eps_min,
        s.eps_max
    );
    data!(
        "worst error/eps   {:.3} (the tessellator's own samples)",
        s.worst_error_ratio
    );
    if let Some((patch, ratio, stop)) = s.worst_stopped {
        data!(
            "budget stops      {} patches stopped at their work budget short of eps (worst: \
             {}, error/eps {ratio:.3}, stopped by {stop})",
            s.stopped,
            patch_name(&scene, patch)
        );
    }
    if !faces.is_empty() {
        let t = Trimmed::of(&faces);
        data!(
            "trimmed error/eps {:.3} (against the trimmed faces, {} samples; {} \
             outside their trim by more than eps; {} face samples, {} \
             farther than eps from the mesh)",
            faces[0].1.ratio(),
            t.samples,
            t.outside,
            t.face_samples,
            t.uncovered
        );
        if let Some((n, f)) = t.edges_off {
            data!(
                "edges off faces   {n} faces whose own edge curves lie farther than eps off their \
                 surface, the mesh following the edges (worst: face #{}, {:.4} = {:.3} eps)",
                f.face,
                f.edge_offset,
                f.edge_offset / f.eps.max(f64::MIN_POSITIVE)
            );
        }
        for (patch, f) in faces.iter().take(args.faces) {
            data!(
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
    data!(
        "placed solids     {} ({} parts)",
        scene.instances.len(),
        scene.parts.len()
    );
    if !scene.skipped.is_empty() {
        data!("skipped faces     {}", scene.skipped.len());
        for f in scene.skipped.iter().take(10) {
            data!("  face #{}: {}", f.face, f.reason);
        }
        if scene.skipped.len() > 10 {
            data!("  …");
        }
    }
    data!(
        "tessellation      {:.2} ms ({} threads)",
        dt.as_secs_f64() * 1e3,
        rayon::current_num_threads()
    );
    data!(
        "eye               {:.3},{:.3},{:.3}",
        view.eye.x,
        view.eye.y,
        view.eye.z
    );
    match view.projection {
        Projection::Perspective => data!(
            "projection        perspective, {:.1}° vertical field of view",
            view.fov_y.to_degrees()
        ),
        Projection::Orthographic { height } => {
            data!("projection        orthographic, {height:.4} units tall")
        }
    }
    if out::text() {
        print_memory(&scene, &s);
        if args.parts {
            print_parts(&scene, &meshes);
        }
    }
    if let Some(p) = picks()? {
        report["picks"] = p;
    }
    Ok(report)
}

fn up_name(up: UpAxis) -> &'static str {
    match up {
        UpAxis::Y => "+y",
        UpAxis::Z => "+z",
    }
}

/// Totals of the trimmed-face fidelity measure.
struct Trimmed<'a> {
    samples: usize,
    outside: usize,
    face_samples: usize,
    uncovered: usize,
    /// Faces whose edges lie more than ε off their surface: how many, and the worst.
    edges_off: Option<(usize, &'a FaceFidelity)>,
}

impl Trimmed<'_> {
    fn of(faces: &[(u32, FaceFidelity)]) -> Trimmed<'_> {
        let off = || faces.iter().map(|f| &f.1).filter(|f| f.edge_offset > f.eps);
        let worst =
            off().max_by(|a, b| (a.edge_offset / a.eps).total_cmp(&(b.edge_offset / b.eps)));
        Trimmed {
            edges_off: worst.map(|w| (off().count(), w)),
            samples: faces.iter().map(|f| f.1.samples).sum(),
            outside: faces.iter().map(|f| f.1.outside).sum(),
            face_samples: faces.iter().map(|f| f.1.face_samples).sum(),
            uncovered: faces.iter().map(|f| f.1.uncovered).sum(),
        }
    }
}

fn vec3(v: DVec3) -> Value {
    json!([v.x, v.y, v.z])
}

/// Everything the text report says, as one JSON object (`stats --json`).
#[allow(clippy::too_many_arguments)]
fn json_report(
    args: &StatsArgs,
    file: &Path,
    scene: &Scene,
    view: &View,
    camera: &Camera,
    s: &MeshStats,
    faces: &[(u32, FaceFidelity)],
    meshes: &[PatchMesh],
    load_ms: f64,
    dt: std::time::Duration,
) -> Value {
    let (lo, hi) = scene.bbox;
    let trimmed = (!faces.is_empty()).then(|| {
        let t = Trimmed::of(faces);
        json!({
            "error_ratio": faces[0].1.ratio(),
            "samples": t.samples,
            "outside": t.outside,
            "face_samples": t.face_samples,
            "uncovered": t.uncovered,
            "edges_off_surface": t.edges_off.map(|(n, f)| json!({
                "faces": n,
                "worst_face": f.face,
                "offset": f.edge_offset,
                "offset_ratio": f.edge_offset / f.eps.max(f64::MIN_POSITIVE),
            })),
            "worst_faces": faces.iter().take(args.faces).map(|(patch, f)| json!({
                "face": f.face,
                "surface": f.surface,
                "error_ratio": f.ratio(),
                "outside": f.outside,
                "missing_ratio": f.missing / f.eps.max(f64::MIN_POSITIVE),
                "patch": patch,
            })).collect::<Vec<_>>(),
        })
    });
    let m = scene.memory();
    let mut report = json!({
        "file": file.display().to_string(),
        "load_ms": load_ms,
        "bbox": { "min": vec3(lo), "max": vec3(hi) },
        "centre": vec3((lo + hi) * 0.5),
        "size": vec3(hi - lo),
        "diagonal": scene.bbox_diagonal(),
        "up": up_name(scene.up),
        "unit": scene.unit,
        "patches": s.patches,
        "triangles": s.triangles,
        "vertices": s.vertices,
        "border_vertices": s.border_vertices,
        "pixel_error": args.tolerance.is_none().then_some(camera.pixel_error),
        "tolerance": args.tolerance,
        "eps_min": s.eps_min,
        "eps_max": s.eps_max,
        "worst_error_ratio": s.worst_error_ratio,
        "budget_stops": s.stopped,
        "worst_budget_stop": s.worst_stopped.map(|(patch, ratio, stop)| json!({
            "patch": patch, "name": patch_name(scene, patch), "error_ratio": ratio,
            "budget": stop.to_string(),
        })),
        "trimmed": trimmed,
        "instances": scene.instances.len(),
        "parts": scene.parts.len(),
        "skipped_faces": scene.skipped.iter()
            .map(|f| json!({ "face": f.face, "reason": f.reason }))
            .collect::<Vec<_>>(),
        "tessellation_ms": dt.as_secs_f64() * 1e3,
        "threads": rayon::current_num_threads(),
        "eye": vec3(view.eye),
        "target": vec3(view.target),
        "projection": match view.projection {
            Projection::Perspective => json!({
                "kind": "perspective",
                "fov_y_deg": view.fov_y.to_degrees(),
            }),
            Projection::Orthographic { height } => json!({
                "kind": "orthographic",
                "height": height,
            }),
        },
        "memory": {
            "scene_bytes": m.total(),
            "mesh_bytes": s.bytes,
            "peak_rss_bytes": patchwork::util::peak_rss_bytes(),
        },
    });
    if args.parts {
        report["instance_list"] = instance_boxes(scene, meshes)
            .into_iter()
            .zip(&scene.instances)
            .map(|(bbox, inst)| {
                json!({
                    "name": inst.name,
                    "part": scene.parts.get(inst.part as usize).map(|p| p.name.as_str()),
                    "shell": inst.shell,
                    "translation": vec3(inst.transform.w_axis.truncate()),
                    "bbox": bbox.map(|(lo, hi)| json!({ "min": vec3(lo), "max": vec3(hi) })),
                })
            })
            .collect();
    }
    report
}

/// Memory: the scene's and the tessellation's own accounting (capacities; see
/// `model::memory` and `PatchMesh::mem_bytes` for what is counted), per patch and per
/// triangle, and the process's resident peak.
fn print_memory(scene: &Scene, meshes: &MeshStats) {
    let m = scene.memory();
    let per = |b: usize, n: usize| b as f64 / n.max(1) as f64;
    let mib = |b: usize| b as f64 / (1024.0 * 1024.0);
    crate::out::outln!(
        "scene memory      {:.1} MiB: {:.0} B/patch (patch structs {:.0}, surfaces {:.0}, other {:.0})",
        mib(m.total()),
        per(m.total(), scene.patches.len()),
        per(m.patches, scene.patches.len()),
        per(m.surfaces, scene.patches.len()),
        per(m.other, scene.patches.len())
    );
    crate::out::outln!(
        "mesh memory       {:.1} MiB: {:.0} B/patch, {:.1} B/triangle (this view's tessellation)",
        mib(meshes.bytes),
        per(meshes.bytes, meshes.patches),
        per(meshes.bytes, meshes.triangles)
    );
    match patchwork::util::peak_rss_bytes() {
        Some(peak) => crate::out::outln!(
            "peak RSS          {:.1} MiB (the whole process so far: load, the tessellation, the fidelity check)",
            mib(peak as usize)
        ),
        None => crate::out::outln!("peak RSS          (not known on this system)"),
    }
}

/// World box of each instance's tessellation (`None`: no faces).
fn instance_boxes(scene: &Scene, meshes: &[PatchMesh]) -> Vec<Option<(DVec3, DVec3)>> {
    let mut boxes: Vec<Option<(DVec3, DVec3)>> = vec![None; scene.instances.len()];
    for (p, m) in scene.patches.iter().zip(meshes) {
        let Some(b) = bounding_box(m.positions.iter().map(|v| v.as_dvec3())) else {
            continue;
        };
        if let Some(slot) = boxes.get_mut(p.instance as usize) {
            *slot = Some(match *slot {
                Some((lo, hi)) => (lo.min(b.0), hi.max(b.1)),
                None => b,
            });
        }
    }
    boxes
}

/// The placed solids / shells: index, part, occurrence path, shell, translation, world box
/// (of the tessellation).
fn print_parts(scene: &Scene, meshes: &[PatchMesh]) {
    let boxes = instance_boxes(scene, meshes);
    crate::out::outln!(
        "instances         (index, part, occurrence, shell, translation, world box)"
    );
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
        crate::out::outln!(
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

/// `patch P` and, for a trimmed face, its entity id.
fn patch_name(scene: &patchwork::model::Scene, patch: u32) -> String {
    match scene.patches.get(patch as usize).map(|p| &p.surface) {
        Some(patchwork::model::PatchSurface::Trimmed(f)) => {
            format!("patch {patch}, face #{}", f.id)
        }
        _ => format!("patch {patch}"),
    }
}
