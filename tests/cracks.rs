//! The claim of the project, measured: independently tessellated teapot patches leave cracks
//! (T-junctions) without fat borders, and none with any fat-border variant, over 20 random
//! views at the default pixel error and at 4 px.
//!
//! Tests that can fail: on the stress tessellation (borders pulled back as far as the pixel
//! error allows, `check::stress`) every model of the crack suite cracks clearly without fat
//! borders, not at all with fat borders of full width, and again with fat borders of half the
//! width; a gap 1 px wider than both fat borders together is found.

mod common;

use glam::Vec3;
use patchwork::check::crack::{contour_margin, run_check_with};
use patchwork::check::stress::retreat_border;
use patchwork::check::{CheckOptions, CheckReport, run_check};
use patchwork::render::{FatBorders, Primitives};
use patchwork::tessellate::PatchMesh;
use patchwork::view::View;

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

/// Every model the crack tests draw: Bézier patches, STEP assemblies and parts (curved and
/// planar faces), and the bunny's independently simplified mesh patches.
const SUITE: [&str; 5] = [
    "teapot.bpt",
    "as1-oc-214.stp",
    "nist_ctc_01_asme1_rd.stp",
    "NIST_MBE_PMI_3.stp",
    "bunny.glb",
];

/// The other shipped meshes (issue 30: "crack-free, `check --stress` on every mesh"): Spot's
/// UV seams and creases, the cake's and the alien's colour parts — borders the bunny has not.
const MESHES: [&str; 3] = ["spot.obj", "cakeBirthday.glb", "alien.glb"];

/// Stress tessellation on every model: clear cracks without fat borders, none with fat
/// borders of full width (every variant users can select: 6 and 4 vertices, 2 triangles),
/// cracks again with the same fat borders at half their width.
#[test]
fn stress_cracks_every_model_and_only_full_width_fat_borders_close_them() {
    let mut renderer = common::renderer();
    // Every model is measured before failing, so a failure names all models it hits.
    let mut failures = Vec::new();
    for file in SUITE.into_iter().chain(MESHES) {
        let scene = common::load(file);
        let opts = CheckOptions {
            views: 4,
            seed: 5,
            size: (384, 288),
            variants: vec![
                FatBorders::Off,
                FatBorders::Six,
                FatBorders::Four,
                FatBorders::Two,
            ],
            stress: true,
            narrowed_width: Some(0.5),
            save_failures: Some(common::scratch(&format!("cracks-stress-{file}"))),
            ..CheckOptions::default()
        };
        let r = run_check(&mut renderer, &scene, &opts, |_| {}).expect("rendering works");
        let off = r.total(FatBorders::Off);
        let full = FatBorders::ALL_ON.map(|fb| r.total(fb).cracks());
        let half = FatBorders::ALL_ON.map(|fb| r.total_narrowed(fb));
        eprintln!(
            "{file}: crack pixels off {}, ×0.5 {:?}, ×1 {full:?} (6 / 4 vertices / 2 \
             triangles), inside {}",
            off.cracks(),
            half.map(|h| h.cracks()),
            off.inside
        );
        // Clearly: more than one crack pixel per two hundred inside pixels (Spot, with few
        // patches, cracks at 0.9 % on these views; the other models at 2–6 %).
        if off.cracks() * 200 <= off.inside {
            failures.push(format!(
                "{file}: the stress tessellation hardly cracks without fat borders: {off:?}"
            ));
        }
        let margin = contour_margin(opts.pixel_error) as u32;
        for v in &r.views {
            for (fb, c) in v.counts.iter().filter(|(fb, _)| *fb != FatBorders::Off) {
                // Not one pixel. The paper's fans, with their apex v_i on the middle of the
                // segment quad's edge v_i1–v_i4, left a T-junction inside the fat border: a
                // pixel centre within the rasterizer's snapping of that line, where it crossed
                // a gap, was drawn by neither triangle (bunny, seed 5 view 0: 1 pixel). The
                // fans now share the whole edge (`render::fat_border`, "No T-junctions").
                if c.cracks() > 0 || c.growth_max_px > margin + 1 {
                    failures.push(format!(
                        "{file} view {} fat borders {fb} of full width: {c:?}",
                        v.index
                    ));
                }
            }
        }
        for (fb, half) in FatBorders::ALL_ON.into_iter().zip(half) {
            if half.cracks() <= 20 {
                failures.push(format!(
                    "{file}: fat borders {fb} at half width close the stress gaps: {half:?}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The patch nearest the eye: in front, so most of its border is seen.
fn nearest_patch(meshes: &[PatchMesh], view: &View) -> usize {
    let eye = view.eye.as_vec3();
    let dist = |m: &PatchMesh| {
        m.positions
            .iter()
            .map(|p| p.distance(eye))
            .fold(f32::INFINITY, f32::min)
    };
    (0..meshes.len())
        .min_by(|&a, &b| dist(&meshes[a]).total_cmp(&dist(&meshes[b])))
        .expect("the model has patches")
}

/// Fault injection: one patch's border pulled back by its own ε + the largest ε of any
/// patch + 1 px (at each vertex's depth), perpendicular to the view. Both fat borders
/// together cover at most ε_a + ε_b, so at least a 1 px wide crack must show along the
/// border — found by the check with fat borders on, where the same views are otherwise
/// crack-free.
#[test]
fn a_gap_one_pixel_wider_than_the_fat_borders_is_found() {
    let scene = common::teapot();
    let mut renderer = common::renderer();
    let opts = CheckOptions {
        views: 3,
        seed: 11,
        variants: vec![FatBorders::Six],
        save_failures: Some(common::scratch("cracks-injected-gap")),
        ..CheckOptions::default()
    };
    let clean = run_check(&mut renderer, &scene, &opts, |_| {}).expect("rendering works");
    assert!(clean.crack_free(), "{:?}", clean.total(FatBorders::Six));
    let mut moved = Vec::new();
    let r = run_check_with(
        &mut renderer,
        &scene,
        &opts,
        |view, meshes| {
            let widest = meshes.iter().map(|m| m.eps_border()).fold(0.0, f64::max);
            let k = nearest_patch(meshes, view);
            let own = meshes[k].eps_border();
            let step = retreat_border(&mut meshes[k], view.viewer().as_vec4(), |p: Vec3| {
                let px = view.pixel_size_at(view.view_depth(p.as_dvec3()));
                (own + widest + px) as f32
            });
            moved.push(step);
        },
        |_| {},
    )
    .expect("rendering works");
    for v in &r.views {
        let c = v.counts[0].1;
        eprintln!("view {}: injected gap → {c:?}", v.index);
        assert!(
            c.cracks() >= 10,
            "view {}: a 1 px gap beyond the fat borders went unseen: {c:?}",
            v.index
        );
    }
    assert!(moved.iter().all(|m| *m > 0.0));
}

/// The T-junction the paper's fan apex made at v_i (the middle of the segment quad's edge
/// v_i1–v_i4) let one pixel through on the bunny under the stress tessellation at
/// `patchwork check --stress`'s defaults (seed 1, 512×384, ½ px), view 12, with the 6- and
/// the 4-vertex fat borders; the fans now share the quad's whole edge.
#[test]
fn stress_bunny_view_with_a_t_junction_pixel_has_none() {
    let mut renderer = common::renderer();
    let scene = common::load("bunny.glb");
    let opts = CheckOptions {
        only_views: Some(vec![12]),
        variants: vec![FatBorders::Off, FatBorders::Six, FatBorders::Four],
        stress: true,
        save_failures: Some(common::scratch("cracks-stress-bunny-view12")),
        ..CheckOptions::default()
    };
    let r = run_check(&mut renderer, &scene, &opts, |_| {}).expect("rendering works");
    let off = r.total(FatBorders::Off);
    assert!(
        off.cracks() > 100,
        "the view hardly cracks without fat borders: {off:?}"
    );
    for fb in [FatBorders::Six, FatBorders::Four] {
        let c = r.total(fb);
        assert_eq!(c.cracks(), 0, "fat borders {fb}: {c:?}");
    }
}

/// The 2-vertex band, mitred by the segments' directions in space (at most 2.75 ε), let
/// pixels through the bunny's patch borders under the stress tessellation at `patchwork
/// check --stress`'s defaults (seed 1, 512×384, ½ px): views 4, 14 and 16, 1 + 4 + 1 crack
/// pixels, where the border turns back on screen. The 2-triangle variant's capped segment
/// quads (`render::fat_border`) hold every segment's ε-neighbourhood on screen.
#[test]
fn stress_bunny_views_where_the_mitred_two_vertex_band_cracked_have_none() {
    let mut renderer = common::renderer();
    let scene = common::load("bunny.glb");
    let opts = CheckOptions {
        only_views: Some(vec![4, 14, 16]),
        variants: vec![FatBorders::Off, FatBorders::Two],
        stress: true,
        save_failures: Some(common::scratch("cracks-stress-bunny-two")),
        ..CheckOptions::default()
    };
    let r = run_check(&mut renderer, &scene, &opts, |_| {}).expect("rendering works");
    let off = r.total(FatBorders::Off);
    assert!(
        off.cracks() > 300,
        "the views hardly crack without fat borders: {off:?}"
    );
    for v in &r.views {
        let c = v.counts[1].1;
        assert_eq!(c.cracks(), 0, "view {}, fat borders 2: {c:?}", v.index);
        assert_eq!(c.growth, 0, "view {}, fat borders 2: {c:?}", v.index);
    }
}
