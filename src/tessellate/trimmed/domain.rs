//! Point-in-polygon tests against a trimmed face's loops, for the trimmed tessellator
//! ([`super`]): which grid points and which triangles lie inside the domain.

use glam::DVec2;

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
