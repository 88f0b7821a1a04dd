//! Triangle strips: every triangle drawn exactly once with its orientation — for random
//! meshes, after random collapse/split sequences, per arc and for multiresolution strips.

use glam::Vec3;
use patchwork::mt::MtHierarchy;
use patchwork::strips::tunnel::{CutStrips, TunnelOptions, TunnelStrips, stripify};
use patchwork::strips::{
    RESTART, arc_strips, decode, encode_path, join_degenerate, same_triangles,
};
use proptest::prelude::*;

/// A w×h grid of quads split along random diagonals, some cells dropped, some triangles
/// flipped (inconsistent orientation), vertex ids shuffled by a multiplier.
fn grid_mesh(w: u32, h: u32, bits: &[bool], flips: &[bool], drop: &[bool]) -> Vec<[u32; 3]> {
    let id = |x: u32, y: u32| y * (w + 1) + x;
    let mut tris = Vec::new();
    let mut k = 0usize;
    for y in 0..h {
        for x in 0..w {
            let pick = |v: &[bool], k: usize| v.get(k % v.len().max(1)).copied().unwrap_or(false);
            let (a, b, c, d) = (id(x, y), id(x + 1, y), id(x + 1, y + 1), id(x, y + 1));
            let pair = if pick(bits, k) {
                [[a, b, c], [a, c, d]]
            } else {
                [[a, b, d], [b, c, d]]
            };
            for (i, mut t) in pair.into_iter().enumerate() {
                if pick(drop, 2 * k + i) {
                    continue;
                }
                if pick(flips, 2 * k + i + 7) {
                    t.swap(0, 1);
                }
                tris.push(t);
            }
            k += 1;
        }
    }
    tris
}

fn grid_positions(w: u32, h: u32, seed: u32) -> Vec<Vec3> {
    let mut out = Vec::new();
    let mut s = seed.wrapping_mul(2654435761).max(1);
    for y in 0..=h {
        for x in 0..=w {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            let z = (s % 1000) as f32 / 1000.0 * 0.3;
            out.push(Vec3::new(
                x as f32,
                y as f32,
                z + 0.2 * (x as f32 * 0.7).sin(),
            ));
        }
    }
    out
}

#[test]
fn encode_swaps_and_orientation() {
    // A fan around vertex 0: every turn pivots on 0, so every inner triangle needs a swap.
    let fan: Vec<[u32; 3]> = (1..6).map(|i| [0, i, i + 1]).collect();
    let mut out = Vec::new();
    assert_eq!(encode_path(&fan, &mut out), 1);
    assert!(same_triangles(&decode(&out), &fan));
    // Three inner triangles, two consecutive pairs with the same pivot: two swaps.
    assert_eq!(out.len(), fan.len() + 2 + 2, "{out:?}");
    let s = TunnelStrips::build(&fan, TunnelOptions::default());
    assert_eq!(s.swap_count(), 2);
    // A zig-zag strip needs none.
    let zig = [[0, 1, 2], [2, 1, 3], [2, 3, 4], [4, 3, 5]];
    out.clear();
    encode_path(&zig, &mut out);
    assert_eq!(out.len(), 6, "{out:?}");
    assert!(same_triangles(&decode(&out), &zig));
    // A flipped neighbour cannot continue the strip with its own orientation: restart.
    let bad = [[0, 1, 2], [1, 2, 3]];
    out.clear();
    assert_eq!(encode_path(&bad, &mut out), 2);
    assert!(out.contains(&RESTART));
    assert!(same_triangles(&decode(&out), &bad));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_meshes_are_covered_once_with_orientation(
        w in 1u32..14, h in 1u32..14,
        bits in prop::collection::vec(any::<bool>(), 1..64),
        flips in prop::collection::vec(prop::bool::weighted(0.1), 1..64),
        drop in prop::collection::vec(prop::bool::weighted(0.15), 1..64),
        greedy in any::<bool>(), aware in any::<bool>(), max_len in 1usize..40,
    ) {
        let tris = grid_mesh(w, h, &bits, &flips, &drop);
        let opts = TunnelOptions { greedy_start: greedy, swap_aware: aware, max_len, ..Default::default() };
        let mut s = TunnelStrips::build(&tris, opts.clone());
        prop_assert_eq!(s.check(), Ok(()));
        let idx = s.to_indices();
        // Adjacent triangles are consistently oriented, so no strip needs an orientation break.
        prop_assert_eq!(idx.strips, s.strip_count());
        prop_assert_eq!(idx.indices.iter().filter(|&&i| i == RESTART).count() + 1, idx.strips.max(1));
        prop_assert!(same_triangles(&decode(&idx.indices), &tris));
        prop_assert_eq!(stripify(&tris, &opts).triangles, tris.len());
        // Joined by zero-area windows instead: one strip, the same oriented triangles, at most
        // three indices per join.
        let joined = join_degenerate(&idx.indices, &mut []);
        prop_assert!(!joined.contains(&RESTART));
        prop_assert!(same_triangles(&decode(&joined), &tris));
        prop_assert!(joined.len() <= idx.indices.len() + 2 * idx.strips.saturating_sub(1));
    }

    #[test]
    fn collapse_split_sequences_keep_the_cover(
        w in 2u32..9, h in 2u32..9, seed in 1u32..1000,
        bits in prop::collection::vec(any::<bool>(), 1..32),
        moves in prop::collection::vec(-6i32..7, 1..24),
        repair_len in 2usize..30, extra in 0usize..6,
    ) {
        let tris = grid_mesh(w, h, &bits, &[false], &[false]);
        let pos = grid_positions(w, h, seed);
        let hier = MtHierarchy::build(&pos, &tris);
        let opts = TunnelOptions { repair_len, extra, ..Default::default() };
        let mut cs = CutStrips::new(&hier, opts);
        let mut cut = Vec::new();
        let store = patchwork::strips::StripStore::new();
        let patch = std::sync::Arc::new(patchwork::model::mesh::MeshPatch {
            hierarchy: hier.clone(),
            ..Default::default()
        });
        let mut drawn = [Vec::new(), Vec::new()];
        for m in moves {
            let target = (cs.applied() as i64 + m as i64).clamp(1, hier.order.len() as i64) as usize;
            cs.move_to(&hier, target);
            prop_assert_eq!(cs.strips.check(), Ok(()));
            // The cut after `target` nodes of the order.
            cut.clear();
            for (t, tri) in hier.triangles.iter().enumerate() {
                let made = hier.rank_of(hier.created_by[t]) < target;
                let gone = hier.removed_by[t] != patchwork::mt::NEVER && hier.rank_of(hier.removed_by[t]) < target;
                if made && !gone { cut.push(*tri); }
            }
            let idx = cs.strips.to_indices();
            prop_assert!(same_triangles(&decode(&idx.indices), &cut), "after moving to {}", target);
            // What the renderer draws for `--primitives repair` and `mts`: its strip store
            // following the same cuts.
            for (k, mts) in [false, true].into_iter().enumerate() {
                store.cut(&patch, target, mts, &mut drawn[k]);
                prop_assert!(same_triangles(&decode(&drawn[k]), &cut), "mts {} at {}", mts, target);
            }
        }
    }
}

#[test]
fn per_arc_strips_draw_every_arc_exactly() {
    let (w, h) = (12, 10);
    let tris = grid_mesh(w, h, &[true, false, false], &[false], &[false]);
    let mut hier = MtHierarchy::build(&grid_positions(w, h, 7), &tris);
    hier.reduce(5.0);
    let (strips, starts) = arc_strips(&hier, &TunnelOptions::default());
    assert_eq!(starts.len(), hier.arc_nodes.len() + 1);
    assert_eq!(strips.triangles, hier.triangles.len());
    for k in 0..hier.arc_nodes.len() {
        let arc = &hier.triangles[hier.arc_start[k] as usize..hier.arc_start[k + 1] as usize];
        let range = &strips.indices[starts[k] as usize..starts[k + 1] as usize];
        assert!(same_triangles(&decode(range), arc), "arc {k}");
    }
    assert!(strips.indices_per_triangle() < 3.0);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// Per-arc strips joined by zero-area windows: every run of adjacent arcs (what a cut
    /// draws as one range) draws exactly its arcs' triangles, with their orientation.
    #[test]
    fn degenerate_joins_keep_every_arc_range(
        w in 2u32..12, h in 2u32..12, seed in 1u32..1000,
        bits in prop::collection::vec(any::<bool>(), 1..32),
        arc_size in 1.0f64..12.0,
    ) {
        let tris = grid_mesh(w, h, &bits, &[false], &[false]);
        let mut hier = MtHierarchy::build(&grid_positions(w, h, seed), &tris);
        hier.reduce(arc_size);
        let (strips, starts) = arc_strips(&hier, &TunnelOptions::default());
        let mut mapped = starts.clone();
        let joined = join_degenerate(&strips.indices, &mut mapped);
        prop_assert!(!joined.contains(&RESTART));
        prop_assert_eq!(mapped.last().copied(), Some(joined.len() as u32));
        // Every range that draws something starts at an even index (parity kept).
        prop_assert!(mapped.iter().all(|&s| s % 2 == 0 || s as usize == joined.len()), "odd start in {:?}", mapped);
        let n = hier.arc_nodes.len();
        for a in 0..n {
            for b in a + 1..=n {
                let arcs = &hier.triangles[hier.arc_start[a] as usize..hier.arc_start[b] as usize];
                let range = &joined[mapped[a] as usize..mapped[b] as usize];
                prop_assert!(same_triangles(&decode(range), arcs), "arcs {}..{}", a, b);
            }
        }
    }
}

fn cut_at(hier: &MtHierarchy, level: usize) -> Vec<[u32; 3]> {
    let mut cut = Vec::new();
    for (t, tri) in hier.triangles.iter().enumerate() {
        let made = hier.rank_of(hier.created_by[t]) < level;
        let gone =
            hier.removed_by[t] != patchwork::mt::NEVER && hier.rank_of(hier.removed_by[t]) < level;
        if made && !gone {
            cut.push(*tri);
        }
    }
    cut
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// Multiresolution strips give exactly the cut at every level, with and without
    /// coherence, for plain and arc-collapsed hierarchies.
    #[test]
    fn multiresolution_strips_draw_the_cut_of_every_level(
        w in 2u32..9, h in 2u32..9, seed in 1u32..1000,
        bits in prop::collection::vec(any::<bool>(), 1..32),
        reduce in prop::option::of(2.0f64..8.0),
        walk in prop::collection::vec(0usize..1000, 1..20),
    ) {
        use patchwork::strips::mts::MultiresStrips;
        let tris = grid_mesh(w, h, &bits, &[false], &[false]);
        let mut hier = MtHierarchy::build(&grid_positions(w, h, seed), &tris);
        if let Some(r) = reduce { hier.reduce(r); }
        let mut m = MultiresStrips::build(&hier, &TunnelOptions::default());
        prop_assert_eq!(m.levels(), hier.order.len());
        let mut out = Vec::new();
        for level in 1..=m.levels() {
            m.extract(level, false, &mut out);
            prop_assert!(same_triangles(&decode(&out), &cut_at(&hier, level)), "level {}", level);
        }
        let mut fresh = Vec::new();
        for x in walk {
            let level = 1 + x % m.levels();
            m.extract(level, true, &mut out);
            m.extract(level, false, &mut fresh);
            prop_assert_eq!(&out, &fresh);
        }
    }
}
