//! Golden images of the lit teapot at three fixed views, compared with FLIP.
//! Regenerate only with `GOLDEN_UPDATE=1` and say why in the commit.

mod common;

use glam::DVec3;
use patchwork::check::golden::{GoldenOutcome, Thresholds, compare_with_golden};
use patchwork::render::{RenderOptions, Shading};
use patchwork::tessellate::tessellate_scene;
use patchwork::view::{self, View};

fn golden(name: &str, dir: Option<DVec3>) {
    let scene = common::teapot();
    let up = scene.up.vector();
    let fov = view::DEFAULT_FOV_Y_DEG.to_radians();
    let size = (400, 300);
    let v = match dir {
        None => View::framing(&scene.bounds, up, fov, size),
        Some(d) => View::framing_from(&scene.bounds, up, d, fov, size),
    };
    let meshes = tessellate_scene(&scene, &v, view::DEFAULT_PIXEL_ERROR);
    let mut renderer = common::renderer();
    let gpu = renderer.upload(&meshes);
    let opts = RenderOptions {
        shading: Shading::Lit,
        msaa: 4,
        ..RenderOptions::default()
    };
    let frame = renderer.render(&gpu, &v, &opts).expect("render");
    let path = common::root().join("golden").join(format!("{name}.png"));
    match compare_with_golden(&path, &frame.to_rgba_image(), Thresholds::default()) {
        Ok(GoldenOutcome::Matched(score)) => eprintln!("{name}: {score:?}"),
        Ok(GoldenOutcome::Updated) => eprintln!("{name}: golden rewritten (GOLDEN_UPDATE=1)"),
        Err(e) => panic!("{e}"),
    }
}

#[test]
fn teapot_default_view() {
    golden("teapot-default", None);
}

#[test]
fn teapot_from_above() {
    golden("teapot-above", Some(DVec3::new(0.2, -0.3, 1.0)));
}

#[test]
fn teapot_from_the_side() {
    golden("teapot-side", Some(DVec3::new(0.0, -1.0, 0.15)));
}
