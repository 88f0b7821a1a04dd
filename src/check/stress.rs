//! Stress tessellations for the crack check: every shared border opened as wide as the pixel
//! error allows, so that only fat borders of the full width close it.
//!
//! Balázs, Guthe, Klein, "Fat Borders" (2004), §3: the only requirement on a patch's level is
//! that it lies within the Hausdorff distance ε of its surface ("especially along the border");
//! each border polyline is then widened by ε on both sides, perpendicular to the border and to
//! the view. Two neighbours' borders may be up to ε_a + ε_b apart across the view, and their
//! two fat borders, ε_a + ε_b together, close that gap — exactly, with nothing to spare.
//!
//! Independent tessellations from [`crate::tessellate`] come nowhere near that bound along
//! their borders (shared straight edges even coincide), so a crack check on them passes with
//! fat borders of a quarter width. [`stress_tessellation`] builds a tessellation that uses the
//! allowance: each patch is tessellated to `STRESS_EPS_FRACTION` of its ε (measured error e),
//! then every border vertex is moved by δ = `STRESS_RETREAT` · (ε − e) perpendicular to its
//! border and to the view, towards the patch's inside ([`retreat_border`]). Every point of the
//! mesh moves by at most δ, so the mesh stays within e + δ ≤ ε of its surface: an honest level,
//! reported as the patch's achieved error. With e ≤ ε/4 (what the fine tessellation measures),
//! two neighbours then gap across the view by at least δ_a + δ_b ≥ 0.6 (ε_a + ε_b) and at most
//! e_a + δ_a + e_b + δ_b ≤ 0.85 (ε_a + ε_b): fat borders of full width must close it, fat
//! borders of half the width cannot.
//!
//! Measured (`tests/cracks.rs`, 4 views at 384×288, 0.5 px): every model of the crack suite
//! shows hundreds to thousands of crack pixels without fat borders, 82–384 with the 6-vertex
//! fat borders at half width, and none at full width (there was one a view or so while the
//! fans had their apex on the T-junction at v_i, see `render::fat_border`). The paper's
//! 2-vertex variant is ε·cos(θ/2) wide at a joint turning by θ; mitred by the segments'
//! directions in space (at most 2.75 ε) it still let pixels through where mesh borders turn
//! back on screen (`check --stress`, 20 views: bunny 6, alien 30, cakeBirthday 261 crack
//! pixels, from 71, 126 and 2 017 unmitred). `FatBorders::Two` now draws capped segment
//! quads (`render::fat_border`): 0 on all three, on lavapipe and GL.
//!
//! Fat borders are drawn [`PatchMesh::border_width`] wide (a Bézier patch's measured border
//! error, not ε): the retreat adds the distance moved to the border error, so the stress
//! tessellation tests the width drawn — with fat borders half as wide as the measured border
//! error the teapot shows 476 crack pixels, with the measured width 0.
//!
//! Not done: the stress meshes are for checking only (the retreat depends on the eye, and it
//! is the opposite of what a renderer wants).

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use crate::model::Scene;
use crate::tessellate::{PatchMesh, tessellate_scene};
use crate::view::View;

/// The stress tessellation's triangles are made to this fraction of each patch's ε.
pub(crate) const STRESS_EPS_FRACTION: f64 = 0.25;
/// Fraction of the error left over (ε − measured) that borders are moved by.
pub(crate) const STRESS_RETREAT: f64 = 0.8;

/// Moves every vertex of `mesh`'s border loops by `amount(position)` object units, perpendicular
/// to the border there and to the direction towards the viewer (homogeneous, as
/// [`View::viewer`]: the eye, or the axis of an orthographic view), towards the inside of the
/// patch (the side of the triangles on the border edges). A vertex on several loops moves
/// once; a vertex whose border edges have no triangle stays. Returns the largest distance
/// moved.
pub fn retreat_border(mesh: &mut PatchMesh, viewer: Vec4, amount: impl Fn(Vec3) -> f32) -> f32 {
    use std::collections::HashMap;
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    // Third vertex of a triangle on each border edge.
    let mut third: HashMap<(u32, u32), u32> = HashMap::new();
    for ring in &mesh.borders {
        let n = ring.len();
        for k in 0..n {
            third.insert(key(ring[k], ring[(k + 1) % n]), u32::MAX);
        }
    }
    for t in &mesh.triangles {
        for j in 0..3 {
            if let Some(c) = third.get_mut(&key(t[j], t[(j + 1) % 3])) {
                *c = t[(j + 2) % 3];
            }
        }
    }
    let p = &mesh.positions;
    // Unit direction from edge (a, b) into its triangle, perpendicular to the edge.
    let inward = |a: u32, b: u32| -> Vec3 {
        match third.get(&key(a, b)) {
            Some(&c) if c != u32::MAX => {
                let (pa, pb, pc) = (p[a as usize], p[b as usize], p[c as usize]);
                let e = (pb - pa).normalize_or_zero();
                let v = pc - pa;
                (v - e * v.dot(e)).normalize_or_zero()
            }
            _ => Vec3::ZERO,
        }
    };
    let mut moves: Vec<(u32, Vec3)> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for ring in &mesh.borders {
        let n = ring.len();
        if n < 2 {
            continue;
        }
        for k in 0..n {
            let (prev, cur, next) = (ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]);
            if !seen.insert(cur) {
                continue;
            }
            let into = inward(prev, cur) + inward(cur, next);
            let v = p[cur as usize];
            let d = (viewer.truncate() - v * viewer.w).normalize_or_zero();
            let tangent = p[next as usize] - p[prev as usize];
            let side = tangent.cross(d).normalize_or_zero();
            if into == Vec3::ZERO || side == Vec3::ZERO {
                continue;
            }
            let side = if side.dot(into) < 0.0 { -side } else { side };
            moves.push((cur, side * amount(v).max(0.0)));
        }
    }
    let mut largest = 0.0f32;
    for (i, m) in moves {
        mesh.positions[i as usize] += m;
        largest = largest.max(m.length());
    }
    if let Some(cut) = mesh.arcs.as_mut() {
        // The positions are no longer the hierarchy's: upload them.
        cut.moved = true;
    }
    largest
}

/// The stress tessellation of `scene` for `view` at `pixel_error` (see the module doc): every
/// patch within its ε, every border pulled back by `STRESS_RETREAT` of what is left of ε.
/// Each mesh reports ε as its target and e + δ as its achieved error; its fat borders are drawn
/// with ε. A patch whose fine tessellation already misses ε (or failed) is left as it is.
pub fn stress_tessellation(scene: &Scene, view: &View, pixel_error: f64) -> Vec<PatchMesh> {
    let mut meshes = tessellate_scene(scene, view, pixel_error * STRESS_EPS_FRACTION);
    let viewer = view.viewer().as_vec4();
    meshes
        .par_iter_mut()
        .zip(&scene.patches)
        .for_each(|(m, patch)| {
            let eps = view.eps_obj(&patch.bounds, pixel_error);
            let err = m.error.max(m.trim_error);
            if m.failure.is_some() || err >= eps {
                return;
            }
            let delta = STRESS_RETREAT * (eps - err);
            let moved = retreat_border(m, viewer, |_| delta as f32) as f64;
            m.eps_target = eps;
            m.error = err + moved;
            // The border moved off its curve by up to `moved` more: the fat borders are as
            // wide as that (`PatchMesh::border_width`), which the crack check then tests.
            m.border_error = m.border_error.map(|b| b + moved);
        });
    meshes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square in the z = 0 plane, two triangles, one border loop.
    fn square() -> PatchMesh {
        PatchMesh {
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            normals: vec![Vec3::Z; 4],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            borders: vec![vec![0, 1, 2, 3]],
            ..PatchMesh::default()
        }
    }

    #[test]
    fn borders_move_inwards_across_the_view_by_the_amount() {
        let mut m = square();
        let eye = Vec3::new(0.5, 0.5, 10.0);
        let moved = retreat_border(&mut m, eye.extend(1.0), |_| 0.1);
        assert!((moved - 0.1).abs() < 1e-6);
        let centre = Vec3::new(0.5, 0.5, 0.0);
        for (before, after) in square().positions.iter().zip(&m.positions) {
            let step = *after - *before;
            assert!((step.length() - 0.1).abs() < 1e-5, "{step:?}");
            // Towards the inside, perpendicular to the view.
            assert!(step.dot(centre - *before) > 0.0, "{step:?}");
            assert!(step.dot((eye - *before).normalize()).abs() < 1e-5);
        }
    }

    #[test]
    fn an_edge_seen_at_an_angle_still_moves_into_the_patch() {
        let mut m = square();
        // Eye far to the side of the +x edge, level with the plane's diagonal.
        let eye = Vec3::new(8.0, 0.5, 3.0);
        retreat_border(&mut m, eye.extend(1.0), |_| 0.05);
        for (before, after) in square().positions.iter().zip(&m.positions) {
            assert!((*after - *before).dot(Vec3::new(0.5, 0.5, 0.0) - *before) > 0.0);
        }
    }
}
