//! One point of the scale benchmark (`patchwork bench --scale`, issue 19): a model loaded
//! from its file, tessellated for the first view, drawn, then driven along the fly-through's
//! camera path ([`super::flythrough::camera_path`]) through [`crate::frame::step`], with what
//! each stage cost in time and memory.
//!
//! The models are grids of Utah teapots (N × N copies of `models/teapot.bpt`'s 32 patches,
//! `GRID_SPACING` apart; 32·N² patches) and any file `prep::load` reads (STEP assemblies).
//! A grid is written as a real `.bpt` file first ([`write_grid`], streamed) and loaded through
//! [`crate::prep::load`] like any other file: reading and parsing the text is part of what is
//! measured. The file is written just before it is read, so it is read from the page cache —
//! the warm-cache load time, not a cold disk's.
//!
//! Memory: the process's resident peak (`VmHWM`, [`crate::util::peak_rss_bytes`]) after
//! loading and at the end, and the structures' own accounting ([`crate::model::Scene::memory`],
//! [`crate::lod::FrameLoop::memory`]). A peak is only the point's own when the point runs in
//! a fresh process: the binary runs each point in a child of itself.
//!
//! Per frame: CPU time (the frame less its GPU wait) and bytes uploaded, from
//! [`crate::frame::StepResult`], averaged over the run.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::DVec3;

use super::flythrough::{FrameRecord, camera_path, jump_frames, summarize};
use crate::check::crack::CheckError;
use crate::frame::{FrameState, StepOptions, step};
use crate::io::LoadError;
use crate::isolate::isolated;
use crate::lod::LodOptions;
use crate::model::BezierPatch;
use crate::render::{RenderOptions, Renderer};
use crate::util::{peak_rss_bytes, rss_bytes};

/// The Utah teapot (32 bicubic patches), the grid's unit.
pub(crate) const TEAPOT_BPT: &str = include_str!("../../models/teapot.bpt");

/// Distance between neighbouring teapots of a grid (the teapot is about 6.4 × 4 × 3.2 units).
pub(crate) const GRID_SPACING: f64 = 8.0;

/// The sweep's grid sizes N: 1 152, 10 368, 100 352 and 1 002 528 patches.
pub const DEFAULT_GRID_SIZES: [usize; 4] = [6, 18, 56, 177];

/// The teapot's patches.
pub fn teapot() -> Result<Vec<BezierPatch>, LoadError> {
    crate::io::bpt::parse(TEAPOT_BPT.as_bytes(), Path::new("models/teapot.bpt"))
}

/// Writes an `n × n` grid of copies of `base`, `spacing` apart in x and y, as a `.bpt` file
/// (`base.len() · n²` patches, streamed: one patch in memory at a time). Copy (i, j) is
/// `base` moved by (spacing·i, spacing·j, 0); its patches are consecutive, copies in row order.
pub fn write_grid(
    path: &Path,
    base: &[BezierPatch],
    n: usize,
    spacing: f64,
) -> std::io::Result<()> {
    let mut out = crate::io::atomic::AtomicFile::create(path)?;
    let copies = (0..n).flat_map(|i| (0..n).map(move |j| (i, j)));
    let patches = copies.flat_map(|(i, j)| {
        let offset = DVec3::new(spacing * i as f64, spacing * j as f64, 0.0);
        base.iter().map(move |p| {
            let (du, dv) = p.degree();
            let moved = p.control_points().iter().map(|c| *c + offset).collect();
            BezierPatch::new(du, dv, moved)
        })
    });
    let mut failed = None;
    let valid = patches.map_while(|p| match p {
        Ok(p) => Some(p),
        Err(e) => {
            failed = Some(e);
            None
        }
    });
    crate::io::bpt::write(&mut out, base.len() * n * n, valid)?;
    if let Some(e) = failed {
        return Err(std::io::Error::other(format!(
            "a moved patch is invalid: {e}"
        )));
    }
    out.commit()
}

/// What a point loads.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// An N × N teapot grid ([`write_grid`]).
    Grid(usize),
    /// A model file.
    File(PathBuf),
}

impl Source {
    /// How the point is named in tables: `teapots 6x6` or the file's name.
    pub fn label(&self) -> String {
        match self {
            Source::Grid(n) => format!("teapots {n}x{n}"),
            Source::File(p) => p
                .file_name()
                .map_or_else(|| p.display().to_string(), |f| f.to_string_lossy().into()),
        }
    }
}

/// Settings of a point.
#[derive(Clone, Debug)]
pub struct ScaleOptions {
    /// Frames of the camera path (the jump comes at 65 %, [`jump_frames`]).
    pub frames: usize,
    pub size: (u32, u32),
    pub fov_y: f64,
    pub lod: LodOptions,
    /// Where a grid's `.bpt` file is written (and removed once loaded).
    pub work_dir: PathBuf,
}

/// One point's figures (one table row). Times in milliseconds, memory in bytes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScalePoint {
    pub model: String,
    pub patches: usize,
    /// `prep::load`: reading, parsing and preparing the file.
    pub load_ms: f64,
    /// Time to the first frame after loading: every patch tessellated for the first view,
    /// the first upload, and frame 0 drawn.
    pub first_frame_ms: f64,
    /// Of which the first tessellation and the first upload.
    pub tessellate_ms: f64,
    pub upload_ms: f64,
    /// Whole frames (update, upload when changed, draw, ID readback): median and largest.
    pub frame_p50_ms: f64,
    pub frame_max_ms: f64,
    /// Mean re-tessellation time per frame (within the budget).
    pub retessellate_ms: f64,
    /// Mean CPU time per frame (the frame less its GPU wait; `None`: no frame drawn).
    pub cpu_ms: Option<f64>,
    /// Mean bytes uploaded per frame (`None`: no frame drawn).
    pub uploaded_bytes: Option<u64>,
    pub frames: usize,
    pub jump_frame: usize,
    /// Frames from the jump until every visible patch is within the pixel error (the jump
    /// frame counts as 1); `None`: not within the run.
    pub converge_frames: Option<usize>,
    /// Triangles in the frustum at frame 0 and at the last frame.
    pub triangles_first: usize,
    pub triangles_last: usize,
    /// [`crate::model::Scene::memory`].
    pub scene_bytes: usize,
    /// [`crate::lod::FrameLoop::memory`] after the first tessellation and at the end (with
    /// cached levels).
    pub lod_bytes_first: usize,
    pub lod_bytes_last: usize,
    /// Resident size when the point starts (the renderer made, nothing loaded): what the
    /// process costs without a model.
    pub rss_start_bytes: Option<u64>,
    /// Resident peak after loading, after the first tessellation, and at the end of the run.
    pub rss_load_bytes: Option<u64>,
    pub rss_tessellate_bytes: Option<u64>,
    pub peak_rss_bytes: Option<u64>,
    /// Why the upload or the frames stopped (a panic inside wgpu, e.g. a buffer larger than
    /// the device allows); the load and first-tessellation figures still hold, the frame
    /// figures are zero.
    pub failure: Option<String>,
}

/// A point and the frames it was measured on.
#[derive(Clone, Debug)]
pub struct PointRun {
    pub point: ScalePoint,
    pub records: Vec<FrameRecord>,
}

/// Why a point could not be measured.
#[derive(Debug, thiserror::Error)]
pub enum ScaleError {
    #[error("writing the teapot grid {}: {source}", .path.display())]
    Grid {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Load(#[from] LoadError),
    #[error(transparent)]
    Frame(#[from] CheckError),
}

/// Measures one point (see the module doc); `on_stage` hears each stage as it begins
/// (`"write"`, `"load"`, `"tessellate"`, `"frames"`), for progress. A panic while uploading
/// or drawing is caught and recorded in [`ScalePoint::failure`].
pub fn run_point(
    renderer: &mut Renderer,
    source: &Source,
    opts: &ScaleOptions,
    mut on_stage: impl FnMut(&str),
) -> Result<PointRun, ScaleError> {
    let rss_start_bytes = rss_bytes();
    let path = match source {
        Source::Grid(n) => {
            on_stage("write");
            let path = opts.work_dir.join(format!("teapots-{n}x{n}.bpt"));
            let written = teapot()
                .map_err(|e| std::io::Error::other(e.to_string()))
                .and_then(|base| write_grid(&path, &base, *n, GRID_SPACING));
            if let Err(source) = written {
                let _ = std::fs::remove_file(&path);
                return Err(ScaleError::Grid { path, source });
            }
            path
        }
        Source::File(p) => p.clone(),
    };
    on_stage("load");
    let t0 = Instant::now();
    let loaded = crate::prep::load(&path);
    let load_ms = ms(t0);
    if matches!(source, Source::Grid(_)) {
        let _ = std::fs::remove_file(&path);
    }
    let scene = loaded?;
    let rss_load_bytes = peak_rss_bytes();
    let scene_bytes = scene.memory().total();

    on_stage("tessellate");
    let n = opts.frames.max(1);
    let first = camera_path(&scene, 0, n, opts.fov_y, opts.size);
    let t0 = Instant::now();
    let mut state = FrameState::new(&scene, &first, opts.lod);
    let tessellate_ms = ms(t0);
    let lod_bytes_first = state.lod.memory().total();
    let rss_tessellate_bytes = peak_rss_bytes();

    // Upload and frames: a scene too big for the device (a buffer past its limits) or a panic
    // inside wgpu ends the point, recorded, rather than the process.
    on_stage("frames");
    let mut records = Vec::with_capacity(n);
    let mut upload_ms = 0.0;
    let drawn = isolated(|| -> Result<(), CheckError> {
        state.upload(renderer)?;
        upload_ms = state.upload_ms;
        let step_opts = StepOptions {
            draw: RenderOptions::default(),
            ..StepOptions::default()
        };
        for i in 0..n {
            let view = camera_path(&scene, i, n, opts.fov_y, opts.size);
            let r = step(renderer, &scene, &mut state, &view, &step_opts)?;
            records.push(FrameRecord::of(i, &r, state.lod.options.pixel_error));
        }
        Ok(())
    });
    let failure = match drawn {
        Ok(Ok(())) => None,
        // Too big for the device (a buffer past its limit): recorded, like a panic.
        Ok(Err(CheckError::Render(e))) => Some(e.to_string()),
        Ok(Err(e)) => return Err(e.into()),
        Err(panic) => Some(last_line(&panic)),
    };
    let jump_frame = jump_frames(n).1;
    let summary = summarize(&records, tessellate_ms, jump_frame);
    let frame_ms: Vec<f64> = records.iter().map(|r| r.frame_ms).collect();
    let point = ScalePoint {
        model: source.label(),
        patches: scene.patches.len(),
        load_ms,
        first_frame_ms: frame_ms
            .first()
            .map_or(0.0, |f| tessellate_ms + upload_ms + f),
        tessellate_ms,
        upload_ms,
        frame_p50_ms: summary.p50_frame_ms,
        frame_max_ms: frame_ms.iter().copied().fold(0.0, f64::max),
        retessellate_ms: records.iter().fold(0.0, |a, r| a + r.tessellation_ms)
            / records.len().max(1) as f64,
        cpu_ms: (!records.is_empty())
            .then(|| records.iter().map(|r| r.cpu_ms).sum::<f64>() / records.len() as f64),
        uploaded_bytes: (!records.is_empty())
            .then(|| records.iter().map(|r| r.uploaded_bytes).sum::<u64>() / records.len() as u64),
        frames: n,
        jump_frame,
        converge_frames: summary.converge_frames,
        triangles_first: records.first().map_or(0, |r| r.triangles),
        triangles_last: records.last().map_or(0, |r| r.triangles),
        scene_bytes,
        lod_bytes_first,
        lod_bytes_last: state.lod.memory().total(),
        rss_start_bytes,
        rss_load_bytes,
        rss_tessellate_bytes,
        peak_rss_bytes: peak_rss_bytes(),
        failure,
    };
    Ok(PointRun { point, records })
}

/// The last non-empty line of a (wgpu) panic message, where it says what was wrong.
fn last_line(message: &str) -> String {
    message
        .lines()
        .map(str::trim)
        .rfind(|l| !l.is_empty())
        .unwrap_or(message)
        .to_owned()
}

fn ms(t0: Instant) -> f64 {
    t0.elapsed().as_secs_f64() * 1e3
}

/// The sweep's grid sizes that stay within `max_patches` (32·N² each).
pub fn sizes_within(sizes: &[usize], max_patches: usize) -> Vec<usize> {
    sizes
        .iter()
        .copied()
        .filter(|&n| n > 0 && 32 * n * n <= max_patches)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_hold_moved_copies_of_the_teapot_in_order() {
        let base = teapot().expect("teapot");
        assert_eq!(base.len(), 32);
        let dir = std::env::temp_dir().join(format!("patchwork-grid-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("g.bpt");
        write_grid(&path, &base, 3, GRID_SPACING).expect("written");
        let back = crate::io::bpt::read(&path).expect("read");
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(back.len(), 32 * 9);
        // Copy (i, j) = 3 i + j, moved by (8 i, 8 j, 0), exactly.
        for (k, p) in back.iter().enumerate() {
            let (copy, q) = (k / 32, &base[k % 32]);
            let offset = DVec3::new(8.0 * (copy / 3) as f64, 8.0 * (copy % 3) as f64, 0.0);
            assert_eq!(p.degree(), q.degree());
            for (a, b) in p.control_points().iter().zip(q.control_points()) {
                assert_eq!(*a, *b + offset, "patch {k}");
            }
        }
    }

    #[test]
    fn sizes_past_the_limit_are_left_out() {
        assert_eq!(sizes_within(&DEFAULT_GRID_SIZES, 200_000), vec![6, 18, 56]);
        assert_eq!(
            sizes_within(&DEFAULT_GRID_SIZES, 1_002_528),
            vec![6, 18, 56, 177]
        );
        assert_eq!(sizes_within(&[0, 1], 100), vec![1]);
    }
}
