//! Trimmed surfaces: a parametric surface (B-spline, NURBS, plane, cylinder, cone, sphere,
//! torus, swept curve — read by truck, evaluated by `model::nurbs` and `model::analytic` where
//! they take it) cut out by closed loops of 3D edge curves, as a
//! STEP `ADVANCED_FACE` defines it. The loops are kept as 3D curves; their parameter-space image
//! is computed by the tessellator for each tolerance (`tessellate::trimmed`).

use std::sync::Arc;

use glam::{DVec2, DVec3};
use truck_stepio::r#in::alias::re_exports::{
    ParametricCurve, ParametricSurface, Point3, SPHint2D, SearchNearestParameter, Vector3,
};
pub use truck_stepio::r#in::alias::{Curve3D, Surface as TruckSurface};

use super::Sphere;
use super::nurbs::{FastSurface, NurbsSurface};

mod project;
pub(crate) use project::{CoarseGrid, LoopSearch};
use project::{KEEP_GUESSES, nearest_of_grid};

pub(crate) fn to_dvec(p: Point3) -> DVec3 {
    DVec3::new(p.x, p.y, p.z)
}

pub(crate) fn vec_to_dvec(v: Vector3) -> DVec3 {
    DVec3::new(v.x, v.y, v.z)
}

pub(crate) fn to_point(p: DVec3) -> Point3 {
    Point3::new(p.x, p.y, p.z)
}

/// One edge of a face boundary: a 3D curve between two vertices, run from `t0` to `t1`
/// (`t0 > t1` when the curve runs against the edge).
#[derive(Clone, Debug)]
pub struct TrimEdge {
    /// STEP entity id of the `EDGE_CURVE`.
    pub id: u64,
    pub curve: Curve3D,
    pub t0: f64,
    pub t1: f64,
    /// The edge's vertices (exact end points of its polyline).
    pub start: DVec3,
    pub end: DVec3,
    /// `(a, length)` when the edge runs across the end of a closed, non-periodic curve's range
    /// `[a, a + length]` (a B-spline circle whose seam lies inside the edge): `t1` is then
    /// past the range and [`TrimEdge::point`] wraps the parameter back into it.
    pub wrap: Option<(f64, f64)>,
}

impl TrimEdge {
    /// Builds an edge from a curve and its end vertices, finding the parameter range that runs
    /// from `start` to `end`. `closed`: the edge starts and ends at one vertex, so on a
    /// periodic curve it runs once around. `None` when the vertices are not on the curve
    /// (within `tol`) or the curve is not finite there.
    pub fn new(
        id: u64,
        curve: Curve3D,
        start: DVec3,
        end: DVec3,
        closed: bool,
        tol: f64,
    ) -> Option<TrimEdge> {
        // truck evaluates an unclamped B-spline wrongly at the end of its range.
        let curve = super::knots::clamp_curve(&curve).unwrap_or(curve);
        let range = curve_range(&curve).filter(|(a, b)| a.is_finite() && b.is_finite());
        // Where both ends of the range are one point (a whole circle), an open edge is
        // located, never taken for the whole range (a tiny arc at the seam is not a whole
        // circle); a trimmed range's ends are the edge's as before. A range that is itself
        // shorter than the tolerance (truck trims a circle to its edge's vertices: a 0.19°
        // arc at a torus's seam, generated model 2-47) is the edge: located, its vertices
        // fell on either side of the circle's seam and the edge ran the long way round.
        let range_ends = range.map(|(a, b)| (a, b, to_dvec(curve.subs(a)), to_dvec(curve.subs(b))));
        let ends = range_ends.filter(|&(a, b, pa, pb)| {
            closed
                || pa.distance(pb) > tol
                || to_dvec(curve.subs(0.5 * (a + b))).distance(pa) <= tol
        });
        let mut wrap = None;
        let (t0, t1) = match ends {
            Some((a, b, pa, pb)) if pa.distance(start) <= tol && pb.distance(end) <= tol => (a, b),
            Some((a, b, pa, pb)) if pb.distance(start) <= tol && pa.distance(end) <= tol => (b, a),
            _ => {
                // The curve is longer than the edge (or unbounded, a line): locate the
                // vertices on it.
                let s = locate(&curve, start, range, tol)?;
                let e = locate(&curve, end, range, tol)?;
                // A closed curve that truck does not know as periodic (a B-spline circle): the
                // curve runs from the edge's start to its end (truck inverts it for an edge
                // against its sense), so an edge whose end comes before its start crosses the
                // range's end and continues from its beginning (a cut spring's short arc over
                // the seam was drawn as the long way round).
                let seam = range_ends
                    .filter(|&(a, b, pa, pb)| !closed && b > a && pa.distance(pb) <= tol)
                    .map(|(a, b, _, _)| (a, b));
                match (curve.period(), seam) {
                    // A closed edge on a periodic curve runs once around; an open one whose
                    // vertices are located at one parameter (a tiny edge, its vertices closer
                    // than the search resolves) is that short chord, not a whole period.
                    (Some(p), _) if closed && (s - e).abs() < 1e-12 => (s, s + p),
                    (None, Some((a, b))) if e < s => {
                        // The end vertex at the range's start is the range's end.
                        let l = b - a;
                        let e = if (e - a).abs() <= 1e-12 * l.max(1.0) {
                            b
                        } else {
                            e + l
                        };
                        wrap = (e > b).then_some((a, l));
                        (s, e)
                    }
                    _ => (s, e),
                }
            }
        };
        let mid = to_dvec(curve.subs(0.5 * (t0 + t1)));
        if !(mid.is_finite() && start.is_finite() && end.is_finite()) {
            return None;
        }
        Some(TrimEdge {
            id,
            curve,
            t0,
            t1,
            start,
            end,
            wrap,
        })
    }

    /// Point at curve parameter `t`.
    pub fn point(&self, t: f64) -> DVec3 {
        let t = match self.wrap {
            Some((a, l)) if t > a + l => a + (t - a).rem_euclid(l),
            _ => t,
        };
        to_dvec(self.curve.subs(t))
    }

    /// Whether the edge starts and ends at the same point.
    pub(crate) fn is_closed(&self) -> bool {
        self.start == self.end
    }
}

/// The parameter range a curve is defined on. A B-spline's is `[u_p, u_{n}]` (degree p, n
/// control points), not its whole knot vector: an unclamped knot vector (OCCT writes closed
/// curves with knots such as (1, 3, 2, …, 3, 1) over −0.145..1.119) has partial spans at both
/// ends where the basis functions do not sum to one.
fn curve_range(curve: &Curve3D) -> Option<(f64, f64)> {
    match curve {
        Curve3D::BSplineCurve(c) => clamped_range(c.knot_vec(), c.degree()),
        Curve3D::NurbsCurve(c) => clamped_range(c.knot_vec(), c.degree()),
        _ => curve.try_range_tuple(),
    }
}

/// `[u_p, u_{len-1-p}]` of a knot vector of degree `p`.
fn clamped_range(knots: &[f64], degree: usize) -> Option<(f64, f64)> {
    (knots.len() > 2 * degree + 1).then(|| (knots[degree], knots[knots.len() - 1 - degree]))
}

/// Parameter of `p` on `curve` (within `tol`): truck's search, else Newton from the tangent
/// estimate at the start of the range (or at 0 for an unbounded curve such as a line).
fn locate(curve: &Curve3D, p: DVec3, range: Option<(f64, f64)>, tol: f64) -> Option<f64> {
    // Inside the curve's range: a B-spline evaluated past its last knot goes on along its
    // last piece, and on a closed one (a B-spline circle) that passes the points just past
    // its seam again. Generated model gen-16-27's chamfer edge from the seam to 0.041 rad
    // past it was located at 36.197 on a range ending at 35.959, and ran a whole turn round.
    let inside = |t: f64| {
        range.is_none_or(|(a, b)| {
            let margin = 1e-9 * (b - a).abs().max(1.0);
            t >= a.min(b) - margin && t <= a.max(b) + margin
        })
    };
    let on = |t: f64| t.is_finite() && inside(t) && to_dvec(curve.subs(t)).distance(p) <= tol;
    // truck's search on a hyperbola or a parabola may never return (its root finder's Newton
    // step has no limit): their parameter in closed form, refined.
    if let Some(t) = conic_parameter(curve, p) {
        let t = newton_nearest(curve, p, t);
        return on(t).then_some(t);
    }
    if let Some(t) = curve.search_nearest_parameter(to_point(p), None, 30)
        && on(t)
    {
        return Some(t);
    }
    let t0 = range.map_or(0.0, |r| r.0);
    let d = vec_to_dvec(curve.der(t0));
    let t = t0 + (p - to_dvec(curve.subs(t0))).dot(d) / d.length_squared().max(1e-300);
    let t = newton_nearest(curve, p, t);
    if on(t) {
        return Some(t);
    }
    // A curve with a nearest point per turn (a thread's helix of 8 turns and more: both
    // searches above ended on another turn, and the edges of generated models gen-8-27 and
    // gen-10-10 were skipped): Newton from the nearest of dense samples.
    let (a, b) = range?;
    let t = newton_nearest(curve, p, nearest_sample(curve, p, a, b, LOCATE_SAMPLES)?);
    on(t).then_some(t)
}

/// Samples of a curve's range [`locate`] falls back on: 16 per turn of a 64-turn helix.
const LOCATE_SAMPLES: usize = 1024;

/// The parameter of the sample of `curve` nearest `p` among `n + 1` equally spaced over
/// `a..b`, `None` when none is finite.
fn nearest_sample(curve: &Curve3D, p: DVec3, a: f64, b: f64, n: usize) -> Option<f64> {
    let dist = |t: f64| to_dvec(curve.subs(t)).distance_squared(p);
    (0..=n)
        .map(|i| a + (b - a) * i as f64 / n as f64)
        .filter(|&t| dist(t).is_finite())
        .min_by(|&s, &t| dist(s).total_cmp(&dist(t)))
}

/// The parameter of the point of a hyperbola (`cosh t, sinh t` placed) or a parabola
/// (`t², 2t` placed) with the same ordinate as `p` in the conic's own frame: `p`'s parameter
/// when it lies on the curve. `None` for other curves.
pub(crate) fn conic_parameter(curve: &Curve3D, p: DVec3) -> Option<f64> {
    use truck_stepio::r#in::alias::Conic3D;
    use truck_stepio::r#in::alias::re_exports::{BoundedCurve, SquareMatrix, Transform};
    let (local, orientation, (t0, t1)) = match curve {
        Curve3D::Conic(Conic3D::Hyperbola(h)) => {
            let inv = h.transform().invert()?;
            let l = inv.transform_point(to_point(p));
            (l.y.asinh(), h.orientation(), h.entity().range_tuple())
        }
        Curve3D::Conic(Conic3D::Parabola(c)) => {
            let inv = c.transform().invert()?;
            let l = inv.transform_point(to_point(p));
            (0.5 * l.y, c.orientation(), c.entity().range_tuple())
        }
        _ => return None,
    };
    let t = if orientation { local } else { t0 + t1 - local };
    t.is_finite().then_some(t)
}

/// Newton's iteration for the parameter of the point of `curve` nearest `p`, from `t`.
fn newton_nearest(curve: &Curve3D, p: DVec3, mut t: f64) -> f64 {
    for _ in 0..30 {
        let r = to_dvec(curve.subs(t)) - p;
        let d1 = vec_to_dvec(curve.der(t));
        let d2 = vec_to_dvec(curve.der2(t));
        let den = d1.length_squared() + r.dot(d2);
        if den.is_nan() || den.abs() <= 1e-300 {
            break;
        }
        let step = r.dot(d1) / den;
        t -= step;
        if !t.is_finite() || step.abs() <= 1e-14 * (1.0 + t.abs()) {
            break;
        }
    }
    t
}

/// The point of `curve` nearest `p`, as a kernel projects a vertex onto its edge's curve to
/// heal an edge whose vertex lies off it: the nearest of 1 025 samples over the curve's range
/// (one period of a periodic curve), refined by Newton inside the range; on an unbounded
/// curve (a line), Newton from the start. `None` when it is not finite.
pub(crate) fn nearest_on_curve(curve: &Curve3D, p: DVec3) -> Option<DVec3> {
    let curve = super::knots::clamp_curve(curve).unwrap_or_else(|| curve.clone());
    let range = curve_range(&curve)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .or_else(|| curve.period().map(|l| (0.0, l)));
    let dist = |t: f64| to_dvec(curve.subs(t)).distance_squared(p);
    let t = match range {
        Some((a, b)) => {
            let best = nearest_sample(&curve, p, a, b, LOCATE_SAMPLES)?;
            let t = newton_nearest(&curve, p, best);
            let inside = curve.period().is_some() || (a.min(b)..=a.max(b)).contains(&t);
            if inside && dist(t) <= dist(best) {
                t
            } else {
                best
            }
        }
        None => locate(&curve, p, None, f64::INFINITY)?,
    };
    let q = to_dvec(curve.subs(t));
    q.is_finite().then_some(q)
}

/// An edge of a loop, with the direction the loop runs it.
#[derive(Clone, Debug)]
pub struct LoopEdge {
    pub edge: Arc<TrimEdge>,
    pub forward: bool,
    /// What the edge is between this face and the next (`model::edges`): sharp as read,
    /// classified when the scene is prepared (`prep::step`).
    pub kind: super::edges::EdgeKind,
}

/// Points along boundary loops that bound them: every edge's ends and parameter midpoint
/// (what a reader's first [`TrimmedFace::bounds`] is made from).
pub(crate) fn loop_points(loops: &[Vec<LoopEdge>]) -> Vec<DVec3> {
    loops
        .iter()
        .flatten()
        .flat_map(|le| {
            [
                le.edge.start,
                le.edge.end,
                le.edge.point(0.5 * (le.edge.t0 + le.edge.t1)),
            ]
        })
        .collect()
}

/// Relative gap (of the surface's size) within which [`TrimmedFace::closed_directions`] takes
/// a surface as closing on itself. OCCT closes a B-spline band only to its modelling
/// tolerance: generated model gen-12-57's band (a cone cut by a sphere, offset) closes in v
/// to 1.1e-7 of a size of 2.8, 4e-8 of it, with its seam edge used twice by the face's
/// loop. At 1e-9 the band was not taken as closed: its loop ran along the seam at v = 0
/// twice, the domain was the square doubled on itself, and the face was drawn 14.9 ε off
/// its surface (6.9 T by Open CASCADE's judge).
pub(crate) const CLOSED_TOL: f64 = 1e-6;

/// A face: a surface and its boundary loops (outer and holes, in any order; the domain is
/// what an even-odd rule over all loops encloses in parameter space).
#[derive(Clone, Debug)]
pub struct TrimmedFace {
    /// STEP entity id of the face.
    pub id: u64,
    pub surface: TruckSurface,
    /// Loops of edges, each running head to tail.
    pub loops: Vec<Vec<LoopEdge>>,
    /// Whether the face lies to the left of its loops in the surface's parameter space (the
    /// STEP convention when the face's sense agrees with the surface's). Only needed for a
    /// loop that runs once around a periodic surface and is closed by a pole or the parameter
    /// range (a sphere cap, a cone up to its apex).
    pub domain_left: bool,
    /// Bounds in the face's own coordinates (before any assembly placement).
    pub bounds: Sphere,
    /// Directions in which the surface closes on itself without being periodic (a revolved
    /// NURBS: S(u_min, v) = S(u_max, v)): `(start, period)`. The tessellator unwraps border
    /// parameters across that seam as for a periodic surface, and evaluation wraps back.
    pub closed: (Interval, Interval),
    /// The surface as we evaluate it ourselves (`model::nurbs`: B-splines without truck's
    /// allocations, offsets of B-splines truck has no type for), when it is one; every
    /// evaluation of the face goes through it. Made from `surface` by
    /// `TrimmedFace::fast_surface`; replace both together.
    pub fast: Option<Arc<FastSurface>>,
    /// Per loop, its first point and that point's parameter as a tessellation of the face
    /// found it (`prep::step`'s probe, [`crate::tessellate::TrimmedTessellator::loop_starts`]):
    /// the first point is an exact vertex, the same at every ε, so later tessellations start
    /// there instead of searching the whole surface for it (that grid search was 58 % of a
    /// small face's tessellation time, Molex SlimStack at 1e-4). Used only where the loop's
    /// first point is still that point and the parameter still lands on it; empty: not known.
    pub loop_starts: Vec<Option<(DVec3, DVec2)>>,
}

impl TrimmedFace {
    /// The surface's kind, as the OCCT comparison names it (`benches/occt_faces.rs`,
    /// `benches/occt_mesh.py --by-kind`): plane, sphere, cylinder, torus, cone, swept or
    /// bspline.
    pub fn kind(&self) -> &'static str {
        match surface_kind(&self.surface) {
            "b-spline" | "nurbs" => "bspline",
            k => k,
        }
    }

    /// Our evaluation of `surface` when it is a B-spline or an analytic surface we take (see
    /// [`TrimmedFace::fast`]).
    pub(crate) fn fast_surface(surface: &TruckSurface) -> Option<Arc<FastSurface>> {
        NurbsSurface::of(surface)
            .map(FastSurface::Nurbs)
            .or_else(|| super::analytic::Analytic::of(surface).map(FastSurface::Analytic))
            .map(Arc::new)
    }

    /// The surface's point at `uv` (no seam wrapping).
    fn at(&self, uv: DVec2) -> DVec3 {
        match &self.fast {
            Some(f) => f.point(uv),
            None => self.surface.point(uv),
        }
    }

    fn at_derivs(&self, uv: DVec2) -> (DVec3, DVec3) {
        match &self.fast {
            Some(f) => f.derivs(uv),
            None => self.surface.derivs(uv),
        }
    }

    /// Detects directions in which `surface` closes on itself (see [`TrimmedFace::closed`]),
    /// to relative tolerance `tol` of its size.
    pub(crate) fn closed_directions(surface: &TruckSurface, tol: f64) -> (Interval, Interval) {
        let (ru, rv) = parameter_bounds(surface);
        let (pu, pv) = (surface.u_period(), surface.v_period());
        let (Some((u0, u1)), Some((v0, v1))) = (ru, rv) else {
            return (None, None);
        };
        let at = |u: f64, v: f64| to_dvec(surface.subs(u, v));
        let size = at(u0, v0)
            .distance(at(u1, v1))
            .max(at(u0, v1).distance(at(u1, v0)));
        let size = size.max(at(0.5 * (u0 + u1), 0.5 * (v0 + v1)).distance(at(u0, v0)));
        let eps = tol * size.max(1e-12);
        let closes = |f: &dyn Fn(f64) -> f64| (0..=6).all(|k| f(k as f64 / 6.0) <= eps);
        let cu = (pu.is_none()
            && u1 > u0
            && closes(&|t| at(u0, v0 + (v1 - v0) * t).distance(at(u1, v0 + (v1 - v0) * t))))
        .then_some((u0, u1 - u0));
        let cv = (pv.is_none()
            && v1 > v0
            && closes(&|t| at(u0 + (u1 - u0) * t, v0).distance(at(u0 + (u1 - u0) * t, v1))))
        .then_some((v0, v1 - v0));
        (cu, cv)
    }

    /// The few nearest of a 24 × 24 grid of parameters over the finite range, best first
    /// (truck's searches need a start on some surfaces; a self-intersecting spindle torus has
    /// two sheets close together, so one guess is not enough).
    fn coarse_guesses(&self, p: DVec3) -> Vec<DVec2> {
        let Some((range, steps)) = self.coarse_steps() else {
            return Vec::new();
        };
        nearest_of_grid(p, KEEP_GUESSES, range, steps, |uv| self.at(uv))
    }

    /// The range and steps of [`TrimmedFace::coarse_guesses`]' grid.
    #[allow(clippy::type_complexity)]
    fn coarse_steps(&self) -> Option<(((f64, f64), (f64, f64)), (usize, usize))> {
        let (range, widened) = self.search_range()?;
        const N: usize = 24;
        // A widened direction across a periodic one (a cone's or cylinder's axis) gets 4× the
        // steps: on a wide cone near its apex the near nappe's grid points can all be nearer
        // than the far nappe's (trj4 #4134 at 24 steps). A plane (nothing periodic, convex
        // distance) keeps 24 × 24: this search runs at each loop's start in every tessellation.
        Some((range, (N * widened.0, N * widened.1)))
    }

    /// The range grid searches cover ([`TrimmedFace::guess_range`] of the finite range or
    /// period), `None` where a direction has neither.
    #[allow(clippy::type_complexity)]
    fn search_range(&self) -> Option<(((f64, f64), (f64, f64)), (usize, usize))> {
        let (ru, rv) = parameter_bounds(&self.surface);
        let (pu, pv) = self.surface.periods();
        let u = ru.or(pu.map(|p| (0.0, p)))?;
        let v = rv.or(pv.map(|p| (0.0, p)))?;
        Some(self.guess_range(u, v))
    }

    /// The range the coarse guesses cover: the surface's finite range, except that a direction
    /// whose range is only nominal (not a B-spline's knots, not a period: the line of a cone,
    /// a cylinder or a plane, which truck gives as `0..1`) spans `3 · reach / speed` either
    /// side of the range's middle, `reach` the farthest the face gets from the surface there
    /// and `speed` |∂S/∂v| there. A cone's face past its apex lies at parameters the nominal
    /// range never comes near, on the other nappe: from guesses in `0..1` the search ends on
    /// the near nappe (trj4's wide cones, their loops 12–22 mm off the surface, error 145 ε).
    /// The factor: on a cone of semi-angle α (v along its axis, speed 1/cos α) a face point is
    /// at most `reach · min(1, cot α) ≤ √2 · reach / speed` away in v.
    /// Also returns the step multiplier per direction (4 where widened across a periodic
    /// direction, else 1).
    #[allow(clippy::type_complexity)]
    fn guess_range(
        &self,
        u: (f64, f64),
        v: (f64, f64),
    ) -> (((f64, f64), (f64, f64)), (usize, usize)) {
        let (ku, kv) = knot_bounds(&self.surface);
        let (pu, pv) = self.periods();
        let mid = DVec2::new(0.5 * (u.0 + u.1), 0.5 * (v.0 + v.1));
        let (su, sv) = self.at_derivs(mid);
        let reach = self.at(mid).distance(self.bounds.center) + self.bounds.radius;
        let widen = |r: (f64, f64), knots: Interval, period: Option<f64>, speed: f64, across| {
            let h = 3.0 * reach / speed;
            let c = 0.5 * (r.0 + r.1);
            if knots.is_some() || period.is_some() || !(h.is_finite() && c - h < r.0) {
                return (r, 1);
            }
            let steps = if across { 4 } else { 1 };
            (((c - h).min(r.0), (c + h).max(r.1)), steps)
        };
        let ((u, mu), (v, mv)) = (
            widen(u, ku, pu, su.length(), pv.is_some()),
            widen(v, kv, pv, sv.length(), pu.is_some()),
        );
        ((u, v), (mu, mv))
    }

    /// Levenberg–Marquardt on |S(u, v) − p|² from `uv`, on the wrapped surface (so it runs across
    /// the seam of a closed direction) and kept inside the finite range elsewhere.
    fn newton(&self, p: DVec3, mut uv: DVec2) -> Option<DVec2> {
        let (ru, rv) = knot_bounds(&self.surface);
        let clamp = |x: f64, r: Interval, closed: bool| match r {
            Some((a, b)) if !closed => x.clamp(a, b),
            _ => x,
        };
        let (pu, pv) = self.periods();
        // Outside its knot range a B-spline extrapolates, and may meet `p` there: start inside.
        uv = DVec2::new(clamp(uv.x, ru, pu.is_some()), clamp(uv.y, rv, pv.is_some()));
        // Levenberg–Marquardt: Gauss–Newton steps, damped until the distance decreases (a
        // plain Gauss–Newton step can stall at a singular point such as a cone's apex).
        let mut lambda = 1e-6;
        let mut r = self.point(uv) - p;
        for _ in 0..60 {
            let (su, sv) = self.derivs(uv);
            let (a, b, c) = (su.dot(su), su.dot(sv), sv.dot(sv));
            let (gu, gv) = (su.dot(r), sv.dot(r));
            if !(a.is_finite()
                && b.is_finite()
                && c.is_finite()
                && gu.is_finite()
                && gv.is_finite())
            {
                break;
            }
            let mut accepted = false;
            while lambda < 1e12 {
                let (ad, cd) = (a + lambda * a.max(1e-300), c + lambda * c.max(1e-300));
                let det = ad * cd - b * b;
                if det.is_nan() || det.abs() <= 1e-300 {
                    lambda *= 4.0;
                    continue;
                }
                let mut step = DVec2::new((cd * gu - b * gv) / det, (ad * gv - b * gu) / det);
                // At most a quarter turn per step in a periodic direction.
                let limit = |x: f64, period: Option<f64>| match period {
                    Some(p) if p > 0.0 => x.clamp(-0.25 * p, 0.25 * p),
                    _ => x,
                };
                step = DVec2::new(limit(step.x, pu), limit(step.y, pv));
                let next = uv - step;
                let next = DVec2::new(
                    clamp(next.x, ru, pu.is_some()),
                    clamp(next.y, rv, pv.is_some()),
                );
                let rn = self.point(next) - p;
                if next.is_finite() && rn.length_squared() <= r.length_squared() {
                    let moved = next.distance(uv);
                    uv = next;
                    r = rn;
                    lambda = (lambda / 4.0).max(1e-9);
                    accepted = moved >= 1e-13 * (1.0 + uv.length());
                    break;
                }
                lambda *= 4.0;
            }
            if !accepted {
                break;
            }
        }
        uv.is_finite().then_some(uv)
    }

    /// A sphere's parameter with the latitude in `[−π/2, π/2]` (truck's sphere extends past its
    /// poles: `(u, v)` beyond a pole is the point `(u + π, ±π − v)`), so that loops and
    /// samples of one face agree on which of the two parameters a point has.
    fn canonical(&self, uv: DVec2) -> DVec2 {
        use std::f64::consts::{FRAC_PI_2, PI};
        use truck_stepio::r#in::alias::ElementarySurface;
        let TruckSurface::ElementarySurface(e) = &self.surface else {
            return uv;
        };
        if !matches!(**e, ElementarySurface::Sphere(_)) {
            return uv;
        }
        // Fold the latitude into (−π, π] first, then across the nearer pole.
        let mut v = (uv.y + PI).rem_euclid(2.0 * PI) - PI;
        let mut u = uv.x;
        if v > FRAC_PI_2 {
            v = PI - v;
            u += PI;
        } else if v < -FRAC_PI_2 {
            v = -PI - v;
            u += PI;
        }
        if (uv.y - v).abs() < 1e-15 {
            return uv;
        }
        DVec2::new(u, v)
    }

    fn wrap(&self, uv: DVec2) -> DVec2 {
        let w = |x: f64, c: Interval| match c {
            Some((a, p)) if p > 0.0 => a + (x - a).rem_euclid(p),
            _ => x,
        };
        DVec2::new(w(uv.x, self.closed.0), w(uv.y, self.closed.1))
    }
}

impl SurfaceEval for TrimmedFace {
    fn point(&self, uv: DVec2) -> DVec3 {
        self.at(self.wrap(uv))
    }

    fn derivs(&self, uv: DVec2) -> (DVec3, DVec3) {
        self.at_derivs(self.wrap(uv))
    }

    fn second_derivs(&self, uv: DVec2) -> (DVec3, DVec3, DVec3) {
        match &self.fast {
            Some(f) => {
                let d = f.eval(self.wrap(uv), 2);
                (d[3], d[4], d[5])
            }
            None => self.surface.second_derivs(self.wrap(uv)),
        }
    }

    /// Best of: truck's search from the (wrapped) hint or a coarse guess, polished by
    /// Gauss–Newton on the wrapped surface, and Gauss–Newton from the hint itself (which runs
    /// across a closed seam where truck's search stops at the end of the knot range).
    fn project(&self, p: DVec3, hint: Option<DVec2>) -> Option<DVec2> {
        self.project_in(p, hint, None)
    }

    fn periods(&self) -> (Option<f64>, Option<f64>) {
        let (pu, pv) = self.surface.periods();
        (
            pu.or(self.closed.0.map(|c| c.1)),
            pv.or(self.closed.1.map(|c| c.1)),
        )
    }
}

/// Surface type name of a face.
pub fn surface_kind(s: &TruckSurface) -> &'static str {
    use truck_stepio::r#in::alias::ElementarySurface as E;
    match s {
        TruckSurface::ElementarySurface(e) => match e.as_ref() {
            E::Plane(_) => "plane",
            E::Sphere(_) => "sphere",
            E::CylindricalSurface(_) => "cylinder",
            E::ToroidalSurface(_) => "torus",
            E::ConicalSurface(_) => "cone",
        },
        TruckSurface::SweptCurve(_) => "swept",
        TruckSurface::BSplineSurface(_) => "b-spline",
        TruckSurface::NurbsSurface(_) => "nurbs",
    }
}

/// Surface evaluation in glam types.
pub trait SurfaceEval {
    fn point(&self, uv: DVec2) -> DVec3;
    /// (∂S/∂u, ∂S/∂v)
    fn derivs(&self, uv: DVec2) -> (DVec3, DVec3);
    /// (S_uu, S_uv, S_vv)
    fn second_derivs(&self, uv: DVec2) -> (DVec3, DVec3, DVec3);
    /// Parameter of the point nearest to `p`, searched from `hint` when given.
    fn project(&self, p: DVec3, hint: Option<DVec2>) -> Option<DVec2>;
    fn periods(&self) -> (Option<f64>, Option<f64>);
}

impl SurfaceEval for TruckSurface {
    fn point(&self, uv: DVec2) -> DVec3 {
        to_dvec(self.subs(uv.x, uv.y))
    }

    fn derivs(&self, uv: DVec2) -> (DVec3, DVec3) {
        (
            vec_to_dvec(self.uder(uv.x, uv.y)),
            vec_to_dvec(self.vder(uv.x, uv.y)),
        )
    }

    fn second_derivs(&self, uv: DVec2) -> (DVec3, DVec3, DVec3) {
        (
            vec_to_dvec(self.uuder(uv.x, uv.y)),
            vec_to_dvec(self.uvder(uv.x, uv.y)),
            vec_to_dvec(self.vvder(uv.x, uv.y)),
        )
    }

    fn project(&self, p: DVec3, hint: Option<DVec2>) -> Option<DVec2> {
        let h = match hint {
            Some(h) => SPHint2D::Parameter(h.x, h.y),
            None => SPHint2D::None,
        };
        let (u, v) = self.search_nearest_parameter(to_point(p), h, 40)?;
        let uv = DVec2::new(u, v);
        uv.is_finite().then_some(uv)
    }

    fn periods(&self) -> (Option<f64>, Option<f64>) {
        (self.u_period(), self.v_period())
    }
}

/// The four sides of the parameter rectangle `(u0, u1, v0, v1)` as curves on the surface,
/// counter-clockwise from `(u0, v0)`, with ids from `id` (`id + k` for side k; sides 1 and 3
/// share `id + 1` where u closes on itself, sides 0 and 2 share `id` where v does: a seam is
/// one edge used twice). Bounds an untrimmed IGES surface, and a STEP face whose only bound
/// is a `VERTEX_LOOP` (a whole sphere).
pub(crate) fn parameter_rectangle(
    surface: &TruckSurface,
    (u0, u1, v0, v1): (f64, f64, f64, f64),
    seams: (bool, bool),
    id: u64,
) -> Vec<TrimEdge> {
    use truck_stepio::r#in::alias::Curve2D;
    use truck_stepio::r#in::alias::re_exports::{Line, PCurve, ParametricCurve, Point2};
    let corners = [(u0, v0), (u1, v0), (u1, v1), (u0, v1)];
    (0..4)
        .map(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            let line = Curve2D::Line(Line(Point2::new(a.0, a.1), Point2::new(b.0, b.1)));
            let curve = Curve3D::PCurve(PCurve::new(Box::new(line), Box::new(surface.clone())));
            let side = match k {
                1 | 3 if seams.0 => 1,
                0 | 2 if seams.1 => 0,
                _ => k as u64,
            };
            let start = to_dvec(curve.subs(0.0));
            let end = to_dvec(curve.subs(1.0));
            TrimEdge {
                id: id + side,
                curve,
                t0: 0.0,
                t1: 1.0,
                start,
                end,
                wrap: None,
            }
        })
        .collect()
}

/// A finite parameter interval, `None` when unbounded.
pub(crate) type Interval = Option<(f64, f64)>;

/// The finite parameter range of a surface, per direction.
pub(crate) fn parameter_bounds(s: &TruckSurface) -> (Interval, Interval) {
    use truck_stepio::r#in::alias::SweptCurve;
    let (mut u, mut v) = s.try_range_tuple();
    // B-splines (and surfaces swept from them) end at their clamped knots (see `curve_range`).
    match s {
        TruckSurface::BSplineSurface(b) => {
            (u, v) = (
                clamped_range(&b.knot_vecs().0, b.udegree()),
                clamped_range(&b.knot_vecs().1, b.vdegree()),
            );
        }
        TruckSurface::NurbsSurface(b) => {
            (u, v) = (
                clamped_range(&b.knot_vecs().0, b.udegree()),
                clamped_range(&b.knot_vecs().1, b.vdegree()),
            );
        }
        TruckSurface::SweptCurve(c) => {
            u = match c.as_ref() {
                SweptCurve::ExtrudedCurve(e) => curve_range(e.entity_curve()),
                SweptCurve::RevolutedCurve(r) => curve_range(r.entity().entity_curve()),
            };
        }
        TruckSurface::ElementarySurface(_) => {}
    }
    let finite = |r: Option<(f64, f64)>| r.filter(|(a, b)| a.is_finite() && b.is_finite());
    (finite(u), finite(v))
}

/// Where a surface really ends: the knot range of a B-spline surface, and of the B-spline
/// curve a swept surface sweeps (beyond it truck extrapolates the curve: a surface of
/// revolution past the pole where its profile meets the axis); `None` for analytic
/// surfaces and lines, whose reported range is nominal (truck gives a cone, a plane or a
/// line `0..1`, an extrusion `0..1` along its vector).
pub(crate) fn knot_bounds(s: &TruckSurface) -> (Interval, Interval) {
    use truck_stepio::r#in::alias::SweptCurve;
    let bspline = |c: &Curve3D| matches!(c, Curve3D::BSplineCurve(_) | Curve3D::NurbsCurve(_));
    let (ru, rv) = parameter_bounds(s);
    match s {
        TruckSurface::BSplineSurface(_) | TruckSurface::NurbsSurface(_) => (ru, rv),
        TruckSurface::SweptCurve(swept) => match swept.as_ref() {
            // truck-stepio inverts a revolution (u the angle, v the curve) unless inverted back.
            SweptCurve::RevolutedCurve(p) if bspline(p.entity().entity_curve()) => {
                if p.orientation() {
                    (ru, None)
                } else {
                    (None, rv)
                }
            }
            SweptCurve::ExtrudedCurve(e) if bspline(e.entity_curve()) => (ru, None),
            _ => (None, None),
        },
        _ => (None, None),
    }
}
