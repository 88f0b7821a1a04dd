//! Unit tests of the frame loop's pieces: queue weights and order, levels, hysteresis, the
//! per-patch cache, reuse within ε, the frame-rate controller.

use super::*;

#[test]
fn too_coarse_outranks_too_fine() {
    // Too coarse: screen error × screen area (pixels, pixels²); on target or too fine: at
    // most 0, the finer the higher.
    let pe = 0.5;
    let w = priority(2.0, 1.0, 4.0, pe);
    let area = std::f64::consts::PI * (pe * 4.0) * (pe * 4.0);
    assert!((w - (pe * 2.0) * area).abs() < 1e-12, "{w}");
    assert_eq!(priority(0.5, 1.0, 4.0, pe), -0.5);
    assert_eq!(priority(1.0, 1.0, 4.0, pe), -1.0);
    // Any coarse patch, however small and however little off, beats any fine one.
    for r in [1.0001, 1.1, 1.5, 3.0, 10.0] {
        assert!(priority(r, 1.0, 1e-6, pe) > priority(1.0 / r, 1.0, 1e6, pe));
        assert!(priority(r, 1.0, 1e-6, pe) > 0.0);
    }
    // Monotone in how far off a patch is, and in its size when too coarse.
    assert!(priority(3.0, 1.0, 4.0, pe) > priority(2.0, 1.0, 4.0, pe));
    assert!(priority(2.0, 1.0, 8.0, pe) > priority(2.0, 1.0, 4.0, pe));
    assert!(priority(0.25, 1.0, 4.0, pe) > priority(0.5, 1.0, 4.0, pe));
}

/// The queue's order as `update` makes it: weights from [`priority`], sorted by
/// [`order_queue`]; returns the patch indices in the order the workers take them.
fn queue_order(patches: &[(f64, f64, f64)], pe: f64) -> Vec<usize> {
    let mut q: Vec<(f64, usize)> = patches
        .iter()
        .enumerate()
        .map(|(i, &(c, w, r))| (priority(c, w, r, pe), i))
        .collect();
    order_queue(&mut q);
    q.into_iter().map(|(_, i)| i).collect()
}

#[test]
fn the_queue_takes_the_largest_screen_error_times_area_first() {
    let pe = 0.5;
    // (current ε, wanted ε, bounding radius)
    let patches = [
        (4.0, 1.0, 1.0),    // 0: very coarse, tiny: 2 px × 1 px² (a pixel at least) = 2
        (1.1, 1.0, 10.0),   // 1: slightly coarse, large: 0.55 px × 78.5 px² = 43
        (0.25, 1.0, 100.0), // 2: too fine, huge: no visible error
        (2.0, 1.0, 4.0),    // 3: coarse, medium: 1 px × 12.6 px² = 12.6
        (0.45, 1.0, 1.0),   // 4: too fine, less so than 2
    ];
    // The paper's weights ((ε_c/ε_w)², ε_w/ε_c) would take 0, 2, 3, 4, 1.
    assert_eq!(queue_order(&patches, pe), [1, 3, 0, 2, 4]);
    // Many patches: the coarse ones in non-increasing error × area, then the fine ones.
    let mut state = 12345u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let many: Vec<(f64, f64, f64)> = (0..200)
        .map(|_| (0.2 + 3.0 * next(), 1.0, 0.1 + 20.0 * next()))
        .collect();
    let order = queue_order(&many, pe);
    let shown = |&(c, w, r): &(f64, f64, f64)| {
        let area = (std::f64::consts::PI * (pe * r / w).powi(2)).max(1.0);
        if c > w { pe * c / w * area } else { -1.0 }
    };
    let first_fine = order
        .iter()
        .position(|&i| many[i].0 <= many[i].1)
        .expect("some fine patches");
    assert!(first_fine > 0);
    assert!(order[first_fine..].iter().all(|&i| many[i].0 <= many[i].1));
    for pair in order[..first_fine].windows(2) {
        let (a, b) = (shown(&many[pair[0]]), shown(&many[pair[1]]));
        assert!(a >= b, "{:?} before {:?}", many[pair[0]], many[pair[1]]);
    }
    // Among the fine ones, the finest (most triangles to save) first.
    for pair in order[first_fine..].windows(2) {
        assert!(many[pair[0]].0 <= many[pair[1]].0);
    }
}

/// A patch at `level` (made there) whose mesh measured `error` and `trim_error`.
fn patch_at(level: i32, error: f64, trim_error: f64) -> PatchLod {
    PatchLod {
        level,
        made: level,
        mesh: Arc::new(PatchMesh {
            triangles: vec![[0, 1, 2]; 5],
            error,
            trim_error,
            ..PatchMesh::default()
        }),
        ..PatchLod::default()
    }
}

/// Switches `p` (patch 0) to `level`, three levels kept, with a loop LRU of its own.
fn switch(p: &mut PatchLod, level: i32, l: &Levels, trimmed: bool) -> Option<Free> {
    let mut lru = LevelCache::default();
    let mut keep = Keep {
        levels: l,
        cache_levels: 3,
        lru: &mut lru,
    };
    p.switch_free(level, trimmed, &mut keep)
}

#[test]
fn a_tessellation_that_holds_a_finer_level_is_relabelled_not_remade() {
    let l = Levels::for_diagonal(1.0);
    // Exact (a plane bounded by lines): holds every finer level.
    let mut p = patch_at(20, 0.0, 0.0);
    assert_eq!(finest_held(&l, &p.mesh), Some(0));
    assert_eq!(switch(&mut p, 14, &l, true), Some(Free::Reused));
    assert_eq!(p.level, 14);
    assert_eq!(p.made, 20);
    // (`powi` may round differently where it is constant-folded: within an ulp or two.)
    assert!((p.mesh.eps_target / l.eps(14) - 1.0).abs() < 1e-12);
    assert_eq!(p.mesh.triangles.len(), 5);
    // Back up to the level it was made at: still the same triangles; past it: work.
    assert_eq!(switch(&mut p, 20, &l, true), Some(Free::Reused));
    assert_eq!(switch(&mut p, 21, &l, true), None);
    // Not a trimmed face: never relabelled.
    assert_eq!(switch(&mut patch_at(20, 0.0, 0.0), 14, &l, false), None);
    // Surface error: held down to the level whose ε it is within REFINE_TARGET of.
    let e = 0.9 * l.eps(20);
    assert_eq!(finest_held(&l, &patch_at(20, e, 0.0).mesh), Some(20));
    assert_eq!(switch(&mut patch_at(20, e, 0.0), 19, &l, true), None);
    let e = 0.6 * l.eps(20);
    assert_eq!(finest_held(&l, &patch_at(20, e, 0.0).mesh), Some(19));
    // Trim chords: held while within ε/2 (0.3 ε_20 ≤ ε_19 / 2 = 0.354 ε_20, not ε_18 / 2).
    let t = 0.3 * l.eps(20);
    let mut p = patch_at(20, 0.0, t);
    assert_eq!(switch(&mut p, 19, &l, true), Some(Free::Reused));
    assert_eq!(switch(&mut p, 18, &l, true), None);
    // A tessellation that stopped short or failed stands for no other level.
    let mut p = patch_at(20, 0.0, 0.0);
    Arc::make_mut(&mut p.mesh).stopped = Some(crate::tessellate::Stop::Rounds(10));
    assert_eq!(switch(&mut p, 14, &l, true), None);
    let mut p = patch_at(20, 0.0, 0.0);
    Arc::make_mut(&mut p.mesh).failure = Some("no".into());
    assert_eq!(switch(&mut p, 14, &l, true), None);
    // A cached level comes first, as it was made.
    let mut p = patch_at(20, 0.0, 0.0);
    let mut lru = LevelCache::default();
    let mut keep = Keep {
        levels: &l,
        cache_levels: 3,
        lru: &mut lru,
    };
    p.install(14, Arc::new(PatchMesh::default()), &mut keep);
    assert_eq!(p.switch_free(20, true, &mut keep), Some(Free::Cached));
    assert_eq!(p.mesh.triangles.len(), 5);
}

#[test]
fn levels_give_the_coarsest_error_within_the_wanted_one() {
    let l = Levels::for_diagonal(100.0);
    for wanted in [1e-5, 3e-4, 0.01, 0.5, 1.0, 7.3, 100.0] {
        let k = l.level_for(wanted);
        assert!(l.eps(k) <= wanted * (1.0 + 1e-12), "{wanted}: {}", l.eps(k));
        assert!(l.eps(k + 1) > wanted, "{wanted}");
    }
    assert_eq!(l.level_for(0.0), 0);
    assert_eq!(l.level_for(f64::NAN), 0);
}

#[test]
fn hysteresis_keeps_a_level_while_the_view_wobbles() {
    let l = Levels::for_diagonal(1.0);
    let f = LodOptions::default().coarsen_factor;
    // Tessellate for wanted 1e-3, then the wanted error wobbles within the band
    // [ε_c, 2 ε_c] (a camera moving back and forth by up to 2×).
    let current = l.eps(l.level_for(1e-3));
    for r in [1.0, 1.5, 1.99, 1.2, 1.0, 1.8] {
        assert!(!needs_update(current, r * current, f), "{r}");
    }
    // Moving closer by any amount past the level: too coarse at once.
    assert!(needs_update(current, current * 0.99, f));
    // Moving away past the band: coarsen.
    assert!(needs_update(current, current * f * 1.01, f));
    // Without hysteresis (factor 1) the same wobble would flip levels.
    let flips = [1e-3, 1.5e-3, 1e-3, 1.5e-3]
        .windows(2)
        .filter(|w| {
            let c = l.eps(l.level_for(w[0]));
            needs_update(c, w[1], 1.0)
        })
        .count();
    assert!(flips > 0);
}

#[test]
fn the_cache_keeps_the_levels_nearest_the_current_one() {
    let mesh = |n: usize| {
        Arc::new(PatchMesh {
            triangles: vec![[0, 0, 0]; n],
            ..PatchMesh::default()
        })
    };
    let mut p = PatchLod {
        level: 10,
        mesh: mesh(10),
        ..PatchLod::default()
    };
    let l = Levels::for_diagonal(1.0);
    let mut lru = LevelCache::default();
    let mut keep = Keep {
        levels: &l,
        cache_levels: 3,
        lru: &mut lru,
    };
    for level in [11, 12, 13] {
        p.install(level, mesh(level as usize), &mut keep);
    }
    assert_eq!(p.level, 13);
    assert_eq!(p.mesh.triangles.len(), 13);
    let mut cached: Vec<i32> = p.cache.iter().map(|c| c.level).collect();
    cached.sort();
    assert_eq!(cached, vec![11, 12]);
    // Every cached mesh is the one made for its level.
    assert!(
        p.cache
            .iter()
            .all(|c| c.mesh.triangles.len() == c.level as usize)
    );
}

/// A mesh of `n` triangles (its bytes grow with `n`).
fn sized(n: usize) -> Arc<PatchMesh> {
    Arc::new(PatchMesh {
        triangles: vec![[0, 0, 0]; n],
        ..PatchMesh::default()
    })
}

/// The cached levels' bytes counted afresh: each level's own, each shared tessellation an
/// instance points to once.
fn recount(patches: &[PatchLod]) -> usize {
    let mut shared = std::collections::HashSet::new();
    let mut bytes = 0;
    for c in patches.iter().flat_map(|p| &p.cache) {
        bytes += arc_bytes(&c.mesh);
        if let Some(inst) = &c.mesh.instance
            && shared.insert(Arc::as_ptr(&inst.shared))
        {
            bytes += arc_bytes(&inst.shared);
        }
    }
    bytes
}

/// Over the byte budget the level evicted is the least recently used one — not the oldest
/// made, the largest or the farthest from its patch's current level — and what is left fits.
#[test]
fn the_byte_budget_evicts_the_least_recently_used_level() {
    let l = Levels::for_diagonal(1.0);
    let mut lru = LevelCache::default();
    // Patch p holds level 0 with 100·(p+1) triangles, then level 1: level 0 is cached,
    // patch 0's first (stamp order 0, 1, 2).
    let mut patches: Vec<PatchLod> = (0..3)
        .map(|p| PatchLod::new(0, sized(100 * (p + 1)), &l))
        .collect();
    let mut keep = Keep {
        levels: &l,
        cache_levels: 3,
        lru: &mut lru,
    };
    for patch in patches.iter_mut() {
        patch.install(1, sized(10), &mut keep);
    }
    // Patch 0 goes back to level 0 (used now) and caches level 1: patch 1's level 0 is now
    // the least recently used, though patch 0's level 1 was made after it.
    assert_eq!(
        patches[0].switch_free(0, false, &mut keep),
        Some(Free::Cached)
    );
    assert_eq!(recount(&patches), lru.bytes());
    let keep_bytes = |p: &PatchLod| p.cache.iter().map(|c| arc_bytes(&c.mesh)).sum::<usize>();
    // A budget whose low-water mark the other two fit under, not with patch 1's level.
    let rest = keep_bytes(&patches[0]) + keep_bytes(&patches[2]);
    let budget = (rest as f64 / cache::LOW_WATER).ceil() as usize;
    assert!(lru.bytes() > budget);
    assert_eq!(lru.evict(&mut patches, budget), 1);
    assert!(patches[1].cache.is_empty(), "patch 1's level 0 stayed");
    assert_eq!(patches[0].cache[0].level, 1);
    assert_eq!(patches[2].cache[0].level, 0);
    assert_eq!(lru.bytes(), rest);
    assert_eq!(recount(&patches), lru.bytes());
    // Within budget: nothing goes. Budget 0: the rest goes.
    assert_eq!(lru.evict(&mut patches, rest), 0);
    assert_eq!(lru.evict(&mut patches, 0), 2);
    assert_eq!((lru.bytes(), recount(&patches)), (0, 0));
}

/// Cached placements of one shared tessellation count it once, for as long as one of them
/// is cached.
#[test]
fn a_shared_tessellation_is_counted_once() {
    let l = Levels::for_diagonal(1.0);
    let mut lru = LevelCache::default();
    let shared = sized(10_000);
    // (Each placement with vertices of its own, which instances never hold, so that its own
    // bytes weigh against the shared mesh's in the eviction below.)
    let instance = |id: u32| {
        Arc::new(PatchMesh {
            patch_id: id,
            positions: Vec::with_capacity(3000),
            instance: Some(crate::tessellate::Instance {
                shared: shared.clone(),
                transform: glam::DMat4::from_translation(glam::DVec3::X * id as f64),
                error_added: 0.0,
            }),
            ..PatchMesh::default()
        })
    };
    let mut patches: Vec<PatchLod> = (0..3).map(|p| PatchLod::new(4, instance(p), &l)).collect();
    let mut keep = Keep {
        levels: &l,
        cache_levels: 3,
        lru: &mut lru,
    };
    for patch in patches.iter_mut() {
        patch.install(5, sized(1), &mut keep);
    }
    let each = arc_bytes(&patches[0].cache[0].mesh);
    assert_eq!(lru.bytes(), 3 * each + arc_bytes(&shared));
    assert!(arc_bytes(&shared) > 3 * each, "the shared mesh dominates");
    assert_eq!(recount(&patches), lru.bytes());
    // Two placements evicted (the low-water mark between one and two of them): the shared
    // mesh still counts for the third.
    let third = each + arc_bytes(&shared);
    let budget = ((third + each / 2) as f64 / cache::LOW_WATER) as usize;
    assert!(budget < lru.bytes());
    assert_eq!(lru.evict(&mut patches, budget), 2);
    assert_eq!(lru.bytes(), third);
    // The last one evicted: nothing counted.
    assert_eq!(lru.evict(&mut patches, 0), 1);
    assert_eq!(lru.bytes(), 0);
}

/// A frame loop with a small byte budget over many frames of a camera zooming in and out of
/// a 3 × 3 teapot grid (placements of shared tessellations): after every update the cached
/// levels fit the budget and the loop's count is the true one; levels are evicted, and some
/// stay cached and come back free.
#[test]
fn cached_levels_stay_within_the_byte_budget_over_many_frames() {
    use crate::view::View;
    let teapot = crate::io::bpt::parse(
        include_str!("../../models/teapot.bpt").as_bytes(),
        std::path::Path::new("models/teapot.bpt"),
    )
    .expect("the teapot parses");
    let grid: Vec<_> = (0..9)
        .flat_map(|k| {
            let offset = glam::DVec3::new(8.0 * (k % 3) as f64, 8.0 * (k / 3) as f64, 0.0);
            teapot.iter().map(move |p| {
                let moved = p.control_points().iter().map(|c| *c + offset).collect();
                let (du, dv) = p.degree();
                crate::model::bezier::BezierPatch::new(du, dv, moved).expect("a moved patch")
            })
        })
        .collect();
    let scene = Scene::from_bezier(grid, crate::model::UpAxis::Z);
    let (c, r) = (scene.bounds.center, scene.bounds.radius);
    let view = |d: f64| {
        let eye = c + glam::DVec3::new(0.3, -1.0, 0.6).normalize() * r * d;
        View::new(eye, c, glam::DVec3::Z, 0.8, (640, 480), &scene.bounds)
    };
    let budget = 48 << 10;
    let options = LodOptions {
        budget: Duration::from_secs(600),
        cache_bytes: budget,
        ..LodOptions::default()
    };
    let mut lod = FrameLoop::new(&scene, &view(3.0), options);
    let (mut evicted, mut from_cache, mut most) = (0, 0, 0);
    for k in 0..40 {
        let d = [3.0, 2.0, 1.4, 1.0, 1.4, 2.0][k % 6];
        let stats = lod.update(&scene, &view(d));
        evicted += stats.evicted;
        from_cache += stats.from_cache;
        most = most.max(lod.cached_bytes());
        assert!(
            lod.cached_bytes() <= budget,
            "frame {k}: {}",
            lod.cached_bytes()
        );
        assert_eq!(lod.cached_bytes(), recount(&lod.patches), "frame {k}");
    }
    assert!(evicted > 0, "the budget never bound");
    assert!(from_cache > 0 && most > budget / 2, "nothing stayed cached");
    assert!(
        lod.patches
            .iter()
            .any(|p| p.cache.iter().any(|c| c.mesh.instance.is_some()))
    );
}

#[test]
fn controller_converges_on_a_linear_cost() {
    // Cost 2 ms + 1 µs per triangle; triangles = 40 000 / pixel error. Target 12 ms:
    // 10 000 triangles, pixel error 4.
    let mut c = PixelErrorController::new(Duration::from_millis(12), 0.5, 64.0);
    let mut pe = c.pixel_error();
    for _ in 0..40 {
        let tris = (40_000.0 / pe) as usize;
        let t = Duration::from_secs_f64(0.002 + 1e-6 * tris as f64);
        pe = c.observe(tris, t);
    }
    assert!((pe - 4.0).abs() < 0.1, "{pe}");
    // A frame time that does not depend on triangles (fill-bound) does not coarsen the
    // picture, even above the target.
    let mut c = PixelErrorController::new(Duration::from_millis(12), 0.5, 64.0);
    let mut pe = c.pixel_error();
    for _ in 0..20 {
        pe = c.observe((40_000.0 / pe) as usize, Duration::from_millis(30));
    }
    assert_eq!(pe, 0.5);
    // A cheap scene stays at the finest pixel error.
    let mut c = PixelErrorController::new(Duration::from_millis(12), 0.5, 64.0);
    for _ in 0..10 {
        c.observe(1000, Duration::from_millis(3));
    }
    assert_eq!(c.pixel_error(), 0.5);
}
