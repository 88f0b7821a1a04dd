//! Nearest-point queries on a patch's original surface, for the fan → original bounds of the
//! MT build (`super::build`, issue 30 item 4): a bounding-volume hierarchy of axis-aligned
//! boxes over the original triangles (Ericson, *Real-Time Collision Detection*, 2005, §6.2:
//! top-down build, median split of the centroids along their widest axis; §6.3.5-style
//! branch-and-bound descent, nearer child first).
//!
//! Exact: every distance it returns is a true point-triangle distance
//! ([`crate::geom::point_triangle_distance`]) to one original triangle, and a subtree is
//! skipped only when its box is farther than anything in it could change (with a relative
//! 1e-9 margin against rounding), so the minima are those of a scan over every triangle.
//! It replaces the scan over the covers of the triangles around a fan (a subset of the same
//! surface: distances to the whole patch surface are never larger), which took most of the
//! build's time at the coarse end where covers hold thousands of pieces.
//!
//! It does not change: the tree is built once per patch; the surface never moves.

use glam::DVec3;

use crate::geom::Prepared;

/// Triangles per leaf at most.
const LEAF: usize = 4;

/// Largest depth of the tree (median splits of up to 2³² triangles): the descent's stack.
const MAX_DEPTH: usize = 64;

/// Box distances are compared with this relative margin, so rounding never skips a triangle
/// at the same distance as the best so far.
const MARGIN: f64 = 1.0 + 1e-9;

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: its first triangle in `tris`; inner node: its first child (the second follows).
    first: u32,
    /// Triangles of a leaf; 0 for an inner node.
    count: u32,
}

/// The original triangles of a patch in a box hierarchy.
#[derive(Clone, Debug, Default)]
pub(super) struct SurfaceBvh {
    nodes: Vec<Node>,
    /// The triangles in leaf order, and their indices in the patch.
    tris: Vec<Prepared>,
    ids: Vec<u32>,
    /// Where each triangle of the patch is in `tris`.
    slot: Vec<u32>,
}

/// What [`SurfaceBvh::piece_bound`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum PieceBound {
    /// A triangle (its index) whose farthest point from the piece, `far`, is within the
    /// asked-for distance: the piece is that close to the surface.
    Within { far: f64, at: u32 },
    /// None is: the true distance from each corner to the surface, and the smallest over the
    /// triangles of the farthest corner's distance to it (convex bound) with that triangle.
    Full {
        corners: [f64; 3],
        convex: f64,
        at: Option<u32>,
    },
}

/// Squared distance from `p` to the box `lo..hi` (0 inside).
fn box_distance_squared(p: DVec3, lo: DVec3, hi: DVec3) -> f64 {
    (lo - p).max(p - hi).max(DVec3::ZERO).length_squared()
}

impl SurfaceBvh {
    /// The hierarchy over `triangles` (their corners).
    pub(super) fn new(triangles: &[[DVec3; 3]]) -> SurfaceBvh {
        let n = triangles.len();
        if n == 0 {
            return SurfaceBvh::default();
        }
        let centroid: Vec<DVec3> = triangles
            .iter()
            .map(|t| (t[0] + t[1] + t[2]) / 3.0)
            .collect();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut nodes = vec![Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            first: 0,
            count: n as u32,
        }];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let (start, count) = (nodes[i].first as usize, nodes[i].count as usize);
            let range = &mut order[start..start + count];
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            let (mut clo, mut chi) = (lo, hi);
            for &t in range.iter() {
                for p in triangles[t as usize] {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
                clo = clo.min(centroid[t as usize]);
                chi = chi.max(centroid[t as usize]);
            }
            nodes[i].lo = lo;
            nodes[i].hi = hi;
            if count <= LEAF {
                continue;
            }
            let extent = chi - clo;
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            let mid = count / 2;
            range.select_nth_unstable_by(mid, |&a, &b| {
                centroid[a as usize][axis]
                    .total_cmp(&centroid[b as usize][axis])
                    .then(a.cmp(&b))
            });
            let child = nodes.len();
            for (first, count) in [(start, mid), (start + mid, count - mid)] {
                nodes.push(Node {
                    lo: DVec3::ZERO,
                    hi: DVec3::ZERO,
                    first: first as u32,
                    count: count as u32,
                });
            }
            nodes[i].first = child as u32;
            nodes[i].count = 0;
            stack.extend([child, child + 1]);
        }
        let mut slot = vec![0; n];
        for (k, &t) in order.iter().enumerate() {
            slot[t as usize] = k as u32;
        }
        SurfaceBvh {
            nodes,
            tris: (order.iter())
                .map(|&t| {
                    let [a, b, c] = triangles[t as usize];
                    Prepared::new(a, b, c)
                })
                .collect(),
            ids: order,
            slot,
        }
    }

    /// The distance from `p` to the surface, or, as soon as one triangle within `stop` is
    /// found, that triangle's distance (`f64::INFINITY` for an empty surface); with the
    /// triangle found (its place in the tree's order), a good `seed` for a query nearby:
    /// measured first, it only prunes more (the result is the same).
    pub(super) fn nearest(&self, p: DVec3, stop: f64, seed: Option<u32>) -> (f64, Option<u32>) {
        let mut best = (f64::INFINITY, None);
        if self.nodes.is_empty() {
            return best;
        }
        if let Some(k) = seed
            && let Some(t) = self.tris.get(k as usize)
        {
            best = (t.distance(p), Some(k));
            if best.0 <= stop {
                return best;
            }
        }
        let mut stack = [0u32; MAX_DEPTH];
        let mut len = 1;
        while len > 0 {
            len -= 1;
            let node = self.nodes[stack[len] as usize];
            if box_distance_squared(p, node.lo, node.hi) > best.0 * best.0 * MARGIN {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                for k in first..first + node.count as usize {
                    let d = self.tris[k].distance(p);
                    if d < best.0 {
                        best = (d, Some(k as u32));
                    }
                    if best.0 <= stop {
                        return best;
                    }
                }
                continue;
            }
            let (l, r) = (node.first, node.first + 1);
            let dl = self.box_squared(l, p);
            let dr = self.box_squared(r, p);
            // Nearer child popped first.
            let (near, far) = if dl <= dr { (l, r) } else { (r, l) };
            stack[len] = far;
            stack[len + 1] = near;
            len += 2;
        }
        best
    }

    fn box_squared(&self, node: u32, p: DVec3) -> f64 {
        let n = &self.nodes[node as usize];
        box_distance_squared(p, n.lo, n.hi)
    }

    /// The distances a piece (a triangle of the simplified surface, or a part of one) has to
    /// the surface: [`PieceBound::Within`] as soon as a triangle is found whose farthest
    /// point from the piece is within `within`, else every corner's true distance to the
    /// surface and the convex bound (see [`PieceBound::Full`]). `seed`: a triangle likely near,
    /// measured first. Ties of the convex bound go to the triangle met first.
    pub(super) fn piece_bound(
        &self,
        piece: &[DVec3; 3],
        within: f64,
        seed: Option<u32>,
    ) -> PieceBound {
        let mut corners = [f64::INFINITY; 3];
        let mut convex = (f64::INFINITY, None);
        let measure =
            |t: &Prepared, id: u32, corners: &mut [f64; 3], convex: &mut (f64, Option<u32>)| {
                let mut far = 0.0f64;
                for (k, &p) in piece.iter().enumerate() {
                    let d = t.distance(p);
                    corners[k] = corners[k].min(d);
                    far = far.max(d);
                }
                if far < convex.0 {
                    *convex = (far, Some(id));
                }
                far
            };
        if let Some(id) = seed
            && let Some(&k) = self.slot.get(id as usize)
        {
            let far = measure(&self.tris[k as usize], id, &mut corners, &mut convex);
            if far <= within {
                return PieceBound::Within { far, at: id };
            }
        }
        if !self.nodes.is_empty() {
            let mut stack = [0u32; MAX_DEPTH];
            let mut len = 1;
            // Whether a box at these squared corner distances could lower a corner's distance
            // or the convex bound.
            let useful = |d: [f64; 3], corners: &[f64; 3], convex: f64| {
                (0..3).any(|k| d[k] <= corners[k] * corners[k] * MARGIN)
                    || d.into_iter().fold(0.0, f64::max) <= convex * convex * MARGIN
            };
            while len > 0 {
                len -= 1;
                let node = self.nodes[stack[len] as usize];
                let d = piece.map(|p| box_distance_squared(p, node.lo, node.hi));
                if !useful(d, &corners, convex.0) {
                    continue;
                }
                if node.count > 0 {
                    let first = node.first as usize;
                    for k in first..first + node.count as usize {
                        let far = measure(&self.tris[k], self.ids[k], &mut corners, &mut convex);
                        if far <= within {
                            return PieceBound::Within {
                                far,
                                at: self.ids[k],
                            };
                        }
                    }
                    continue;
                }
                let (l, r) = (node.first, node.first + 1);
                let sum = |c: u32| piece.iter().map(|&p| self.box_squared(c, p)).sum::<f64>();
                let (near, far) = if sum(l) <= sum(r) { (l, r) } else { (r, l) };
                stack[len] = far;
                stack[len + 1] = near;
                len += 2;
            }
        }
        PieceBound::Full {
            corners,
            convex: convex.0,
            at: convex.1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::point_triangle_distance;

    /// A wavy grid of `n` × `n` quads, each split in two, with a few triangles lifted.
    fn surface(n: u32) -> Vec<[DVec3; 3]> {
        let at = |i: u32, j: u32| {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            DVec3::new(x, y, 0.1 * (7.0 * x).sin() * (5.0 * y).cos())
        };
        let mut tris = Vec::new();
        for i in 0..n {
            for j in 0..n {
                tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        for k in (0..tris.len()).step_by(37) {
            tris[k][1].z += 0.3;
        }
        tris
    }

    fn brute(tris: &[[DVec3; 3]], p: DVec3) -> f64 {
        tris.iter()
            .map(|t| point_triangle_distance(p, t[0], t[1], t[2]))
            .fold(f64::INFINITY, f64::min)
    }

    fn points(k: usize) -> Vec<DVec3> {
        (0..k)
            .map(|i| {
                let f = i as f64;
                DVec3::new(
                    (f * 0.618).fract() * 1.4 - 0.2,
                    (f * 0.414).fract() * 1.4 - 0.2,
                    (f * 0.732).fract() * 0.8 - 0.4,
                )
            })
            .collect()
    }

    #[test]
    fn nearest_is_the_minimum_over_every_triangle() {
        let tris = surface(20);
        let bvh = SurfaceBvh::new(&tris);
        for p in points(300) {
            assert_eq!(bvh.nearest(p, -1.0, None).0, brute(&tris, p), "at {p}");
        }
    }

    /// A seed (any triangle, the last one found as `Builder::sample_lower` passes, or one out
    /// of range) changes neither the distance nor, with a stop, whether it is within it.
    #[test]
    fn a_seed_changes_nothing() {
        let tris = surface(12);
        let bvh = SurfaceBvh::new(&tris);
        let mut last = None;
        for (i, p) in points(300).into_iter().enumerate() {
            let exact = brute(&tris, p);
            for seed in [last, Some((i * 7 % tris.len()) as u32), Some(u32::MAX)] {
                let (d, at) = bvh.nearest(p, -1.0, seed);
                assert_eq!(d, exact, "at {p}, seed {seed:?}");
                assert!(at.is_some());
                let stop = exact * 1.5;
                let (within, _) = bvh.nearest(p, stop, seed);
                assert!(
                    within >= exact && within <= stop,
                    "at {p}: {within} for {exact}"
                );
            }
            last = bvh.nearest(p, -1.0, last).1;
        }
    }

    #[test]
    fn piece_bounds_match_a_scan() {
        let tris = surface(16);
        let bvh = SurfaceBvh::new(&tris);
        let pts = points(240);
        for (i, w) in pts.windows(3).enumerate().step_by(3) {
            let piece = [w[0], w[0] + (w[1] - w[0]) * 0.2, w[0] + (w[2] - w[0]) * 0.3];
            let corners = piece.map(|p| brute(&tris, p));
            let convex = tris
                .iter()
                .map(|t| {
                    piece
                        .iter()
                        .map(|&p| point_triangle_distance(p, t[0], t[1], t[2]))
                        .fold(0.0, f64::max)
                })
                .fold(f64::INFINITY, f64::min);
            let seed = (i % 2 == 0).then_some(i as u32);
            match bvh.piece_bound(&piece, -1.0, seed) {
                PieceBound::Full {
                    corners: c,
                    convex: v,
                    at,
                } => {
                    assert_eq!((c, v), (corners, convex), "piece {i}");
                    let t = tris[at.expect("a triangle") as usize];
                    let far = piece
                        .iter()
                        .map(|&p| point_triangle_distance(p, t[0], t[1], t[2]))
                        .fold(0.0, f64::max);
                    assert_eq!(far, convex);
                }
                other => panic!("{other:?}"),
            }
            // Asked for a distance the convex bound reaches, it stops with a triangle there.
            match bvh.piece_bound(&piece, convex, seed) {
                PieceBound::Within { far, .. } => assert!(far <= convex),
                other => panic!("{other:?}"),
            }
        }
    }
}
