//! Instanced parts on the GPU (issue 19 item 2): a part placed k times is uploaded once per
//! level, in its own coordinates, and drawn once per placement (`render::resident`,
//! instances). Each shared mesh is uploaded once for all its placements (and not at all
//! without instancing); a placement lands where its world-space copy does (ID images and
//! depth against the same frame drawn from copies; a fault that drops the placements shows);
//! frames stay crack-free with fat borders per placement.

mod common;

use std::collections::HashSet;
use std::sync::Arc;
use std::time::Duration;

use patchwork::drive::flythrough::{FlythroughOptions, camera_path, run};
use patchwork::lod::{FrameLoop, LodOptions};
use patchwork::model::Scene;
use patchwork::render::resident::Fault;
use patchwork::render::{
    BorderGeometry, Frame, RenderOptions, Renderer, ResidentGeometry, Shading, UploadStats,
};
use patchwork::tessellate::PatchMesh;
use patchwork::view::View;

const SIZE: (u32, u32) = (400, 300);

fn views(scene: &Scene) -> Vec<View> {
    (0..3)
        .map(|i| camera_path(scene, 4 * i, 12, 45f64.to_radians(), SIZE))
        .collect()
}

/// Bytes a patch's geometry takes as lists (a placement's: of its world-space copy): 32 per
/// vertex, 12 per triangle, 40 per border point (one per border vertex and one per ring).
fn bytes(m: &PatchMesh) -> u64 {
    let world = m.world();
    let m = world.as_ref();
    let points = BorderGeometry::of(std::iter::once(m)).points.len();
    (32 * m.positions.len() + 12 * m.triangles.len() + 40 * points) as u64
}

/// The loop's meshes made resident on `renderer` (instances drawn as placements or not),
/// drawn for `view` with IDs and depth.
fn draw(
    renderer: &mut Renderer,
    lod: &FrameLoop,
    view: &View,
    instances: bool,
    fault: Fault,
) -> (ResidentGeometry, UploadStats, Frame) {
    renderer.instances = instances;
    let mut resident = ResidentGeometry::new(renderer);
    resident.fault = fault;
    let stats = resident
        .update(renderer, lod.shared_meshes(), lod.generation())
        .expect("the scene fits the device");
    let opts = RenderOptions {
        shading: Shading::Ids,
        ids: true,
        depth: true,
        ..RenderOptions::default()
    };
    let frame = renderer.render(&resident, view, &opts).expect("renders");
    (resident, stats, frame)
}

#[test]
fn each_shared_mesh_is_uploaded_once_for_all_its_placements() {
    let scene = common::load("as1-oc-214.stp");
    let mut renderer = common::renderer();
    let view = &views(&scene)[0];
    let lod = FrameLoop::new(&scene, view, LodOptions::default());
    let drawn: Vec<(usize, &Arc<PatchMesh>)> = lod.shared_meshes().collect();
    let placed: Vec<&Arc<PatchMesh>> = drawn
        .iter()
        .map(|d| d.1)
        .filter(|m| m.instance.is_some())
        .collect();
    let mut shared: HashSet<*const PatchMesh> = HashSet::new();
    let mut shared_bytes = 0;
    for m in &placed {
        let s = &m.instance.as_ref().expect("placed").shared;
        if shared.insert(Arc::as_ptr(s)) {
            shared_bytes += bytes(s);
        }
    }
    // as1's nuts, bolts and plates: several placements of one face at one level.
    assert!(
        shared.len() < placed.len(),
        "{} placements of {} shared meshes: nothing to share",
        placed.len(),
        shared.len()
    );
    let own_bytes: u64 = placed.iter().map(|m| bytes(m)).sum();
    let (inst, inst_stats, _) = draw(&mut renderer, &lod, view, true, Fault::None);
    let (copies, copy_stats, _) = draw(&mut renderer, &lod, view, false, Fault::None);
    assert_eq!(inst.shared_meshes(), shared.len());
    assert_eq!(inst.placed_patches(), placed.len());
    assert_eq!(inst_stats.placed, placed.len());
    // Exactly: the shared meshes once instead of every placement's copy.
    assert_eq!(
        inst_stats.geometry_bytes + own_bytes,
        copy_stats.geometry_bytes + shared_bytes,
        "{inst_stats:?} {copy_stats:?}"
    );
    assert!(inst_stats.uploaded_bytes() < copy_stats.uploaded_bytes());
    // A 64-byte record per placement and a 4-byte index per drawn one.
    assert_eq!(inst_stats.instance_bytes, 68 * placed.len() as u64);
    assert_eq!(inst.memory().records_used, 64 * placed.len() as u64);
    assert_eq!(copies.memory().records_used, 0);
    assert_eq!(copies.shared_meshes(), 0);
    assert_eq!(copies.placed_patches(), 0);
    assert_eq!(copy_stats.instance_bytes, 0);
    // Without shared tessellations no mesh is an instance.
    let alone = FrameLoop::new(
        &scene,
        view,
        LodOptions {
            instancing: false,
            ..LodOptions::default()
        },
    );
    assert!(alone.meshes().all(|m| m.instance.is_none()));
}

/// IDs and depth of two frames: pixels whose patch differs, pixels where the same patch's
/// depth differs by more than `depth_tol` (relative), and covered pixels; and pixels whose
/// patch in `a` shows nowhere among the 3 × 3 pixels around it in `b` and not at the same
/// depth as `b`'s (more than rounding at an edge or a tie between coplanar faces).
fn compare(a: &Frame, b: &Frame, depth_tol: f32) -> (usize, usize, usize, usize) {
    let (ia, ib) = (a.ids.as_ref().expect("ids"), b.ids.as_ref().expect("ids"));
    let (da, db) = (
        a.depth.as_ref().expect("depth"),
        b.depth.as_ref().expect("depth"),
    );
    let (w, h) = (a.width as usize, a.height as usize);
    let near = |k: usize, id: u32| {
        let (x, y) = (k % w, k / w);
        (y.saturating_sub(1)..(y + 2).min(h))
            .any(|yy| (x.saturating_sub(1)..(x + 2).min(w)).any(|xx| ib[yy * w + xx] == id))
    };
    let mut ids = 0;
    let mut depth = 0;
    let mut far = 0;
    for k in 0..ia.len() {
        if ia[k] != ib[k] {
            ids += 1;
            // A tie between coplanar faces (contact faces of a nut on a plate) may go
            // either way with the rounding: the same depth, another patch.
            let tie = ia[k] != 0 && ib[k] != 0 && (da[k] - db[k]).abs() <= depth_tol * da[k].abs();
            far += usize::from(!near(k, ia[k]) && !tie);
        } else if ia[k] != 0 && (da[k] - db[k]).abs() > depth_tol * da[k].abs() {
            depth += 1;
        }
    }
    (ids, depth, ia.iter().filter(|&&i| i != 0).count(), far)
}

#[test]
fn an_instanced_placement_lands_where_its_world_copy_does() {
    let scene = common::load("as1-oc-214.stp");
    let mut renderer = common::renderer();
    for (v, view) in views(&scene).iter().enumerate() {
        let lod = FrameLoop::new(&scene, view, LodOptions::default());
        let (inst, _, a) = draw(&mut renderer, &lod, view, true, Fault::None);
        let (_, _, b) = draw(&mut renderer, &lod, view, false, Fault::None);
        assert!(inst.placed_patches() > 0, "view {v}: nothing drawn placed");
        // The same vertices up to f32 rounding of the placement (applied on the GPU instead
        // of in f64): a few edge pixels may change hands.
        let (ids, depth, covered, far) = compare(&a, &b, 1e-4);
        eprintln!(
            "view {v}: {ids} ID ({far} off an edge) and {depth} depth pixels differ of {covered}"
        );
        assert!(covered > 10_000, "view {v}: {covered} pixels covered");
        assert!(ids * 200 <= covered, "view {v}: {ids} of {covered} pixels");
        assert_eq!(
            far, 0,
            "view {v}: pixels show a patch not even next to them"
        );
        assert!(
            depth * 1000 <= covered,
            "view {v}: {depth} of {covered} pixels"
        );
        // Every patch covers about as many pixels in both (thin faces change a few edge
        // pixels). Pixels where two coplanar faces tie (another patch at the same depth, as
        // in `compare`) are left out: a tie goes either way with the rounding, over a whole
        // contact face (on llvmpipe's GL, 17 of one small face's 33 pixels went to the face
        // it ties with when placed).
        let (ia, ib) = (a.ids.as_ref().expect("ids"), b.ids.as_ref().expect("ids"));
        let (da, db) = (
            a.depth.as_ref().expect("depth"),
            b.depth.as_ref().expect("depth"),
        );
        let tie = |k: usize| {
            ia[k] != ib[k]
                && ia[k] != 0
                && ib[k] != 0
                && (da[k] - db[k]).abs() <= 1e-4 * da[k].abs()
        };
        let count = |ids: &[u32]| {
            let mut c = vec![0usize; scene.patches.len() + 1];
            for (k, &i) in ids.iter().enumerate() {
                if !tie(k) {
                    c[i as usize] += 1;
                }
            }
            c
        };
        let (ca, cb) = (count(ia), count(ib));
        for p in 1..ca.len() {
            let d = ca[p].abs_diff(cb[p]);
            assert!(
                d <= 10 + cb[p] / 10,
                "view {v}: patch {} covers {} pixels placed, {} as a copy",
                p - 1,
                ca[p],
                cb[p]
            );
        }
        // Mutation: placements dropped (every placed patch drawn at its part's origin).
        let (_, _, wrong) = draw(&mut renderer, &lod, view, true, Fault::UnplacedInstances);
        let (ids, _, _, far) = compare(&wrong, &b, 1e-4);
        assert!(
            ids * 20 > covered && far * 40 > covered,
            "view {v}: placements dropped, yet only {ids} of {covered} pixels differ ({far})"
        );
    }
}

#[test]
fn placed_frames_along_a_camera_path_match_world_copies() {
    // One resident geometry updated frame after frame (records reused and freed, shared
    // meshes released, record indices rewritten where they changed) against a whole upload
    // of the same meshes as world-space copies each frame.
    let scene = common::load("as1-oc-214.stp");
    let mut renderer = common::renderer();
    let frames = 16;
    let path = |i| camera_path(&scene, i, frames, 45f64.to_radians(), SIZE);
    let mut lod = FrameLoop::new(
        &scene,
        &path(0),
        LodOptions {
            budget: Duration::from_millis(2),
            ..LodOptions::default()
        },
    );
    let mut resident = ResidentGeometry::new(&renderer);
    let opts = RenderOptions {
        shading: Shading::Ids,
        ids: true,
        depth: true,
        ..RenderOptions::default()
    };
    let mut placed_updates = 0;
    for i in 0..frames {
        let view = path(i);
        if i > 0 {
            lod.update(&scene, &view);
        }
        let u = resident
            .update(&renderer, lod.shared_meshes(), lod.generation())
            .expect("the scene fits the device");
        if i > 0 {
            placed_updates += u.placed;
        }
        let a = renderer.render(&resident, &view, &opts).expect("renders");
        let whole = renderer.upload(lod.meshes());
        let b = renderer.render(&whole, &view, &opts).expect("renders");
        let (ids, _, covered, far) = compare(&a, &b, 1e-4);
        assert!(
            ids * 200 <= covered && far == 0,
            "frame {i}: {ids} of {covered} pixels differ, {far} off an edge"
        );
        if let Some(v) = a.visible_ids(scene.patches.len()) {
            lod.set_visible(&v);
        }
    }
    assert!(
        placed_updates > 0,
        "no placed patch changed after the first frame: the test proves nothing"
    );
}

#[test]
fn frames_with_placed_parts_are_crack_free() {
    let scene = common::load("as1-oc-214.stp");
    let mut renderer = common::renderer();
    // A budget too small for more than a few patches per frame: placements of one face sit
    // at different levels, some drawn placed from different shared meshes.
    let opts = FlythroughOptions {
        frames: 24,
        size: (256, 192),
        fov_y: 45f64.to_radians(),
        lod: LodOptions {
            budget: Duration::from_nanos(1),
            ..LodOptions::default()
        },
        target: None,
        cracks: true,
        ortho: false,
    };
    let (records, summary) = run(&mut renderer, &scene, &opts, |_| {}).expect("renders");
    assert!(summary.placed_patches > 0, "{summary:?}");
    assert!(
        summary.shared_meshes < summary.placed_patches,
        "{summary:?}"
    );
    let off: usize = records.iter().filter_map(|r| r.crack_pixels_off).sum();
    assert!(
        off > 0,
        "no crack without fat borders: the check could not fail"
    );
    for r in &records {
        assert_eq!(r.crack_pixels, Some(0), "frame {}: {r:?}", r.frame);
    }
}
