//! A mesh's triangles in a uniform grid of cubic cells, for the distance from a face sample
//! to the nearest triangle ([`super::FaceFidelity::missing`]): cells in rings around the
//! sample's cell until no triangle outside the rings can be nearer (the expanding-ring
//! nearest-neighbour search over a uniform grid; Cleary & Wyvill, The Visual Computer 4(2),
//! 1988). Exact: the nearest triangle's distance, as a scan of every triangle gives it.

use glam::DVec3;

/// A mesh's triangles binned in a grid of cubic cells (each triangle in every cell its box
/// overlaps), for nearest-triangle distances.
pub(super) struct TriangleGrid<'a> {
    positions: &'a [DVec3],
    triangles: &'a [[u32; 3]],
    /// Per vertex, how much farther a point may lie from the mesh there (interpolated over
    /// each triangle); empty or all 0: plain distances.
    allowance: &'a [f64],
    /// The largest allowance: an untested triangle beyond a bound may still come this much
    /// nearer.
    max_allowance: f64,
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// Per cell, the range of `items` holding its triangles.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl<'a> TriangleGrid<'a> {
    /// Most cells per axis.
    const MAX_DIM: usize = 32;

    pub(super) fn new(
        positions: &'a [DVec3],
        triangles: &'a [[u32; 3]],
        allowance: &'a [f64],
    ) -> TriangleGrid<'a> {
        let corners = |t: &[u32; 3]| t.map(|i| positions[i as usize]);
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for t in triangles {
            for p in corners(t) {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        let extent = (hi - lo).max_element();
        let cell = if extent.is_finite() && extent > 0.0 {
            // About one triangle per occupied cell, for a mesh that is a surface.
            let per_axis = (triangles.len() as f64).sqrt().ceil().max(1.0);
            extent / per_axis.min(Self::MAX_DIM as f64)
        } else {
            1.0
        };
        let dim = |d: f64| ((d / cell).floor() as usize + 1).clamp(1, Self::MAX_DIM);
        let size = hi - lo;
        let dims = if lo.is_finite() {
            [dim(size.x), dim(size.y), dim(size.z)]
        } else {
            [1, 1, 1]
        };
        let max_allowance = allowance
            .iter()
            .copied()
            .filter(|a| a.is_finite())
            .fold(0.0, f64::max);
        let mut grid = TriangleGrid {
            positions,
            triangles,
            allowance,
            max_allowance,
            lo: if lo.is_finite() { lo } else { DVec3::ZERO },
            cell,
            dims,
            start: Vec::new(),
            items: Vec::new(),
        };
        let n = dims[0] * dims[1] * dims[2];
        let mut count = vec![0u32; n + 1];
        let cells_of = |g: &TriangleGrid<'_>, t: &[u32; 3]| {
            let c = corners(t);
            let a = g.cell_of(c[0].min(c[1]).min(c[2]));
            let b = g.cell_of(c[0].max(c[1]).max(c[2]));
            (a, b)
        };
        for t in triangles {
            let (a, b) = cells_of(&grid, t);
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        count[grid.index([x, y, z]) + 1] += 1;
                    }
                }
            }
        }
        for k in 1..=n {
            count[k] += count[k - 1];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[n] as usize];
        for (ti, t) in triangles.iter().enumerate() {
            let (a, b) = cells_of(&grid, t);
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        let c = grid.index([x, y, z]);
                        items[fill[c] as usize] = ti as u32;
                        fill[c] += 1;
                    }
                }
            }
        }
        grid.start = count;
        grid.items = items;
        grid
    }

    fn cell_of(&self, p: DVec3) -> [usize; 3] {
        let c = (p - self.lo) / self.cell;
        let f = |x: f64, d: usize| {
            if x.is_nan() {
                0
            } else {
                (x.floor().max(0.0) as usize).min(d - 1)
            }
        };
        [
            f(c.x, self.dims[0]),
            f(c.y, self.dims[1]),
            f(c.z, self.dims[2]),
        ]
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[0] * self.dims[1] + c[1]) * self.dims[2] + c[2]
    }

    /// Distance from `q` to triangle `t`, less the allowance interpolated at its nearest point
    /// (never below 0).
    fn triangle_distance(&self, q: DVec3, t: u32) -> f64 {
        let tri = self.triangles[t as usize];
        let [a, b, c] = tri.map(|i| self.positions[i as usize]);
        let given = tri.map(|i| self.allowance.get(i as usize).copied().unwrap_or(0.0));
        if given.iter().all(|&g| g <= 0.0 || !g.is_finite()) {
            return crate::geom::point_triangle_distance(q, a, b, c);
        }
        let p = crate::geom::closest_point_on_triangle(q, a, b, c);
        // Barycentric coordinates of p; a degenerate triangle gets its smallest allowance.
        let (v0, v1, v2) = (b - a, c - a, p - a);
        let (d00, d01, d11) = (v0.dot(v0), v0.dot(v1), v1.dot(v1));
        let (d20, d21) = (v2.dot(v0), v2.dot(v1));
        let den = d00 * d11 - d01 * d01;
        let allowed = if den > 1e-300 {
            let v = ((d11 * d20 - d01 * d21) / den).clamp(0.0, 1.0);
            let w = ((d00 * d21 - d01 * d20) / den).clamp(0.0, 1.0);
            let u = (1.0 - v - w).max(0.0);
            given[0] * u + given[1] * v + given[2] * w
        } else {
            given.iter().copied().fold(f64::INFINITY, f64::min)
        };
        (q.distance(p) - allowed.max(0.0)).max(0.0)
    }

    /// Distance from `q` to the nearest triangle (less its allowance): cells in rings around `q`'s cell until no
    /// triangle outside the rings can be nearer.
    pub(super) fn distance(&self, q: DVec3) -> f64 {
        let c = self.cell_of(q);
        let mut best = f64::INFINITY;
        let max_k = *self.dims.iter().max().unwrap_or(&1);
        for k in 0..=max_k {
            // A ring as large as the mesh: every triangle once instead.
            if (2 * k + 1).pow(3) > self.triangles.len() {
                return (0..self.triangles.len() as u32)
                    .map(|t| self.triangle_distance(q, t))
                    .fold(best, f64::min);
            }
            let range = |i: usize| (c[i].saturating_sub(k), (c[i] + k).min(self.dims[i] - 1));
            let (rx, ry, rz) = (range(0), range(1), range(2));
            for x in rx.0..=rx.1 {
                for y in ry.0..=ry.1 {
                    for z in rz.0..=rz.1 {
                        let ring = x.abs_diff(c[0]).max(y.abs_diff(c[1])).max(z.abs_diff(c[2]));
                        if ring != k {
                            continue;
                        }
                        let cell = self.index([x, y, z]);
                        let (s, e) = (self.start[cell] as usize, self.start[cell + 1] as usize);
                        for &t in &self.items[s..e] {
                            best = best.min(self.triangle_distance(q, t));
                        }
                    }
                }
            }
            // Untested triangles lie outside the rings' box: at least this far, across its
            // faces inside the grid (nothing lies beyond the grid's own faces).
            let mut bound = f64::INFINITY;
            for (i, (a, b)) in [rx, ry, rz].into_iter().enumerate() {
                if a > 0 {
                    bound = bound.min(q[i] - (self.lo[i] + a as f64 * self.cell));
                }
                if b + 1 < self.dims[i] {
                    bound = bound.min(self.lo[i] + (b + 1) as f64 * self.cell - q[i]);
                }
            }
            if best <= (bound - self.max_allowance).max(0.0) || bound == f64::INFINITY {
                return best;
            }
        }
        best
    }
}
