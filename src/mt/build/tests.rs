//! Tests of the MT build (`super`): monotone errors, cuts as triangulations within their
//! error, and node errors that bound a dense Hausdorff measurement.

// Test code throughout: the architecture check (stages, printing) reads up to here.
#[cfg(test)]
use super::super::fixtures::{bumpy, dense_hausdorff, edges_used, sampled_hausdorff};
use super::*;
use crate::model::mesh::border_loops;

#[test]
fn errors_are_monotone_along_the_dag() {
    let m = bumpy(12);
    let h = MtHierarchy::build(&m.positions, &m.triangles);
    assert!(h.node_count() > 100, "{} nodes", h.node_count());
    for t in 0..h.triangles.len() {
        let (c, r) = (h.created_by[t], h.removed_by[t]);
        if r != NEVER {
            assert!(c < r, "arc goes back in time");
            assert!(h.node_error[c as usize] <= h.node_error[r as usize]);
        }
    }
}

#[test]
fn every_cut_is_a_triangulation_of_the_patch_within_its_error() {
    let m = bumpy(12);
    let h = MtHierarchy::build(&m.positions, &m.triangles);
    let original_border: f64 = 12.0 * 4.0 * 0.25; // perimeter of the 3 × 3 square
    let mut errors: Vec<f64> = h.node_error.clone();
    errors.sort_by(f64::total_cmp);
    let mut cut = Vec::new();
    for q in [0.0, 0.1, 0.3, 0.6, 0.9, 1.0] {
        let eps = errors[((errors.len() - 1) as f64 * q) as usize];
        let achieved = h.cut(eps, &mut cut);
        assert!(achieved <= eps);
        // No overlaps, no holes: every edge used once (border) or twice (inside), and
        // exactly one border loop around the square.
        let uses = edges_used(&cut);
        assert!(uses.values().all(|&u| u <= 2), "overlap at ε {eps}");
        let loops = border_loops(&cut);
        assert_eq!(loops.len(), 1, "ε {eps}: {} border loops", loops.len());
        // The border may cut the square's corners (the node error measures that), but every
        // vertex of the square's outline stays within the cut's error of the cut's border: what
        // a fat border of width ε needs to reach the neighbour's.
        let ring = &loops[0];
        let outline: Vec<DVec3> = ring
            .iter()
            .map(|&v| m.positions[v as usize].as_dvec3())
            .collect();
        let original_ring = &border_loops(&m.triangles)[0];
        for &v in original_ring {
            let p = m.positions[v as usize].as_dvec3();
            let d = (0..outline.len())
                .map(|k| {
                    let (a, b) = (outline[k], outline[(k + 1) % outline.len()]);
                    p.distance(crate::geom::closest_point_on_segment(p, a, b))
                })
                .fold(f64::INFINITY, f64::min);
            assert!(
                d <= 1.1 * achieved + 1e-9,
                "outline vertex {v} is {d} from the border at ε {eps}"
            );
        }
        // Area is kept up to what cutting corners within ε removes (a hole would lose more
        // and show as a second border loop above).
        let area: f64 = cut
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
                let n = (b - a).cross(c - a);
                0.5 * DVec3::new(0.0, 0.0, 1.0).dot(n).abs()
            })
            .sum();
        assert!(
            (area - 9.0).abs() < 0.02 + achieved * original_border,
            "projected area {area} at ε {eps}"
        );
    }
    // The coarsest cut is much smaller than the original.
    let coarsest = h.cut(f64::INFINITY, &mut cut);
    assert!(
        cut.len() * 10 < m.triangles.len(),
        "{} triangles",
        cut.len()
    );
    assert!(coarsest >= 0.0);
}

#[test]
fn cut_triangles_hold_the_hausdorff_bound() {
    let m = bumpy(10);
    let h = MtHierarchy::build(&m.positions, &m.triangles);
    let pos: Vec<DVec3> = m.positions.iter().map(|p| p.as_dvec3()).collect();
    let mut cut = Vec::new();
    for eps in [0.002, 0.01, 0.05] {
        let achieved = h.cut(eps, &mut cut);
        let worst = sampled_hausdorff(&pos, &cut, &m.triangles);
        assert!(
            worst <= eps + 1e-9,
            "ε {eps}: Hausdorff {worst} (achieved {achieved})"
        );
    }
}

/// A flat polygon triangulated as a zig-zag strip (as modellers write a candle's top)
/// has ears: border corners in one triangle each. Collapsing one would remove its
/// triangle and leave no fan to measure the error on (a hole measured as error 0); every
/// cut keeps the polygon whole within its error.
#[test]
fn ears_are_not_collapsed_away() {
    let n = 16;
    let ring: Vec<Vec3> = (0..n)
        .map(|k| {
            let a = std::f32::consts::TAU * k as f32 / n as f32;
            Vec3::new(a.cos(), a.sin(), 0.0)
        })
        .collect();
    // Zig-zag: 0, 1, n-1, 2, n-2, ... so vertices 0 and n/2 are ears.
    let order: Vec<u32> = std::iter::once(0)
        .chain((1..n).flat_map(|k| [k, n - k]).take(n as usize - 1))
        .collect();
    let triangles: Vec<[u32; 3]> = order
        .windows(3)
        .enumerate()
        .map(|(k, w)| {
            if k % 2 == 0 {
                [w[0], w[1], w[2]]
            } else {
                [w[1], w[0], w[2]]
            }
        })
        .collect();
    assert_eq!(triangles.len(), n as usize - 2);
    let h = MtHierarchy::build(&ring, &triangles);
    let pos: Vec<DVec3> = ring.iter().map(|p| p.as_dvec3()).collect();
    let mut cut = Vec::new();
    let mut errors = h.node_error.clone();
    errors.sort_by(f64::total_cmp);
    for &eps in &errors {
        h.cut(eps, &mut cut);
        let worst = dense_hausdorff(&pos, &cut, &triangles, 8);
        assert!(
            worst <= eps * (1.0 + 1e-9) + 1e-9,
            "ε {eps}: Hausdorff {worst}"
        );
    }
}

/// The node errors bound the Hausdorff distance of every cut to the original measured
/// densely (45 points per triangle, both ways), not only at the build's own samples: a
/// bumpy patch, reduced and not, over the whole range of errors.
#[test]
fn cut_errors_bound_a_dense_hausdorff_measurement() {
    let m = bumpy(10);
    let pos: Vec<DVec3> = m.positions.iter().map(|p| p.as_dvec3()).collect();
    let fine = MtHierarchy::build(&m.positions, &m.triangles);
    let mut reduced = fine.clone();
    reduced.reduce(5.0);
    let mut cut = Vec::new();
    for (name, h) in [("built", &fine), ("reduced", &reduced)] {
        let mut errors = h.node_error.clone();
        errors.sort_by(f64::total_cmp);
        for q in [0.1, 0.3, 0.5, 0.7, 0.9, 1.0] {
            let eps = errors[((errors.len() - 1) as f64 * q) as usize];
            h.cut(eps, &mut cut);
            let worst = dense_hausdorff(&pos, &cut, &m.triangles, 8);
            assert!(
                worst <= eps * (1.0 + 1e-9) + 1e-12,
                "{name}: ε {eps}: dense Hausdorff {worst} ({:.3} ε)",
                worst / eps
            );
        }
    }
}

/// The largest ratio of a dense two-sided Hausdorff measurement (`k` steps per edge) of a cut
/// to the cut's ε, over cuts at several quantiles of the node errors.
fn worst_dense_ratio(h: &MtHierarchy, pos: &[DVec3], original: &[[u32; 3]], k: u32) -> f64 {
    let mut errors: Vec<f64> = h.node_error.iter().copied().filter(|&e| e > 0.0).collect();
    errors.sort_by(f64::total_cmp);
    let mut cut = Vec::new();
    let mut worst = 0.0f64;
    for q in [0.1, 0.3, 0.5, 0.7, 0.9, 1.0] {
        let Some(&eps) = errors.get(((errors.len().max(1) - 1) as f64 * q) as usize) else {
            continue;
        };
        h.cut(eps, &mut cut);
        worst = worst.max(dense_hausdorff(pos, &cut, original, k) / eps);
    }
    worst
}

/// The dense check catches errors that undercount: the same hierarchy with every node error
/// halved (still monotone) has a cut farther from the original than its ε.
#[test]
fn halved_node_errors_fail_the_dense_check() {
    let m = bumpy(10);
    let pos: Vec<DVec3> = m.positions.iter().map(|p| p.as_dvec3()).collect();
    let mut h = MtHierarchy::build(&m.positions, &m.triangles);
    h.reduce(5.0);
    assert!(worst_dense_ratio(&h, &pos, &m.triangles, 8) <= 1.0 + 1e-9);
    let mut parts = h.parts();
    for e in &mut parts.node_error {
        *e *= 0.5;
    }
    let halved = MtHierarchy::from_parts(parts, pos.len()).expect("still a valid hierarchy");
    let ratio = worst_dense_ratio(&halved, &pos, &m.triangles, 8);
    assert!(
        ratio > 1.2,
        "halved errors pass the dense check ({ratio:.3} ε)"
    );
}

/// Node errors are certified (`super::bound`), so a dense measurement of a cut on real
/// scanned geometry (four patches of 200 triangles of the Stanford bunny, borders and all)
/// never exceeds its ε beyond rounding. With the sampled errors the build had before, cuts
/// came out up to 7.9 % beyond their ε (10.6 % once the fan was also measured against the
/// surface around it); this test then allowed 10 %. It fails for undercounting errors
/// (halved).
const BUNNY_SHORTFALL: f64 = 1.0 + 1e-9;

/// models/bunny.glb, welded and partitioned into patches of about `target` triangles.
fn bunny_patches(target: usize) -> Vec<crate::model::mesh::MeshPatch> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/models/bunny.glb");
    let crate::io::Model::Mesh(mut mesh) =
        crate::io::read(std::path::Path::new(path)).expect("the bunny loads")
    else {
        panic!("the bunny is a mesh");
    };
    mesh.weld();
    crate::prep::partition(&mesh, target)
}

#[test]
fn bunny_patches_hold_a_dense_hausdorff_bound() {
    let patches = bunny_patches(200);
    // A spread of patches (the partition's order follows the surface).
    let (mut worst, mut halved_worst) = (0.0f64, 0.0f64);
    for p in patches.iter().step_by(patches.len() / 4).take(4) {
        let pos: Vec<DVec3> = p.positions.iter().map(|v| v.as_dvec3()).collect();
        let mut h = MtHierarchy::build(&p.positions, &p.triangles);
        assert!(h.node_count() > 20, "{} nodes", h.node_count());
        let built = worst_dense_ratio(&h, &pos, &p.triangles, 6);
        h.reduce(crate::mt::DEFAULT_ARC_SIZE);
        let reduced = worst_dense_ratio(&h, &pos, &p.triangles, 6);
        worst = worst.max(built).max(reduced);
        let mut parts = h.parts();
        for e in &mut parts.node_error {
            *e *= 0.5;
        }
        let halved = MtHierarchy::from_parts(parts, pos.len()).expect("a valid hierarchy");
        halved_worst = halved_worst.max(worst_dense_ratio(&halved, &pos, &p.triangles, 6));
    }
    assert!(worst <= BUNNY_SHORTFALL, "dense Hausdorff {worst:.4} ε");
    assert!(
        halved_worst > BUNNY_SHORTFALL * 1.2,
        "halved errors pass ({halved_worst:.3} ε)"
    );
}

/// The build stops only when no valid collapse is left: on the coarsest cut, rebuilt as a
/// fresh mesh, every candidate is refused (a candidate refused once and never retried after
/// its neighbourhood changed would show up here).
#[test]
fn no_valid_collapse_is_left_at_the_coarsest_level() {
    let bunny = bunny_patches(1500);
    let grid = bumpy(12);
    let cases = [(&grid.positions, &grid.triangles)]
        .into_iter()
        .chain(bunny.iter().take(6).map(|p| (&p.positions, &p.triangles)));
    for (positions, triangles) in cases {
        let h = MtHierarchy::build(positions, triangles);
        let mut coarse = Vec::new();
        h.cut(f64::INFINITY, &mut coarse);
        assert!(
            !coarse.is_empty() && coarse.len() * 4 < triangles.len(),
            "{} of {} triangles at the coarsest level",
            coarse.len(),
            triangles.len()
        );
        let mut b = Builder::new(positions, &coarse, None);
        let mut around = Vec::new();
        for v in 0..positions.len() as u32 {
            around.clear();
            b.neighbours_into(v, &mut around);
            for &w in &around {
                let valid = b.candidate(v, w).is_some() && b.allowed(v, w);
                assert!(!valid, "collapse {v} → {w} left undone");
            }
        }
    }
}

/// Triangles the hierarchy of `positions` draws at `eps`.
fn drawn(positions: &[glam::Vec3], triangles: &[[u32; 3]], eps: f64) -> usize {
    let mut cut = Vec::new();
    MtHierarchy::build(positions, triangles).cut(eps, &mut cut);
    cut.len()
}

/// Collapses are ordered by their error, not by where the mesh sits: the same bunny patches
/// moved 40 diagonals away draw the same triangles at the same ε (within rounding). The
/// quadrics once started at glam's `DMat4::default()`, the identity, which added 1 + |p|² to
/// every cost: collapses went by distance from the origin, and the bunny drew 3× the
/// triangles at ε = 0.5 % of its diagonal (24 846 where 7 718 now).
#[test]
fn collapse_order_does_not_depend_on_where_the_mesh_sits() {
    let patches = bunny_patches(1500);
    let shift = glam::Vec3::new(60.0, -80.0, 40.0);
    let (mut here, mut there) = (0usize, 0usize);
    for p in patches.iter().step_by(patches.len() / 6).take(6) {
        let moved: Vec<glam::Vec3> = p.positions.iter().map(|&v| v + shift).collect();
        // ε = 0.5 %, 0.25 % and 0.12 % of the bunny's diagonal (2.6), summed: moved, the f32
        // positions round differently, and the certified bounds (their splits and depth
        // limits) follow; each ε alone came out 0.96–1.08× here on 2026-12-04, the sum 1.017×.
        for eps in [0.013, 0.0065, 0.003] {
            here += drawn(&p.positions, &p.triangles, eps);
            there += drawn(&moved, &p.triangles, eps);
        }
    }
    let ratio = there as f64 / here as f64;
    assert!(
        (0.95..=1.05).contains(&ratio),
        "{here} triangles in place, {there} moved ({ratio:.3}×)"
    );
}

/// A flat patch whose border is a staircase (as a region grown over a mesh's triangles is)
/// loses its stairs once ε is past their size: corners of the border collapse when the node
/// error allows, and what is drawn stays within the original outline by about that error.
/// With corners turning by more than 45° kept, every stair stayed at every ε (seen failing:
/// 26 of 48 border vertices left at ε = 4).
#[test]
fn a_staircase_border_simplifies_within_its_error() {
    // Unit squares (two triangles each, split along the diagonal that leaves no stair corner
    // in a triangle of its own: such an ear is never collapsed) below the staircase j ≤ i of
    // a 12 × 12 grid.
    let n = 12u32;
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let positions: Vec<glam::Vec3> = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| glam::Vec3::new(i as f32, j as f32, 0.0)))
        .collect();
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in j..n {
            triangles.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
            triangles.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let h = MtHierarchy::build(&positions, &triangles);
    let mut cut = Vec::new();
    // One stair: cutting a stair's corner moves the border by 0.71.
    let eps = 1.0;
    let achieved = h.cut(eps, &mut cut);
    let loops = border_loops(&cut);
    assert_eq!(loops.len(), 1, "{} border loops", loops.len());
    let original = border_loops(&triangles)[0].len();
    assert!(
        loops[0].len() * 3 < original,
        "{} of {original} border vertices left at ε {eps}",
        loops[0].len()
    );
    let pos: Vec<DVec3> = positions.iter().map(|v| v.as_dvec3()).collect();
    let dense = dense_hausdorff(&pos, &cut, &triangles, 8);
    assert!(
        dense <= achieved * BUNNY_SHORTFALL + 1e-9,
        "dense Hausdorff {dense} beyond the cut's error {achieved}"
    );
}

/// Arc collapse merges a node into one of larger error, which delays the finer node's
/// triangles to a coarser ε. Merging only nodes within `MAX_MERGE_ERROR_RATIO` of each other
/// keeps the bunny's cuts near the unreduced hierarchy's (1.4× over all its patches at 0.5 %
/// of the diagonal); Holst's unlimited reduction to 5 triangles per arc drew 5×. Measured at
/// ε = 0.005 (six patches: 720 triangles unreduced, 728 within the ratio, 4 173 unlimited):
/// at 0.013, where this test first looked, the cuts are now near their coarsest (153 / 157 /
/// 223) since interior vertices may move onto the border.
#[test]
fn reduction_within_an_error_ratio_keeps_cuts_small() {
    let patches = bunny_patches(1500);
    let (mut built, mut within, mut unlimited) = (0usize, 0usize, 0usize);
    let mut cut = Vec::new();
    for p in patches.iter().step_by(patches.len() / 6).take(6) {
        let h = MtHierarchy::build(&p.positions, &p.triangles);
        let mut a = h.clone();
        a.reduce_within(
            crate::mt::DEFAULT_ARC_SIZE,
            crate::mt::MAX_MERGE_ERROR_RATIO,
        );
        let mut b = h.clone();
        b.reduce(crate::mt::DEFAULT_ARC_SIZE);
        for (sum, h) in [(&mut built, &h), (&mut within, &a), (&mut unlimited, &b)] {
            h.cut(0.005, &mut cut);
            *sum += cut.len();
        }
    }
    assert!(
        (within as f64) <= 1.6 * built as f64,
        "{within} triangles reduced within the ratio, {built} unreduced"
    );
    assert!(
        unlimited > 2 * within,
        "unlimited reduction drew {unlimited}, within the ratio {within}: the limit is not seen"
    );
}

/// A flat `n × n` grid with thin spikes: `spikes` vertices (picked by `seed`) raised by up
/// to `height`.
fn spiky_grid(n: u32, spikes: usize, height: f32, seed: u64) -> (Vec<glam::Vec3>, Vec<[u32; 3]>) {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut rnd = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let mut positions: Vec<glam::Vec3> = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| glam::Vec3::new(i as f32, j as f32, 0.0)))
        .collect();
    for _ in 0..spikes {
        let (i, j) = (
            1 + (rnd() * (n - 1) as f64) as u32,
            1 + (rnd() * (n - 1) as f64) as u32,
        );
        positions[at(i, j) as usize].z = height * (0.2 + 0.8 * rnd() as f32);
    }
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            if rnd() < 0.5 {
                triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            } else {
                triangles.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
                triangles.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
    (positions, triangles)
}

/// Node errors are certified bounds, not samples: on flat grids with thin spikes (single
/// vertices raised), every cut at every node error of the hierarchy is within that error of
/// the original, measured densely (136 points per triangle, both ways). Seen failing with the
/// sampled errors the build had before (7 samples per triangle, originals measured against
/// the whole fan): these three grids measured 1.50, 1.29 and 1.19 × ε.
#[test]
fn spikes_between_samples_stay_within_the_certified_error() {
    for (seed, spikes, height) in [(31, 3, 4.0), (6, 20, 0.5), (13, 3, 4.0)] {
        let (positions, triangles) = spiky_grid(8, spikes, height, seed);
        let pos: Vec<DVec3> = positions.iter().map(|v| v.as_dvec3()).collect();
        let h = MtHierarchy::build(&positions, &triangles);
        let mut errors: Vec<f64> = h.node_error.iter().copied().filter(|&e| e > 1e-9).collect();
        errors.sort_by(f64::total_cmp);
        errors.dedup();
        let mut cut = Vec::new();
        for &eps in &errors {
            h.cut(eps, &mut cut);
            let dense = dense_hausdorff(&pos, &cut, &triangles, 16);
            assert!(
                dense <= eps * (1.0 + 1e-9) + 1e-9,
                "seed {seed}: a cut at ε {eps} is {dense} ({:.3} ε) from the original",
                dense / eps
            );
        }
    }
}

/// `bumpy(n)` flat-shaded: every triangle with vertices of its own (at the shared positions)
/// and its face normal, as a file with per-face normals is welded (`model::creases`).
fn flat_shaded(n: u32) -> (Vec<glam::Vec3>, Vec<glam::Vec3>, Vec<[u32; 3]>) {
    let m = bumpy(n);
    let (mut positions, mut normals, mut triangles) = (Vec::new(), Vec::new(), Vec::new());
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let normal = (b - a).cross(c - a).normalize();
        let first = positions.len() as u32;
        positions.extend([a, b, c]);
        normals.extend([normal; 3]);
        triangles.push([first, first + 1, first + 2]);
    }
    (positions, normals, triangles)
}

#[test]
fn a_flat_shaded_surface_simplifies_across_its_creases() {
    let n = 12;
    let (positions, normals, triangles) = flat_shaded(n);
    let smooth = bumpy(n);
    let unsplit = MtHierarchy::build(&smooth.positions, &smooth.triangles);
    // With creases as borders, every triangle is an island: nothing simplifies.
    let islands = MtHierarchy::build(&positions, &triangles);
    assert_eq!(drawn(&positions, &triangles, 1.0), triangles.len());
    assert_eq!(islands.node_count(), 1);
    // Each vertex's first vertex at its position (flat_shaded copies positions exactly).
    let first = |v: u32| {
        let p = positions[v as usize];
        positions.iter().position(|&q| q == p).unwrap_or(0) as u32
    };
    let position_of: Vec<u32> = (0..positions.len() as u32).map(first).collect();
    let h = MtHierarchy::build_across_seams(&positions, &position_of, &normals, &triangles);
    let merged: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
    let original: Vec<[u32; 3]> = triangles.iter().map(|t| t.map(first)).collect();
    let mut cut = Vec::new();
    let mut unsplit_cut = Vec::new();
    for rel in [0.002, 0.01, 0.05] {
        let eps = rel * 3.0;
        let achieved = h.cut(eps, &mut cut);
        assert!(achieved <= eps);
        // As small as the smooth surface's cut: the creases cost nothing.
        unsplit.cut(eps, &mut unsplit_cut);
        assert!(
            cut.len() <= unsplit_cut.len() + unsplit_cut.len() / 10 + 2,
            "ε {eps}: {} triangles against {} without creases",
            cut.len(),
            unsplit_cut.len()
        );
        // One surface at the positions: a triangulation within ε of the original.
        let at_positions: Vec<[u32; 3]> = cut.iter().map(|t| t.map(first)).collect();
        let uses = edges_used(&at_positions);
        assert!(uses.values().all(|&u| u <= 2), "overlap at ε {eps}");
        assert_eq!(border_loops(&at_positions).len(), 1, "holes at ε {eps}");
        let d = dense_hausdorff(&merged, &at_positions, &original, 6);
        assert!(d <= eps * (1.0 + 1e-9), "ε {eps}: dense distance {d}");
        // Every corner keeps a normal of its position, its own triangle's where it can: the
        // normals of a cut triangle lie within the crease angle of its face.
        for t in &cut {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let face = (b - a).cross(c - a).normalize();
            for &v in t {
                assert!(
                    normals[v as usize].dot(face) > 0.9,
                    "ε {eps}: corner {v} turned"
                );
            }
        }
    }
    // The cut after every prefix of the order is the original triangles with each removed
    // vertex replaced along its targets, with no triangle of zero area left over: what
    // multiresolution strips substitute (`strips::mts`).
    for applied in 1..=h.order.len() {
        let mut expected: Vec<[u32; 3]> = (0..h.triangles.len())
            .filter(|&t| {
                let created = h.rank_of(h.created_by[t]) < applied;
                let removed = h.removed_by[t];
                created && (removed == NEVER || h.rank_of(removed) >= applied)
            })
            .map(|t| h.triangles[t])
            .collect();
        let mut substituted: Vec<[u32; 3]> = (triangles.iter())
            .map(|t| t.map(|v| h.vertex_at(v, applied)))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
            .collect();
        expected.sort_unstable();
        substituted.sort_unstable();
        assert_eq!(substituted, expected, "after {applied} nodes");
    }
}

/// An interior vertex may move onto the border, as meshoptimizer's manifold vertices may: a
/// flat square grid goes down to its two triangles at no error (seen failing while interior
/// vertices reached the border only along creases: the last of them stayed with its fan;
/// over the bunny's patches, 1 373 / 749 triangles at 1 / 2 % of the diagonal against
/// 1 101 / 530 since).
#[test]
fn a_flat_grid_simplifies_to_its_two_triangles() {
    for seed in [1, 2, 3] {
        let (positions, triangles) = spiky_grid(10, 0, 0.0, seed);
        let h = MtHierarchy::build(&positions, &triangles);
        let mut cut = Vec::new();
        h.cut(1e-9, &mut cut);
        assert_eq!(
            cut.len(),
            2,
            "seed {seed}: {} triangles at no error",
            cut.len()
        );
    }
}
