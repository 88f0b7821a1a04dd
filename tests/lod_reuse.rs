//! A trimmed face's tessellation relabelled to a finer level by the frame loop (`lod`'s reuse
//! within ε: its measured errors hold the finer level) is within that level's ε of the
//! trimmed face by the independent measure of `check::fidelity`; and the control: the same
//! old tessellations taken for the finer ε without that check are not, for some faces — the
//! measure would see a wrong relabelling.

mod common;

use std::time::Duration;

use patchwork::check::fidelity::measure_placed;
use patchwork::lod::{FrameLoop, LodOptions};
use patchwork::model::{PatchSurface, Scene};
use patchwork::tessellate::PatchMesh;
use patchwork::view::{DEFAULT_FOV_Y_DEG, View};

/// The framing view, and the view from a quarter of its distance (ε per patch about 4×
/// finer: two levels of √2 and more).
fn far_and_near(scene: &Scene) -> (View, View) {
    let (fov, size) = (DEFAULT_FOV_Y_DEG.to_radians(), (1024, 768));
    let up = scene.up.vector();
    let far = View::framing(&scene.bounds, up, fov, size);
    let c = scene.bounds.center;
    let near = View::new(c + (far.eye - c) * 0.25, c, up, fov, size, &scene.bounds);
    (far, near)
}

#[test]
fn relabelled_tessellations_hold_their_new_tolerance() {
    let (mut reused, mut wrong_if_unchecked) = (0, 0);
    // Planes bounded by lines and circles (relabelled) beside cylinders, cones and tori (made
    // anew); the B-spline files measure for minutes at the near view's ε.
    for file in ["nist_ctc_01_asme1_rd.stp", "screw.step"] {
        let scene = common::load(file);
        let (far, near) = far_and_near(&scene);
        let options = LodOptions {
            budget: Duration::from_secs(600),
            ..LodOptions::default()
        };
        let mut lod = FrameLoop::new(&scene, &far, options);
        let old: Vec<PatchMesh> = (0..scene.patches.len())
            .map(|i| lod.mesh(i).expect("a mesh per patch").world().into_owned())
            .collect();
        let stats = lod.update(&scene, &near);
        assert_eq!(stats.queue_left, 0, "{file}: the budget did every job");
        reused += stats.reused;
        for (i, patch) in scene.patches.iter().enumerate() {
            let PatchSurface::Trimmed(face) = &patch.surface else {
                continue;
            };
            let new = lod.mesh(i).expect("a mesh per patch").world().into_owned();
            if new.triangles.is_empty() || old[i].triangles.is_empty() {
                continue;
            }
            let same = new.positions == old[i].positions && new.triangles == old[i].triangles;
            if same && new.eps_target < old[i].eps_target {
                // Relabelled: judged at its new ε.
                let f =
                    measure_placed(face, &patch.transform, &new, new.eps_target).expect("measured");
                assert!(
                    f.ratio() <= 1.0 && f.outside == 0,
                    "{file}: patch {i} relabelled from ε {} to {}: {f:?}",
                    old[i].eps_target,
                    new.eps_target
                );
            } else if new.eps_target < old[i].eps_target {
                // Made anew: would the old one, relabelled unchecked, have held the new ε?
                let f = measure_placed(face, &patch.transform, &old[i], new.eps_target)
                    .expect("measured");
                if f.ratio() > 1.0 {
                    wrong_if_unchecked += 1;
                }
            }
        }
    }
    eprintln!(
        "{reused} patches relabelled; {wrong_if_unchecked} old tessellations would be over ε"
    );
    assert!(
        reused > 0,
        "nothing was relabelled: the test proves nothing"
    );
    assert!(
        wrong_if_unchecked > 0,
        "every old tessellation held the finer ε: the control could not fail"
    );
}
