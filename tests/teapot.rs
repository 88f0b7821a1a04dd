//! The shipped teapot tessellated for a view: every patch within its ε, finite normals at the
//! lid's and bottom's poles, and neighbours at different resolutions (the cracks are real).

mod common;

use patchwork::tessellate::{MeshStats, tessellate_scene};
use patchwork::view::{self, View};

#[test]
fn teapot_tessellation_holds_eps_and_has_finite_normals() {
    let scene = common::teapot();
    let fov = view::DEFAULT_FOV_Y_DEG.to_radians();
    for px in [0.25, 0.5, 4.0] {
        let v = View::framing(&scene.bounds, scene.up.vector(), fov, (1024, 768));
        let meshes = tessellate_scene(&scene, &v, px);
        for m in &meshes {
            assert!(
                m.error <= m.eps_target,
                "patch {}: {} > {}",
                m.patch_id,
                m.error,
                m.eps_target
            );
            assert!(m.eps_target > 0.0);
            for n in &m.normals {
                assert!(
                    n.is_finite() && (n.length() - 1.0).abs() < 1e-3,
                    "patch {}: {n:?}",
                    m.patch_id
                );
            }
            assert_eq!(m.borders.len(), 1, "one closed border loop per patch");
        }
        let s = MeshStats::of(&meshes);
        assert!(s.worst_error_ratio <= 1.0);
        // Independent resolutions: not all patches use the same grid.
        let first = meshes[0].resolution;
        assert!(
            meshes.iter().any(|m| m.resolution != first),
            "all patches share one grid"
        );
    }
}

#[test]
fn finer_pixel_error_means_more_triangles() {
    let scene = common::teapot();
    let v = View::framing(&scene.bounds, scene.up.vector(), 0.8, (1024, 768));
    let tris = |px| MeshStats::of(&tessellate_scene(&scene, &v, px)).triangles;
    let (a, b, c) = (tris(0.25), tris(1.0), tris(4.0));
    assert!(a > b && b > c, "{a} {b} {c}");
}
