//! Memory stays flat over many views (issue 21 item 6): 1 000 frames of an assembly
//! (models/as1-oc-214.stp, 96×72) through the frame loop in one process — the camera path of
//! the fly-through (orbit, zoom, jump, still) run twice, so the second 500 views repeat the
//! first 500 — and the resident size (VmRSS) after the last 500 views is within a small
//! margin of the size after the first 500. A leak of 64 KiB per view, made on purpose, shows.

mod common;

use patchwork::drive::flythrough::camera_path;
use patchwork::frame::{FrameState, StepOptions, step};
use patchwork::lod::LodOptions;
use patchwork::util::rss_bytes;

/// Views per round of the camera path.
const ROUND: usize = 500;
const SIZE: (u32, u32) = (96, 72);
/// Growth allowed from the end of the first round to the end of the second.
const MARGIN: u64 = 8 << 20;

/// Runs two rounds of `views` views each; `leak` bytes per view are kept on purpose. Returns
/// VmRSS after the first round and after the second.
fn two_rounds(views: usize, leak: usize) -> (u64, u64) {
    let mut renderer = common::renderer();
    let scene = common::load("as1-oc-214.stp");
    let fov = 45f64.to_radians();
    let options = LodOptions {
        budget: std::time::Duration::from_millis(4),
        ..LodOptions::default()
    };
    let mut state = FrameState::new(&scene, &camera_path(&scene, 0, views, fov, SIZE), options);
    let mut kept: Vec<Vec<u8>> = Vec::new();
    let mut rss = Vec::new();
    for round in 0..2 {
        for i in 0..views {
            let view = camera_path(&scene, i, views, fov, SIZE);
            let r = step(
                &mut renderer,
                &scene,
                &mut state,
                &view,
                &StepOptions::default(),
            )
            .expect("the frame renders");
            assert_eq!(r.frame.width, SIZE.0, "round {round} view {i}");
            if leak > 0 {
                // Touched, so the pages are resident.
                kept.push(vec![1u8; leak]);
            }
        }
        rss.push(rss_bytes().expect("VmRSS readable on Linux"));
    }
    (rss[0], rss[1])
}

#[test]
fn memory_stays_flat_over_a_thousand_views() {
    let t0 = std::time::Instant::now();
    let (first, second) = two_rounds(ROUND, 0);
    let took = t0.elapsed();
    eprintln!(
        "VmRSS after {ROUND} views {:.1} MiB, after {} views {:.1} MiB ({took:.1?})",
        first as f64 / 1048576.0,
        2 * ROUND,
        second as f64 / 1048576.0
    );
    assert!(
        second <= first + MARGIN,
        "memory grew by {} bytes over the last {ROUND} views (allowed {MARGIN})",
        second.saturating_sub(first)
    );
    // The check can fail: 64 KiB kept per view (12.5 MiB over 200 views) is seen.
    let (first, second) = two_rounds(200, 64 << 10);
    assert!(
        second > first + MARGIN,
        "a leak of 64 KiB per view went unseen: {first} → {second}"
    );
}
