//! Implosion animations: crack-free in every frame by parts (closed solids), in the assembled
//! frame by patches, growth bounded, goldens of the first, middle and last frame.

mod common;

use glam::DVec3;
use patchwork::anim::{Explosion, GroupBy};
use patchwork::check::crack::contour_margin;
use patchwork::check::golden::{GoldenOutcome, Thresholds, compare_with_golden};
use patchwork::drive::implode::{AnimOptions, AnimRecord, run};
use patchwork::view::{self, View};

/// The fixed camera of an animation: framing the whole flight.
fn view_for(scene: &patchwork::model::Scene, by: GroupBy, size: (u32, u32)) -> View {
    let bounds = Explosion::new(scene, by, 1.0).bounds(scene);
    View::framing(
        &bounds,
        scene.up.vector(),
        view::DEFAULT_FOV_Y_DEG.to_radians(),
        size,
    )
}

/// Runs an animation with the crack check; keeps the lit images of the frames in `keep`.
fn animate(
    scene: &patchwork::model::Scene,
    opts: &AnimOptions,
    size: (u32, u32),
    keep: &[usize],
) -> (Vec<AnimRecord>, Vec<(usize, image::RgbaImage)>) {
    let view = view_for(scene, opts.by, size);
    let mut renderer = common::renderer();
    let mut kept = Vec::new();
    let records = run(&mut renderer, scene, &view, opts, |r, frame| {
        if keep.contains(&r.frame) {
            kept.push((r.frame, frame.to_rgba_image()));
        }
        Ok(())
    })
    .expect("renders");
    (records, kept)
}

fn golden(name: &str, img: &image::RgbaImage) {
    let path = common::root().join("golden").join(format!("{name}.png"));
    match compare_with_golden(&path, img, Thresholds::default()) {
        Ok(GoldenOutcome::Matched(score)) => eprintln!("{name}: {score:?}"),
        Ok(GoldenOutcome::Updated) => eprintln!("{name}: golden rewritten (GOLDEN_UPDATE=1)"),
        Err(e) => panic!("{e}"),
    }
}

#[test]
fn explosion_groups_placed_parts_and_frames_the_flight() {
    let scene = common::load("as1-oc-214.stp");
    let e = Explosion::new(&scene, GroupBy::Parts, 1.0);
    // as1 places 18 parts (some parts more than once): one group per placement.
    assert_eq!(e.groups, 18);
    for (a, pa) in scene.patches.iter().enumerate() {
        for (b, pb) in scene.patches.iter().enumerate().skip(a + 1) {
            let same_placement = pa.part == pb.part && pa.transform == pb.transform;
            assert_eq!(
                same_placement,
                e.offsets[a] == e.offsets[b],
                "patches {a} and {b}"
            );
        }
    }
    assert!(
        e.offsets
            .iter()
            .all(|o| o.length() > 0.4 * scene.bounds.radius)
    );
    let bounds = e.bounds(&scene);
    for (p, o) in scene.patches.iter().zip(&e.offsets) {
        for c in [p.bounds.center, p.bounds.center + *o] {
            assert!(c.distance(bounds.center) + p.bounds.radius <= bounds.radius * (1.0 + 1e-9));
        }
    }
    let teapot = common::teapot();
    let e = Explosion::new(&teapot, GroupBy::Patches, 1.0);
    assert_eq!(e.groups, teapot.patches.len());
    assert_eq!(e.at(0.0), vec![DVec3::ZERO; teapot.patches.len()]);
}

#[test]
fn assembly_implosion_by_parts_is_crack_free_in_every_frame() {
    let scene = common::load("as1-oc-214.stp");
    let frames = 13;
    let opts = AnimOptions {
        frames,
        by: GroupBy::Parts,
        check: true,
        save_failures: Some(common::scratch("anim-as1")),
        ..AnimOptions::default()
    };
    let (records, kept) = animate(&scene, &opts, (400, 300), &[0, frames / 2, frames - 1]);
    assert_eq!(records.len(), frames);
    assert_eq!(records[0].amount, 1.0);
    assert_eq!(records[frames - 1].amount, 0.0);
    let margin = contour_margin(opts.lod.pixel_error) as u32;
    // The control: the same frames without fat borders crack (the parts' faces are
    // tessellated independently), so the check could fail.
    let off: usize = records
        .iter()
        .map(|r| {
            r.cracks_off
                .expect("fat borders are drawn: control counted")
                .cracks()
        })
        .sum();
    eprintln!("as1: {off} crack pixels without fat borders over {frames} frames");
    assert!(
        off > 0,
        "no crack without fat borders: the check could not fail"
    );
    for r in &records {
        let c = r.cracks.expect("checked");
        assert!(
            c.inside > 1000,
            "frame {}: the assembly is in view",
            r.frame
        );
        assert_eq!(c.cracks(), 0, "frame {}: {c:?}", r.frame);
        assert!(
            c.growth_max_px <= margin + 1 && c.growth * 10_000 <= c.inside,
            "frame {}: growth {c:?}",
            r.frame
        );
    }
    assert!(patchwork::drive::implode::frames_pass(
        &records,
        GroupBy::Parts,
        18,
        0.5
    ));
    for (k, img) in &kept {
        let name = match *k {
            0 => "implode-as1-first",
            k if k == frames - 1 => "implode-as1-last",
            _ => "implode-as1-middle",
        };
        golden(name, img);
    }
}

#[test]
fn teapot_implosion_by_patches_closes_crack_free_with_bounded_growth() {
    let scene = common::teapot();
    let opts = AnimOptions {
        frames: 13,
        by: GroupBy::Patches,
        check: true,
        save_failures: Some(common::scratch("anim-teapot")),
        ..AnimOptions::default()
    };
    let (records, _) = animate(&scene, &opts, (400, 300), &[]);
    for r in &records {
        let c = r.cracks.expect("checked");
        // Patches flying apart leave real openings, so cracks count only once assembled.
        // Growth: see `growth_within_bound` (tips of edge-on slivers, ≤ 2 pixels per patch).
        assert!(
            c.growth <= 2 * scene.patches.len(),
            "frame {}: growth {c:?}",
            r.frame
        );
    }
    assert!(patchwork::drive::implode::frames_pass(
        &records,
        GroupBy::Patches,
        scene.patches.len(),
        0.5
    ));
    let last = records.last().expect("frames");
    let off = last
        .cracks_off
        .expect("fat borders are drawn: control counted");
    let last = last.cracks.expect("checked");
    assert!(last.inside > 1000);
    assert_eq!(last.cracks(), 0, "assembled: {last:?}");
    // The control of the same frame: without fat borders it cracks.
    assert!(off.cracks() > 0, "assembled without fat borders: {off:?}");
}
