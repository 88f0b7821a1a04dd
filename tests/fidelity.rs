//! The tessellation's error measured against the *trimmed* faces, independently of the
//! tessellator's refinement (`check::fidelity`), and proof that the measure sees what it must:
//! a mesh built for 2ε, a face moved off its surface, a mesh over the wrong side of its trim.

mod common;

use std::sync::Arc;

use glam::DVec3;
use patchwork::check::fidelity::{measure, measure_placed, measure_scene};
use patchwork::model::{PatchSurface, Scene, TrimmedFace};
use patchwork::tessellate::{PatchMesh, Tessellators};
use patchwork::view::{DEFAULT_FOV_Y_DEG, DEFAULT_PIXEL_ERROR, View};

const STEP: [&str; 5] = [
    "as1-oc-214.stp",
    "NIST_MBE_PMI_3.stp",
    "nist_ctc_01_asme1_rd.stp",
    "NIST_MBE_PMI_11.stp",
    "screw.step",
];

fn framing(scene: &Scene) -> View {
    View::framing(
        &scene.bounds,
        scene.up.vector(),
        DEFAULT_FOV_Y_DEG.to_radians(),
        (1024, 768),
    )
}

#[test]
fn every_shipped_face_is_within_its_tolerance_of_the_trimmed_face() {
    for file in STEP {
        let scene = common::load(file);
        let faces = measure_scene(&scene, &framing(&scene), DEFAULT_PIXEL_ERROR);
        assert_eq!(
            faces.len(),
            scene.patches.len(),
            "{file}: every patch measured"
        );
        let (patch, worst) = faces[0];
        assert!(
            worst.ratio() <= 1.0 && worst.outside == 0,
            "{file}: face #{} (patch {patch}, {}) is {:.2}× its tolerance from the trimmed face, \
             {} samples outside its trim",
            worst.face,
            worst.surface,
            worst.ratio(),
            worst.outside
        );
        assert!(faces.iter().all(|f| f.1.samples >= 28), "{file}");
    }
}

/// Each face of as1 tessellated for a coarser tolerance but judged at ε: the curved faces go
/// over. (The tessellator's grid bound is conservative: meshes built for 2ε stay within about
/// ε on as1, so 4ε is the coarsening that must show.)
#[test]
fn a_mesh_built_for_four_times_the_tolerance_fails() {
    let scene = common::load("as1-oc-214.stp");
    let view = framing(&scene);
    let mut t = Tessellators::new();
    let mut worst: f64 = 0.0;
    for p in &scene.patches {
        let PatchSurface::Trimmed(face) = &p.surface else {
            continue;
        };
        let eps = view.eps_obj(&p.bounds, DEFAULT_PIXEL_ERROR);
        let mut m = PatchMesh::default();
        t.patch(p, 4.0 * eps, &mut m);
        let f = measure_placed(face, &p.transform, &m, eps).expect("measured");
        worst = worst.max(f.ratio());
    }
    assert!(worst > 1.3, "4ε meshes measured at most {worst:.2} ε");
}

/// One face's mesh, in its own coordinates, with the tolerance it was built for.
fn face_mesh(
    file: &str,
    pick: impl Fn(&TrimmedFace) -> bool,
) -> (Arc<TrimmedFace>, Vec<DVec3>, Vec<[u32; 3]>, f64) {
    let scene = common::load(file);
    let p = scene
        .patches
        .iter()
        .find(|p| matches!(&p.surface, PatchSurface::Trimmed(f) if pick(f)))
        .expect("such a face");
    let PatchSurface::Trimmed(face) = &p.surface else {
        unreachable!("matched above")
    };
    let local = patchwork::model::Patch {
        transform: glam::DMat4::IDENTITY,
        ..p.clone()
    };
    let eps = face.bounds.radius * 1e-3;
    let mut m = PatchMesh::default();
    Tessellators::new().patch(&local, eps, &mut m);
    let pos = m.positions.iter().map(|v| v.as_dvec3()).collect();
    (face.clone(), pos, m.triangles, eps)
}

/// A face moved 2ε along its normal is 2ε off; a mesh over the face's holes lies outside its
/// trim.
#[test]
fn a_face_off_its_surface_or_outside_its_trim_fails() {
    // A face with holes: the plate of as1 (a plane with several loops).
    let (face, pos, tris, eps) = face_mesh("as1-oc-214.stp", |f| f.loops.len() >= 3);
    let ok = measure(&face, &pos, &tris, eps).expect("measured");
    assert!(ok.ratio() <= 1.0 && ok.outside == 0, "{ok:?}");

    let n = {
        let (a, b, c) = (
            pos[tris[0][0] as usize],
            pos[tris[0][1] as usize],
            pos[tris[0][2] as usize],
        );
        (b - a).cross(c - a).normalize()
    };
    let moved: Vec<DVec3> = pos.iter().map(|p| *p + n * 2.0 * eps).collect();
    let off = measure(&face, &moved, &tris, eps).expect("measured");
    assert!(off.ratio() > 1.9, "moved by 2ε: {off:?}");

    // The mesh of the face with its holes filled (the defect a tessellator that loses an
    // inner loop makes), judged against the face with its holes.
    let extent = |lp: &Vec<patchwork::model::trimmed::LoopEdge>| {
        let pts: Vec<DVec3> = lp.iter().map(|le| le.edge.start).collect();
        patchwork::model::bounding_box(pts).map_or(0.0, |(lo, hi)| lo.distance(hi))
    };
    let outer = face
        .loops
        .iter()
        .max_by(|a, b| extent(a).total_cmp(&extent(b)))
        .expect("loops")
        .clone();
    let filled = TrimmedFace {
        loops: vec![outer],
        ..(*face).clone()
    };
    let mut m = PatchMesh::default();
    patchwork::tessellate::TrimmedTessellator::new()
        .tessellate(&filled, eps, &mut m)
        .expect("the filled face tessellates");
    let pos: Vec<DVec3> = m.positions.iter().map(|v| v.as_dvec3()).collect();
    let wrong = measure(&face, &pos, &m.triangles, eps).expect("measured");
    assert!(wrong.outside > 0 && wrong.ratio() > 10.0, "{wrong:?}");
}

/// Curved, periodic faces with seams (the screw's cones and cylinder, its tori): the measure
/// does not mistake a seam for a boundary, and still sees a mesh 2ε off.
#[test]
fn seams_are_not_boundaries() {
    let (face, pos, tris, eps) = face_mesh("screw.step", |f| f.id == 1151);
    let ok = measure(&face, &pos, &tris, eps).expect("measured");
    assert!(ok.ratio() <= 1.0 && ok.outside == 0, "{ok:?}");
    let centre = pos.iter().copied().sum::<DVec3>() / pos.len() as f64;
    let grown: Vec<DVec3> = pos
        .iter()
        .map(|p| *p + (*p - centre).normalize_or_zero() * 2.0 * eps)
        .collect();
    let off = measure(&face, &grown, &tris, eps).expect("measured");
    assert!(off.ratio() > 1.3, "{off:?}");
}

/// A hole a whole period away from its outer loop in parameter space (linkrods face #291: a
/// cylinder whose outer loop runs over u ∈ −2π..0 and a slot at u ≈ π): the tessellator must
/// still cut it, not fill it; the measure sees the difference.
#[test]
fn a_hole_a_period_away_is_cut() {
    let scene = patchwork::prep::load(&common::root().join("models/corpus/linkrods.step.gz"))
        .expect("linkrods loads");
    let p = scene
        .patches
        .iter()
        .find(|p| matches!(&p.surface, PatchSurface::Trimmed(f) if f.id == 291))
        .expect("face #291");
    let PatchSurface::Trimmed(face) = &p.surface else {
        unreachable!("matched above")
    };
    assert_eq!(face.loops.len(), 2, "outer loop and slot");
    let view = framing(&scene);
    let eps = view.eps_obj(&p.bounds, DEFAULT_PIXEL_ERROR);
    let mut m = PatchMesh::default();
    Tessellators::new().patch(p, eps, &mut m);
    let f = measure_placed(face, &p.transform, &m, eps).expect("measured");
    assert!(f.outside == 0 && f.ratio() <= 1.0, "{f:?}");
}
