//! Resident GPU geometry (`render::resident`): frames drawn from it equal frames drawn from a
//! whole `Renderer::upload` bit for bit while patches are re-tessellated along a camera path;
//! a frame uploads exactly the bytes of the patches that changed (and the draw arguments);
//! a frame where nothing changed uploads nothing. A stale slot (fault injected) shows.

mod common;

use std::sync::Arc;

use patchwork::drive::flythrough::camera_path;
use patchwork::frame::{FrameState, StepOptions, step};
use patchwork::lod::{FrameLoop, LodOptions};
use patchwork::model::Scene;
use patchwork::render::resident::Fault;
use patchwork::render::{
    BorderGeometry, BorderPoint, FatBorders, Frame, Primitives, RenderOptions, Renderer,
    ResidentGeometry, Shading, UploadStats,
};
use patchwork::strips::Join;
use patchwork::tessellate::PatchMesh;
use patchwork::view::View;

const SIZE: (u32, u32) = (320, 240);
const FRAMES: usize = 14;

fn view(scene: &Scene, i: usize) -> View {
    camera_path(scene, i, FRAMES, 45f64.to_radians(), SIZE)
}

/// The options of frame `i`: shading, fat-border variant and MSAA cycle through every
/// choice; depth and IDs always.
fn options(i: usize) -> RenderOptions {
    RenderOptions {
        shading: [Shading::Lit, Shading::Flat, Shading::Ids][i % 3],
        fat_borders: [
            FatBorders::Six,
            FatBorders::Four,
            FatBorders::Two,
            FatBorders::Off,
        ][i % 4],
        msaa: if i % 5 == 2 { 4 } else { 1 },
        depth: true,
        ids: true,
        ..RenderOptions::default()
    }
}

fn differing(a: &Frame, b: &Frame) -> usize {
    let colour = a
        .color
        .chunks_exact(4)
        .zip(b.color.chunks_exact(4))
        .filter(|(x, y)| x != y)
        .count();
    let depth = match (&a.depth, &b.depth) {
        (Some(x), Some(y)) => x
            .iter()
            .zip(y)
            .filter(|(p, q)| p.to_bits() != q.to_bits())
            .count(),
        _ => usize::MAX,
    };
    let ids = match (&a.ids, &b.ids) {
        (Some(x), Some(y)) => x.iter().zip(y).filter(|(p, q)| p != q).count(),
        _ => usize::MAX,
    };
    colour + depth + ids
}

/// Drives a frame loop along the camera path, keeping `resident` up to date; `each` sees the
/// frame index, the loop, the update's figures and the patches it changed.
fn drive(
    renderer: &mut Renderer,
    scene: &Scene,
    resident: &mut ResidentGeometry,
    mut each: impl FnMut(usize, &mut Renderer, &FrameLoop, &ResidentGeometry, UploadStats, usize),
) {
    let mut lod = FrameLoop::new(
        scene,
        &view(scene, 0),
        LodOptions {
            budget: std::time::Duration::from_millis(5),
            ..LodOptions::default()
        },
    );
    let mut held: Vec<Option<Arc<PatchMesh>>> = vec![None; scene.patches.len()];
    for i in 0..FRAMES {
        let v = view(scene, i);
        if i > 0 {
            lod.update(scene, &v);
        }
        let changed = lod
            .shared_meshes()
            .filter(|(k, m)| !held[*k].as_ref().is_some_and(|h| Arc::ptr_eq(h, m)))
            .count();
        for (k, m) in lod.shared_meshes() {
            held[k] = Some(m.clone());
        }
        let stats = resident
            .update(renderer, lod.shared_meshes(), lod.generation())
            .expect("the scene fits the device");
        each(i, renderer, &lod, resident, stats, changed);
        let f = renderer
            .render(
                &*resident,
                &v,
                &RenderOptions {
                    ids: true,
                    ..RenderOptions::default()
                },
            )
            .expect("renders");
        if let Some(visible) = f.visible_ids(scene.patches.len()) {
            lod.set_visible(&visible);
        }
    }
}

/// Frames through the resident geometry against whole uploads; returns the differing pixels
/// per frame and how many frames updated some but not all patches.
fn compare(renderer: &mut Renderer, scene: &Scene, fault: Fault) -> (Vec<usize>, usize) {
    let mut resident = ResidentGeometry::new(renderer);
    resident.fault = fault;
    compare_with(renderer, scene, resident)
}

/// [`compare`] with a resident geometry set up by the caller.
fn compare_with(
    renderer: &mut Renderer,
    scene: &Scene,
    mut resident: ResidentGeometry,
) -> (Vec<usize>, usize) {
    let mut diffs = Vec::new();
    let mut partial = 0;
    drive(
        renderer,
        scene,
        &mut resident,
        |i, renderer, lod, resident, stats, _| {
            let drawn = lod.meshes().count();
            partial += usize::from(stats.patches > 0 && stats.patches < drawn);
            let v = view(scene, i);
            let opts = options(i);
            let a = renderer.render(resident, &v, &opts).expect("renders");
            let whole = renderer.upload(lod.meshes());
            let b = renderer.render(&whole, &v, &opts).expect("renders");
            diffs.push(differing(&a, &b));
        },
    );
    (diffs, partial)
}

#[test]
fn resident_frames_equal_whole_uploads_bit_for_bit() {
    let mut renderer = common::renderer();
    let gl = renderer.gpu().info.backend == wgpu::Backend::Gl;
    let teapot = common::teapot();
    let bunny = common::load("bunny.glb");
    let cases = [
        (&teapot, "teapot", Primitives::List, None),
        (&teapot, "teapot", Primitives::Strips, None),
        (
            &teapot,
            "teapot",
            Primitives::Strips,
            Some(Join::Degenerate),
        ),
        (&bunny, "bunny", Primitives::Auto, None),
        (&bunny, "bunny", Primitives::List, None),
    ];
    for (scene, name, primitives, join) in cases {
        renderer.primitives = primitives;
        renderer.strip_join = join.unwrap_or(if gl { Join::Degenerate } else { Join::Restart });
        let (diffs, partial) = compare(&mut renderer, scene, Fault::None);
        assert!(
            partial >= 2,
            "{name} {primitives:?}: only {partial} frames re-tessellated part of the scene, the test proves little"
        );
        assert!(
            diffs.iter().all(|&d| d == 0),
            "{name} {primitives:?} {join:?}: differing pixels per frame {diffs:?}"
        );
    }
}

#[test]
fn many_arenas_draw_the_same_picture() {
    // Pools capped at 128 KiB: the teapot's geometry spreads over many arenas (as a scene past
    // the device's largest buffer does); the draws still follow patch order, bit for bit.
    let mut renderer = common::renderer();
    let scene = common::teapot();
    for primitives in [Primitives::List, Primitives::Strips] {
        renderer.primitives = primitives;
        let mut resident = ResidentGeometry::new(&renderer);
        resident.arena_bytes = Some(128 << 10);
        let (diffs, partial) = compare_with(&mut renderer, &scene, resident);
        assert!(partial >= 2, "{primitives:?}: {partial}");
        assert!(
            diffs.iter().all(|&d| d == 0),
            "{primitives:?}: differing pixels per frame {diffs:?}"
        );
    }
    let mut resident = ResidentGeometry::new(&renderer);
    resident.arena_bytes = Some(128 << 10);
    let lod = FrameLoop::new(&scene, &view(&scene, 0), LodOptions::default());
    resident
        .update(&renderer, lod.shared_meshes(), 1)
        .expect("fits in many arenas");
    let memory = resident.memory();
    assert!(memory.arenas >= 2, "{memory:?}");
    // One patch larger than an arena cannot be placed anywhere.
    let mut tiny = ResidentGeometry::new(&renderer);
    tiny.arena_bytes = Some(256);
    let err = tiny.update(&renderer, lod.shared_meshes(), 1);
    assert!(
        matches!(err, Err(patchwork::render::RenderError::TooLarge { .. })),
        "{err:?}"
    );
}

#[test]
fn a_stale_slot_shows_in_the_picture() {
    // The mutation the test above must catch: a changed patch left as it was.
    let mut renderer = common::renderer();
    let scene = common::teapot();
    renderer.primitives = Primitives::List;
    let (diffs, _) = compare(&mut renderer, &scene, Fault::KeepFirstStale);
    assert!(
        diffs.iter().any(|&d| d > 0),
        "a stale slot drew the same pictures: the comparison could not fail ({diffs:?})"
    );
}

/// Bytes of one patch's geometry drawn as triangle lists: surface vertices (position and
/// normal as 3 × f32 each, patch id u32, colour 4 × u8: 32 bytes), 3 indices of 4 bytes per
/// triangle, and its fat borders (one 40-byte point per border vertex and one per ring,
/// expanded on the GPU).
fn list_patch_bytes(m: &PatchMesh) -> u64 {
    let borders = BorderGeometry::of(std::iter::once(m));
    assert_eq!(size_of::<BorderPoint>(), 40);
    assert_eq!(
        borders.points.len(),
        m.border_vertex_count() + m.borders.len()
    );
    (32 * m.positions.len() + 12 * m.triangles.len() + 40 * borders.points.len()) as u64
}

#[test]
fn a_frame_uploads_exactly_the_changed_patches_bytes() {
    let mut renderer = common::renderer();
    renderer.primitives = Primitives::List;
    let scene = common::teapot();
    let indirect = renderer.gpu().indirect;
    let mut resident = ResidentGeometry::new(&renderer);
    let mut held: Vec<Option<Arc<PatchMesh>>> = vec![None; scene.patches.len()];
    let mut partial = 0;
    drive(
        &mut renderer,
        &scene,
        &mut resident,
        |i, _, lod, resident, stats, changed| {
            let expected: u64 = lod
                .shared_meshes()
                .filter(|(k, m)| !held[*k].as_ref().is_some_and(|h| Arc::ptr_eq(h, m)))
                .map(|(_, m)| list_patch_bytes(m))
                .sum();
            for (k, m) in lod.shared_meshes() {
                held[k] = Some(m.clone());
            }
            partial += usize::from(changed > 0 && changed < lod.meshes().count());
            assert_eq!(stats.patches, changed, "frame {i}");
            assert_eq!(stats.geometry_bytes, expected, "frame {i}: {stats:?}");
            assert_eq!(stats.static_bytes, 0);
            if stats.compactions == 0 {
                assert_eq!(stats.reindexed_bytes, 0, "frame {i}");
            }
            // Draw arguments: one per merged draw (three for fat borders, one per variant),
            // written when the draw list was rebuilt.
            let border = resident.border_draw_count() as u64;
            let args = if indirect && stats.rebuilt {
                20 * (resident.draw_count() as u64 - border) + 3 * 20 * border
            } else {
                0
            };
            assert_eq!(stats.args_bytes, args, "frame {i}");
            assert_eq!(
                stats.uploaded_bytes(),
                expected + stats.reindexed_bytes + args,
                "frame {i}"
            );
        },
    );
    assert!(
        partial >= 2,
        "only {partial} frames changed part of the scene"
    );
}

#[test]
fn a_frame_where_nothing_changed_uploads_nothing() {
    let mut renderer = common::renderer();
    let scene = common::teapot();
    let v = view(&scene, 0);
    let mut state = FrameState::new(&scene, &v, LodOptions::default());
    let first = state.upload(&renderer).expect("the scene fits the device");
    assert_eq!(first.patches, scene.patches.len());
    assert!(first.geometry_bytes > 0);
    // Still camera: step until the frame loop is settled, then once more.
    let mut settled = false;
    for _ in 0..6 {
        let r = step(
            &mut renderer,
            &scene,
            &mut state,
            &v,
            &StepOptions::default(),
        )
        .expect("renders");
        let u = r.upload.expect("the default frame is resident");
        if r.stats.retessellated + r.stats.from_cache == 0 && settled {
            assert_eq!(u, UploadStats::default(), "{u:?}");
            assert_eq!(u.uploaded_bytes(), 0);
            // Only the uniform block of the colour and ID passes.
            assert_eq!(r.uploaded_bytes, renderer.last_render().uniform_bytes);
            assert!(r.uploaded_bytes <= 2 * 256, "{}", r.uploaded_bytes);
            return;
        }
        settled = r.stats.retessellated + r.stats.from_cache == 0;
    }
    panic!("the frame loop never settled on a still camera");
}

#[test]
fn a_new_generation_without_new_meshes_only_rebuilds_the_draws() {
    let renderer = common::renderer();
    let scene = common::teapot();
    let v = view(&scene, 0);
    let lod = FrameLoop::new(&scene, &v, LodOptions::default());
    let mut resident = ResidentGeometry::new(&renderer);
    let first = resident
        .update(&renderer, lod.shared_meshes(), 7)
        .expect("fits");
    assert_eq!(first.patches, lod.meshes().count());
    // The same generation: nothing walked, nothing written.
    assert_eq!(
        resident
            .update(&renderer, lod.shared_meshes(), 7)
            .expect("fits"),
        UploadStats::default()
    );
    // Another generation, the same meshes: no geometry, only the draw arguments again.
    let again = resident
        .update(&renderer, lod.shared_meshes(), 8)
        .expect("fits");
    assert_eq!(again.patches, 0);
    assert_eq!(again.geometry_bytes, 0);
    assert!(again.rebuilt);
    let args = if renderer.gpu().indirect {
        let border = resident.border_draw_count() as u64;
        20 * (resident.draw_count() as u64 - border) + 3 * 20 * border
    } else {
        0
    };
    assert_eq!(again.uploaded_bytes(), args);
}

#[test]
fn packing_every_pool_keeps_the_picture() {
    // Compaction moves vertices: the moved patches' indices are written again. The frame
    // after packing equals a whole upload's. The teapot's surfaces are resident; the bunny's
    // mesh patches draw from static buffers and only their fat-border points (which no index
    // refers to) are resident.
    for (name, moves_vertices) in [("teapot.bpt", true), ("bunny.glb", false)] {
        let mut renderer = common::renderer();
        let scene = common::load(name);
        let mut resident = ResidentGeometry::new(&renderer);
        let mut last = None;
        drive(
            &mut renderer,
            &scene,
            &mut resident,
            |i, _, lod, _, _, _| {
                if i + 1 == FRAMES {
                    last = Some(lod.meshes().cloned().collect::<Vec<_>>());
                }
            },
        );
        let meshes = last.expect("frames ran");
        let packed = resident.compact_all(&renderer);
        assert!(packed.compactions > 0, "{name}: {packed:?}");
        assert!(packed.copied_bytes > 0, "{name}: {packed:?}");
        assert_eq!(
            packed.reindexed_bytes > 0,
            moves_vertices,
            "{name}: {packed:?}"
        );
        assert_eq!(packed.geometry_bytes, 0);
        let v = view(&scene, FRAMES - 1);
        for i in 0..4 {
            let opts = options(i);
            let a = renderer.render(&resident, &v, &opts).expect("renders");
            let whole = renderer.upload(&meshes);
            let b = renderer.render(&whole, &v, &opts).expect("renders");
            assert_eq!(differing(&a, &b), 0, "{name}: options {opts:?}");
        }
    }
}
