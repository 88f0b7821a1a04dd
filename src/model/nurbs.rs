//! Our own B-spline / NURBS surface evaluation (point, first and second derivatives) by the
//! Cox–de Boor recurrence on the one knot span a parameter falls in (Piegl & Tiller, "The NURBS
//! Book", §2.2–2.3: the p + 1 non-zero basis functions of every degree up to p, their
//! derivatives from the next lower degree), without allocating: truck's evaluation builds every
//! basis function of the knot vector in a new `Vec` for each point (measured: 65 % of a
//! degree-11 thread face's tessellation in `try_bspline_basis_functions`, malloc and free).
//! A surface of an offset (`OFFSET_SURFACE` of a B-spline) is evaluated here too: the base point
//! moved along the unit normal, whose derivatives come from the base's second derivatives.
//!
//! Degrees up to `MAX_DEGREE` and clamped knot vectors (`model::knots` clamps on reading);
//! anything else stays with truck (`NurbsSurface::of` returns `None`).

use super::trimmed::TruckSurface;
use glam::{DVec2, DVec3, DVec4};

/// Highest degree evaluated here (STEP allows any; OCCT's own limit is 25).
pub(crate) const MAX_DEGREE: usize = 25;
const M: usize = MAX_DEGREE + 1;

/// A B-spline or NURBS surface: `S(u, v) = Σ N_i(u) N_j(v) w_ij P_ij / Σ N_i(u) N_j(v) w_ij`.
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsSurface {
    degree: (usize, usize),
    knots: (Vec<f64>, Vec<f64>),
    /// Control points in homogeneous form `(w x, w y, w z, w)`, row `i` (along u) after row
    /// `i − 1`, `count.1` per row.
    points: Vec<DVec4>,
    count: (usize, usize),
    rational: bool,
}

/// What a surface evaluation gives: `[S, S_u, S_v, S_uu, S_uv, S_vv]` up to the order asked.
pub(crate) type Derivs = [DVec3; 6];

/// A surface we evaluate ourselves.
#[derive(Clone, Debug, PartialEq)]
pub enum FastSurface {
    Nurbs(NurbsSurface),
    /// `base + distance · n`, n the base's unit normal `S_u × S_v / |S_u × S_v|`.
    Offset {
        base: NurbsSurface,
        distance: f64,
    },
    /// The same of a surface truck evaluates (a swept B-spline curve: extrusion, revolution),
    /// from truck's first and second derivatives.
    OffsetOfTruck {
        base: TruckSurface,
        distance: f64,
    },
    /// A plane, sphere, cylinder, cone or torus in closed form
    /// (`model::analytic`): truck's own surface, so truck's projection search still applies.
    Analytic(super::analytic::Analytic),
}

impl FastSurface {
    /// Bytes behind this value (knot vectors and control points; a truck base's own heap
    /// is not counted, as a face's truck surface is not).
    pub(crate) fn heap_bytes(&self) -> usize {
        match self {
            FastSurface::Nurbs(n) | FastSurface::Offset { base: n, .. } => {
                (n.knots.0.capacity() + n.knots.1.capacity()) * size_of::<f64>()
                    + n.points.capacity() * size_of::<DVec4>()
            }
            FastSurface::OffsetOfTruck { .. } | FastSurface::Analytic(_) => 0,
        }
    }

    /// Whether this is the face's truck surface evaluated our way (so truck's own searches on
    /// it find this surface's points): an analytic surface. A B-spline's search stays ours, as
    /// it was before analytic surfaces were taken here; an offset is not truck's surface.
    pub(crate) fn is_truck_surface(&self) -> bool {
        matches!(self, FastSurface::Analytic(_))
    }

    /// The point at `uv` (as `eval(uv, 0)[0]`, without returning the derivatives' array).
    #[inline]
    pub(crate) fn point(&self, uv: DVec2) -> DVec3 {
        match self {
            FastSurface::Analytic(a) => a.eval(uv, 0)[0],
            _ => self.eval(uv, 0)[0],
        }
    }

    /// The first derivatives at `uv` (as `eval(uv, 1)[1..3]`).
    #[inline]
    pub(crate) fn derivs(&self, uv: DVec2) -> (DVec3, DVec3) {
        let d = match self {
            FastSurface::Analytic(a) => a.eval(uv, 1),
            _ => self.eval(uv, 1),
        };
        (d[1], d[2])
    }

    /// Point, first and (for `order` 2) second derivatives.
    pub(crate) fn eval(&self, uv: DVec2, order: usize) -> Derivs {
        match self {
            FastSurface::Nurbs(n) => n.eval(uv, order),
            FastSurface::Offset { base, distance } => {
                offset_eval(&|uv, o| base.eval(uv, o), *distance, uv, order)
            }
            FastSurface::OffsetOfTruck { base, distance } => {
                offset_eval(&|uv, o| truck_eval(base, uv, o), *distance, uv, order)
            }
            FastSurface::Analytic(a) => a.eval(uv, order),
        }
    }
}

impl NurbsSurface {
    /// Truck's B-spline or NURBS surface in our form; `None` for other surfaces, degrees above
    /// `MAX_DEGREE` and knot vectors that are not clamped.
    pub fn of(s: &TruckSurface) -> Option<NurbsSurface> {
        let (knots, rows, rational): (_, Vec<Vec<DVec4>>, bool) = match s {
            TruckSurface::BSplineSurface(b) => {
                let rows = b.control_points().iter();
                let rows = rows.map(|r| r.iter().map(|p| DVec4::new(p.x, p.y, p.z, 1.0)));
                (b.knot_vecs(), rows.map(Iterator::collect).collect(), false)
            }
            TruckSurface::NurbsSurface(n) => {
                let b = n.non_rationalized();
                let rows = b.control_points().iter();
                let rows = rows.map(|r| r.iter().map(|p| DVec4::new(p.x, p.y, p.z, p.w)));
                (b.knot_vecs(), rows.map(Iterator::collect).collect(), true)
            }
            _ => return None,
        };
        let count = (rows.len(), rows.first().map_or(0, Vec::len));
        if rows.iter().any(|r| r.len() != count.1) {
            return None;
        }
        let knots: (Vec<f64>, Vec<f64>) = (knots.0.to_vec(), knots.1.to_vec());
        let degree = (
            knots.0.len().checked_sub(count.0 + 1)?,
            knots.1.len().checked_sub(count.1 + 1)?,
        );
        let ok = |k: &[f64], p: usize, n: usize| {
            p <= MAX_DEGREE
                && n > p
                && k.iter().all(|x| x.is_finite())
                && k.windows(2).all(|w| w[0] <= w[1])
                && k[..=p].iter().all(|&x| x == k[0])
                && k[k.len() - 1 - p..].iter().all(|&x| x == k[k.len() - 1])
                && k[0] < k[k.len() - 1]
        };
        if !(ok(&knots.0, degree.0, count.0) && ok(&knots.1, degree.1, count.1)) {
            return None;
        }
        let points: Vec<DVec4> = rows.into_iter().flatten().collect();
        if !points.iter().all(|p| p.is_finite()) || rational && points.iter().any(|p| p.w <= 0.0) {
            return None;
        }
        Some(NurbsSurface {
            degree,
            knots,
            points,
            count,
            rational,
        })
    }

    /// Point, first and (for `order` 2) second derivatives at `uv` (outside the knot range
    /// the end spans' polynomials, as truck extrapolates).
    pub(crate) fn eval(&self, uv: DVec2, order: usize) -> Derivs {
        let (pu, pv) = self.degree;
        let (bu, su) = basis(&self.knots.0, pu, self.count.0, uv.x, order);
        let (bv, sv) = basis(&self.knots.1, pv, self.count.1, uv.y, order);
        // Homogeneous sums: A, A_u, A_v, A_uu, A_uv, A_vv.
        let mut h = [DVec4::ZERO; 6];
        #[allow(clippy::needless_range_loop)] // a indexes three basis rows and the points
        for a in 0..=pu {
            let row = &self.points[(su - pu + a) * self.count.1 + (sv - pv)..];
            let mut r = [DVec4::ZERO; 3];
            for (b, q) in row.iter().take(pv + 1).enumerate() {
                r[0] += *q * bv[0][b];
                if order >= 1 {
                    r[1] += *q * bv[1][b];
                }
                if order >= 2 {
                    r[2] += *q * bv[2][b];
                }
            }
            h[0] += r[0] * bu[0][a];
            if order >= 1 {
                h[1] += r[0] * bu[1][a];
                h[2] += r[1] * bu[0][a];
            }
            if order >= 2 {
                h[3] += r[0] * bu[2][a];
                h[4] += r[1] * bu[1][a];
                h[5] += r[2] * bu[0][a];
            }
        }
        if !self.rational {
            return h.map(|q| q.truncate());
        }
        // Quotient rule: S = A / w, then each derivative of A = w S solved for S's.
        let w = h.map(|q| q.w);
        let a = h.map(|q| q.truncate());
        let s = a[0] / w[0];
        let mut out = [DVec3::ZERO; 6];
        out[0] = s;
        if order >= 1 {
            out[1] = (a[1] - w[1] * s) / w[0];
            out[2] = (a[2] - w[2] * s) / w[0];
        }
        if order >= 2 {
            out[3] = (a[3] - 2.0 * w[1] * out[1] - w[3] * s) / w[0];
            out[4] = (a[4] - w[1] * out[2] - w[2] * out[1] - w[4] * s) / w[0];
            out[5] = (a[5] - 2.0 * w[2] * out[2] - w[5] * s) / w[0];
        }
        out
    }
}

/// The knot span of `t`: `k` in `p ..= n − 1` with `knots[k] ≤ t < knots[k + 1]`, the end
/// spans beyond the range (`n` control points).
fn span(knots: &[f64], p: usize, n: usize, t: f64) -> usize {
    let (lo, hi) = (p, n - 1);
    if t.is_nan() || t <= knots[lo] {
        // NaN too: the first span.
        return lo;
    }
    if t >= knots[hi + 1] {
        return hi;
    }
    // Largest k in lo..=hi with knots[k] <= t.
    lo + knots[lo + 1..=hi].partition_point(|&x| x <= t)
}

/// The p + 1 basis functions non-zero at `t` and (to `order`) their first and second
/// derivatives, `[N, N', N'']` for `N_{k−p} … N_k`, and the span `k`.
fn basis(knots: &[f64], p: usize, n: usize, t: f64, order: usize) -> ([[f64; M]; 3], usize) {
    let k = span(knots, p, n, t);
    // Row d (kept for the last three d, at d % 3): N_{k−d+j, d} for j in 0..=d.
    let mut table = [[0.0f64; M]; 3];
    table[0][0] = 1.0;
    let ratio = |num: f64, den: f64| if den > 0.0 { num / den } else { 0.0 };
    for d in 1..=p {
        let below = table[(d - 1) % 3];
        let row = &mut table[d % 3];
        for (j, r) in row.iter_mut().enumerate().take(d + 1) {
            let i = k + j - d;
            let mut v = 0.0;
            if j >= 1 {
                v += ratio(t - knots[i], knots[i + d] - knots[i]) * below[j - 1];
            }
            if j < d {
                v += ratio(knots[i + d + 1] - t, knots[i + d + 1] - knots[i + 1]) * below[j];
            }
            *r = v;
        }
    }
    // Derivative of the degree-d row from `lower`, a degree d − 1 row (values or derivatives):
    // N'_{i,d} = d (N_{i,d−1} / (t_{i+d} − t_i) − N_{i+1,d−1} / (t_{i+d+1} − t_{i+1})).
    let derive = |d: usize, lower: &[f64; M]| {
        let mut out = [0.0f64; M];
        if d == 0 {
            return out;
        }
        for (j, o) in out.iter_mut().enumerate().take(d + 1) {
            let i = k + j - d;
            let mut v = 0.0;
            if j >= 1 {
                v += ratio(lower[j - 1], knots[i + d] - knots[i]);
            }
            if j < d {
                v -= ratio(lower[j], knots[i + d + 1] - knots[i + 1]);
            }
            *o = d as f64 * v;
        }
        out
    };
    let mut out = [[0.0f64; M]; 3];
    out[0] = table[p % 3];
    if order >= 1 && p >= 1 {
        out[1] = derive(p, &table[(p - 1) % 3]);
    }
    if order >= 2 && p >= 2 {
        out[2] = derive(p, &derive(p - 1, &table[(p - 2) % 3]));
    }
    (out, k)
}

/// `base + distance · n` and its derivatives. The normal's derivatives need the base's third
/// derivatives for the offset's second ones: those come from central differences of the
/// offset's first derivatives (they only steer grid steps and searches).
fn offset_eval(
    base: &dyn Fn(DVec2, usize) -> Derivs,
    distance: f64,
    uv: DVec2,
    order: usize,
) -> Derivs {
    // The point needs the base's first derivatives (the normal), each further order one more.
    let b = base(uv, order.min(1) + 1);
    let first = |b: &Derivs| {
        let m = b[1].cross(b[2]);
        let len = m.length();
        let n = m / len;
        // d(m/|m|) = (dm − n (n · dm)) / |m|.
        let dn = |dm: DVec3| (dm - n * n.dot(dm)) / len;
        let mu = b[3].cross(b[2]) + b[1].cross(b[4]);
        let mv = b[4].cross(b[2]) + b[1].cross(b[5]);
        (n, dn(mu), dn(mv))
    };
    let mut out = [DVec3::ZERO; 6];
    if order == 0 {
        out[0] = b[0] + distance * b[1].cross(b[2]).normalize();
        return out;
    }
    let (n, nu, nv) = first(&b);
    out[0] = b[0] + distance * n;
    out[1] = b[1] + distance * nu;
    out[2] = b[2] + distance * nv;
    if order >= 2 {
        let h = 1e-6 * (1.0 + uv.abs().max_element());
        let at = |d: DVec2| {
            let b = base(uv + d, 2);
            let (_, nu, nv) = first(&b);
            (b[1] + distance * nu, b[2] + distance * nv)
        };
        let (up, um) = (at(DVec2::new(h, 0.0)), at(DVec2::new(-h, 0.0)));
        let (vp, vm) = (at(DVec2::new(0.0, h)), at(DVec2::new(0.0, -h)));
        out[3] = (up.0 - um.0) / (2.0 * h);
        out[4] = (vp.0 - vm.0) / (2.0 * h);
        out[5] = (vp.1 - vm.1) / (2.0 * h);
    }
    out
}

/// Truck's evaluation of `s` as [`Derivs`] (to `order` ≤ 2).
fn truck_eval(s: &TruckSurface, uv: DVec2, order: usize) -> Derivs {
    use super::trimmed::SurfaceEval;
    let mut out = [DVec3::ZERO; 6];
    out[0] = s.point(uv);
    if order >= 1 {
        (out[1], out[2]) = s.derivs(uv);
    }
    if order >= 2 {
        (out[3], out[4], out[5]) = s.second_derivs(uv);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::trimmed::SurfaceEval;
    use truck_stepio::r#in::alias::re_exports::{
        BSplineSurface, KnotVec, NurbsSurface as TNurbs, Point3, Vector4,
    };

    fn bspline(pu: usize, pv: usize, nu: usize, nv: usize, seed: u64) -> TruckSurface {
        let mut x = seed;
        let mut rnd = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let knots = |p: usize, n: usize, rnd: &mut dyn FnMut() -> f64| {
            let mut inner: Vec<f64> = (0..n - p - 1).map(|_| rnd() * 3.0).collect();
            inner.sort_by(f64::total_cmp);
            let mut k = vec![0.0; p + 1];
            k.extend(inner);
            k.extend(vec![3.0; p + 1]);
            KnotVec::from(k)
        };
        let ku = knots(pu, nu, &mut rnd);
        let kv = knots(pv, nv, &mut rnd);
        let pts: Vec<Vec<Point3>> = (0..nu)
            .map(|i| {
                (0..nv)
                    .map(|j| Point3::new(i as f64 + rnd(), j as f64 + rnd(), 2.0 * rnd()))
                    .collect()
            })
            .collect();
        TruckSurface::BSplineSurface(Box::new(BSplineSurface::new((ku, kv), pts)))
    }

    fn close(a: DVec3, b: DVec3, scale: f64) -> bool {
        a.distance(b) <= 1e-9 * (1.0 + scale)
    }

    /// Our evaluation agrees with truck's points and first derivatives on random B-splines of
    /// degrees 1–11, at random parameters, span ends and the range's ends; our second
    /// derivatives with central differences of our first ones (truck's `uuder` is half the
    /// true value at the start of a clamped cubic's range, so it is no reference there).
    #[test]
    fn bspline_evaluation_agrees_with_truck() {
        let mut truck_off = 0;
        for (seed, (pu, pv, nu, nv)) in [(1, 1, 2, 2), (3, 2, 5, 4), (2, 11, 3, 42), (5, 5, 9, 7)]
            .into_iter()
            .enumerate()
        {
            let t = bspline(pu, pv, nu, nv, seed as u64 + 7);
            let ours = NurbsSurface::of(&t).expect("clamped B-spline");
            for k in 0..=40 {
                let uv = DVec2::new(3.0 * (k % 7) as f64 / 6.0, 3.0 * (k * 5 % 11) as f64 / 10.0);
                let d = ours.eval(uv, 2);
                let (tu, tv) = t.derivs(uv);
                let want = [t.point(uv), tu, tv];
                let scale = want.iter().map(|w| w.length()).fold(0.0, f64::max);
                for (i, (a, b)) in d.iter().zip(want).enumerate() {
                    assert!(
                        close(*a, b, scale),
                        "deg {pu}x{pv} at {uv}: #{i} {a} vs {b}"
                    );
                }
                let h = 1e-6;
                let q = |du: f64, dv: f64| ours.eval(uv + DVec2::new(du, dv), 1);
                let (up, um, vp, vm) = (q(h, 0.0), q(-h, 0.0), q(0.0, h), q(0.0, -h));
                let fd = [
                    (up[1] - um[1]) / (2.0 * h),
                    (vp[1] - vm[1]) / (2.0 * h),
                    (vp[2] - vm[2]) / (2.0 * h),
                ];
                let scale = fd.iter().map(|w| w.length()).fold(0.0, f64::max);
                for (i, (a, b)) in d[3..].iter().zip(fd).enumerate() {
                    assert!(
                        a.distance(b) <= 1e-5 * (1.0 + scale),
                        "deg {pu}x{pv} at {uv}: second #{i} {a} vs differences {b}"
                    );
                }
                let (tuu, tuv, tvv) = t.second_derivs(uv);
                truck_off += [tuu, tuv, tvv]
                    .iter()
                    .zip(&d[3..])
                    .filter(|(a, b)| !close(**a, **b, scale))
                    .count();
            }
        }
        eprintln!("second derivatives where truck's differ from ours: {truck_off}");
    }

    /// A rational surface (a quarter cylinder with weights √½): our quotient-rule derivatives
    /// agree with truck's.
    #[test]
    fn nurbs_evaluation_agrees_with_truck() {
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let row = |z: f64| {
            vec![
                Vector4::new(1.0, 0.0, z, 1.0),
                Vector4::new(w, w, w * z, w),
                Vector4::new(0.0, 1.0, z, 1.0),
            ]
        };
        let b = BSplineSurface::new(
            (KnotVec::bezier_knot(1), KnotVec::bezier_knot(2)),
            vec![row(0.0), row(2.0)],
        );
        let t = TruckSurface::NurbsSurface(Box::new(TNurbs::new(b)));
        let ours = NurbsSurface::of(&t).expect("NURBS");
        for k in 0..=10 {
            let uv = DVec2::new(k as f64 / 10.0, (k * 3 % 10) as f64 / 10.0);
            let d = ours.eval(uv, 2);
            assert!(
                (d[0].truncate().length() - 1.0).abs() < 1e-12,
                "on the cylinder"
            );
            let (tu, tv) = t.derivs(uv);
            let (tuu, tuv, tvv) = t.second_derivs(uv);
            for (i, (a, b)) in d
                .iter()
                .zip([t.point(uv), tu, tv, tuu, tuv, tvv])
                .enumerate()
            {
                assert!(close(*a, b, 4.0), "at {uv}: #{i} {a} vs {b}");
            }
        }
    }

    /// An offset of a plane-like B-spline is the plane moved along its normal, and the
    /// offset's derivatives match central differences of its points.
    #[test]
    fn offset_of_a_bspline_is_moved_along_the_normal() {
        let t = bspline(3, 2, 5, 4, 11);
        let base = NurbsSurface::of(&t).expect("B-spline");
        let f = FastSurface::Offset {
            base: base.clone(),
            distance: 0.3,
        };
        for k in 1..10 {
            let uv = DVec2::new(0.3 * k as f64, 0.29 * (10 - k) as f64);
            let b = base.eval(uv, 1);
            let n = b[1].cross(b[2]).normalize();
            let d = f.eval(uv, 2);
            assert!(d[0].distance(b[0] + 0.3 * n) < 1e-12);
            let h = 1e-5;
            let p = |du: f64, dv: f64| f.eval(uv + DVec2::new(du, dv), 0)[0];
            let fu = (p(h, 0.0) - p(-h, 0.0)) / (2.0 * h);
            let fv = (p(0.0, h) - p(0.0, -h)) / (2.0 * h);
            assert!(
                d[1].distance(fu) < 1e-6 * (1.0 + fu.length()),
                "{} vs {fu}",
                d[1]
            );
            assert!(
                d[2].distance(fv) < 1e-6 * (1.0 + fv.length()),
                "{} vs {fv}",
                d[2]
            );
        }
    }

    /// Unclamped knots and degrees above the limit stay with truck.
    #[test]
    fn unclamped_or_too_high_degrees_are_not_taken() {
        let pts = vec![vec![Point3::new(0.0, 0.0, 0.0); 3]; 3];
        let unclamped = TruckSurface::BSplineSurface(Box::new(BSplineSurface::new(
            (
                KnotVec::from(vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0]),
                KnotVec::bezier_knot(2),
            ),
            pts,
        )));
        assert!(NurbsSurface::of(&unclamped).is_none());
    }
}
