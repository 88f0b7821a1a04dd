//! Bézier patch tessellation with a guaranteed, then measured, error.
//!
//! Balázs et al. (fat borders), section 3, only require that every patch can be drawn within
//! ε of the true surface, especially along its border; this module provides that for Bézier
//! patches on a uniform `nu × nv` parameter grid, each cell split along its shorter diagonal.
//!
//! **Bound.** For linear interpolation of `S` over a triangle of a grid cell of size
//! `hu × hv`, Taylor expansion around the evaluation point gives
//! `|S − L| ≤ (M_uu hu² + 2 M_uv hu hv + M_vv hv²) / 8`, where `M_xy` bound the second
//! derivatives over the patch (from the control net's second differences, see
//! `BezierPatch::second_derivative_bounds`). The resolution is the smallest grid (greedy in
//! the direction that gains most) whose bound is ≤ ε.
//!
//! **Measurement.** The error reported is the largest distance between `S(u,v)` and the
//! triangle point with the same parameters, sampled at every triangle's centroid and every
//! edge midpoint. This parametric distance bounds the two-sided Hausdorff distance between
//! surface and triangles from above. It is what callers (fat borders, tests) should trust.
//!
//! Not done here: adaptive (non-uniform) grids, trimming.

use glam::DVec3;

use super::{PatchMesh, dedup_ring};
use crate::model::BezierPatch;

/// Upper limit on the segments per parameter direction (protects memory when ε is tiny).
pub const MAX_SEGMENTS: u32 = 512;

/// A grid resolution: segments in u and v.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Resolution {
    pub nu: u32,
    pub nv: u32,
}

/// Reusable tessellator: keeps its scratch buffers between calls.
#[derive(Debug, Default)]
pub struct BezierTessellator {
    grid: Vec<DVec3>,
}

impl BezierTessellator {
    pub fn new() -> Self {
        Self::default()
    }

    /// Smallest grid whose a-priori bound is ≤ `eps` (capped at [`MAX_SEGMENTS`]), and that bound.
    pub(crate) fn resolution_for(patch: &BezierPatch, eps: f64) -> (Resolution, f64) {
        let m = patch.second_derivative_bounds();
        let bound = |nu: u32, nv: u32| {
            let (hu, hv) = (1.0 / nu as f64, 1.0 / nv as f64);
            (m.uu * hu * hu + 2.0 * m.uv * hu * hv + m.vv * hv * hv) / 8.0
        };
        if eps.is_nan() || eps <= 0.0 {
            return (
                Resolution {
                    nu: MAX_SEGMENTS,
                    nv: MAX_SEGMENTS,
                },
                bound(MAX_SEGMENTS, MAX_SEGMENTS),
            );
        }
        // Each pure term alone must fit: a lower bound to start the greedy search from.
        let start = |mm: f64| ((mm / (8.0 * eps)).sqrt().ceil() as u32).clamp(1, MAX_SEGMENTS);
        let (mut nu, mut nv) = (start(m.uu), start(m.vv));
        while bound(nu, nv) > eps && (nu < MAX_SEGMENTS || nv < MAX_SEGMENTS) {
            let gain_u = if nu < MAX_SEGMENTS {
                bound(nu, nv) - bound(nu + 1, nv)
            } else {
                -1.0
            };
            let gain_v = if nv < MAX_SEGMENTS {
                bound(nu, nv) - bound(nu, nv + 1)
            } else {
                -1.0
            };
            // Gain per added vertex row/column; a direction at its cap never grows (a NaN
            // gain from an infinite bound must not push it past the cap).
            let grow_u = nv >= MAX_SEGMENTS
                || (nu < MAX_SEGMENTS && gain_u / (nv as f64 + 1.0) >= gain_v / (nu as f64 + 1.0));
            if grow_u {
                nu += 1;
            } else {
                nv += 1;
            }
        }
        (Resolution { nu, nv }, bound(nu, nv))
    }

    /// Tessellates `patch` so that its distance to the triangles is ≤ `eps` (object units),
    /// writing into `out` (its buffers are reused). `out.error` is the measured error.
    pub fn tessellate(&mut self, patch: &BezierPatch, eps: f64, out: &mut PatchMesh) {
        let (res, _bound) = Self::resolution_for(patch, eps);
        self.tessellate_grid(patch, res, eps, out);
    }

    /// Tessellates on a given grid; `eps` is only recorded as the target.
    pub(crate) fn tessellate_grid(
        &mut self,
        patch: &BezierPatch,
        res: Resolution,
        eps: f64,
        out: &mut PatchMesh,
    ) {
        let (nu, nv) = (res.nu.max(1), res.nv.max(1));
        let (cu, cv) = (nu as usize + 1, nv as usize + 1);
        let param = |i: usize, n: u32| i as f64 / n as f64;
        out.positions.clear();
        out.normals.clear();
        out.triangles.clear();
        out.borders.clear();
        out.border_kinds.clear();
        out.eps_target = eps;
        out.resolution = Resolution { nu, nv };

        self.grid.clear();
        for i in 0..cu {
            for j in 0..cv {
                let (u, v) = (param(i, nu), param(j, nv));
                let p = patch.eval(u, v);
                self.grid.push(p);
                out.positions.push(p.as_vec3());
                out.normals.push(patch.normal(u, v).as_vec3());
            }
        }
        let idx = |i: usize, j: usize| (i * cv + j) as u32;
        let mut error: f64 = 0.0;
        // Positions as the GPU gets them (f32), for an honest measurement.
        let g = |k: u32| out.positions[k as usize].as_dvec3();
        for i in 0..nu as usize {
            for j in 0..nv as usize {
                let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
                let (pa, pb, pc, pd) = (g(a), g(b), g(c), g(d));
                let (u0, u1) = (param(i, nu), param(i + 1, nu));
                let (v0, v1) = (param(j, nv), param(j + 1, nv));
                let tris: [Tri; 2] = if pa.distance_squared(pc) <= pb.distance_squared(pd) {
                    [
                        ([a, b, c], [(u0, v0), (u1, v0), (u1, v1)], [pa, pb, pc]),
                        ([a, c, d], [(u0, v0), (u1, v1), (u0, v1)], [pa, pc, pd]),
                    ]
                } else {
                    [
                        ([a, b, d], [(u0, v0), (u1, v0), (u0, v1)], [pa, pb, pd]),
                        ([b, c, d], [(u1, v0), (u1, v1), (u0, v1)], [pb, pc, pd]),
                    ]
                };
                for (t, uv, p) in &tris {
                    out.triangles.push(*t);
                    error = error.max(triangle_error(patch, uv, p));
                }
            }
        }
        out.error = error;
        out.stopped = (error > eps && nu >= MAX_SEGMENTS && nv >= MAX_SEGMENTS)
            .then_some(super::Stop::Segments(MAX_SEGMENTS));

        // Border loop: u = 0 (v up), v = 1 (u up), u = 1 (v down), v = 0 (u down), each
        // vertex with the kind of the side its segment to the next runs along.
        let sides = patch.sides();
        let mut ring = Vec::with_capacity(2 * (cu + cv));
        ring.extend((0..cv - 1).map(|j| (idx(0, j), sides[0])));
        ring.extend((0..cu - 1).map(|i| (idx(i, cv - 1), sides[1])));
        ring.extend((1..cv).rev().map(|j| (idx(cu - 1, j), sides[2])));
        ring.extend((1..cu).rev().map(|i| (idx(i, 0), sides[3])));
        let (ring, kinds) = dedup_ring(&ring, &out.positions);
        if ring.len() >= 2 {
            out.borders.push(ring);
            out.border_kinds.push(kinds);
        }
        out.border_error = Some(border_error(patch, nu, nv, &out.positions));
    }
}

/// Largest distance between the boundary curves of `patch` and the border polyline of its
/// `nu × nv` grid (`positions`, row-major in u, as the GPU gets them), sampled at a quarter,
/// half and three quarters of every border segment: the width a fat border must have
/// (`PatchMesh::border_width`). A segment of a smooth curve deviates most near its middle.
fn border_error(patch: &BezierPatch, nu: u32, nv: u32, positions: &[glam::Vec3]) -> f64 {
    let cv = nv as usize + 1;
    let at = |i: usize, j: usize| positions[i * cv + j].as_dvec3();
    let (fu, fv) = (nu as f64, nv as f64);
    let mut worst: f64 = 0.0;
    let mut segment = |(i0, j0): (usize, usize), (i1, j1): (usize, usize)| {
        let (p0, p1) = (at(i0, j0), at(i1, j1));
        for t in [0.25, 0.5, 0.75] {
            let u = (i0 as f64 + t * (i1 as f64 - i0 as f64)) / fu;
            let v = (j0 as f64 + t * (j1 as f64 - j0 as f64)) / fv;
            worst = worst.max(patch.eval(u, v).distance(p0.lerp(p1, t)));
        }
    };
    let (nu, nv) = (nu as usize, nv as usize);
    for j in 0..nv {
        segment((0, j), (0, j + 1));
        segment((nu, j), (nu, j + 1));
    }
    for i in 0..nu {
        segment((i, 0), (i + 1, 0));
        segment((i, nv), (i + 1, nv));
    }
    worst
}

/// A triangle: vertex indices, parameters and (f32-rounded) positions of its corners.
type Tri = ([u32; 3], [(f64, f64); 3], [DVec3; 3]);

/// Sampled parametric distance between `S` and the linear triangle (centroid, edge midpoints).
fn triangle_error(patch: &BezierPatch, uv: &[(f64, f64); 3], p: &[DVec3; 3]) -> f64 {
    const SAMPLES: [[f64; 3]; 4] = [
        [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
        [0.5, 0.5, 0.0],
        [0.0, 0.5, 0.5],
        [0.5, 0.0, 0.5],
    ];
    let mut e: f64 = 0.0;
    for w in SAMPLES {
        let u = w[0] * uv[0].0 + w[1] * uv[1].0 + w[2] * uv[2].0;
        let v = w[0] * uv[0].1 + w[1] * uv[1].1 + w[2] * uv[2].1;
        let lin = w[0] * p[0] + w[1] * p[1] + w[2] * p[2];
        e = e.max(patch.eval(u, v).distance(lin));
    }
    e
}

/// Dense check used by tests: sampled distance on an `k × k` barycentric lattice of every
/// triangle (more samples than the per-frame measurement).
#[cfg(test)]
pub(crate) fn dense_error(patch: &BezierPatch, mesh: &PatchMesh, k: usize) -> f64 {
    let (nu, nv) = (mesh.resolution.nu as f64, mesh.resolution.nv as f64);
    let cv = mesh.resolution.nv as usize + 1;
    let uv_of = |idx: u32| {
        let (i, j) = (idx as usize / cv, idx as usize % cv);
        (i as f64 / nu, j as f64 / nv)
    };
    let mut e: f64 = 0.0;
    for t in &mesh.triangles {
        let uv = t.map(uv_of);
        let p = t.map(|k| mesh.positions[k as usize].as_dvec3());
        for a in 0..=k {
            for b in 0..=(k - a) {
                let w = [
                    a as f64 / k as f64,
                    b as f64 / k as f64,
                    (k - a - b) as f64 / k as f64,
                ];
                let u = w[0] * uv[0].0 + w[1] * uv[1].0 + w[2] * uv[2].0;
                let v = w[0] * uv[0].1 + w[1] * uv[1].1 + w[2] * uv[2].1;
                let lin = w[0] * p[0] + w[1] * p[1] + w[2] * p[2];
                e = e.max(patch.eval(u, v).distance(lin));
            }
        }
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn patch_from(du: usize, dv: usize, coords: &[f64]) -> Option<BezierPatch> {
        let ctrl = (0..(du + 1) * (dv + 1))
            .map(|k| {
                let (i, j) = (k / (dv + 1), k % (dv + 1));
                DVec3::new(
                    i as f64 + coords[3 * k % coords.len()],
                    j as f64 + coords[(3 * k + 1) % coords.len()],
                    coords[(3 * k + 2) % coords.len()],
                )
            })
            .collect();
        BezierPatch::new(du, dv, ctrl).ok()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn measured_error_is_within_eps(
            du in 1usize..=6, dv in 1usize..=6,
            coords in proptest::collection::vec(-2.0f64..2.0, 48),
            eps in 0.002f64..0.2,
        ) {
            let Some(patch) = patch_from(du, dv, &coords) else { return Ok(()); };
            let mut t = BezierTessellator::new();
            let mut m = PatchMesh::default();
            t.tessellate(&patch, eps, &mut m);
            prop_assume!(m.resolution.nu < MAX_SEGMENTS && m.resolution.nv < MAX_SEGMENTS);
            prop_assert!(m.error <= eps, "measured {} > eps {}", m.error, eps);
            let dense = dense_error(&patch, &m, 6);
            // f32 rounding of vertex positions adds at most a few ulps of the coordinates.
            prop_assert!(dense <= eps * (1.0 + 1e-4) + 1e-5, "dense {} > eps {}", dense, eps);
        }
    }

    #[test]
    fn coarser_tolerance_gives_fewer_triangles() {
        let coords: Vec<f64> = (0..48)
            .map(|k| ((k * 37 % 17) as f64 - 8.0) / 8.0)
            .collect();
        let patch = patch_from(3, 3, &coords).expect("valid");
        let mut t = BezierTessellator::new();
        let mut fine = PatchMesh::default();
        let mut coarse = PatchMesh::default();
        t.tessellate(&patch, 0.001, &mut fine);
        t.tessellate(&patch, 0.1, &mut coarse);
        assert!(fine.triangles.len() > 4 * coarse.triangles.len());
        assert!(fine.error <= 0.001 && coarse.error <= 0.1);
    }

    #[test]
    fn border_loop_is_closed_and_on_the_boundary() {
        let coords: Vec<f64> = (0..48)
            .map(|k| ((k * 13 % 11) as f64 - 5.0) / 6.0)
            .collect();
        let patch = patch_from(3, 2, &coords).expect("valid");
        let mut t = BezierTessellator::new();
        let mut m = PatchMesh::default();
        t.tessellate_grid(&patch, Resolution { nu: 5, nv: 7 }, 0.0, &mut m);
        assert_eq!(m.borders.len(), 1);
        assert_eq!(m.borders[0].len(), 2 * (5 + 7));
        assert_eq!(m.triangles.len(), 2 * 5 * 7);
        assert_eq!(
            m.positions[0].as_dvec3(),
            patch.eval(0.0, 0.0).as_vec3().as_dvec3()
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// The border error is what the border polyline really is off its boundary curves:
        /// 32 samples per segment stay within it (up to the 3-sample measurement's
        /// shortfall on curves that are not quadratic, a few per cent) and it is below ε.
        #[test]
        fn border_error_bounds_the_dense_border_deviation(
            du in 1usize..=5, dv in 1usize..=5,
            coords in proptest::collection::vec(-2.0f64..2.0, 48),
            eps in 0.005f64..0.2,
        ) {
            let Some(patch) = patch_from(du, dv, &coords) else { return Ok(()); };
            let mut m = PatchMesh::default();
            BezierTessellator::new().tessellate(&patch, eps, &mut m);
            prop_assume!(m.resolution.nu < MAX_SEGMENTS && m.resolution.nv < MAX_SEGMENTS);
            let b = m.border_error.expect("Bézier patches measure their border");
            prop_assert!(b <= eps * (1.0 + 1e-4) + 1e-5, "border {} > eps {}", b, eps);
            let (nu, nv) = (m.resolution.nu as usize, m.resolution.nv as usize);
            let at = |i: usize, j: usize| m.positions[i * (nv + 1) + j].as_dvec3();
            let mut dense: f64 = 0.0;
            let mut seg = |a: (usize, usize), c: (usize, usize)| {
                for k in 1..32 {
                    let t = k as f64 / 32.0;
                    let u = (a.0 as f64 + t * (c.0 as f64 - a.0 as f64)) / nu as f64;
                    let v = (a.1 as f64 + t * (c.1 as f64 - a.1 as f64)) / nv as f64;
                    let on = at(a.0, a.1).lerp(at(c.0, c.1), t);
                    dense = dense.max(patch.eval(u, v).distance(on));
                }
            };
            for j in 0..nv {
                seg((0, j), (0, j + 1));
                seg((nu, j), (nu, j + 1));
            }
            for i in 0..nu {
                seg((i, 0), (i + 1, 0));
                seg((i, nv), (i + 1, nv));
            }
            prop_assert!(dense <= 1.05 * b + 1e-5, "dense border {} > measured {}", dense, b);
        }
    }

    /// A patch whose border is straight but whose inside bulges: the border error is ~0 while
    /// the surface error is not, so its fat borders get the floor width, not ε.
    #[test]
    fn straight_borders_get_thin_fat_borders() {
        let mut ctrl = Vec::new();
        for i in 0..3 {
            for j in 0..3 {
                let z = if i == 1 && j == 1 { 2.0 } else { 0.0 };
                ctrl.push(DVec3::new(i as f64, j as f64, z));
            }
        }
        let patch = BezierPatch::new(2, 2, ctrl).expect("valid");
        let mut m = PatchMesh::default();
        BezierTessellator::new().tessellate(&patch, 0.01, &mut m);
        assert!(m.error > 0.002, "the inside is curved: {}", m.error);
        assert!(m.border_error.expect("measured") < 1e-6);
        let full = m.eps_border();
        assert_eq!(m.border_width(), crate::tessellate::MIN_BORDER_WIDTH * full);
    }
}
