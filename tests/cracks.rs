//! The claim of the project, measured: independently tessellated teapot patches leave cracks
//! (T-junctions) without fat borders, and none with any fat-border variant, over 20 random
//! views at the default pixel error and at 4 px.

mod common;

use patchwork::check::crack::contour_margin;
use patchwork::check::{CheckOptions, CheckReport, run_check};
use patchwork::render::{FatBorders, Primitives};

const VIEWS: usize = 20;

fn check(pixel_error: f64, seed: u64) -> CheckReport {
    check_with(pixel_error, seed, Primitives::List, VIEWS)
}

fn check_with(pixel_error: f64, seed: u64, primitives: Primitives, views: usize) -> CheckReport {
    let scene = common::teapot();
    let mut renderer = common::renderer();
    renderer.primitives = primitives;
    let opts = CheckOptions {
        views,
        seed,
        pixel_error,
        save_failures: Some(common::scratch(&format!(
            "cracks-{pixel_error}px-{primitives:?}"
        ))),
        ..CheckOptions::default()
    };
    run_check(&mut renderer, &scene, &opts, |_| {}).expect("rendering works")
}

fn assert_crack_free(report: &CheckReport, pixel_error: f64) {
    let off = report.total(FatBorders::Off);
    assert!(
        off.cracks() > 0,
        "without fat borders the independent tessellations must show cracks (got none): \
         the check could not fail"
    );
    for variant in FatBorders::ALL_ON {
        let t = report.total(variant);
        for v in &report.views {
            let c = v
                .counts
                .iter()
                .find(|(fb, _)| *fb == variant)
                .expect("variant measured")
                .1;
            assert_eq!(
                c.cracks(),
                0,
                "view {} with fat borders {variant} at {pixel_error} px: {c:?} (images in \
                 target/test-output)",
                v.index
            );
        }
        // Growth: a fat border reaches ε (γ px at the patch's nearest point) beyond a border
        // that lies on the silhouette, and rasterization rounds by up to one pixel, so nothing
        // may be covered farther than margin + 1 px outside the true silhouette, and such
        // pixels must stay rare (≤ 1 in 10 000 of the inside pixels).
        let margin = contour_margin(pixel_error) as u32;
        assert!(
            t.growth_max_px <= margin + 1,
            "{variant}: growth reaches {} px",
            t.growth_max_px
        );
        assert!(
            t.growth * 10_000 <= t.inside,
            "{variant}: {} growth pixels of {}",
            t.growth,
            t.inside
        );
    }
}

#[test]
fn no_cracks_with_fat_borders_at_half_a_pixel() {
    let r = check(0.5, 1);
    assert_eq!(r.views.len(), VIEWS);
    assert_crack_free(&r, 0.5);
}

#[test]
fn no_cracks_with_fat_borders_at_four_pixels() {
    let r = check(4.0, 2);
    assert_crack_free(&r, 4.0);
}

/// Triangle strips (tunneling per patch) draw the same triangles: still crack-free.
#[test]
fn no_cracks_with_strips_at_half_a_pixel() {
    let r = check_with(0.5, 3, Primitives::Strips, 8);
    assert_eq!(r.views.len(), 8);
    assert_crack_free(&r, 0.5);
}
