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

#[test]
fn a_tessellation_that_holds_a_finer_level_is_relabelled_not_remade() {
    let l = Levels::for_diagonal(1.0);
    // Exact (a plane bounded by lines): holds every finer level.
    let mut p = patch_at(20, 0.0, 0.0);
    assert_eq!(finest_held(&l, &p.mesh), Some(0));
    assert_eq!(p.switch_free(14, &l, true, 3), Some(Free::Reused));
    assert_eq!(p.level, 14);
    assert_eq!(p.made, 20);
    // (`powi` may round differently where it is constant-folded: within an ulp or two.)
    assert!((p.mesh.eps_target / l.eps(14) - 1.0).abs() < 1e-12);
    assert_eq!(p.mesh.triangles.len(), 5);
    // Back up to the level it was made at: still the same triangles; past it: work.
    assert_eq!(p.switch_free(20, &l, true, 3), Some(Free::Reused));
    assert_eq!(p.switch_free(21, &l, true, 3), None);
    // Not a trimmed face: never relabelled.
    assert_eq!(patch_at(20, 0.0, 0.0).switch_free(14, &l, false, 3), None);
    // Surface error: held down to the level whose ε it is within REFINE_TARGET of.
    let e = 0.9 * l.eps(20);
    assert_eq!(finest_held(&l, &patch_at(20, e, 0.0).mesh), Some(20));
    assert_eq!(patch_at(20, e, 0.0).switch_free(19, &l, true, 3), None);
    let e = 0.6 * l.eps(20);
    assert_eq!(finest_held(&l, &patch_at(20, e, 0.0).mesh), Some(19));
    // Trim chords: held while within ε/2 (0.3 ε_20 ≤ ε_19 / 2 = 0.354 ε_20, not ε_18 / 2).
    let t = 0.3 * l.eps(20);
    let mut p = patch_at(20, 0.0, t);
    assert_eq!(p.switch_free(19, &l, true, 3), Some(Free::Reused));
    assert_eq!(p.switch_free(18, &l, true, 3), None);
    // A tessellation that stopped short or failed stands for no other level.
    let mut p = patch_at(20, 0.0, 0.0);
    Arc::make_mut(&mut p.mesh).stopped = Some(crate::tessellate::Stop::Rounds(10));
    assert_eq!(p.switch_free(14, &l, true, 3), None);
    let mut p = patch_at(20, 0.0, 0.0);
    Arc::make_mut(&mut p.mesh).failure = Some("no".into());
    assert_eq!(p.switch_free(14, &l, true, 3), None);
    // A cached level comes first, as it was made.
    let mut p = patch_at(20, 0.0, 0.0);
    p.install(14, Arc::new(PatchMesh::default()), 3);
    assert_eq!(p.switch_free(20, &l, true, 3), Some(Free::Cached));
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
    for level in [11, 12, 13] {
        p.install(level, mesh(level as usize), 3);
    }
    assert_eq!(p.level, 13);
    assert_eq!(p.mesh.triangles.len(), 13);
    let mut cached: Vec<i32> = p.cache.iter().map(|c| c.0).collect();
    cached.sort();
    assert_eq!(cached, vec![11, 12]);
    // Every cached mesh is the one made for its level.
    assert!(
        p.cache
            .iter()
            .all(|(l, m)| m.triangles.len() == *l as usize)
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
