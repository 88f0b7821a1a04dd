//! A trimmed face's tessellation relabelled to a finer level by the frame loop (`lod`'s reuse
//! within ε: its measured errors hold the finer level) is within that level's ε of the
//! trimmed face by the independent measure of `check::fidelity`; and the control: the same
//! old tessellations taken for the finer ε without that check are not, for some faces — the
//! measure would see a wrong relabelling.
//!
//! And what does not depend on ε is reused: each loop's first point found by the load's probe
//! (`TrimmedFace::loop_starts`) gives every later tessellation the same mesh as a search from
//! scratch.

mod common;

use std::time::Duration;

use patchwork::check::fidelity::measure_placed;
use patchwork::lod::{FrameLoop, LodOptions};
use patchwork::model::{PatchSurface, Scene};
use patchwork::tessellate::{PatchMesh, TrimmedTessellator};
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

/// The first 300 faces of three files with many small faces (surfaces of revolution, B-splines, the
/// poles of spheres, holes) tessellated at two levels with the loop starts the probe kept and
/// with none (a search from scratch). The kept start is the searched one up to its last bits,
/// and the triangulation follows such bits where points are cocircular, so the meshes are not
/// always the same: where they differ, the kept one holds ε by `check::fidelity` as well as the
/// searched one does. A start that no longer lands on its point (a stale entry) is not used:
/// that mesh is exactly the searched one.
#[test]
fn loop_starts_kept_by_the_probe_give_meshes_as_good_as_a_search() {
    let (mut faces, mut differ) = (0, 0);
    for file in [
        "corpus/Molex_SlimStack_54722-0804_2x40_P0.50mm_Vertical.step.gz",
        "corpus/TFBGA-100_8x8mm_Layout10x10_P0.8mm.step",
        "screw.step",
    ] {
        let scene = common::load(file);
        let mut t = TrimmedTessellator::new();
        let (mut kept, mut searched, mut stale_mesh) = (
            PatchMesh::default(),
            PatchMesh::default(),
            PatchMesh::default(),
        );
        let mut seen = std::collections::HashSet::new();
        for patch in &scene.patches {
            let PatchSurface::Trimmed(face) = &patch.surface else {
                continue;
            };
            // (The first 300 faces of each file: the measure is slow at these ε.)
            if seen.len() == 300 || !seen.insert(std::sync::Arc::as_ptr(face)) {
                continue;
            }
            let id = face.id;
            assert!(
                face.loop_starts.len() == face.loops.len()
                    && face.loop_starts.iter().all(Option::is_some),
                "{file}: face #{id}: the probe kept {:?} for {} loops",
                face.loop_starts,
                face.loops.len()
            );
            let mut fresh = (**face).clone();
            fresh.loop_starts.clear();
            // Stale: the right points, parameters elsewhere on the surface.
            let mut stale = (**face).clone();
            for s in stale.loop_starts.iter_mut().flatten() {
                s.1 += glam::DVec2::new(0.37, -0.29);
            }
            for eps in [face.bounds.radius * 1e-2, face.bounds.radius * 3e-3] {
                let a = t.tessellate(face, eps, &mut kept).is_ok();
                let b = t.tessellate(&fresh, eps, &mut searched).is_ok();
                let c = t.tessellate(&stale, eps, &mut stale_mesh).is_ok();
                assert_eq!((a, c), (b, b), "{file}: face #{id} at ε {eps:e}");
                assert!(
                    stale_mesh.positions == searched.positions
                        && stale_mesh.triangles == searched.triangles,
                    "{file}: face #{id} at ε {eps:e}: a stale start was used"
                );
                if !a
                    || (kept.positions == searched.positions
                        && kept.triangles == searched.triangles)
                {
                    continue;
                }
                differ += 1;
                let identity = glam::DMat4::IDENTITY;
                let k = measure_placed(face, &identity, &kept, eps).expect("measured");
                let s = measure_placed(face, &identity, &searched, eps).expect("measured");
                assert!(
                    k.ratio() <= s.ratio().max(1.0) && k.outside <= s.outside,
                    "{file}: face #{id} at ε {eps:e}: kept start {k:?}, searched {s:?}"
                );
            }
            faces += 1;
        }
    }
    eprintln!("{faces} faces, {differ} meshes not bit-identical to a search from scratch");
    assert!(
        faces > 400 && differ > 0,
        "{faces} faces, {differ} differ: nothing compared"
    );
}
