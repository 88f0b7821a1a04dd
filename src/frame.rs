//! One frame of the LOD loop — the only implementation, driven by the viewer, `bench
//! --flythrough` ([`crate::drive::flythrough`]) and `implode` ([`crate::drive::implode`]).
//!
//! Balázs, Guthe and Klein, "Fat Borders" (2004), §4.2: per frame, update the level of detail
//! within the time budget ([`FrameLoop::update`]), upload what changed, draw surfaces and fat
//! borders (each patch's border as wide as its own current ε, so the frame is crack-free while
//! the queue is behind), read the patch-ID buffer back for the next frame's visibility, and
//! report the screen-space errors.
//!
//! The default frame keeps the geometry resident ([`ResidentGeometry`]): only the patches
//! whose tessellation changed are uploaded, and the draw list is rebuilt only when the frame
//! loop's generation moved. An animation moves patches: they are tessellated for where they
//! are drawn (moved bounding spheres) and translated at upload; moved and heat-mapped frames
//! change every mesh's vertices, so they go through [`Renderer::upload`] whole. Optionally the
//! frame is judged against the watertight reference (`crate::check::crack::Judge`), with fat
//! borders as drawn and, as a control, without them.

use std::time::{Duration, Instant};

use glam::DVec3;

use crate::check::crack::{CheckError, CrackCounts, Judge, Verdict, reference_meshes};
use crate::lod::{FrameLoop, LodOptions, UpdateStats};
use crate::model::Scene;
use crate::render::{
    FatBorders, Frame, Geometry, GpuMeshes, RenderError, RenderOptions, Renderer, ResidentGeometry,
    Shading, UploadStats,
};
use crate::tessellate::PatchMesh;
use crate::view::View;

/// Per-view state of the frame loop: the LOD state and what is uploaded. The scene stays
/// immutable; two `FrameState`s over one scene are independent.
#[derive(Debug)]
pub struct FrameState {
    pub lod: FrameLoop,
    /// The default path's geometry, resident between frames (made on first use).
    resident: Option<ResidentGeometry>,
    /// The meshes of the last moved or heat-mapped frame, uploaded whole.
    uploaded: Option<GpuMeshes>,
    /// Milliseconds spent on the last upload.
    pub upload_ms: f64,
}

impl FrameState {
    /// Tessellates every patch for `view` (no budget: the first frame must show something).
    pub fn new(scene: &Scene, view: &View, options: LodOptions) -> FrameState {
        FrameState {
            lod: FrameLoop::new(scene, view, options),
            resident: None,
            uploaded: None,
            upload_ms: 0.0,
        }
    }

    /// Makes the current meshes resident now (e.g. to time the first upload apart from the
    /// first frame); later default frames upload only the patches the LOD changed.
    pub fn upload(&mut self, renderer: &Renderer) -> Result<UploadStats, RenderError> {
        let t0 = Instant::now();
        let resident = self
            .resident
            .get_or_insert_with(|| ResidentGeometry::new(renderer));
        let stats = resident.update(renderer, self.lod.shared_meshes(), self.lod.generation())?;
        self.upload_ms = t0.elapsed().as_secs_f64() * 1e3;
        Ok(stats)
    }

    /// The resident geometry (after the first default frame or [`FrameState::upload`]).
    pub fn resident(&self) -> Option<&ResidentGeometry> {
        self.resident.as_ref()
    }
}

/// What a frame draws, beyond the camera.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepOptions<'a> {
    /// How the frame is drawn (the patch-ID pass is always added, for visibility).
    pub draw: RenderOptions,
    /// Animation: per-patch offsets (indexed like the scene's patches).
    pub offsets: Option<&'a [DVec3]>,
    /// Colour every patch by its screen-space error ([`heat_color`]), lit.
    pub heat_map: bool,
    /// Judge the frame against the watertight reference (not timed).
    pub check: bool,
}

/// What one frame did.
#[derive(Debug)]
pub struct StepResult {
    pub frame: Frame,
    pub stats: UpdateStats,
    /// Update, upload, draw and ID readback (the check is not timed).
    pub frame_time: Duration,
    /// Wall time of the upload: the resident geometry's update (changed patches built and
    /// written, draw list rebuilt), or a whole [`Renderer::upload`] for moved / heat-mapped
    /// frames.
    pub upload_ms: f64,
    /// Wall time of the render: encoding, submission, the GPU's work and the readback of the
    /// colour and patch-ID passes.
    pub draw_ms: f64,
    /// `frame_time` less the time blocked waiting for the GPU (the polls until each pass's
    /// readback buffer is mapped, [`crate::render::RenderStats::gpu_wait`]): the LOD update,
    /// the upload, encoding and submitting the passes, copying the read-back rows and the
    /// visibility pass. (On a software adapter, rasterization that runs at submission on the
    /// calling thread counts as CPU here.)
    pub cpu_ms: f64,
    /// Bytes written to the GPU: changed patches' geometry, static buffers built, indirect
    /// draw arguments ([`UploadStats::uploaded_bytes`]) — or every byte of a whole upload —
    /// plus the uniform block of each pass.
    pub uploaded_bytes: u64,
    /// The resident geometry's update (default frames; `None` for moved / heat-mapped ones).
    pub upload: Option<UploadStats>,
    /// Largest and 99th-percentile screen-space error of the visible patches, pixels.
    pub max_error_px: f64,
    pub p99_error_px: f64,
    /// With [`StepOptions::check`]: the frame as drawn, judged at the asked pixel error.
    pub verdict: Option<Verdict>,
    /// With [`StepOptions::check`] and fat borders drawn: the control, the same frame without
    /// fat borders (shows that the check sees the cracks they close).
    pub control: Option<CrackCounts>,
}

/// Runs one frame for `view` (see the module doc).
pub fn step(
    renderer: &mut Renderer,
    scene: &Scene,
    state: &mut FrameState,
    view: &View,
    opts: &StepOptions<'_>,
) -> Result<StepResult, CheckError> {
    let start = Instant::now();
    let offsets = opts.offsets.filter(|o| o.iter().any(|v| *v != DVec3::ZERO));
    let moved = offsets.map(|o| crate::anim::moved_scene(scene, o));
    let drawn_scene = moved.as_ref().unwrap_or(scene);
    let stats = state.lod.update(drawn_scene, view);
    let t_upload = Instant::now();
    let (geometry, upload, upload_bytes) = if offsets.is_none() && !opts.heat_map {
        let resident = state
            .resident
            .get_or_insert_with(|| ResidentGeometry::new(renderer));
        let u = resident.update(renderer, state.lod.shared_meshes(), state.lod.generation())?;
        (Geometry::Resident(resident), Some(u), u.uploaded_bytes())
    } else {
        let gpu = renderer.upload(&drawn_meshes(&state.lod, offsets, opts.heat_map));
        let bytes = gpu.uploaded_bytes();
        (Geometry::Uploaded(state.uploaded.insert(gpu)), None, bytes)
    };
    let upload_ms = t_upload.elapsed().as_secs_f64() * 1e3;
    state.upload_ms = upload_ms;
    let draw = RenderOptions {
        ids: true,
        shading: if opts.heat_map {
            Shading::Lit
        } else {
            opts.draw.shading
        },
        ..opts.draw
    };
    let t_draw = Instant::now();
    let frame = renderer.render(geometry, view, &draw)?;
    let draw_ms = t_draw.elapsed().as_secs_f64() * 1e3;
    let drawn = renderer.last_render();
    if let Some(v) = frame.visible_ids(scene.patches.len()) {
        state.lod.set_visible(&v);
    }
    let frame_time = start.elapsed();
    let cpu_ms = frame_time.saturating_sub(drawn.gpu_wait).as_secs_f64() * 1e3;
    let (max_error_px, p99_error_px) = state.lod.screen_errors();
    let (verdict, control) = if opts.check {
        // At the pixel error asked: a patch drawn coarser than asked (the queue behind its
        // budget) is still closed by its own, wider, fat borders.
        let pe = state.lod.options.pixel_error;
        let (mut reference, _) = reference_meshes(drawn_scene, view, pe);
        if let Some(o) = offsets {
            reference = crate::anim::translated(reference.iter().enumerate(), o);
        }
        let judge = Judge::new(renderer, &reference, view, pe)?;
        let verdict = judge.count(renderer, geometry, opts.draw.fat_borders)?;
        let control = if opts.draw.fat_borders == FatBorders::Off {
            None
        } else {
            Some(judge.count(renderer, geometry, FatBorders::Off)?.counts)
        };
        (Some(verdict), control)
    } else {
        (None, None)
    };
    Ok(StepResult {
        frame,
        stats,
        frame_time,
        upload_ms,
        draw_ms,
        cpu_ms,
        uploaded_bytes: upload_bytes + drawn.uniform_bytes,
        upload,
        max_error_px,
        p99_error_px,
        verdict,
        control,
    })
}

/// The frame loop's meshes as drawn: translated by their patch's offset, or coloured by
/// their screen-space error.
fn drawn_meshes(lod: &FrameLoop, offsets: Option<&[DVec3]>, heat_map: bool) -> Vec<PatchMesh> {
    let errors = heat_map.then(|| lod.patch_errors_px());
    let asked = lod.options.pixel_error;
    let meshes: Vec<PatchMesh> = lod
        .meshes_with_index()
        .map(|(i, m)| match &errors {
            Some(e) => PatchMesh {
                color: Some(heat_color(e[i], asked)),
                ..m.world().into_owned()
            },
            None => m.world().into_owned(),
        })
        .collect();
    match offsets {
        Some(o) => {
            let indices = lod.meshes_with_index().map(|(i, _)| i);
            crate::anim::translated(indices.zip(meshes.iter()), o)
        }
        None => meshes,
    }
}

/// Heat-map colour of a screen error `e` (pixels) for pixel error `asked`: blue when finer
/// than asked, green on target, yellow to red when coarser (red at 4× the pixel error).
pub fn heat_color(e: f64, asked: f64) -> [f32; 3] {
    let r = (e / asked.max(1e-12)).max(1e-12).log2();
    if r <= 0.0 {
        let t = (-r / 2.0).min(1.0) as f32; // 1/4 of the asked error → pure blue
        [0.1, 0.8 * (1.0 - t) + 0.2 * t, 0.2 + 0.8 * t]
    } else {
        let t = (r / 2.0).min(1.0) as f32;
        [0.2 + 0.8 * t, 0.8 * (1.0 - t) + 0.1, 0.1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heat_colors_run_blue_green_red() {
        let fine = heat_color(0.125, 0.5);
        let on = heat_color(0.5, 0.5);
        let coarse = heat_color(2.0, 0.5);
        assert!(fine[2] > fine[0] && fine[2] > fine[1]);
        assert!(on[1] > on[0] && on[1] > on[2]);
        assert!(coarse[0] > coarse[1] && coarse[0] > coarse[2]);
    }
}
