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
        // Corners stay, so the border keeps the square's outline: same length.
        let ring = &loops[0];
        let len: f64 = (0..ring.len())
            .map(|k| {
                let a = m.positions[ring[k] as usize].as_dvec3();
                let b = m.positions[ring[(k + 1) % ring.len()] as usize].as_dvec3();
                a.distance(b)
            })
            .sum();
        assert!(
            (len - original_border).abs() < 0.05 * original_border,
            "border length {len} at ε {eps}"
        );
        // Area is kept (a hole would lose some).
        let area: f64 = cut
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
                let n = (b - a).cross(c - a);
                0.5 * DVec3::new(0.0, 0.0, 1.0).dot(n).abs()
            })
            .sum();
        assert!(
            (area - 9.0).abs() < 0.02,
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

/// Samples leave gaps: measured densely on real scanned geometry (four patches of 200
/// triangles of the Stanford bunny, borders and all), cuts come out up to 5.2 % beyond their ε
/// built and 7.9 % reduced (both ways: cut → original 1.052 ε and original → cut 1.017 ε
/// built, at 6 and at 12 steps per edge alike), where the smooth `bumpy` patch stays within
/// it. The node errors are sampled, not rigorous bounds (issue 19); this test holds the
/// shortfall to 10 % and fails for undercounting errors (halved).
const BUNNY_SHORTFALL: f64 = 1.1;

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
        let mut b = Builder::new(positions, &coarse);
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
