//! Searches for the parameter of a point known to lie on a face (a point of a trim curve, a
//! vertex of a tessellation) beyond the coarse grid of [`SurfaceEval::project`]: a grid fine
//! enough to step on every sheet nearer than what the coarse search found.

use glam::{DVec2, DVec3};

use super::{SurfaceEval, TrimmedFace};

/// Guesses kept from a grid search for the nearest point.
pub(super) const KEEP_GUESSES: usize = 8;
/// Most points of [`TrimmedFace::fine_guesses`]' grid.
const FINE_GRID: usize = 4096;

/// The `keep` parameters of the `(nu + 1) × (nv + 1)` grid over `((u0, u1), (v0, v1))`
/// nearest to `p` (`at`: the surface's point), nearest first.
pub(super) fn nearest_of_grid(
    p: DVec3,
    keep: usize,
    ((u0, u1), (v0, v1)): ((f64, f64), (f64, f64)),
    (nu, nv): (usize, usize),
    at: impl Fn(DVec2) -> DVec3,
) -> Vec<DVec2> {
    let mut best: Vec<(f64, DVec2)> = Vec::with_capacity(keep + 1);
    for i in 0..=nu {
        for j in 0..=nv {
            let uv = DVec2::new(
                u0 + (u1 - u0) * i as f64 / nu as f64,
                v0 + (v1 - v0) * j as f64 / nv as f64,
            );
            let d = at(uv).distance_squared(p);
            if !d.is_finite() || best.len() == keep && d >= best[keep - 1].0 {
                continue;
            }
            let k = best.partition_point(|b| b.0 <= d);
            best.insert(k, (d, uv));
            best.truncate(keep);
        }
    }
    best.into_iter().map(|b| b.1).collect()
}

impl TrimmedFace {
    /// For a point that should lie on the surface whose nearest point found by
    /// [`SurfaceEval::project`] is `off` away: the best few of a grid whose 3D steps are at
    /// most `off / 2` (at most [`FINE_GRID`] points, shared by the two directions in proportion
    /// to the surface's extent along each), best first. A sheet nearer than the coarse grid's
    /// steps — the next turn of a thread's helical face, whose pitch is a third of the coarse
    /// steps along the helix (generated model gen-1-94: every loop point on the wrong turn,
    /// 0.09 off, error 190 ε) — then has a grid point nearer than `off`.
    fn fine_guesses(&self, p: DVec3, off: f64) -> Vec<DVec2> {
        let Some((range, _)) = self.search_range() else {
            return Vec::new();
        };
        let ((u0, u1), (v0, v1)) = range;
        let at = |a: f64, b: f64| self.at(DVec2::new(u0 + (u1 - u0) * a, v0 + (v1 - v0) * b));
        // The longest of 5 isolines per direction, as polylines of 32 segments.
        let extent = |along_u: bool| {
            (0..=4)
                .map(|k| {
                    let c = k as f64 / 4.0;
                    let q = |t: f64| if along_u { at(t, c) } else { at(c, t) };
                    (0..32)
                        .map(|i| q(i as f64 / 32.0).distance(q((i + 1) as f64 / 32.0)))
                        .sum::<f64>()
                })
                .fold(0.0, f64::max)
        };
        let (lu, lv) = (extent(true), extent(false));
        if !(lu.is_finite() && lv.is_finite() && off > 0.0) {
            return Vec::new();
        }
        let h = (0.5 * off).max((lu * lv / FINE_GRID as f64).sqrt());
        let steps = |l: f64| ((l / h).ceil() as usize).clamp(1, FINE_GRID);
        let (nu, nv) = (steps(lu), steps(lv));
        let (nu, nv) = (nu.min(FINE_GRID / nv).max(1), nv.min(FINE_GRID / nu).max(1));
        nearest_of_grid(p, KEEP_GUESSES, range, (nu, nv), |uv| self.at(uv))
    }

    /// As [`SurfaceEval::project`] for a point that should lie on the surface (a point of a
    /// trim curve, a vertex of a tessellation): when the nearest point found is farther than
    /// `tol`, the range is searched again on a grid fine enough to step on every sheet nearer
    /// than that (`TrimmedFace::fine_guesses`), and the nearer result kept. Returns the
    /// parameter and whether the fine search ran.
    pub(crate) fn project_on(
        &self,
        p: DVec3,
        hint: Option<DVec2>,
        tol: f64,
    ) -> (Option<DVec2>, bool) {
        let first = self.project(p, hint);
        let off = |uv: &DVec2| self.point(*uv).distance(p);
        let d = first.as_ref().map_or(f64::INFINITY, off);
        if d <= tol || !d.is_finite() {
            return (first, false);
        }
        let better = self
            .fine_guesses(p, d)
            .into_iter()
            .filter_map(|g| self.newton(p, g))
            .map(|uv| self.canonical(uv))
            .min_by(|a, b| off(a).total_cmp(&off(b)))
            .filter(|uv| off(uv) < d);
        (better.or(first), true)
    }

    /// The parameter of a point of a loop walked along its curve: from `hint` (the previous
    /// point's), again without a hint when that lands farther than `far` (a pole or a seam can
    /// mislead the local search), and on a fine grid ([`TrimmedFace::project_on`]) while
    /// `fine_left`: the first fine search that still ends farther than `far` (an edge off its
    /// surface) clears it, so such a loop pays for one.
    pub(crate) fn project_along(
        &self,
        p: DVec3,
        hint: Option<DVec2>,
        far: f64,
        fine_left: &mut bool,
    ) -> Option<DVec2> {
        let off = |uv: DVec2| self.point(uv).distance(p);
        let uv = self.project(p, hint);
        if uv.is_some_and(|uv| off(uv) <= far) {
            return uv;
        }
        let g = if *fine_left {
            let (g, fine) = self.project_on(p, None, far);
            if fine && g.is_none_or(|g| off(g) > far) {
                *fine_left = false;
            }
            g
        } else {
            self.project(p, None)
        };
        match (uv, g) {
            (Some(a), Some(b)) if off(a) <= off(b) => Some(a),
            (a, b) => b.or(a),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::*;
    use truck_stepio::r#in::alias::re_exports::{BSplineSurface, KnotVec, Point3};

    /// A thread's flank: a ruled strip from radius 0.26 to 0.33 winding 4 turns up a pitch of
    /// 0.1 (degree 1 × 3, 8 control points a turn), as OCCT writes a swept V-thread.
    fn thread_flank() -> TrimmedFace {
        let per_turn = 8;
        let n = 4 * per_turn + 1;
        let row = |r: f64, dz: f64| -> Vec<Point3> {
            (0..n)
                .map(|k| {
                    let a = std::f64::consts::TAU * k as f64 / per_turn as f64;
                    Point3::new(
                        r * a.cos(),
                        r * a.sin(),
                        0.1 * k as f64 / per_turn as f64 + dz,
                    )
                })
                .collect()
        };
        let mut kv = vec![0.0; 4];
        kv.extend((1..n - 3).map(|k| k as f64));
        kv.extend(vec![(n - 3) as f64; 4]);
        let surface = TruckSurface::BSplineSurface(Box::new(BSplineSurface::new(
            (KnotVec::bezier_knot(1), KnotVec::from(kv)),
            vec![row(0.26, 0.0), row(0.33, 0.04)],
        )));
        TrimmedFace {
            id: 1,
            fast: TrimmedFace::fast_surface(&surface),
            closed: (None, None),
            surface,
            loops: Vec::new(),
            domain_left: true,
            bounds: Sphere {
                center: DVec3::new(0.0, 0.0, 0.2),
                radius: 0.45,
            },
            loop_starts: Vec::new(),
        }
    }

    /// Points of the flank found from no hint: the coarse grid (24 steps along 4 turns, 0.3
    /// apart, three times the pitch) ends some of them on the next turn, 0.1 off; the fine
    /// search of `project_on` finds every one on its own turn.
    #[test]
    fn points_of_a_thread_project_onto_their_own_turn() {
        let face = thread_flank();
        let (mut coarse_wrong, mut fine_wrong) = (0, 0);
        for k in 0..60 {
            let uv = DVec2::new((k % 5) as f64 / 4.0, 0.45 * k as f64 + 0.1);
            let p = face.point(uv);
            let off = |uv: Option<DVec2>| uv.map_or(f64::INFINITY, |uv| face.point(uv).distance(p));
            if off(face.project(p, None)) > 1e-6 {
                coarse_wrong += 1;
            }
            let (fine, _) = face.project_on(p, None, 1e-6);
            if off(fine) > 1e-6 {
                fine_wrong += 1;
            }
        }
        assert_eq!(fine_wrong, 0, "points the fine search left on another turn");
        assert!(
            coarse_wrong > 0,
            "the coarse search alone never failed: no test of the fine one"
        );
    }
}
