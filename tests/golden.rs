//! Golden images of the lit teapot at three fixed views, compared with FLIP.
//! Regenerate only with `GOLDEN_UPDATE=1` and say why in the commit.

mod common;

use glam::DVec3;
use patchwork::check::golden::{GoldenOutcome, Thresholds, compare_with_golden};
use patchwork::render::{Primitives, RenderOptions, Shading};
use patchwork::tessellate::tessellate_scene;
use patchwork::view::{self, View};

fn golden(name: &str, dir: Option<DVec3>) {
    golden_of(common::teapot(), name, dir)
}

/// With the default primitives (`auto`: lists for tessellated patches).
fn golden_of(scene: patchwork::model::Scene, name: &str, dir: Option<DVec3>) {
    golden_with(scene, name, dir, Primitives::default())
}

/// Triangle strips draw the same triangles: the same goldens hold.
#[test]
fn strips_match_the_list_goldens() {
    golden_with(common::teapot(), "teapot-default", None, Primitives::Strips);
    golden_with(
        common::teapot(),
        "teapot-side",
        Some(DVec3::new(0.0, -1.0, 0.15)),
        Primitives::Strips,
    );
    // Trimmed NURBS faces of a STEP assembly.
    golden_with(
        common::load("as1-oc-214.stp"),
        "step-as1",
        None,
        Primitives::Strips,
    );
}

fn golden_with(
    scene: patchwork::model::Scene,
    name: &str,
    dir: Option<DVec3>,
    primitives: Primitives,
) {
    let up = scene.up.vector();
    let fov = view::DEFAULT_FOV_Y_DEG.to_radians();
    let size = (400, 300);
    let v = match dir {
        None => View::framing(&scene.bounds, up, fov, size),
        Some(d) => View::framing_from(&scene.bounds, up, d, fov, size),
    };
    let meshes = tessellate_scene(&scene, &v, view::DEFAULT_PIXEL_ERROR);
    let mut renderer = common::renderer();
    renderer.primitives = primitives;
    let gpu = renderer.upload(&meshes);
    // Tessellated patches: lists unless strips are asked for.
    let lists = 3 * gpu.triangle_count() as u64;
    match primitives {
        Primitives::Auto | Primitives::List => assert_eq!(gpu.index_count(), lists),
        _ => assert!(gpu.index_count() < lists, "{name}: {}", gpu.index_count()),
    }
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

/// STEP models: an assembly (18 placed parts), a sheet-metal part with B-spline bends (in
/// inches, scaled to mm), an analytic part and a revolved NURBS part.
#[test]
fn step_models() {
    for (file, name) in [
        ("as1-oc-214.stp", "step-as1"),
        ("NIST_MBE_PMI_3.stp", "step-nist-pmi3"),
        ("nist_ctc_01_asme1_rd.stp", "step-nist-ctc01"),
        ("NIST_MBE_PMI_11.stp", "step-nist-pmi11"),
    ] {
        golden_of(common::load(file), name, None);
    }
}
