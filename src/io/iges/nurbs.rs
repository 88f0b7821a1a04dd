//! IGES curves and surfaces as (rational) B-splines before they become truck types: the
//! representation every curve entity is converted to (lines and circular arcs exactly,
//! Piegl & Tiller, *The NURBS Book*, §7.5 for the arc), so that a transformation matrix (124)
//! applies to control points only, and one conversion to truck's `Curve3D` / `Curve2D` /
//! `Surface` serves them all.

use glam::{DMat4, DVec3};
use truck_stepio::r#in::alias::re_exports::{
    BSplineCurve, BSplineSurface, KnotVec, NurbsCurve, NurbsSurface, Point2, Point3, Vector3,
    Vector4,
};
use truck_stepio::r#in::alias::{Curve2D, Curve3D, ElementarySurface, Surface};

/// A B-spline curve (rational when `weights` is given), used on `[t0, t1]`.
#[derive(Clone, Debug)]
pub struct Nurbs {
    pub degree: usize,
    pub knots: Vec<f64>,
    pub points: Vec<DVec3>,
    pub weights: Option<Vec<f64>>,
    pub t0: f64,
    pub t1: f64,
}

/// Why a B-spline cannot be used.
pub(crate) fn check_bspline(
    degree: usize,
    knots: &[f64],
    n_points: usize,
    weights: Option<&[f64]>,
) -> Result<(), String> {
    if degree == 0 {
        return Err("degree 0".into());
    }
    if knots.len() != n_points + degree + 1 {
        return Err(format!(
            "{} knots for {n_points} control points of degree {degree}",
            knots.len()
        ));
    }
    if knots.windows(2).any(|w| w[1] < w[0]) || knots.iter().any(|k| !k.is_finite()) {
        return Err("the knots decrease or are not finite".into());
    }
    if knots[degree] >= knots[n_points] {
        return Err("the knot vector has an empty parameter range".into());
    }
    if let Some(w) = weights
        && w.iter().any(|w| !(w.is_finite() && *w > 0.0))
    {
        return Err("a weight is not positive".into());
    }
    Ok(())
}

impl Nurbs {
    /// A line segment from `a` to `b`, parameter 0..1.
    pub fn line(a: DVec3, b: DVec3) -> Nurbs {
        Nurbs {
            degree: 1,
            knots: vec![0.0, 0.0, 1.0, 1.0],
            points: vec![a, b],
            weights: None,
            t0: 0.0,
            t1: 1.0,
        }
    }

    /// A circular arc about `c` in the plane z = `c.z`, counter-clockwise from angle `a0` by
    /// `sweep` (0 < sweep ≤ 2π), radius `r`: rational quadratic, one span per quarter at most.
    pub fn arc(c: DVec3, r: f64, a0: f64, sweep: f64) -> Nurbs {
        let spans = (sweep / std::f64::consts::FRAC_PI_2 - 1e-9).ceil().max(1.0) as usize;
        let d = sweep / spans as f64;
        let w = (0.5 * d).cos();
        let at = |a: f64, s: f64| c + DVec3::new(a.cos(), a.sin(), 0.0) * r * s;
        let mut points = vec![at(a0, 1.0)];
        let mut weights = vec![1.0];
        let mut knots = vec![0.0; 3];
        for k in 0..spans {
            let a = a0 + d * k as f64;
            points.push(at(a + 0.5 * d, 1.0 / w));
            weights.push(w);
            points.push(at(a + d, 1.0));
            weights.push(1.0);
            let t = (k + 1) as f64;
            let multiplicity = if k + 1 == spans { 3 } else { 2 };
            knots.extend(std::iter::repeat_n(t, multiplicity));
        }
        Nurbs {
            degree: 2,
            knots,
            points,
            weights: Some(weights),
            t0: 0.0,
            t1: spans as f64,
        }
    }

    pub(crate) fn transformed(mut self, m: &DMat4) -> Nurbs {
        for p in &mut self.points {
            *p = m.transform_point3(*p);
        }
        self
    }

    /// As a truck 3D curve.
    pub(crate) fn curve3d(&self) -> Result<Curve3D, String> {
        let knots = KnotVec::from(self.knots.clone());
        let p3 = |p: &DVec3| Point3::new(p.x, p.y, p.z);
        Ok(match &self.weights {
            None => Curve3D::BSplineCurve(
                BSplineCurve::try_new(knots, self.points.iter().map(p3).collect())
                    .map_err(|e| e.to_string())?,
            ),
            Some(w) => Curve3D::NurbsCurve(NurbsCurve::new(
                BSplineCurve::try_new(
                    knots,
                    self.points
                        .iter()
                        .zip(w)
                        .map(|(p, w)| Vector4::new(p.x * w, p.y * w, p.z * w, *w))
                        .collect(),
                )
                .map_err(|e| e.to_string())?,
            )),
        })
    }

    /// As a truck 2D curve (x, y of the control points: a parameter-space curve).
    pub(crate) fn curve2d(&self) -> Result<Curve2D, String> {
        let knots = KnotVec::from(self.knots.clone());
        Ok(match &self.weights {
            None => Curve2D::BSplineCurve(
                BSplineCurve::try_new(
                    knots,
                    self.points.iter().map(|p| Point2::new(p.x, p.y)).collect(),
                )
                .map_err(|e| e.to_string())?,
            ),
            Some(w) => Curve2D::NurbsCurve(NurbsCurve::new(
                BSplineCurve::try_new(
                    knots,
                    self.points
                        .iter()
                        .zip(w)
                        .map(|(p, w)| Vector3::new(p.x * w, p.y * w, *w))
                        .collect(),
                )
                .map_err(|e| e.to_string())?,
            )),
        })
    }
}

/// A B-spline surface (rational when `weights` is given): `points[i][j]`, i along u.
#[derive(Clone, Debug)]
pub struct NurbsPatch {
    pub degrees: (usize, usize),
    pub knots: (Vec<f64>, Vec<f64>),
    pub points: Vec<Vec<DVec3>>,
    pub weights: Option<Vec<Vec<f64>>>,
    /// The parameter rectangle the entity uses: (u0, u1, v0, v1).
    pub range: (f64, f64, f64, f64),
}

impl NurbsPatch {
    pub(crate) fn transformed(mut self, m: &DMat4) -> NurbsPatch {
        for p in self.points.iter_mut().flatten() {
            *p = m.transform_point3(*p);
        }
        self
    }

    /// As a truck surface, its knot vectors clamped (`model::knots`).
    pub fn surface(&self) -> Result<Surface, String> {
        let knots = (
            KnotVec::from(self.knots.0.clone()),
            KnotVec::from(self.knots.1.clone()),
        );
        let s = match &self.weights {
            None => Surface::BSplineSurface(Box::new(
                BSplineSurface::try_new(
                    knots,
                    self.points
                        .iter()
                        .map(|row| row.iter().map(|p| Point3::new(p.x, p.y, p.z)).collect())
                        .collect(),
                )
                .map_err(|e| e.to_string())?,
            )),
            Some(w) => Surface::NurbsSurface(Box::new(NurbsSurface::new(
                BSplineSurface::try_new(
                    knots,
                    self.points
                        .iter()
                        .zip(w)
                        .map(|(row, wr)| {
                            row.iter()
                                .zip(wr)
                                .map(|(p, w)| Vector4::new(p.x * w, p.y * w, p.z * w, *w))
                                .collect()
                        })
                        .collect(),
                )
                .map_err(|e| e.to_string())?,
            ))),
        };
        Ok(crate::model::knots::clamp_surface(&s).unwrap_or(s))
    }
}

/// A surface entity: a B-spline patch, or a plane (108, 190) parametrised by arc length along
/// two orthonormal axes from `origin` (no finite parameter range).
#[derive(Clone, Debug)]
pub enum SurfaceDef {
    Nurbs(NurbsPatch),
    Plane { origin: DVec3, x: DVec3, y: DVec3 },
}

impl SurfaceDef {
    pub(crate) fn transformed(self, m: &DMat4) -> SurfaceDef {
        match self {
            SurfaceDef::Nurbs(n) => SurfaceDef::Nurbs(n.transformed(m)),
            SurfaceDef::Plane { origin, x, y } => SurfaceDef::Plane {
                origin: m.transform_point3(origin),
                x: m.transform_vector3(x),
                y: m.transform_vector3(y),
            },
        }
    }

    pub fn surface(&self) -> Result<Surface, String> {
        match self {
            SurfaceDef::Nurbs(n) => n.surface(),
            SurfaceDef::Plane { origin: o, x, y } => {
                let p = |v: DVec3| Point3::new(v.x, v.y, v.z);
                let plane = truck_stepio::r#in::alias::re_exports::Plane::new(
                    p(*o),
                    p(*o + *x),
                    p(*o + *y),
                );
                Ok(Surface::ElementarySurface(Box::new(
                    ElementarySurface::Plane(plane),
                )))
            }
        }
    }

    /// The parameter rectangle a whole patch covers; `None` for an unbounded plane.
    pub fn range(&self) -> Option<(f64, f64, f64, f64)> {
        match self {
            SurfaceDef::Nurbs(n) => Some(n.range),
            SurfaceDef::Plane { .. } => None,
        }
    }
}
