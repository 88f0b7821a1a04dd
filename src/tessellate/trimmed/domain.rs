//! Point-in-polygon tests against a trimmed face's loops, for the trimmed tessellator
//! ([`super`]): which grid points and which triangles lie inside the domain.

use std::collections::VecDeque;

use glam::{DVec2, DVec3};
use spade::Triangulation;

use super::Cdt;
use crate::model::trimmed::SurfaceEval;

/// Per triangle (its vertex indices from the least, orientation kept: [`memo_key`]), what an
/// earlier refinement round found of it. A round changes the triangulation only round the
/// points it inserts; the other triangles need no second test (a fuzzed face,
/// `tests/data/fuzz/trimmed/zigzag_edge_retried_4x`, had each of its 280 000 triangles tested
/// against its 17 000 border segments and sampled again every round). Each round keeps the
/// entries of its own triangles only.
pub(super) type Memo<T> = crate::util::IntMap<[u32; 3], T>;

/// The key of triangle `t` in a [`Memo`], and the rotation `r` it took: `key[k] = t[(r + k) % 3]`.
pub(super) fn memo_key(t: [u32; 3]) -> ([u32; 3], usize) {
    let r = if t[0] <= t[1] && t[0] <= t[2] {
        0
    } else if t[1] <= t[2] {
        1
    } else {
        2
    };
    ([t[r], t[(r + 1) % 3], t[(r + 2) % 3]], r)
}

/// Per-edge values of a triangle `t` (edge `j` from `t[j]` to `t[j + 1]`) in the order of its
/// [`memo_key`] of rotation `r`.
pub(super) fn edges_to_key<T: Copy>(by_t: [T; 3], r: usize) -> [T; 3] {
    [0, 1, 2].map(|k| by_t[(r + k) % 3])
}

/// The inverse of [`edges_to_key`]: per-edge values in key order back in `t`'s.
pub(super) fn edges_from_key<T: Copy>(by_key: [T; 3], r: usize) -> [T; 3] {
    [0, 1, 2].map(|j| by_key[(j + 3 - r) % 3])
}

/// A triangle whose parameter-space area is below this fraction of its longest side squared
/// (scaled space) has no inside to test: see [`inside_faces`].
const SLIVER: f64 = 1e-9;

/// The trimmed domain for point-in-polygon tests (even-odd rule over every loop segment),
/// with the segments binned by height: a query visits the segments of its band only, not all
/// of them (a face with crossing trim curves tests every triangle, every refinement round).
/// Band limits are quantiles of the segments' end heights, so bands stay short where the
/// segments crowd (a fuzzed face: 7 600 segments near one height, one curve 10¹⁰ away).
pub(super) struct Domain<'a> {
    segs: &'a [(DVec2, DVec2)],
    /// Ascending limits between bands: band k holds heights in [limits[k−1], limits[k]).
    limits: Vec<f64>,
    bands: Vec<Vec<u32>>,
}

impl<'a> Domain<'a> {
    pub(super) fn new(segs: &'a [(DVec2, DVec2)]) -> Self {
        let mut ys: Vec<f64> = segs.iter().flat_map(|s| [s.0.y, s.1.y]).collect();
        ys.sort_unstable_by(f64::total_cmp);
        let n = ((segs.len() as f64).sqrt() as usize).clamp(1, 256);
        let mut limits: Vec<f64> = (1..n).map(|k| ys[k * ys.len() / n]).collect();
        limits.dedup();
        let mut d = Domain {
            segs,
            bands: vec![Vec::new(); limits.len() + 1],
            limits,
        };
        for (i, s) in segs.iter().enumerate() {
            let (a, b) = (d.band(s.0.y.min(s.1.y)), d.band(s.0.y.max(s.1.y)));
            for band in &mut d.bands[a..=b] {
                band.push(i as u32);
            }
        }
        d
    }

    /// The band of height `y` (monotone in `y`).
    fn band(&self, y: f64) -> usize {
        self.limits.partition_point(|&l| l <= y)
    }

    /// Whether `p` is inside (crossings of a ray towards +x are odd). A segment only crosses
    /// the ray when `p.y` lies within its heights, so within its bands.
    pub(super) fn contains(&self, p: DVec2) -> bool {
        let mut c = false;
        for &i in &self.bands[self.band(p.y)] {
            let (a, b) = self.segs[i as usize];
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    c = !c;
                }
            }
        }
        c
    }
}

/// Triangles of the CDT inside the domain, as vertex indices: by parity across the
/// constraint edges from the hull (`use_parity`), else by the even-odd test of each
/// triangle's centroid (`uvs`: parameters; the CDT holds them times `scale`; `pos`: their 3D
/// points).
///
/// A sliver (three border points on a straight line in parameters, such as a circle that is
/// an isoline of a cone) has no inside in parameters, and rounding puts its centroid on
/// either side of the border; in 3D it is a whole triangle, across the chord of two border
/// steps. It lies where its 3D centroid is nearer the surface: of the two parameters a
/// quarter of a grid step either side of its centroid (across its longest side), the one
/// whose surface point is nearer is tested. (Tested at the centroid itself, the slivers of
/// generated model gen-45-9's inner cone along its small circle read as inside: triangles
/// over the hole, 1.97 ε off the face at 3e-3 of its radius, and refinement, which cannot
/// insert a point inside them, stopped at its rounds.) `memo` keeps what the centroid tests
/// found, for the next round ([`Memo`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn inside_faces(
    cdt: &Cdt,
    uvs: &[DVec2],
    pos: &[DVec3],
    domain: &Domain<'_>,
    use_parity: bool,
    s: &impl SurfaceEval,
    scale: DVec2,
    memo: &mut Memo<bool>,
) -> Vec<[u32; 3]> {
    let tri_of = |f: spade::handles::FaceHandle<'_, spade::handles::InnerTag, _, _, _, _>| {
        let v = f.vertices();
        [
            v[0].fix().index() as u32,
            v[1].fix().index() as u32,
            v[2].fix().index() as u32,
        ]
    };
    if !use_parity {
        let inside = |t: [u32; 3]| {
            let [a, b, c] = t.map(|i| uvs[i as usize]);
            let centroid = (a + b + c) / 3.0;
            let [qa, qb, qc] = [a, b, c].map(|x| x * scale);
            let sides = [(qa, qb), (qb, qc), (qc, qa)];
            let (p, q) = sides
                .into_iter()
                .max_by(|x, y| {
                    x.0.distance_squared(x.1)
                        .total_cmp(&y.0.distance_squared(y.1))
                })
                .unwrap_or((qa, qb));
            let longest = p.distance_squared(q);
            if (qb - qa).perp_dot(qc - qa).abs() > SLIVER * longest || longest == 0.0 {
                return domain.contains(centroid);
            }
            let across = (q - p).perp().normalize_or_zero() * 0.25 / scale;
            let mid = t.map(|i| pos[i as usize]).iter().sum::<DVec3>() / 3.0;
            let near = |uv: DVec2| s.point(uv).distance(mid);
            let side = match near(centroid + across) <= near(centroid - across) {
                true => centroid + across,
                false => centroid - across,
            };
            domain.contains(side)
        };
        let mut earlier = std::mem::take(memo);
        let mut out = Vec::new();
        for t in cdt.inner_faces().map(tri_of) {
            let key = memo_key(t).0;
            let is_in = earlier.remove(&key).unwrap_or_else(|| inside(t));
            memo.insert(key, is_in);
            if is_in {
                out.push(t);
            }
        }
        return out;
    }
    // Flood fill from the hull: parity flips across every constraint edge.
    let n = cdt.num_all_faces();
    let mut state: Vec<u8> = vec![2; n]; // 0 outside, 1 inside, 2 unknown
    let mut queue = VecDeque::new();
    for e in cdt.convex_hull() {
        // `e` has the outer face on its left; its twin's face is inner.
        let inner = e.rev().face();
        if let Some(f) = inner.as_inner() {
            let idx = f.fix().index();
            if state[idx] == 2 {
                state[idx] = u8::from(e.is_constraint_edge());
                queue.push_back(f.fix());
            }
        }
    }
    while let Some(fh) = queue.pop_front() {
        let f = cdt.face(fh);
        let s0 = state[fh.index()];
        for e in f.adjacent_edges() {
            let other = e.rev().face();
            if let Some(o) = other.as_inner() {
                let idx = o.fix().index();
                if state[idx] == 2 {
                    state[idx] = if e.is_constraint_edge() { 1 - s0 } else { s0 };
                    queue.push_back(o.fix());
                }
            }
        }
    }
    cdt.inner_faces()
        .filter(|f| state[f.fix().index()] == 1)
        .map(tri_of)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The even-odd rule over every segment, as the tessellator had it.
    fn brute(segs: &[(DVec2, DVec2)], p: DVec2) -> bool {
        let mut c = false;
        for &(a, b) in segs {
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                c = !c;
            }
        }
        c
    }

    /// A triangle seen in any rotation has one key, and its per-edge values (memoized in key
    /// order) come back on the same vertex pairs. Seen failing with the inverse rotation
    /// taken the wrong way (`(j + r) % 3`).
    #[test]
    fn memo_keys_and_edge_values_agree_across_rotations() {
        let t = [7u32, 3, 9];
        let rotations = [[7, 3, 9], [3, 9, 7], [9, 7, 3]];
        let edge = |t: [u32; 3], j: usize| (t[j], t[(j + 1) % 3]);
        let key0 = memo_key(t).0;
        assert_eq!(key0, [3, 9, 7]);
        for rot in rotations {
            let (key, r) = memo_key(rot);
            assert_eq!(key, key0, "{rot:?}");
            assert_eq!(
                [0, 1, 2].map(|k| key[k]),
                [0, 1, 2].map(|k| rot[(r + k) % 3])
            );
            // Each edge's value is its own vertex pair: stored from this rotation, read back
            // in another, every edge keeps its pair.
            let by_key = edges_to_key([0, 1, 2].map(|j| edge(rot, j)), r);
            for other in rotations {
                let (_, r2) = memo_key(other);
                let back = edges_from_key(by_key, r2);
                assert_eq!(
                    back,
                    [0, 1, 2].map(|j| edge(other, j)),
                    "{rot:?} → {other:?}"
                );
            }
        }
        // The other orientation is another triangle.
        assert_ne!(memo_key([7, 9, 3]).0, key0);
    }

    #[test]
    fn banded_queries_agree_with_every_segment() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut r = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for case in 0..40 {
            // Closed polylines: wobbly circles, self-crossing stars, and one crowded at a
            // height with a point 10¹⁰ away (the fuzzed face's shape).
            let n = 3 + (r() * 300.0) as usize;
            let mut pts: Vec<DVec2> = (0..n)
                .map(|i| {
                    let t = i as f64 / n as f64 * std::f64::consts::TAU * (1 + case % 3) as f64;
                    DVec2::new(t.cos(), t.sin()) * (1.0 + 0.5 * r())
                })
                .collect();
            if case % 5 == 0 {
                pts[0] = DVec2::new(7e10, 3e9);
            }
            let segs: Vec<(DVec2, DVec2)> = (0..n).map(|i| (pts[i], pts[(i + 1) % n])).collect();
            let domain = Domain::new(&segs);
            for _ in 0..300 {
                let p = DVec2::new(r() * 3.0 - 1.5, r() * 3.0 - 1.5);
                assert_eq!(domain.contains(p), brute(&segs, p), "case {case}, {p}");
            }
            // Queries at the segments' own end heights (band limits).
            for &(a, _) in segs.iter().take(20) {
                let p = DVec2::new(a.x - 0.1, a.y);
                assert_eq!(domain.contains(p), brute(&segs, p), "case {case}, {p}");
            }
        }
        assert!(!Domain::new(&[]).contains(DVec2::ZERO));
    }
}
