//! Small geometric kernels shared by the checks and the mesh hierarchy.

use glam::DVec3;

/// Closest point to `p` on the triangle `(a, b, c)` (degenerate triangles included), by the
/// Voronoi-region walk of Ericson, *Real-Time Collision Detection* (2005), §5.1.5.
pub(crate) fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    Prepared::new(a, b, c).closest_point(p)
}

/// A triangle with what [`closest_point_on_triangle`] derives from its corners alone, kept
/// for triangles measured against many points (the same operations in the same order: the
/// results are bit-identical).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Prepared {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    ab: DVec3,
    ac: DVec3,
    /// Whether the corners are on a line (or two are the same).
    flat: bool,
}

impl Prepared {
    pub(crate) fn new(a: DVec3, b: DVec3, c: DVec3) -> Prepared {
        let (ab, ac) = (b - a, c - a);
        Prepared {
            a,
            b,
            c,
            ab,
            ac,
            flat: ab.cross(ac) == DVec3::ZERO,
        }
    }

    /// Distance from `p` to the triangle.
    #[inline]
    pub(crate) fn distance(&self, p: DVec3) -> f64 {
        self.closest_point(p).distance(p)
    }

    /// [`closest_point_on_triangle`].
    #[inline]
    pub(crate) fn closest_point(&self, p: DVec3) -> DVec3 {
        let Prepared {
            a,
            b,
            c,
            ab,
            ac,
            flat,
        } = *self;
        if flat {
            // Two corners the same, or all three on a line: the walk below would divide 0 by 0
            // (a triangle (a, a, c) gave NaN, and a caller's `min` then skipped it: a tube
            // tessellated to slivers along its seam read as 3.2 ε from its own mesh).
            return nearest_edge_point(p, a, b, c);
        }
        let ap = p - a;
        let d1 = ab.dot(ap);
        let d2 = ac.dot(ap);
        if d1 <= 0.0 && d2 <= 0.0 {
            return a;
        }
        let bp = p - b;
        let d3 = ab.dot(bp);
        let d4 = ac.dot(bp);
        if d3 >= 0.0 && d4 <= d3 {
            return b;
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return a + ab * (d1 / (d1 - d3));
        }
        let cp = p - c;
        let d5 = ab.dot(cp);
        let d6 = ac.dot(cp);
        if d6 >= 0.0 && d5 <= d6 {
            return c;
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return a + ac * (d2 / (d2 - d6));
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
        }
        let denom = va + vb + vc;
        if denom.abs() < f64::MIN_POSITIVE {
            // Collinear corners not caught above.
            return nearest_edge_point(p, a, b, c);
        }
        a + ab * (vb / denom) + ac * (vc / denom)
    }
}

/// The nearest point to `p` on the three edges of `(a, b, c)`.
fn nearest_edge_point(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    [(a, b), (b, c), (c, a)]
        .into_iter()
        .map(|(s, e)| closest_point_on_segment(p, s, e))
        .min_by(|x, y| x.distance_squared(p).total_cmp(&y.distance_squared(p)))
        .unwrap_or(a)
}

/// Closest point to `p` on the segment `s..e`.
pub(crate) fn closest_point_on_segment(p: DVec3, s: DVec3, e: DVec3) -> DVec3 {
    let d = e - s;
    let len2 = d.length_squared();
    if len2 <= 0.0 {
        return s;
    }
    s + d * ((p - s).dot(d) / len2).clamp(0.0, 1.0)
}

/// Distance from `p` to the triangle `(a, b, c)`.
pub fn point_triangle_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    closest_point_on_triangle(p, a, b, c).distance(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: the minimum over a fine barycentric sampling.
    fn sampled(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
        let n = 200;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                best = best.min((a + (b - a) * u + (c - a) * v).distance(p));
            }
        }
        best
    }

    #[test]
    fn matches_brute_force_in_every_region() {
        let (a, b, c) = (
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.5),
            DVec3::new(0.3, 1.5, -0.2),
        );
        let mut state = 7u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 6.0 - 3.0
        };
        for _ in 0..300 {
            let p = DVec3::new(rnd(), rnd(), rnd());
            let d = point_triangle_distance(p, a, b, c);
            let s = sampled(p, a, b, c);
            assert!(d <= s + 1e-9 && s - d < 0.02, "p {p}: {d} vs sampled {s}");
        }
    }

    #[test]
    fn degenerate_triangles() {
        let p = DVec3::new(0.5, 1.0, 0.0);
        let (a, b) = (DVec3::ZERO, DVec3::X);
        assert!((point_triangle_distance(p, a, b, b) - 1.0).abs() < 1e-12);
        assert!((point_triangle_distance(p, a, a, a) - p.length()).abs() < 1e-12);
        let mid = DVec3::new(0.5, 0.0, 0.0);
        assert!((point_triangle_distance(p, a, mid, b) - 1.0).abs() < 1e-12);
        // A corner repeated in every position, the point beside, before and beyond the
        // segment: (a, a, b) and (a, b, a) gave NaN.
        for (q, want) in [
            (p, 1.0),
            (DVec3::new(-1.0, 1.0, 0.0), 2f64.sqrt()),
            (DVec3::new(2.0, 0.0, 1.0), 2f64.sqrt()),
        ] {
            for (x, y, z) in [(a, a, b), (a, b, a), (b, a, a), (a, b, b), (b, a, b)] {
                let d = point_triangle_distance(q, x, y, z);
                assert!(
                    (d - want).abs() < 1e-12,
                    "{q} to ({x}, {y}, {z}): {d}, not {want}"
                );
            }
        }
    }
}
