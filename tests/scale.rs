//! The scale benchmark's driver on tiny teapot grids: the rows count exactly the patches the
//! grid has, their convergence agrees with the per-frame errors, and `bench --scale` hands a
//! child process's point back through its CSV.

mod common;

use std::process::Command;
use std::time::Duration;

use patchwork::drive::flythrough::jump_frames;
use patchwork::drive::scale::{PointRun, ScaleOptions, Source, run_point};
use patchwork::lod::LodOptions;

fn options(frames: usize, budget: Duration) -> ScaleOptions {
    ScaleOptions {
        frames,
        size: (256, 192),
        fov_y: 45f64.to_radians(),
        lod: LodOptions {
            budget,
            ..LodOptions::default()
        },
        work_dir: common::scratch("scale"),
    }
}

/// The convergence the records show: the first frame from the jump on whose visible patches
/// are all within the pixel error (1 % slack for the levels' rounding), counted from the jump
/// frame as 1.
fn converged_after(run: &PointRun, jump: usize) -> Option<usize> {
    run.records
        .iter()
        .find(|r| r.frame >= jump && r.max_error_px <= r.pixel_error * 1.01)
        .map(|r| r.frame - jump + 1)
}

#[test]
fn grid_points_count_their_patches_and_converge_as_their_frames_say() {
    let mut renderer = common::renderer();
    let frames = 12;
    let mut converged = Vec::new();
    // A roomy budget and one so small that each frame re-tessellates a single batch: the
    // queue is then still behind several frames after the jump.
    for (n, budget) in [
        (1, Duration::from_millis(200)),
        (2, Duration::from_millis(200)),
        (2, Duration::from_nanos(1)),
    ] {
        let mut stages = Vec::new();
        let run = run_point(
            &mut renderer,
            &Source::Grid(n),
            &options(frames, budget),
            |s| stages.push(s.to_owned()),
        )
        .expect("the point runs");
        let p = &run.point;
        assert_eq!(p.patches, 32 * n * n, "{n}x{n}");
        assert_eq!(p.model, format!("teapots {n}x{n}"));
        assert_eq!(stages, ["write", "load", "tessellate", "frames"]);
        assert_eq!(run.records.len(), frames);
        assert_eq!(p.frames, frames);
        assert_eq!(p.jump_frame, jump_frames(frames).1);
        assert_eq!(
            p.converge_frames,
            converged_after(&run, p.jump_frame),
            "{n}x{n}"
        );
        // Before convergence every frame after the jump shows a patch too coarse.
        let until = p.converge_frames.unwrap_or(frames - p.jump_frame + 1) - 1;
        for r in &run.records[p.jump_frame..p.jump_frame + until] {
            assert!(r.max_error_px > r.pixel_error * 1.01, "frame {}", r.frame);
        }
        assert_eq!(p.triangles_first, run.records[0].triangles);
        assert_eq!(p.triangles_last, run.records[frames - 1].triangles);
        assert!(p.triangles_first > 0);
        // 16 control points of 24 bytes per patch at least; times measured.
        assert!(p.scene_bytes >= p.patches * 16 * 24);
        assert!(p.lod_bytes_first > 0 && p.lod_bytes_last > 0);
        assert!(p.load_ms > 0.0 && p.first_frame_ms >= p.tessellate_ms + p.upload_ms);
        if cfg!(target_os = "linux") {
            let (start, load, peak) = (
                p.rss_start_bytes.expect("VmRSS"),
                p.rss_load_bytes.expect("VmHWM"),
                p.peak_rss_bytes.expect("VmHWM"),
            );
            // Readings only, no order between them: the kernel updates VmHWM lazily, so a
            // VmRSS read earlier can exceed a VmHWM read later (seen once on the GL run).
            assert!(start > 0 && load > 0 && peak > 0, "{start} {load} {peak}");
        }
        // The grid's file is gone once loaded.
        assert!(
            !options(frames, budget)
                .work_dir
                .join(format!("teapots-{n}x{n}.bpt"))
                .exists()
        );
        converged.push(p.converge_frames);
    }
    // With the tiny budget the queue cannot catch up at once (the first two runs converge,
    // the starved one later or never).
    assert!(
        converged[0].is_some() && converged[1].is_some(),
        "{converged:?}"
    );
    assert!(
        converged[2].is_none_or(|c| c > converged[1].unwrap_or(0)),
        "{converged:?}"
    );
}

#[test]
fn bench_scale_measures_each_point_in_a_child_process() {
    let csv = common::scratch("scale").join("bench-scale.csv");
    let _ = std::fs::remove_file(&csv);
    let o = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args([
            "bench",
            "--scale",
            "--sizes",
            "1,2,40",
            "--max-patches",
            "200",
            "--frames",
            "4",
            "--size",
            "128x96",
            "--csv",
        ])
        .arg(&csv)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("| teapots 2x2 | 128 |"), "{stdout}");
    let text = std::fs::read_to_string(&csv).expect("the CSV");
    let rows: Vec<_> = text
        .lines()
        .skip(1)
        .map(|l| patchwork::report::scale::parse_row(l).expect("a row"))
        .collect();
    // 40x40 is past --max-patches.
    let patches: Vec<usize> = rows.iter().map(|r| r.patches).collect();
    assert_eq!(patches, [32, 128]);
    for r in &rows {
        // Each child read its own peak: a fresh process, more than nothing.
        let peak = r.peak_rss_bytes.expect("VmHWM on Linux");
        assert!(peak >= r.rss_start_bytes.expect("VmRSS"), "{r:?}");
    }
}
