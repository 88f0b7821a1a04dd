//! `patchwork stats`: tessellate for a view and print the figures (and the worst faces, the
//! placed solids).

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use glam::DVec3;

use patchwork::check::fidelity::measure_meshes;
use patchwork::model::{Scene, bounding_box};
use patchwork::tessellate::{MeshStats, PatchMesh, tessellate_scene};

use super::load_built;
use crate::args::CameraArgs;
use crate::error::CliError;

#[derive(Args, Debug)]
pub struct StatsArgs {
    file: PathBuf,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    #[command(flatten)]
    camera: CameraArgs,
    /// Print the placed solids / shells (instances): part, occurrence, shell, world bounding box.
    #[arg(long)]
    parts: bool,
    /// How many of the worst trimmed faces to name (error measured against the trimmed face).
    #[arg(long, default_value_t = 5)]
    faces: usize,
}

pub fn run(args: &StatsArgs) -> Result<(), CliError> {
    let t_load = Instant::now();
    let scene = load_built(&args.file, &args.cache)?;
    let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
    let camera = args.camera.validate()?;
    let view = camera.view(&scene)?;
    // Warm-up run (thread pool start), then the timed one.
    let _ = tessellate_scene(&scene, &view, camera.pixel_error);
    let t0 = Instant::now();
    let meshes = tessellate_scene(&scene, &view, camera.pixel_error);
    let dt = t0.elapsed();
    let s = MeshStats::of(&meshes);
    println!("file              {}", args.file.display());
    println!("load              {load_ms:.0} ms");
    println!("patches           {}", s.patches);
    println!("triangles         {}", s.triangles);
    println!("vertices          {}", s.vertices);
    println!("border vertices   {}", s.border_vertices);
    println!("pixel error       {} px", camera.pixel_error);
    println!(
        "eps range         {:.3e} .. {:.3e} (object units)",
        s.eps_min, s.eps_max
    );
    println!(
        "worst error/eps   {:.3} (the tessellator's own samples)",
        s.worst_error_ratio
    );
    let faces = measure_meshes(&scene, &meshes);
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
    print_memory(&scene, &s);
    if args.parts {
        print_parts(&scene, &meshes);
    }
    Ok(())
}

/// Memory: the scene's and the tessellation's own accounting (capacities; see
/// `model::memory` and `PatchMesh::mem_bytes` for what is counted), per patch and per
/// triangle, and the process's resident peak.
fn print_memory(scene: &Scene, meshes: &MeshStats) {
    let m = scene.memory();
    let per = |b: usize, n: usize| b as f64 / n.max(1) as f64;
    let mib = |b: usize| b as f64 / (1024.0 * 1024.0);
    println!(
        "scene memory      {:.1} MiB: {:.0} B/patch (patch structs {:.0}, surfaces {:.0}, other {:.0})",
        mib(m.total()),
        per(m.total(), scene.patches.len()),
        per(m.patches, scene.patches.len()),
        per(m.surfaces, scene.patches.len()),
        per(m.other, scene.patches.len())
    );
    println!(
        "mesh memory       {:.1} MiB: {:.0} B/patch, {:.1} B/triangle (this view's tessellation)",
        mib(meshes.bytes),
        per(meshes.bytes, meshes.patches),
        per(meshes.bytes, meshes.triangles)
    );
    match patchwork::util::peak_rss_bytes() {
        Some(peak) => println!(
            "peak RSS          {:.1} MiB (the whole process so far: load, two tessellations, the fidelity check)",
            mib(peak as usize)
        ),
        None => println!("peak RSS          (not known on this system)"),
    }
}

/// The placed solids / shells: index, part, occurrence path, shell, translation, world box
/// (of the tessellation).
fn print_parts(scene: &Scene, meshes: &[PatchMesh]) {
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
