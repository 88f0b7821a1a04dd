//! Deterministic fly-through: a recorded camera path (orbit, zoom in close, a sudden jump,
//! then still) driven through the [`FrameLoop`](crate::lod::FrameLoop), with per-frame figures, a summary and a plot.

use std::time::{Duration, Instant};

use glam::DVec3;

use crate::check::crack::CheckError;
use crate::frame::{FrameState, StepOptions, step};
use crate::lod::{InstancingStats, LodMemory, LodOptions, PixelErrorController};
use crate::model::Scene;
use crate::render::{RenderOptions, Renderer};
use crate::view::View;

/// Where the camera is at frame `i` of `n`: orbit half a turn (40 % of the frames), zoom in
/// to half the distance (25 %), jump to the far side at that close distance, and hold
/// still (35 %) so the queue can converge.
pub fn camera_path(scene: &Scene, i: usize, n: usize, fov_y: f64, size: (u32, u32)) -> View {
    let up = scene.up.vector();
    let framing = View::framing(&scene.bounds, up, fov_y, size);
    let centre = scene.bounds.center;
    let d0 = framing.eye.distance(centre);
    let start = (framing.eye - centre).normalize();
    let (orbit_end, zoom_end) = jump_frames(n);
    let t = i as f64;
    let rotate = |dir: DVec3, angle: f64| glam::DQuat::from_axis_angle(up, angle) * dir;
    let close = 0.5;
    let (dir, dist) = if i < orbit_end {
        let s = t / orbit_end as f64;
        (rotate(start, std::f64::consts::PI * s), d0)
    } else if i < zoom_end {
        let s = (t - orbit_end as f64) / (zoom_end - orbit_end) as f64;
        let s = s * s * (3.0 - 2.0 * s);
        (
            rotate(start, std::f64::consts::PI),
            d0 * (1.0 + (close - 1.0) * s),
        )
    } else {
        // The jump: the opposite side, tilted, close.
        let dir = rotate(start, 0.0) + up * 0.3;
        (dir.normalize(), d0 * close)
    };
    View::new(centre + dir * dist, centre, up, fov_y, size, &scene.bounds)
}

/// (first zoom frame, the jump frame) of a path of `n` frames.
pub fn jump_frames(n: usize) -> (usize, usize) {
    let orbit_end = (n * 40 / 100).max(1);
    let zoom_end = (n * 65 / 100).max(orbit_end + 1);
    (orbit_end, zoom_end)
}

/// Settings of a fly-through run.
#[derive(Clone, Debug)]
pub struct FlythroughOptions {
    pub frames: usize,
    pub size: (u32, u32),
    pub fov_y: f64,
    /// Orthographic views along the same path ([`View::orthographic`]: the zoom shrinks the
    /// image's height with the distance).
    pub ortho: bool,
    pub lod: LodOptions,
    /// Frame-rate target mode: pick the pixel error per frame for this frame time.
    pub target: Option<Duration>,
    /// Measure crack pixels every frame (against a watertight reference; not timed).
    pub cracks: bool,
}

/// One frame's figures (one CSV row).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameRecord {
    pub frame: usize,
    /// Whole frame: culling, queue, re-tessellation, upload (when the drawn meshes changed),
    /// draw, ID readback.
    pub frame_ms: f64,
    pub tessellation_ms: f64,
    /// Upload (only the patches that changed, see `frame::StepResult::upload_ms`).
    pub upload_ms: f64,
    /// Render and readback wall time.
    pub draw_ms: f64,
    /// The frame less the time blocked waiting for the GPU (`frame::StepResult::cpu_ms`).
    pub cpu_ms: f64,
    /// Bytes written to the GPU (`frame::StepResult::uploaded_bytes`).
    pub uploaded_bytes: u64,
    pub retessellated: usize,
    pub from_cache: usize,
    /// Trimmed faces whose tessellation held the wanted level (relabelled, not made).
    pub reused: usize,
    pub queue_left: usize,
    /// Of `queue_left`, the trimmed faces still waiting.
    pub trimmed_waiting: usize,
    /// Tessellations made this frame (a shared surface once), the worker time they took
    /// (summed over the workers) and their triangles (`lod::UpdateStats::made`).
    pub made: usize,
    pub made_cpu_ms: f64,
    pub made_triangles: usize,
    /// Of `made`, redone work: levels the loop had made before and dropped.
    pub redone: usize,
    pub redone_cpu_ms: f64,
    /// Screen-space error of the patches visible in this frame, pixels.
    pub max_error_px: f64,
    pub p99_error_px: f64,
    pub triangles: usize,
    /// Pixel error asked for this frame.
    pub pixel_error: f64,
    /// Crack pixels (fat borders on), when measured.
    pub crack_pixels: Option<usize>,
    /// Control: crack pixels of the same frame with fat borders off, when measured (shows
    /// that the check sees the cracks fat borders close).
    pub crack_pixels_off: Option<usize>,
}

impl FrameRecord {
    /// The record of frame `frame`, from what [`step`] reported, at pixel error
    /// `pixel_error`.
    pub fn of(frame: usize, r: &crate::frame::StepResult, pixel_error: f64) -> FrameRecord {
        FrameRecord {
            frame,
            frame_ms: r.frame_time.as_secs_f64() * 1e3,
            tessellation_ms: r.stats.tessellation.as_secs_f64() * 1e3,
            upload_ms: r.upload_ms,
            draw_ms: r.draw_ms,
            cpu_ms: r.cpu_ms,
            uploaded_bytes: r.uploaded_bytes,
            retessellated: r.stats.retessellated,
            from_cache: r.stats.from_cache,
            reused: r.stats.reused,
            queue_left: r.stats.queue_left,
            trimmed_waiting: r.stats.trimmed_left,
            made: r.stats.made,
            made_cpu_ms: r.stats.made_cpu.as_secs_f64() * 1e3,
            made_triangles: r.stats.made_triangles,
            redone: r.stats.redone,
            redone_cpu_ms: r.stats.redone_cpu.as_secs_f64() * 1e3,
            max_error_px: r.max_error_px,
            p99_error_px: r.p99_error_px,
            triangles: r.stats.triangles,
            pixel_error,
            crack_pixels: r.verdict.as_ref().map(|v| v.counts.cracks()),
            crack_pixels_off: r.control.map(|c| c.cracks()),
        }
    }
}

/// Summary of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FlythroughSummary {
    pub initial_ms: f64,
    /// First upload of the drawn meshes, before the first frame (builds static buffers and
    /// strips), and its bytes.
    pub initial_upload_ms: f64,
    pub initial_upload_bytes: u64,
    /// Bytes uploaded per frame: mean and largest.
    pub mean_uploaded_bytes: f64,
    pub max_uploaded_bytes: u64,
    pub p50_cpu_ms: f64,
    pub p99_cpu_ms: f64,
    pub jump_frame: usize,
    /// Wall time from the jump frame until every visible patch is within the pixel error
    /// (`None`: never within the run), and the frames it took.
    pub converge_ms: Option<f64>,
    pub converge_frames: Option<usize>,
    pub p50_frame_ms: f64,
    pub p99_frame_ms: f64,
    pub p99_tessellation_ms: f64,
    pub max_crack_pixels: Option<usize>,
    pub total_crack_pixels: Option<usize>,
    /// Tessellations shared by the placements of a part over the whole run.
    pub instancing: InstancingStats,
    /// After the last frame: shared meshes resident on the GPU, patches drawn as their
    /// placements (instanced parts), and the resident geometry's live bytes (records
    /// included).
    pub shared_meshes: usize,
    pub placed_patches: usize,
    pub resident_bytes: u64,
    /// After the last frame: the frame loop's memory, its cached levels' bytes as the LRU
    /// budget counts them ([`crate::lod::FrameLoop::cached_bytes`]) and the cached levels
    /// evicted for that budget over the run.
    pub lod_memory: LodMemory,
    pub cached_bytes: usize,
    pub evicted: u64,
}

/// Runs the fly-through; `on_frame` sees every record (progress).
pub fn run(
    renderer: &mut Renderer,
    scene: &Scene,
    opts: &FlythroughOptions,
    mut on_frame: impl FnMut(&FrameRecord),
) -> Result<(Vec<FrameRecord>, FlythroughSummary), CheckError> {
    let n = opts.frames.max(1);
    let first =
        camera_path(scene, 0, n, opts.fov_y, opts.size).with_ortho(opts.ortho, &scene.bounds);
    let t0 = Instant::now();
    let mut state = FrameState::new(scene, &first, opts.lod);
    let initial_ms = t0.elapsed().as_secs_f64() * 1e3;
    let mut controller = opts
        .target
        .map(|t| PixelErrorController::new(t, opts.lod.pixel_error, 64.0));
    // Cracks: against the reference for each view, at the pixel error asked, with fat borders
    // as wide as each patch's own ε; the same frame without fat borders is the control.
    let step_opts = StepOptions {
        draw: RenderOptions::default(),
        check: opts.cracks,
        ..StepOptions::default()
    };
    let mut records = Vec::with_capacity(n);
    // GPU buffers are rebuilt only when the drawn meshes change.
    let initial_upload = state.upload(renderer)?;
    let initial_upload_ms = state.upload_ms;
    for i in 0..n {
        let view =
            camera_path(scene, i, n, opts.fov_y, opts.size).with_ortho(opts.ortho, &scene.bounds);
        let r = step(renderer, scene, &mut state, &view, &step_opts)?;
        let pixel_error = state.lod.options.pixel_error;
        let record = FrameRecord::of(i, &r, pixel_error);
        on_frame(&record);
        records.push(record);
        if let Some(c) = controller.as_mut() {
            state.lod.options.pixel_error = c.observe(r.stats.triangles, r.frame_time);
        }
    }
    let mut summary = summarize(&records, initial_ms, jump_frames(n).1);
    summary.initial_upload_ms = initial_upload_ms;
    summary.instancing = state.lod.instancing();
    summary.lod_memory = state.lod.memory();
    summary.cached_bytes = state.lod.cached_bytes();
    summary.evicted = state.lod.evicted();
    if let Some(r) = state.resident() {
        summary.shared_meshes = r.shared_meshes();
        summary.placed_patches = r.placed_patches();
        summary.resident_bytes = r.memory().used_total();
    }
    summary.initial_upload_bytes = initial_upload.uploaded_bytes();
    Ok((records, summary))
}

fn percentile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    values[((values.len() - 1) as f64 * q).round() as usize]
}

/// Summary figures of a run whose camera jumps at `jump_frame`.
pub(crate) fn summarize(
    records: &[FrameRecord],
    initial_ms: f64,
    jump_frame: usize,
) -> FlythroughSummary {
    let mut frame: Vec<f64> = records.iter().map(|r| r.frame_ms).collect();
    let mut tess: Vec<f64> = records.iter().map(|r| r.tessellation_ms).collect();
    let mut cpu: Vec<f64> = records.iter().map(|r| r.cpu_ms).collect();
    let bytes: Vec<u64> = records.iter().map(|r| r.uploaded_bytes).collect();
    let mut converge_ms = None;
    let mut converge_frames = None;
    let mut elapsed = 0.0;
    for r in records.iter().filter(|r| r.frame >= jump_frame) {
        elapsed += r.frame_ms;
        // Within the pixel error (and 1 % slack for rounding of ε levels).
        if r.max_error_px <= r.pixel_error * 1.01 {
            converge_ms = Some(elapsed);
            converge_frames = Some(r.frame - jump_frame + 1);
            break;
        }
    }
    let cracks: Vec<usize> = records.iter().filter_map(|r| r.crack_pixels).collect();
    FlythroughSummary {
        initial_ms,
        initial_upload_ms: 0.0,
        initial_upload_bytes: 0,
        mean_uploaded_bytes: bytes.iter().sum::<u64>() as f64 / bytes.len().max(1) as f64,
        max_uploaded_bytes: bytes.iter().copied().max().unwrap_or(0),
        p50_cpu_ms: percentile(&mut cpu.clone(), 0.5),
        p99_cpu_ms: percentile(&mut cpu, 0.99),
        jump_frame,
        converge_ms,
        converge_frames,
        p50_frame_ms: percentile(&mut frame.clone(), 0.5),
        p99_frame_ms: percentile(&mut frame, 0.99),
        p99_tessellation_ms: percentile(&mut tess, 0.99),
        max_crack_pixels: cracks.iter().copied().max(),
        total_crack_pixels: (!cracks.is_empty()).then(|| cracks.iter().sum()),
        instancing: InstancingStats::default(),
        shared_meshes: 0,
        placed_patches: 0,
        resident_bytes: 0,
        lod_memory: LodMemory::default(),
        cached_bytes: 0,
        evicted: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(frame: usize, ms: f64, err: f64) -> FrameRecord {
        FrameRecord {
            frame,
            frame_ms: ms,
            max_error_px: err,
            pixel_error: 0.5,
            ..FrameRecord::default()
        }
    }

    #[test]
    fn convergence_counts_time_from_the_jump() {
        let r = vec![
            record(0, 10.0, 0.5),
            record(1, 10.0, 3.0), // jump
            record(2, 20.0, 1.0),
            record(3, 30.0, 0.5),
            record(4, 10.0, 0.5),
        ];
        let s = summarize(&r, 0.0, 1);
        assert_eq!(s.converge_frames, Some(3));
        assert_eq!(s.converge_ms, Some(60.0));
        assert_eq!(s.p99_frame_ms, 30.0);
        let never = summarize(&r[..3], 0.0, 1);
        assert_eq!(never.converge_ms, None);
    }
}
