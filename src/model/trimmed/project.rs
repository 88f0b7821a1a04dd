//! Searches for the parameter of a point known to lie on a face (a point of a trim curve, a
//! vertex of a tessellation) beyond the coarse grid of [`SurfaceEval::project`]: a grid fine
//! enough to step on every sheet nearer than what the coarse search found. And that coarse
//! grid kept ([`CoarseGrid`]): its points depend on the face alone, so a caller projecting
//! many points from scratch (`check::fidelity`) evaluates them once, not per point.

use glam::{DVec2, DVec3};

use super::{SurfaceEval, TrimmedFace};

/// Guesses kept from a grid search for the nearest point.
pub(super) const KEEP_GUESSES: usize = 8;
/// Most points of [`TrimmedFace::fine_guesses`]' grid.
const FINE_GRID: usize = 4096;

/// The parameters of the `(nu + 1) × (nv + 1)` grid over `((u0, u1), (v0, v1))`, u outer.
fn grid_parameters(
    ((u0, u1), (v0, v1)): ((f64, f64), (f64, f64)),
    (nu, nv): (usize, usize),
) -> impl Iterator<Item = DVec2> {
    (0..=nu).flat_map(move |i| {
        (0..=nv).map(move |j| {
            DVec2::new(
                u0 + (u1 - u0) * i as f64 / nu as f64,
                v0 + (v1 - v0) * j as f64 / nv as f64,
            )
        })
    })
}

/// The `keep` parameters of `points` (parameter, surface point) nearest to `p`, nearest first
/// (of equally near ones the first).
fn nearest_of(p: DVec3, keep: usize, points: impl Iterator<Item = (DVec2, DVec3)>) -> Vec<DVec2> {
    let mut best: Vec<(f64, DVec2)> = Vec::with_capacity(keep + 1);
    for (uv, q) in points {
        let d = q.distance_squared(p);
        if !d.is_finite() || best.len() == keep && d >= best[keep - 1].0 {
            continue;
        }
        let k = best.partition_point(|b| b.0 <= d);
        best.insert(k, (d, uv));
        best.truncate(keep);
    }
    best.into_iter().map(|b| b.1).collect()
}

/// The `keep` parameters of the `(nu + 1) × (nv + 1)` grid over `((u0, u1), (v0, v1))`
/// nearest to `p` (`at`: the surface's point), nearest first.
pub(super) fn nearest_of_grid(
    p: DVec3,
    keep: usize,
    range: ((f64, f64), (f64, f64)),
    steps: (usize, usize),
    at: impl Fn(DVec2) -> DVec3,
) -> Vec<DVec2> {
    nearest_of(
        p,
        keep,
        grid_parameters(range, steps).map(|uv| (uv, at(uv))),
    )
}

/// The grid of a face's coarse search ([`SurfaceEval::project`] without a hint), its surface
/// points evaluated once ([`TrimmedFace::coarse_grid`]). A search through it
/// ([`TrimmedFace::project_in`]) finds the very guesses the face's own search finds: the same
/// points in the same order.
#[derive(Clone, Debug, Default)]
pub(crate) struct CoarseGrid {
    points: Vec<(DVec2, DVec3)>,
}

impl CoarseGrid {
    /// The guesses for `p`, nearest first.
    pub(super) fn nearest(&self, p: DVec3) -> Vec<DVec2> {
        nearest_of(p, KEEP_GUESSES, self.points.iter().copied())
    }
}

/// What a walk along a face's loops ([`TrimmedFace::project_along`]) carries from one point to
/// the next: whether it may still pay for a fine search, and the face's coarse grid, evaluated
/// at the first search that needs it (none without a hint, or a hinted one that landed far).
/// A hinted search that lands near needs no grid; a fuzzed face whose edge lies 10¹⁴ off it
/// (`tests/data/fuzz/trimmed/edge_far_off_cone`) searched without a hint at each of its points,
/// and evaluated the grid anew each time (40 % of its load). Plain fields, no cell: the walk
/// owns it (`model` holds no interior mutability: `tests/architecture.rs`).
pub(crate) struct LoopSearch {
    /// Whether a fine search may still run (see [`TrimmedFace::project_along`]).
    pub(crate) fine_left: bool,
    grid: Option<CoarseGrid>,
}

impl LoopSearch {
    pub(crate) fn new() -> Self {
        LoopSearch {
            fine_left: true,
            grid: None,
        }
    }
}

impl TrimmedFace {
    /// As [`SurfaceEval::project`], the coarse search (without a hint) through `grid` when
    /// given: the face's own [`TrimmedFace::coarse_grid`], whose points are this search's
    /// (the same result, without evaluating them again).
    pub(crate) fn project_in(
        &self,
        p: DVec3,
        hint: Option<DVec2>,
        grid: Option<&CoarseGrid>,
    ) -> Option<DVec2> {
        let guesses = match (hint, grid) {
            (Some(h), _) => vec![h],
            (None, Some(g)) => g.nearest(p),
            (None, None) => self.coarse_guesses(p),
        };
        let start = guesses.first().map(|h| self.wrap(*h));
        // Truck's own search evaluates truck's surface, which is not this face's where we
        // evaluate it ourselves (an offset; B-splines as before): Gauss–Newton from the
        // guesses alone then. An analytic surface is truck's, evaluated in closed form.
        let truck = match self.fast.as_deref() {
            Some(f) if !f.is_truck_surface() => None,
            _ => self
                .surface
                .project(p, start)
                .map(|uv| self.wrap(uv))
                .and_then(|uv| self.newton(p, uv)),
        };
        let off = |uv: &DVec2| self.point(*uv).distance(p);
        let mut found: Vec<DVec2> = truck
            .into_iter()
            .chain(guesses.iter().filter_map(|g| self.newton(p, *g)))
            .map(|uv| self.canonical(uv))
            .collect();
        let mut best = found
            .iter()
            .copied()
            .min_by(|a, b| off(a).total_cmp(&off(b)))?;
        if let Some(pole) = self.stalled_at_pole(best, p) {
            let starts: Vec<DVec2> = self.around_pole(best, pole).collect();
            found.extend(
                starts
                    .into_iter()
                    .filter_map(|g| self.newton(p, g))
                    .map(|uv| self.canonical(uv)),
            );
            best = found
                .iter()
                .copied()
                .min_by(|a, b| off(a).total_cmp(&off(b)))?;
        }
        let Some(h) = hint else {
            return Some(best);
        };
        // Where the surface covers itself twice (past a sphere's pole), several parameters
        // are equally near: the one nearest the hint keeps a polyline on one sheet.
        let tie = off(&best) + 1e-9 * self.bounds.radius.max(1e-300);
        let (pu, pv) = self.periods();
        let from_hint = |uv: &DVec2| {
            let d = *uv - h;
            let w = |x: f64, p: Option<f64>| match p {
                Some(p) if p > 0.0 => x - (x / p).round() * p,
                _ => x,
            };
            DVec2::new(w(d.x, pu), w(d.y, pv)).length_squared()
        };
        found
            .into_iter()
            .filter(|uv| off(uv) <= tie)
            .min_by(|a, b| from_hint(a).total_cmp(&from_hint(b)))
    }

    /// The grid of this face's coarse search with its surface points (empty where the search
    /// has no range): see [`CoarseGrid`].
    pub(crate) fn coarse_grid(&self) -> CoarseGrid {
        let points = match self.coarse_steps() {
            Some((range, steps)) => grid_parameters(range, steps)
                .map(|uv| (uv, self.at(uv)))
                .collect(),
            None => Vec::new(),
        };
        CoarseGrid { points }
    }

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
    /// parameter and whether the fine search ran. The coarse search goes through `grid` when
    /// given (the face's own [`TrimmedFace::coarse_grid`]: the same result).
    pub(crate) fn project_on(
        &self,
        p: DVec3,
        hint: Option<DVec2>,
        tol: f64,
        grid: Option<&CoarseGrid>,
    ) -> (Option<DVec2>, bool) {
        let first = self.project_in(p, hint, grid);
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
    /// `search` carries `fine_left` and the face's coarse grid from one point to the next.
    pub(crate) fn project_along(
        &self,
        p: DVec3,
        hint: Option<DVec2>,
        far: f64,
        search: &mut LoopSearch,
    ) -> Option<DVec2> {
        fn grid<'g>(g: &'g mut Option<CoarseGrid>, face: &TrimmedFace) -> &'g CoarseGrid {
            g.get_or_insert_with(|| face.coarse_grid())
        }
        // A hinted search needs no grid (`project_in` starts from the hint alone); its result,
        // when near, is the whole answer, and no grid is evaluated.
        let uv = match hint {
            Some(_) => self.project_in(p, hint, None),
            None => self.project_in(p, None, Some(grid(&mut search.grid, self))),
        };
        if uv.is_some_and(|uv| self.point(uv).distance(p) <= far) {
            return uv;
        }
        let g = grid(&mut search.grid, self);
        self.project_along_from(p, uv, far, &mut search.fine_left, Some(g))
    }

    /// As [`TrimmedFace::project_along`], coarse searches through `grid` when given (the
    /// face's own [`TrimmedFace::coarse_grid`]: the same result).
    pub(crate) fn project_along_in(
        &self,
        p: DVec3,
        hint: Option<DVec2>,
        far: f64,
        fine_left: &mut bool,
        grid: Option<&CoarseGrid>,
    ) -> Option<DVec2> {
        let uv = self.project_in(p, hint, grid);
        self.project_along_from(p, uv, far, fine_left, grid)
    }

    /// The rest of [`TrimmedFace::project_along_in`] once its first search found `uv`: that,
    /// when it lies within `far`, else the searches without a hint.
    fn project_along_from(
        &self,
        p: DVec3,
        uv: Option<DVec2>,
        far: f64,
        fine_left: &mut bool,
        grid: Option<&CoarseGrid>,
    ) -> Option<DVec2> {
        let off = |uv: DVec2| self.point(uv).distance(p);
        if uv.is_some_and(|uv| off(uv) <= far) {
            return uv;
        }
        let g = if *fine_left {
            let (g, fine) = self.project_on(p, None, far, grid);
            if fine && g.is_none_or(|g| off(g) > far) {
                *fine_left = false;
            }
            g
        } else {
            self.project_in(p, None, grid)
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
            bounds: Sphere {
                center: DVec3::new(0.0, 0.0, 0.2),
                radius: 0.45,
            },
            ..face_on(surface)
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
            let (fine, _) = face.project_on(p, None, 1e-6, None);
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

    /// A face on `surface` with bounds around the origin (no loops: the searches need none).
    fn face_on(surface: TruckSurface) -> TrimmedFace {
        TrimmedFace {
            id: 2,
            fast: TrimmedFace::fast_surface(&surface),
            closed: (None, None),
            surface,
            loops: Vec::new(),
            domain_left: true,
            bounds: Sphere {
                center: DVec3::ZERO,
                radius: 2.0,
            },
            loop_starts: Vec::new(),
        }
    }

    /// Searches from scratch through a face's kept coarse grid find the very parameters its
    /// own search finds (bit for bit): on the thread flank (a B-spline), a cone (widened grid
    /// across its axis) and a torus, for points on, near and far from the surface.
    #[test]
    fn a_search_through_the_kept_grid_is_the_face_s_own_search() {
        use truck_stepio::r#in::alias::ElementarySurface;
        use truck_stepio::r#in::alias::re_exports::{
            Invertible, Line, Processor, RevolutedCurve, Torus, Vector3,
        };
        let mut cone = Processor::new(RevolutedCurve::by_revolution(
            Line(Point3::new(0.4, 0.0, 0.0), Point3::new(0.9, 0.0, 1.0)),
            Point3::new(0.0, 0.0, 0.0),
            Vector3::unit_z(),
        ));
        cone.invert();
        let torus = Processor::new(Torus::new(Point3::new(0.1, 0.0, 0.0), 1.0, 0.3));
        let elementary = |e| TruckSurface::ElementarySurface(Box::new(e));
        let faces = [
            thread_flank(),
            face_on(elementary(ElementarySurface::ConicalSurface(cone))),
            face_on(elementary(ElementarySurface::ToroidalSurface(torus))),
        ];
        let mut compared = 0;
        for face in &faces {
            let grid = face.coarse_grid();
            assert!(!grid.points.is_empty(), "face {}: no grid", face.id);
            for k in 0..40 {
                let uv = DVec2::new(0.37 * k as f64, 0.23 * k as f64 - 1.0);
                let off = DVec3::new(0.01 * k as f64, -0.02, 0.015 * (k % 7) as f64);
                let p = face.point(uv) + off;
                assert_eq!(
                    face.project_in(p, None, Some(&grid)),
                    face.project(p, None),
                    "face {} at {p}",
                    face.id
                );
                assert_eq!(
                    face.project_on(p, None, 1e-9, Some(&grid)),
                    face.project_on(p, None, 1e-9, None),
                    "face {} at {p}: project_on",
                    face.id
                );
                compared += 1;
            }
        }
        assert_eq!(compared, 120);
    }
}
