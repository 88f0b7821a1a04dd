//! The frame loop at scale (issue 19): culling through the bounding-volume hierarchy keeps
//! exactly the patches a linear scan keeps, and instanced parts share their tessellations
//! without changing a single vertex. CPU only: no adapter needed.

mod common;

use glam::DVec3;
use patchwork::lod::{FrameLoop, LodOptions};
use patchwork::model::Scene;
use patchwork::tessellate::{PatchMesh, Tessellators, placed};
use patchwork::view::View;

/// Views around and inside the model: far, close to a corner (most patches culled), and
/// looking away.
fn views(scene: &Scene) -> Vec<View> {
    let (c, r) = (scene.bounds.center, scene.bounds.radius);
    let up = scene.up.vector();
    let side = if up == DVec3::Z { DVec3::X } else { DVec3::Z };
    let size = (320, 240);
    let fov = 45f64.to_radians();
    [
        (c + (side + up * 0.4) * 3.0 * r, c),
        (
            c + side * 0.6 * r,
            c + side * 0.2 * r + up.cross(side) * 0.5 * r,
        ),
        (c - up.cross(side) * 0.7 * r, c - up.cross(side) * 2.0 * r),
    ]
    .into_iter()
    .map(|(eye, target)| View::new(eye, target, up, fov, size, &scene.bounds))
    .collect()
}

#[test]
fn culling_keeps_exactly_the_patches_a_linear_scan_keeps() {
    for name in ["as1-oc-214.stp", "bunny.glb"] {
        let scene = common::load(name);
        let vs = views(&scene);
        let mut lod = FrameLoop::new(&scene, &vs[0], LodOptions::default());
        let mut some_culled = false;
        for v in vs.iter().chain(vs.iter().rev()) {
            lod.update(&scene, v);
            let drawn: Vec<usize> = lod.meshes_with_index().map(|(i, _)| i).collect();
            let linear: Vec<usize> = (0..scene.patches.len())
                .filter(|&i| v.sees_sphere(&scene.patches[i].bounds))
                .collect();
            assert_eq!(drawn, linear, "{name}: eye {}", v.eye);
            some_culled |= linear.len() < scene.patches.len() && !linear.is_empty();
        }
        assert!(some_culled, "{name}: the views should cull some patches");
    }
}

/// Every patch's mesh as drawn equals, vertex for vertex, the patch tessellated on its own at
/// the same ε; on as1 (bolts and nuts placed several times) most placed faces got a copy.
#[test]
fn instanced_parts_share_tessellations_without_changing_a_vertex() {
    let scene = common::load("as1-oc-214.stp");
    let vs = views(&scene);
    let mut lod = FrameLoop::new(&scene, &vs[0], LodOptions::default());
    for v in &vs {
        lod.update(&scene, v);
    }
    let stats = lod.instancing();
    assert!(
        stats.shared_patches > scene.patches.len() / 4,
        "as1 places its bolts and nuts several times: {stats:?} of {} patches",
        scene.patches.len()
    );
    assert!(stats.saved > 0 && stats.made > 0, "{stats:?}");
    let mut t = Tessellators::new();
    let mut checked = 0;
    for i in 0..scene.patches.len() {
        let m = lod.mesh(i).expect("one mesh per patch").world();
        let mut own = PatchMesh::default();
        t.patch(&scene.patches[i], m.eps_target, &mut own);
        assert_eq!(m.patch_id, own.patch_id);
        assert_eq!(m.positions, own.positions, "patch {i}");
        assert_eq!(m.normals, own.normals, "patch {i}");
        assert_eq!(m.triangles, own.triangles, "patch {i}");
        assert_eq!(m.borders, own.borders, "patch {i}");
        assert_eq!(m.color, own.color, "patch {i}");
        checked += 1;
    }
    assert_eq!(checked, scene.patches.len());
}

/// Mutation check of the test above: a copy placed for another placement of the same surface
/// is not the patch's own mesh, so comparing vertices does catch a wrong placement.
#[test]
fn a_copy_placed_for_another_placement_differs() {
    let scene = common::load("as1-oc-214.stp");
    let key = patchwork::tessellate::shared_surface;
    let (a, b) = (0..scene.patches.len())
        .flat_map(|a| (a + 1..scene.patches.len()).map(move |b| (a, b)))
        .find(|&(a, b)| {
            key(&scene.patches[a]).is_some()
                && key(&scene.patches[a]) == key(&scene.patches[b])
                && scene.patches[a].transform != scene.patches[b].transform
        })
        .expect("as1 places a part twice");
    let mut t = Tessellators::new();
    let eps = scene.bounds.radius * 1e-3;
    let mut unplaced = PatchMesh::default();
    t.unplaced(&scene.patches[a], eps, &mut unplaced);
    let (mut own_a, mut own_b) = (PatchMesh::default(), PatchMesh::default());
    t.patch(&scene.patches[a], eps, &mut own_a);
    t.patch(&scene.patches[b], eps, &mut own_b);
    let unplaced = std::sync::Arc::new(unplaced);
    assert_eq!(
        placed(&unplaced, &scene.patches[a]).world().positions,
        own_a.positions
    );
    assert_eq!(
        placed(&unplaced, &scene.patches[b]).world().positions,
        own_b.positions
    );
    assert_ne!(
        placed(&unplaced, &scene.patches[b]).world().positions,
        own_a.positions
    );
}

/// A 3 × 2 grid of teapots (the scene, small): every copy of a patch shares the first
/// one's tessellation, translated, and stays within f32 rounding of its own tessellation.
#[test]
fn translated_bezier_copies_share_tessellations() {
    let scene = teapot_grid(3, 2);
    let vs = views(&scene);
    let mut lod = FrameLoop::new(&scene, &vs[0], LodOptions::default());
    lod.update(&scene, &vs[1]);
    let stats = lod.instancing();
    assert_eq!(stats.shared_patches, scene.patches.len(), "{stats:?}");
    // Copies at the same distance want the same level: fewer tessellations than patches.
    assert!(
        stats.saved > 0 && stats.made < scene.patches.len() as u64,
        "{stats:?}"
    );
    let mut t = Tessellators::new();
    for (i, patch) in scene.patches.iter().enumerate() {
        let m = lod.mesh(i).expect("a mesh").world();
        let mut own = PatchMesh::default();
        t.patch(patch, m.eps_target, &mut own);
        assert_eq!(m.patch_id, own.patch_id);
        // The same grid (a quad's diagonal may flip with rounding: either is within ε).
        assert_eq!(m.resolution, own.resolution, "patch {i}");
        assert_eq!(m.triangles.len(), own.triangles.len(), "patch {i}");
        assert_eq!(m.borders, own.borders, "patch {i}");
        let far = m
            .positions
            .iter()
            .zip(&own.positions)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0f32, f32::max);
        assert!(
            far < 1e-5,
            "patch {i}: a copy is {far} off its own tessellation"
        );
        assert!(
            m.error <= m.eps_target,
            "patch {i}: error {} > ε {}",
            m.error,
            m.eps_target
        );
    }
}

/// An `nx × ny` grid of teapots 8 units apart (the scene, small).
fn teapot_grid(nx: usize, ny: usize) -> Scene {
    use patchwork::io::Model;
    use patchwork::model::{BezierPatch, UpAxis};
    let Ok(Model::Bezier(teapot)) = patchwork::io::read(&common::root().join("models/teapot.bpt"))
    else {
        panic!("the teapot reads as Bézier patches");
    };
    let mut patches = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let offset = DVec3::new(8.0 * i as f64, 8.0 * j as f64, 0.0);
            for b in &teapot {
                let (du, dv) = b.degree();
                let ctrl = b.control_points().iter().map(|c| *c + offset).collect();
                patches.push(BezierPatch::new(du, dv, ctrl).expect("a translated patch"));
            }
        }
    }
    Scene::from_bezier(patches, UpAxis::Z)
}

/// Issue 19: the loop keeps each shared tessellation once, not a moved copy per placement.
/// Every instance holds no vertices of its own (its struct only: under a quarter of its
/// world copy's bytes on this grid) and the shared meshes are counted once, apart, in the
/// loop's memory.
#[test]
fn placements_hold_no_vertices_of_their_own() {
    let scene = teapot_grid(4, 4);
    let vs = views(&scene);
    let mut lod = FrameLoop::new(&scene, &vs[0], LodOptions::default());
    lod.update(&scene, &vs[1]);
    let (mut instances, mut world_bytes) = (0, 0);
    for i in 0..scene.patches.len() {
        let m = lod.mesh(i).expect("a mesh");
        if m.instance.is_some() {
            instances += 1;
            assert_eq!(
                m.mem_bytes(),
                std::mem::size_of::<PatchMesh>(),
                "patch {i}: a placement holds geometry of its own"
            );
            assert!(m.triangle_count() > 0, "patch {i}");
        }
        world_bytes += m.world().mem_bytes();
    }
    assert_eq!(instances, scene.patches.len());
    // Current tessellations: a struct and the Arc's counters per placement, nothing else;
    // the shared meshes counted apart, once.
    let mem = lod.memory();
    let per = std::mem::size_of::<PatchMesh>() + 2 * std::mem::size_of::<usize>();
    assert_eq!(mem.current, scene.patches.len() * per, "{mem:?}");
    assert!(mem.shared > 0, "{mem:?}");
    assert!(
        mem.current * 4 < world_bytes,
        "the placements hold {} bytes; their world copies take {world_bytes}",
        mem.current
    );
}

/// The largest and 99th-percentile screen errors are those of the patches drawn (all
/// visible after the first frame), as a sort of their errors gives them.
#[test]
fn screen_errors_are_the_drawn_patches_order_statistics() {
    let scene = teapot_grid(4, 4);
    let vs = views(&scene);
    let lod = FrameLoop::new(&scene, &vs[0], LodOptions::default());
    let all = lod.patch_errors_px();
    let mut e: Vec<f64> = lod.meshes_with_index().map(|(i, _)| all[i]).collect();
    assert!(e.len() > 100, "{} patches drawn", e.len());
    e.sort_by(f64::total_cmp);
    let p99 = e[((e.len() - 1) as f64 * 0.99).round() as usize];
    assert!(p99 < e[e.len() - 1], "the errors should differ: {e:?}");
    assert_eq!(lod.screen_errors(), (e[e.len() - 1], p99));
}
