//! An assembly flying together (or apart), driven through [`crate::frame::step`]: one
//! [`crate::anim::Explosion`] offset per group, eased per frame; patches tessellated for where
//! they are drawn; optionally every frame judged against the moved watertight reference, with
//! a fat-borders-off control. `patchwork implode` writes the frames; the viewer's `--implode`
//! loops the same offsets.

use crate::anim::{Explosion, GroupBy, amount, moved_scene};
use crate::check::crack::{CheckError, CrackCounts};
use crate::frame::{FrameState, StepOptions, step};
use crate::lod::LodOptions;
use crate::model::Scene;
use crate::render::{Frame, RenderError, RenderOptions, Renderer};
use crate::view::View;

/// Options of an animation run.
#[derive(Clone, Debug)]
pub struct AnimOptions {
    pub frames: usize,
    /// Explode (assembled → apart) instead of implode.
    pub explode: bool,
    pub by: GroupBy,
    /// Offsets at full explosion, × the model's radius.
    pub distance: f64,
    pub lod: LodOptions,
    /// How frames are drawn (the patch-ID pass is added for the frame loop's visibility).
    pub render: RenderOptions,
    /// Count crack and growth pixels every frame against the moved watertight reference
    /// (not timed).
    pub check: bool,
    /// With `check`: write the check image and crack mask of frames with cracks or growth
    /// here (`frameNNNN-actual.png`, `frameNNNN-diff.png`).
    pub save_failures: Option<std::path::PathBuf>,
}

impl Default for AnimOptions {
    fn default() -> Self {
        AnimOptions {
            frames: 48,
            explode: false,
            by: GroupBy::Parts,
            distance: 1.0,
            lod: LodOptions::default(),
            render: RenderOptions::default(),
            check: false,
            save_failures: None,
        }
    }
}

/// One frame's figures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AnimRecord {
    pub frame: usize,
    /// 0 = assembled, 1 = fully exploded.
    pub amount: f64,
    /// Frame loop update, translation, upload, draw and ID readback.
    pub frame_ms: f64,
    pub tessellation_ms: f64,
    pub retessellated: usize,
    pub triangles: usize,
    /// Largest screen error of the visible patches, pixels.
    pub max_error_px: f64,
    /// With [`AnimOptions::check`]: crack and growth pixels (fat borders as drawn).
    pub cracks: Option<CrackCounts>,
    /// With [`AnimOptions::check`] and fat borders drawn: the control, the same frame's
    /// counts with fat borders off (shows that the check sees the cracks they close).
    pub cracks_off: Option<CrackCounts>,
}

/// The growth an animation frame may show, as a sentence, and whether `c` stays within it.
///
/// Parts (closed solids): no covered pixel farther than the crack check's contour margin + 1
/// from the reference silhouette, as for still views. Patches flying apart: an open patch seen
/// edge-on is a sub-pixel sliver that the pixel reference covers only where it happens to hit
/// a pixel centre, while its fat border (≤ ε wide) covers it continuously, so the tip of the
/// widened sliver reaches pixels the reference misses — at a distance that grows as the tip
/// gets thinner, so no distance bounds it. Bounded instead: at most two such pixels per moving
/// patch (measured: ≤ 9 a frame for the 32 teapot patches, none with fat borders off).
pub fn growth_within_bound(
    c: &CrackCounts,
    by: GroupBy,
    groups: usize,
    pixel_error: f64,
) -> (String, bool) {
    match by {
        GroupBy::Parts => {
            let px = crate::check::crack::contour_margin(pixel_error) as u32 + 1;
            (format!("≤ {px} px out"), c.growth_max_px <= px)
        }
        GroupBy::Patches => {
            let n = 2 * groups;
            (format!("≤ {n} pixels a frame"), c.growth <= n)
        }
    }
}

/// Whether checked frames pass: no crack pixel in any frame when parts (closed solids) move,
/// none in the assembled last frame when patches move (flying patches leave real openings);
/// growth within [`growth_within_bound`] in every frame.
pub fn frames_pass(records: &[AnimRecord], by: GroupBy, groups: usize, pixel_error: f64) -> bool {
    let checked: Vec<CrackCounts> = records.iter().filter_map(|r| r.cracks).collect();
    let growth_ok = checked
        .iter()
        .all(|c| growth_within_bound(c, by, groups, pixel_error).1);
    let cracks_ok = match by {
        GroupBy::Parts => checked.iter().all(|c| c.cracks() == 0),
        GroupBy::Patches => checked.last().is_none_or(|c| c.cracks() == 0),
    };
    growth_ok && cracks_ok
}

/// Runs the animation for a fixed `view`; `on_frame` gets every frame's image and figures
/// (write it, show progress).
pub fn run(
    renderer: &mut Renderer,
    scene: &Scene,
    view: &View,
    opts: &AnimOptions,
    mut on_frame: impl FnMut(&AnimRecord, &Frame) -> Result<(), RenderError>,
) -> Result<Vec<AnimRecord>, CheckError> {
    let n = opts.frames.max(1);
    let explosion = Explosion::new(scene, opts.by, opts.distance);
    let first = moved_scene(scene, &explosion.at(amount(0, n, opts.explode)));
    let mut state = FrameState::new(&first, view, opts.lod);
    let mut records = Vec::with_capacity(n);
    for k in 0..n {
        let a = amount(k, n, opts.explode);
        let offsets = explosion.at(a);
        let r = step(
            renderer,
            scene,
            &mut state,
            view,
            &StepOptions {
                draw: opts.render,
                offsets: Some(&offsets),
                check: opts.check,
                ..StepOptions::default()
            },
        )?;
        if let Some(dir) = &opts.save_failures
            && let Some(v) = r.verdict.as_ref().filter(|v| v.failed())
        {
            v.save(dir, &format!("frame{k:04}"))?;
        }
        let record = AnimRecord {
            frame: k,
            amount: a,
            frame_ms: r.frame_time.as_secs_f64() * 1e3,
            tessellation_ms: r.stats.tessellation.as_secs_f64() * 1e3,
            retessellated: r.stats.retessellated,
            triangles: r.stats.triangles,
            max_error_px: r.max_error_px,
            cracks: r.verdict.map(|v| v.counts),
            cracks_off: r.control,
        };
        on_frame(&record, &r.frame)?;
        records.push(record);
    }
    Ok(records)
}
