//! The fidelity measure's fast paths give the exhaustive measure's figures: the spatial
//! indices over the boundary segments (`check::fidelity::segment_index`) bit for bit, and
//! placements measured once for a shared mesh within `SHARED_VERTEX_TOLERANCE`.

mod common;

use patchwork::check::fidelity::{
    FaceFidelity, Search, measure_meshes_search, measure_placed_with,
};
use patchwork::model::PatchSurface;
use patchwork::tessellate::{tessellate_scene, tessellate_scene_tolerance};
use patchwork::util::NoProgress;
use patchwork::view::DEFAULT_PIXEL_ERROR;

/// Planes, cylinders, cones, spheres, tori, B-splines; loops around periodic surfaces and
/// through poles; a thread whose loops run around many periods.
const MODELS: [&str; 6] = [
    "corpus/bearing.iges.gz",
    "corpus/cube_filet.stp",
    "corpus/periodic_u_cst.step",
    "corpus/sewfaces.step",
    "as1-oc-214.stp",
    "screw.step",
];

#[test]
fn indexed_boundary_queries_give_the_exhaustive_figures_bit_for_bit() {
    for file in MODELS {
        let t0 = std::time::Instant::now();
        let scene = common::load(file);
        // The OCCT judge's tolerance (3e-3 of the diagonal): few enough samples for the scan.
        let meshes = tessellate_scene_tolerance(&scene, 3e-3 * scene.bbox_diagonal());
        let mut measured = 0;
        for (p, mesh) in scene.patches.iter().zip(&meshes) {
            let PatchSurface::Trimmed(face) = &p.surface else {
                continue;
            };
            let at =
                |search| measure_placed_with(face, &p.transform, mesh, mesh.eps_target, search);
            let (fast, scan) = (at(Search::Indexed), at(Search::Exhaustive));
            assert_eq!(
                fast, scan,
                "{file}: face #{} ({}): the indexed measure differs from the scan",
                face.id, p.id
            );
            measured += usize::from(scan.is_some());
        }
        assert!(measured > 0, "{file}: no trimmed face measured");
        eprintln!(
            "{file}: {measured} faces, {:.1} s",
            t0.elapsed().as_secs_f64()
        );
    }
}

fn by_patch(mut v: Vec<(u32, FaceFidelity)>) -> Vec<(u32, FaceFidelity)> {
    v.sort_by_key(|(id, _)| *id);
    v
}

/// `a` and `b` within `rel` of each other (relative to ε) in every figure, counts equal.
fn close(a: &FaceFidelity, b: &FaceFidelity, rel: f64) -> bool {
    let near = |x: f64, y: f64| (x - y).abs() <= rel * a.eps;
    a.face == b.face
        && a.eps == b.eps
        && near(a.error, b.error)
        && near(a.surface_error, b.surface_error)
        && near(a.missing, b.missing)
        && near(a.edge_offset, b.edge_offset)
        && a.outside == b.outside
        && a.uncovered == b.uncovered
        && a.samples == b.samples
        && a.face_samples == b.face_samples
}

/// as1 places its bolts, nuts and plates several times. At one world tolerance every
/// placement's mesh is one mesh in the part's coordinates: measured once, the figures are
/// each placement's own to 1e-9 ε. For the view, placements get their own ε and mesh: each
/// is measured on its own (a key without ε would hand one placement's figures to another).
#[test]
fn placements_sharing_a_mesh_are_measured_once_with_their_own_figures() {
    let scene = common::load("as1-oc-214.stp");
    let tol = 0.05 * scene.bbox_diagonal() / 100.0;
    let cases = [
        (
            "one tolerance",
            tessellate_scene_tolerance(&scene, tol),
            1e-9,
        ),
        (
            "the view",
            tessellate_scene(&scene, &common::framing(&scene), 4.0 * DEFAULT_PIXEL_ERROR),
            1e-9,
        ),
    ];
    for (what, meshes, rel) in cases {
        let shared = by_patch(measure_meshes_search(
            &scene,
            &meshes,
            &NoProgress,
            Search::Indexed,
            true,
        ));
        let own = by_patch(measure_meshes_search(
            &scene,
            &meshes,
            &NoProgress,
            Search::Indexed,
            false,
        ));
        assert_eq!(shared.len(), own.len(), "{what}");
        assert!(own.len() > 100, "{what}: {} faces", own.len());
        for ((pa, a), (pb, b)) in shared.iter().zip(&own) {
            assert_eq!(pa, pb, "{what}");
            assert!(
                close(a, b, rel),
                "{what}: patch {pa}: shared {a:?}\nown {b:?}"
            );
        }
    }
}
