//! The LOD frame loop on a scripted camera path: crack-free in every frame with fat borders,
//! also while the re-tessellation queue is behind; the queue catches up once the camera stops.
//! Cracks are counted at the pixel error asked, and every frame also without fat borders: the
//! control that shows the check sees the cracks they close.

mod common;

use std::time::Duration;

use patchwork::drive::flythrough::{FlythroughOptions, run};
use patchwork::lod::LodOptions;

fn options(frames: usize, budget: Duration) -> FlythroughOptions {
    FlythroughOptions {
        frames,
        size: (512, 384),
        fov_y: 45f64.to_radians(),
        ortho: false,
        lod: LodOptions {
            budget,
            ..LodOptions::default()
        },
        target: None,
        cracks: true,
    }
}

#[test]
fn every_frame_is_crack_free_while_the_queue_is_behind() {
    let mut renderer = common::renderer();
    for (file, frames) in [("teapot.bpt", 60), ("NIST_MBE_PMI_11.stp", 40)] {
        let scene = common::load(file);
        // A budget too small for more than one patch per frame: the queue falls behind.
        let (records, summary) = run(
            &mut renderer,
            &scene,
            &options(frames, Duration::from_nanos(1)),
            |_| {},
        )
        .expect("rendering works");
        assert!(
            records.iter().any(|r| r.queue_left > 0),
            "{file}: the queue never fell behind, the test proves nothing"
        );
        assert!(
            records
                .iter()
                .any(|r| r.max_error_px > r.pixel_error * 1.01),
            "{file}: no frame was drawn coarser than asked"
        );
        let off: usize = records.iter().filter_map(|r| r.crack_pixels_off).sum();
        eprintln!("{file}: {off} crack pixels without fat borders over {frames} frames");
        assert!(
            off > 0,
            "{file}: no crack without fat borders in any frame: the check could not fail"
        );
        for r in &records {
            assert_eq!(r.crack_pixels, Some(0), "{file} frame {}: {r:?}", r.frame);
            // Past the budget a frame still makes progress: one patch, or one per worker
            // while the cost per patch is not yet measured.
            assert!(
                r.retessellated <= rayon::current_num_threads().max(1),
                "{file}: budget overrun {r:?}"
            );
        }
        // Once the camera holds still after the jump, one patch per frame catches up.
        assert!(
            summary.converge_frames.is_some(),
            "{file}: never converged: {:?}",
            records.last()
        );
    }
}

#[test]
fn with_a_budget_to_spare_the_jump_converges_at_once() {
    let mut renderer = common::renderer();
    let scene = common::teapot();
    // A budget no frame reaches (32 patches re-tessellate in a few ms): what is checked is the
    // queue's rule, not this machine's speed, which a test on a loaded 2-core runner cannot
    // hold to a wall-clock budget (issue 34). Frame times at the 40 ms budget are measured by
    // `patchwork bench --flythrough` and benches/frame.rs.
    let (records, summary) = run(
        &mut renderer,
        &scene,
        &options(20, Duration::from_secs(60)),
        |_| {},
    )
    .expect("rendering works");
    // Only patches visible in the previous frame are
    // queued (the paper's rule), so a patch the jump newly reveals is refined one frame late:
    // within the pixel error by the second frame after the jump.
    assert!(
        summary.converge_frames.is_some_and(|f| f <= 2),
        "{records:?}"
    );
    // Before the jump the camera moves smoothly: never more than one level (√2) off.
    for r in &records[..summary.jump_frame] {
        assert!(r.max_error_px <= r.pixel_error * 1.5, "{r:?}");
    }
    assert_eq!(summary.max_crack_pixels, Some(0));
    let off: usize = records.iter().filter_map(|r| r.crack_pixels_off).sum();
    assert!(
        off > 0,
        "no crack without fat borders: the check could not fail"
    );
}

/// On a still camera the budget the visible queue leaves goes to patches the last frame did
/// not show: with every patch marked hidden, a new view tessellates nothing (the paper's rule:
/// no work for what was not seen), and the same view again refines all of them.
#[test]
fn a_still_camera_refines_what_the_last_frame_did_not_show() {
    use patchwork::lod::FrameLoop;
    use patchwork::view::{DEFAULT_FOV_Y_DEG, View};
    let scene = common::load("teapot.bpt");
    let (fov, size) = (DEFAULT_FOV_Y_DEG.to_radians(), (512, 384));
    let up = scene.up.vector();
    let far = View::framing(&scene.bounds, up, fov, size);
    let c = scene.bounds.center;
    let near = View::new(c + (far.eye - c) * 0.3, c, up, fov, size, &scene.bounds);
    let options = LodOptions {
        budget: Duration::from_secs(600),
        ..LodOptions::default()
    };
    let mut lod = FrameLoop::new(&scene, &far, options);
    let n = scene.patches.len();
    lod.set_visible(&vec![false; n]);
    let moved = lod.update(&scene, &near);
    assert_eq!(
        (moved.retessellated, moved.ahead),
        (0, 0),
        "a moving camera tessellated hidden patches: {moved:?}"
    );
    let max_px = lod.patch_errors_px().into_iter().fold(0.0f64, f64::max);
    assert!(
        max_px > 0.5 * 1.01,
        "the near view needs nothing finer ({max_px} px): the test proves nothing"
    );
    let still = lod.update(&scene, &near);
    assert!(
        still.ahead > 0 && still.ahead == still.retessellated && still.queue_left == 0,
        "{still:?}"
    );
    let worst = lod.patch_errors_px().into_iter().fold(0.0f64, f64::max);
    assert!(
        worst <= 0.5 * (1.0 + 1e-9),
        "still {worst} px after the still frame"
    );
}
