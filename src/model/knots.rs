//! Clamping B-spline knot vectors, by knot insertion (Boehm, "Inserting new knots into
//! B-spline curves", CAD 12(4), 1980; Piegl & Tiller, *The NURBS Book*, §5.2, A5.1).
//!
//! A B-spline of degree p over knots t₀ … t_{m−1} is defined on [t_p, t_{m−1−p}]. Writers such
//! as OCCT store closed and periodic curves and surfaces *unclamped*: the knots outside that
//! range are not repeated (a spring's sweep: u knots (−2π, 0 ×6, 2π ×6, 4π), degree 6). truck
//! evaluates such a spline correctly inside the range but not at its end: at u = t_{m−1−p}
//! it picks the span beyond, where the basis functions no longer sum to one. There the
//! derivative of a rational surface came out exactly zero, which the tessellator took for a
//! pole, and the seam of the spring was torn open (1 506 ε on `gen-1-14`, 245 757 triangles).
//!
//! `clamp_surface` and `clamp_curve` return the same spline with clamped knot vectors
//! (the end knots repeated p + 1 times): a knot at t_p is inserted until it has multiplicity
//! p, the control points whose basis functions vanish on the range are dropped, and the one
//! knot left before the run is set to t_p (on the range no basis function depends on it).
//! Knot insertion changes no point of the spline, so on its range the result is the same
//! curve or surface up to rounding; beyond it, there is nothing (truck extrapolates the
//! clamped end polynomial instead of the neighbouring span). Rational splines are clamped in
//! homogeneous coordinates. Swept surfaces keep their curves as they are.

use glam::DVec4;
use truck_stepio::r#in::alias::re_exports::{
    BSplineCurve, BSplineSurface, KnotVec, NurbsCurve, NurbsSurface, Point3, Vector4,
};

use super::trimmed::{Curve3D, TruckSurface};

/// The same surface with clamped knot vectors, `None` when they already are (or the surface
/// is not a B-spline).
pub(crate) fn clamp_surface(s: &TruckSurface) -> Option<TruckSurface> {
    match s {
        TruckSurface::BSplineSurface(b) => {
            let grid = b
                .control_points()
                .iter()
                .map(|row| row.iter().map(|p| DVec4::new(p.x, p.y, p.z, 1.0)).collect())
                .collect();
            let (ku, kv, grid) = clamp_grid(b.knot_vecs(), b.udegree(), b.vdegree(), grid)?;
            let pts = map_grid(grid, |q| Point3::new(q.x, q.y, q.z));
            let out = BSplineSurface::try_new((ku, kv), pts).ok()?;
            Some(TruckSurface::BSplineSurface(Box::new(out)))
        }
        TruckSurface::NurbsSurface(n) => {
            let b = n.non_rationalized();
            let grid = b
                .control_points()
                .iter()
                .map(|row| row.iter().map(|p| DVec4::new(p.x, p.y, p.z, p.w)).collect())
                .collect();
            let (ku, kv, grid) = clamp_grid(b.knot_vecs(), b.udegree(), b.vdegree(), grid)?;
            let pts = map_grid(grid, |q| Vector4::new(q.x, q.y, q.z, q.w));
            let out = BSplineSurface::try_new((ku, kv), pts).ok()?;
            Some(TruckSurface::NurbsSurface(Box::new(NurbsSurface::new(out))))
        }
        _ => None,
    }
}

/// The same curve with a clamped knot vector, `None` when it already is (or the curve is not
/// a B-spline).
pub(crate) fn clamp_curve(c: &Curve3D) -> Option<Curve3D> {
    match c {
        Curve3D::BSplineCurve(b) => {
            let pts: Vec<DVec4> = b
                .control_points()
                .iter()
                .map(|p| DVec4::new(p.x, p.y, p.z, 1.0))
                .collect();
            let (t, mut rows) = clamp_direction(b.knot_vec(), b.degree(), vec![pts])?;
            let pts = rows.pop()?.into_iter().map(|q| Point3::new(q.x, q.y, q.z));
            let out = BSplineCurve::try_new(KnotVec::from(t), pts.collect()).ok()?;
            Some(Curve3D::BSplineCurve(out))
        }
        Curve3D::NurbsCurve(n) => {
            let b = n.non_rationalized();
            let pts: Vec<DVec4> = b
                .control_points()
                .iter()
                .map(|p| DVec4::new(p.x, p.y, p.z, p.w))
                .collect();
            let (t, mut rows) = clamp_direction(b.knot_vec(), b.degree(), vec![pts])?;
            let pts = rows
                .pop()?
                .into_iter()
                .map(|q| Vector4::new(q.x, q.y, q.z, q.w));
            let out = BSplineCurve::try_new(KnotVec::from(t), pts.collect()).ok()?;
            Some(Curve3D::NurbsCurve(NurbsCurve::new(out)))
        }
        _ => None,
    }
}

type Grid = Vec<Vec<DVec4>>;

fn map_grid<T>(grid: Grid, f: impl Fn(DVec4) -> T + Copy) -> Vec<Vec<T>> {
    grid.into_iter()
        .map(|row| row.into_iter().map(f).collect())
        .collect()
}

/// Clamps both directions of a control grid (`grid[i][j]`, i along u): `None` if neither
/// needed it.
fn clamp_grid(
    knots: &(KnotVec, KnotVec),
    pu: usize,
    pv: usize,
    grid: Grid,
) -> Option<(KnotVec, KnotVec, Grid)> {
    let (nu, nv) = (grid.len(), grid.first().map_or(0, Vec::len));
    if nu == 0 || nv == 0 || grid.iter().any(|r| r.len() != nv) {
        return None;
    }
    // u: one curve per column j.
    let columns: Grid = (0..nv)
        .map(|j| (0..nu).map(|i| grid[i][j]).collect())
        .collect();
    let (ku, grid) = match clamp_direction(&knots.0, pu, columns) {
        Some((ku, cols)) => {
            let nu = cols[0].len();
            let g: Grid = (0..nu)
                .map(|i| (0..nv).map(|j| cols[j][i]).collect())
                .collect();
            (Some(ku), g)
        }
        None => (None, grid),
    };
    // v: one curve per row i.
    let (kv, grid) = match clamp_direction(&knots.1, pv, grid.clone()) {
        Some((kv, rows)) => (Some(kv), rows),
        None => (None, grid),
    };
    if ku.is_none() && kv.is_none() {
        return None;
    }
    let ku = ku.map_or_else(|| knots.0.clone(), KnotVec::from);
    let kv = kv.map_or_else(|| knots.1.clone(), KnotVec::from);
    Some((ku, kv, grid))
}

/// Clamps the knot vector `knots` of degree `p` shared by the curves `rows` (each with
/// `knots.len() − p − 1` control points). `None` when it is already clamped at both ends, or
/// is too short to have a range.
fn clamp_direction(knots: &[f64], p: usize, mut rows: Grid) -> Option<(Vec<f64>, Grid)> {
    let m = knots.len();
    if m < 2 * p + 2 || rows.iter().any(|r| r.len() + p + 1 != m) {
        return None;
    }
    let start_ok = knots[0] == knots[p];
    let end_ok = knots[m - 1] == knots[m - 1 - p];
    if start_ok && end_ok {
        return None;
    }
    let mut t = knots.to_vec();
    if !start_ok {
        clamp_start(&mut t, p, &mut rows)?;
    }
    if !end_ok {
        reverse(&mut t, &mut rows);
        clamp_start(&mut t, p, &mut rows)?;
        reverse(&mut t, &mut rows);
    }
    Some((t, rows))
}

/// The same spline with the knots negated and reversed and the control points reversed.
fn reverse(t: &mut [f64], rows: &mut Grid) {
    t.reverse();
    for k in t.iter_mut() {
        *k = -*k;
    }
    for r in rows.iter_mut() {
        r.reverse();
    }
}

/// Clamps the start of the range: t_p repeated p + 1 times at the front.
fn clamp_start(t: &mut Vec<f64>, p: usize, rows: &mut Grid) -> Option<()> {
    let a = t[p];
    // Knots within rounding of t_p are t_p (a file's 0 and 1e-17).
    let span = (t[t.len() - 1] - t[0]).abs();
    let tol = 1e-13 * span.max(a.abs()).max(1e-300);
    for k in t.iter_mut() {
        if (*k - a).abs() <= tol {
            *k = a;
        }
    }
    let mult = |t: &[f64]| t.iter().filter(|&&k| k == a).count();
    for _ in mult(t)..p {
        insert(t, p, rows, a)?;
    }
    let first = t.iter().position(|&k| k == a)?;
    let drop = (first + mult(t)).saturating_sub(p + 1);
    t.drain(..drop);
    for r in rows.iter_mut() {
        r.drain(..drop);
    }
    t[0] = a;
    Some(())
}

/// Inserts the knot `x` once into every curve (Boehm): the curves do not change.
fn insert(t: &mut Vec<f64>, p: usize, rows: &mut Grid, x: f64) -> Option<()> {
    // The span: t_k ≤ x < t_{k+1}.
    let k = t.iter().rposition(|&k| k <= x)?;
    if k < p || k + 1 >= t.len() {
        return None;
    }
    for r in rows.iter_mut() {
        let mut q = Vec::with_capacity(r.len() + 1);
        q.extend_from_slice(&r[..=k - p]);
        for i in k - p + 1..=k {
            let den = t[i + p] - t[i];
            let alpha = if den > 0.0 { (x - t[i]) / den } else { 0.0 };
            q.push(r[i] * alpha + r[i - 1] * (1.0 - alpha));
        }
        q.extend_from_slice(&r[k..]);
        *r = q;
    }
    t.insert(k + 1, x);
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use truck_stepio::r#in::alias::re_exports::{InnerSpace, ParametricCurve, ParametricSurface};

    /// Evaluates a (non-rational) B-spline of degree p at `x` from scratch, Cox–de Boor on
    /// the full knot vector with half-open spans: the definition, independent of truck.
    fn reference(t: &[f64], p: usize, pts: &[DVec4], x: f64) -> DVec4 {
        let n = pts.len();
        let mut basis: Vec<f64> = (0..t.len() - 1)
            .map(|i| f64::from(t[i] <= x && x < t[i + 1]))
            .collect();
        for d in 1..=p {
            for i in 0..t.len() - 1 - d {
                let l = if t[i + d] > t[i] {
                    (x - t[i]) / (t[i + d] - t[i]) * basis[i]
                } else {
                    0.0
                };
                let r = if t[i + d + 1] > t[i + 1] {
                    (t[i + d + 1] - x) / (t[i + d + 1] - t[i + 1]) * basis[i + 1]
                } else {
                    0.0
                };
                basis[i] = l + r;
            }
        }
        (0..n).map(|i| pts[i] * basis[i]).sum()
    }

    fn unclamped_curve() -> (Vec<f64>, usize, Vec<DVec4>) {
        // Uniform cubic, 7 control points: range [3, 7], nothing repeated.
        let t: Vec<f64> = (0..11).map(f64::from).collect();
        let pts = (0..7)
            .map(|i| {
                let a = f64::from(i);
                DVec4::new(a.cos() * 3.0, a.sin() * 2.0, 0.3 * a * a, 1.0)
            })
            .collect();
        (t, 3, pts)
    }

    #[test]
    fn clamping_keeps_every_point_of_the_range() {
        let (t, p, pts) = unclamped_curve();
        let (ct, rows) = clamp_direction(&t, p, vec![pts.clone()]).expect("unclamped");
        let q = &rows[0];
        assert_eq!(ct.len(), q.len() + p + 1);
        assert_eq!(&ct[..=p], &[3.0; 4]);
        assert_eq!(&ct[ct.len() - 1 - p..], &[7.0; 4]);
        for k in 0..400 {
            let x = 3.0 + 4.0 * f64::from(k) / 400.0;
            let d = reference(&t, p, &pts, x).distance(reference(&ct, p, q, x));
            assert!(d < 1e-12, "at {x}: {d}");
        }
        // The clamped curve ends at its last control point.
        let end = reference(&t, p, &pts, 7.0 - 1e-12);
        assert!(end.distance(q[q.len() - 1]) < 1e-9);
        assert!(
            clamp_direction(&ct, p, rows).is_none(),
            "clamping is idempotent"
        );
    }

    #[test]
    fn the_clamped_end_has_the_derivative_of_the_range_not_of_the_span_beyond() {
        // The spring of gen-1-14 in u: degree 6, knots (−2π, 0 ×6, 2π ×6, 4π), rational.
        let tau = std::f64::consts::TAU;
        let mut knots = vec![-tau];
        knots.extend([0.0; 6]);
        knots.extend([tau; 6]);
        knots.push(2.0 * tau);
        let pts: Vec<Vector4> = (0..7)
            .map(|i| {
                let a = f64::from(i) * 0.9;
                let w = 1.0 + 0.2 * a.sin();
                Vector4::new(a.cos() * w, a.sin() * w, a * w, w)
            })
            .collect();
        let c = Curve3D::NurbsCurve(NurbsCurve::new(BSplineCurve::new(
            KnotVec::from(knots),
            pts,
        )));
        let clamped = clamp_curve(&c).expect("unclamped");
        let near = tau - 1e-7;
        for x in [0.0, 1e-3, 1.0, 3.0, 5.0, near] {
            let d = (c.subs(x) - clamped.subs(x)).magnitude();
            assert!(d < 1e-10, "point at {x}: {d}");
        }
        // At the range's end: the derivative is the limit from inside.
        let inside = c.der(near);
        let at_end = clamped.der(tau);
        assert!((inside - at_end).magnitude() < 1e-4 * inside.magnitude());
        // (truck on the unclamped curve gives the span beyond: what this module exists for.)
        assert!((c.der(tau) - inside).magnitude() > 1e-2 * inside.magnitude());
    }

    #[test]
    fn surfaces_are_clamped_in_each_direction() {
        let (t, _, pts) = unclamped_curve();
        let grid: Vec<Vec<Point3>> = (0..7)
            .map(|i| {
                (0..5)
                    .map(|j| {
                        let q = pts[i];
                        Point3::new(
                            q.x + f64::from(j as u32),
                            q.y,
                            q.z * f64::from(j as u32 + 1),
                        )
                    })
                    .collect()
            })
            .collect();
        let kv = KnotVec::from(vec![0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0]);
        let s = TruckSurface::BSplineSurface(Box::new(BSplineSurface::new(
            (KnotVec::from(t), kv),
            grid,
        )));
        let c = clamp_surface(&s).expect("unclamped in u");
        let TruckSurface::BSplineSurface(b) = &c else {
            panic!("kind kept")
        };
        assert_eq!(b.knot_vecs().0[0], 3.0);
        assert_eq!(b.knot_vecs().1.len(), 7, "v already clamped");
        for i in 0..=20 {
            for j in 0..=10 {
                let (u, v) = (3.0 + 4.0 * f64::from(i) / 20.0, f64::from(j) / 10.0);
                let (u, v) = (u.min(7.0 - 1e-12), v.min(1.0 - 1e-12));
                let d = (s.subs(u, v) - c.subs(u, v)).magnitude();
                assert!(d < 1e-10, "({u}, {v}): {d}");
            }
        }
        assert!(clamp_surface(&c).is_none());
    }
}
