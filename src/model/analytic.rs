//! Our own evaluation of truck-stepio's analytic surfaces — plane, sphere, cylinder, cone,
//! torus — point, first and second derivatives, in closed form.
//!
//! truck evaluates a placed analytic surface as a `Processor`: the entity's point (a revolved
//! line for a cylinder or a cone, rotated by a 4 × 4 matrix built per point from two matrix
//! products, its sine and cosine taken again for every derivative) mapped through a 4 × 4
//! placement. Measured on kicad-demo-video's `stats`: 54 % of the fidelity measure in that
//! evaluation. Here the rotation is Rodrigues' formula on one sine and cosine per point
//! (R(θ) x = (a·x) a + cos θ (x − (a·x) a) + sin θ (a × x), a the unit axis; its θ-derivative
//! is R(θ)(a × x)), and the placement one 3 × 3 product and a translation, taken from the very
//! `Processor` truck would evaluate: the same entity, the same matrix, the same orientation
//! (`false`: u and v exchanged). The sphere and torus formulas are truck's own
//! (`truck_geometry::Sphere` with truck-stepio's latitude-first parameters, `Torus`), so a
//! point agrees with truck's to rounding (compared on random parameters in the tests, 1e-12
//! relative to the surface's size).
//!
//! Not taken (stay with truck, `Analytic::of` returns `None`): a placement that is not affine
//! (a last row other than (0, 0, 0, 1)), and swept surfaces. A surface of revolution of a
//! curve evaluated this way (the same rotation over truck's curve point) changed figures
//! beyond rounding — SOT23's revolved face #3521 read 1.819 ε instead of 0.741 ε, R_MELF's
//! bounding box moved by 1e-3 — and is not profiled hot on the boards (4 such surfaces on
//! kicad-demo-video), so it stays with truck until that is understood; an extrusion is
//! cheap in truck already (the sweep vector added to the curve's point).

use glam::{DMat3, DVec2, DVec3};
use truck_stepio::r#in::alias::ElementarySurface;
use truck_stepio::r#in::alias::re_exports::Matrix4;

use super::nurbs::Derivs;
use super::trimmed::{TruckSurface, to_dvec, vec_to_dvec};

/// An analytic surface as truck-stepio parametrises it, with its placement.
#[derive(Clone, Debug, PartialEq)]
pub struct Analytic {
    shape: Shape,
    /// The placement's linear part and translation (identity for a plane, which truck keeps
    /// placed in its points).
    linear: DMat3,
    translation: DVec3,
    /// truck's `orientation()`: `false` exchanges the parameters (the entity is evaluated at
    /// `(v, u)`).
    orientation: bool,
}

/// The entity before its placement, in truck's parameters.
#[derive(Clone, Debug, PartialEq)]
enum Shape {
    /// `o + u du + v dv`.
    Plane { o: DVec3, du: DVec3, dv: DVec3 },
    /// truck-stepio's sphere: u the longitude, v the latitude.
    Sphere { center: DVec3, radius: f64 },
    /// `center + ((R + r cos v) cos u, (R + r cos v) sin u, r sin v)`.
    Torus {
        center: DVec3,
        major: f64,
        minor: f64,
    },
    /// The line `p + u d` (truck's `Line::subs`: `p0 + (p1 − p0) u`) turned by the angle v
    /// about the line through `origin` along the unit `axis` (right-handed): truck-stepio's
    /// cylinder and cone.
    Revolution {
        origin: DVec3,
        axis: DVec3,
        p: DVec3,
        d: DVec3,
    },
}

impl Analytic {
    /// Our evaluation of `s` when it is an analytic surface with an affine placement; `None`
    /// otherwise.
    pub fn of(s: &TruckSurface) -> Option<Analytic> {
        let out = match s {
            TruckSurface::ElementarySurface(e) => match e.as_ref() {
                ElementarySurface::Plane(p) => Some(Analytic {
                    shape: Shape::Plane {
                        o: to_dvec(p.origin()),
                        du: vec_to_dvec(p.u_axis()),
                        dv: vec_to_dvec(p.v_axis()),
                    },
                    linear: DMat3::IDENTITY,
                    translation: DVec3::ZERO,
                    orientation: true,
                }),
                ElementarySurface::Sphere(p) => {
                    let sphere = p.entity().0;
                    Analytic::placed(
                        Shape::Sphere {
                            center: to_dvec(sphere.center()),
                            radius: sphere.radius(),
                        },
                        p.transform(),
                        p.orientation(),
                    )
                }
                ElementarySurface::ToroidalSurface(p) => {
                    let t = p.entity();
                    Analytic::placed(
                        Shape::Torus {
                            center: to_dvec(t.center()),
                            major: t.large_radius(),
                            minor: t.small_radius(),
                        },
                        p.transform(),
                        p.orientation(),
                    )
                }
                ElementarySurface::CylindricalSurface(p) | ElementarySurface::ConicalSurface(p) => {
                    let r = p.entity();
                    let line = r.entity_curve();
                    Analytic::placed(
                        Shape::Revolution {
                            origin: to_dvec(r.origin()),
                            axis: vec_to_dvec(r.axis()),
                            p: to_dvec(line.0),
                            d: to_dvec(line.1) - to_dvec(line.0),
                        },
                        p.transform(),
                        p.orientation(),
                    )
                }
            },
            TruckSurface::SweptCurve(_)
            | TruckSurface::BSplineSurface(_)
            | TruckSurface::NurbsSurface(_) => None,
        }?;
        let finite = match &out.shape {
            Shape::Plane { o, du, dv } => o.is_finite() && du.is_finite() && dv.is_finite(),
            Shape::Sphere { center, radius } => center.is_finite() && radius.is_finite(),
            Shape::Torus {
                center,
                major,
                minor,
            } => center.is_finite() && major.is_finite() && minor.is_finite(),
            Shape::Revolution { origin, axis, p, d } => {
                origin.is_finite() && axis.is_finite() && p.is_finite() && d.is_finite()
            }
        };
        (finite && out.linear.is_finite() && out.translation.is_finite()).then_some(out)
    }

    /// `shape` placed by truck's column-major `m` (`m[c][r]`), when `m` is affine.
    fn placed(shape: Shape, m: &Matrix4, orientation: bool) -> Option<Analytic> {
        let col = |c: usize| DVec3::new(m[c][0], m[c][1], m[c][2]);
        let affine = m[0][3] == 0.0 && m[1][3] == 0.0 && m[2][3] == 0.0 && m[3][3] == 1.0;
        affine.then(|| Analytic {
            shape,
            linear: DMat3::from_cols(col(0), col(1), col(2)),
            translation: col(3),
            orientation,
        })
    }

    /// Point, first and (for `order` 2) second derivatives at `uv`: `[S, S_u, S_v, S_uu, S_uv,
    /// S_vv]` (the derivatives not asked for are zero).
    #[inline(always)]
    pub(crate) fn eval(&self, uv: DVec2, order: usize) -> Derivs {
        let mut d = if self.orientation {
            self.shape.eval(uv.x, uv.y, order)
        } else {
            let mut d = self.shape.eval(uv.y, uv.x, order);
            d.swap(1, 2);
            d.swap(3, 5);
            d
        };
        // As cgmath's `Matrix4 * Vector4`: columns summed in order, w = 1 for the point and 0
        // for a vector.
        d[0] = self.map(d[0]) + self.translation;
        let last = match order {
            0 => 0,
            1 => 2,
            _ => 5,
        };
        for x in &mut d[1..=last] {
            *x = self.map(*x);
        }
        d
    }

    /// The placement's linear part applied to `x`.
    #[inline]
    fn map(&self, x: DVec3) -> DVec3 {
        let l = &self.linear;
        l.x_axis * x.x + l.y_axis * x.y + l.z_axis * x.z
    }
}

impl Shape {
    /// The entity's point and derivatives at `(u, v)` in truck's parameters.
    #[inline(always)]
    fn eval(&self, u: f64, v: f64, order: usize) -> Derivs {
        let mut out = [DVec3::ZERO; 6];
        match self {
            Shape::Plane { o, du, dv } => {
                // truck's `Plane::subs`: `o + u (p − o) + v (q − o)`.
                out[0] = *o + *du * u + *dv * v;
                out[1] = *du;
                out[2] = *dv;
            }
            Shape::Sphere { center, radius } => {
                // truck-stepio's sphere at (u, v) is truck's at colatitude s = π/2 − v,
                // longitude u.
                let s = std::f64::consts::FRAC_PI_2 - v;
                let (ss, cs) = (s.sin(), s.cos());
                let (su, cu) = (u.sin(), u.cos());
                let n = DVec3::new(ss * cu, ss * su, cs);
                out[0] = *center + *radius * n;
                if order >= 1 {
                    out[1] = *radius * ss * DVec3::new(-su, cu, 0.0);
                    out[2] = -(*radius * DVec3::new(cs * cu, cs * su, -ss));
                }
                if order >= 2 {
                    out[3] = -*radius * ss * DVec3::new(cu, su, 0.0);
                    out[4] = -(*radius * cs * DVec3::new(-su, cu, 0.0));
                    out[5] = -*radius * n;
                }
            }
            Shape::Torus {
                center,
                major,
                minor,
            } => {
                let (su, cu) = (u.sin(), u.cos());
                let (sv, cv) = (v.sin(), v.cos());
                let ring = major + minor * cv;
                out[0] = *center + DVec3::new(ring * cu, ring * su, minor * sv);
                if order >= 1 {
                    out[1] = DVec3::new(-(ring * su), ring * cu, 0.0);
                    let s = -minor * sv;
                    out[2] = DVec3::new(s * cu, s * su, minor * cv);
                }
                if order >= 2 {
                    out[3] = DVec3::new(-(ring * cu), -(ring * su), 0.0);
                    let s = -minor * sv;
                    out[4] = DVec3::new(-(s * su), s * cu, 0.0);
                    let c = -minor * cv;
                    out[5] = DVec3::new(c * cu, c * su, -minor * sv);
                }
            }
            Shape::Revolution { origin, axis, p, d } => {
                let (s, c) = (v.sin(), v.cos());
                let a = *axis;
                // Rodrigues: the rotation by v about the unit axis.
                let rot = |x: DVec3| {
                    let along = a * a.dot(x);
                    along + (x - along) * c + a.cross(x) * s
                };
                let w = (*p + *d * u) - *origin;
                out[0] = *origin + rot(w);
                if order >= 1 {
                    out[1] = rot(*d);
                    out[2] = rot(a.cross(w));
                }
                if order >= 2 {
                    // The line's second derivative is zero.
                    out[4] = rot(a.cross(*d));
                    out[5] = rot(a.cross(a.cross(w)));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::trimmed::SurfaceEval;
    use truck_stepio::r#in::alias::re_exports::{
        InnerSpace, Invertible, KnotVec, Line, Plane, Point3, Processor, RevolutedCurve, Sphere,
        Torus, Transformed, Vector3,
    };

    /// A deterministic generator of uniform numbers in [0, 1).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, a: f64, b: f64) -> f64 {
            a + (b - a) * self.next()
        }
        fn vector(&mut self, r: f64) -> Vector3 {
            Vector3::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
        }
    }

    /// A random rigid placement (an axis-angle rotation, a translation), as a STEP
    /// `AXIS2_PLACEMENT_3D` gives.
    fn placement(rng: &mut Rng) -> Matrix4 {
        use truck_stepio::r#in::alias::re_exports::Rad;
        let axis = rng.vector(1.0).normalize();
        Matrix4::from_translation(rng.vector(50.0))
            * Matrix4::from_axis_angle(axis, Rad(rng.range(-3.0, 3.0)))
    }

    /// One of each surface kind truck-stepio makes, placed at random, in both orientations
    /// where the kind has one.
    fn surfaces(rng: &mut Rng) -> Vec<(&'static str, TruckSurface)> {
        let elementary = |e| TruckSurface::ElementarySurface(Box::new(e));
        let m = placement(rng);
        let o = Point3::new(
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
        );
        let plane = Plane::new(o, o + rng.vector(3.0), o + rng.vector(3.0));
        let sphere = Processor::new(truck_stepio::r#in::alias::Sphere(Sphere::new(
            Point3::new(0.0, 0.0, 0.0),
            rng.range(0.5, 20.0),
        )))
        .transformed(m);
        let torus = Processor::new(Torus::new(
            Point3::new(0.0, 0.0, 0.0),
            rng.range(2.0, 20.0),
            rng.range(0.1, 2.0),
        ))
        .transformed(placement(rng));
        // truck-stepio's cylinder: the line at the radius along the axis, revolved, inverted.
        let r = rng.range(0.1, 10.0);
        let centre = Point3::new(1.0, -2.0, 3.0);
        let z = rng.vector(1.0);
        let p = centre + rng.vector(1.0).cross(z).normalize_to(r);
        let mut cylinder = Processor::new(RevolutedCurve::by_revolution(Line(p, p + z), centre, z));
        cylinder.invert();
        // Its cone: the line (r, 0, 0) + t (tan α, 0, 1) about z, placed, inverted.
        let q = Point3::new(rng.range(0.0, 5.0), 0.0, 0.0);
        let slope = Vector3::new(rng.range(-1.5, 1.5), 0.0, 1.0);
        let mut cone = Processor::new(RevolutedCurve::by_revolution(
            Line(q, q + slope),
            Point3::new(0.0, 0.0, 0.0),
            Vector3::unit_z(),
        ));
        cone.transform_by(placement(rng));
        let uninverted = cone;
        cone.invert();
        vec![
            ("plane", elementary(ElementarySurface::Plane(plane))),
            ("sphere", elementary(ElementarySurface::Sphere(sphere))),
            (
                "torus",
                elementary(ElementarySurface::ToroidalSurface(torus)),
            ),
            (
                "cylinder",
                elementary(ElementarySurface::CylindricalSurface(cylinder)),
            ),
            ("cone", elementary(ElementarySurface::ConicalSurface(cone))),
            (
                "cone, not inverted",
                elementary(ElementarySurface::ConicalSurface(uninverted)),
            ),
        ]
    }

    /// Our point and derivatives agree with truck's on every analytic surface kind, at random
    /// parameters (angles over several turns, lines beyond their nominal range), within 1e-12
    /// of the size of the values compared (and of the surface: a derivative that truck gives as
    /// zero is zero to rounding here).
    #[test]
    fn analytic_evaluation_agrees_with_truck() {
        let mut rng = Rng(31);
        let mut compared = 0;
        for _ in 0..20 {
            for (name, s) in surfaces(&mut rng) {
                let ours = Analytic::of(&s).unwrap_or_else(|| panic!("{name}: not taken"));
                for _ in 0..50 {
                    let uv = DVec2::new(rng.range(-7.0, 7.0), rng.range(-7.0, 7.0));
                    let d = ours.eval(uv, 2);
                    let (tu, tv) = s.derivs(uv);
                    let (tuu, tuv, tvv) = s.second_derivs(uv);
                    let want = [s.point(uv), tu, tv, tuu, tuv, tvv];
                    let size = want.iter().map(|w| w.length()).fold(1.0, f64::max);
                    for (i, (a, b)) in d.iter().zip(want).enumerate() {
                        let scale = size.max(b.length());
                        assert!(
                            a.distance(b) <= 1e-12 * scale,
                            "{name} at {uv}: #{i} ours {a} truck {b} ({:e} relative)",
                            a.distance(b) / scale
                        );
                        compared += 1;
                    }
                    // Lower orders give the same point and first derivatives.
                    let d1 = ours.eval(uv, 1);
                    assert_eq!(d1[..3], d[..3], "{name}: order 1");
                    assert_eq!(ours.eval(uv, 0)[0], d[0], "{name}: order 0");
                }
            }
        }
        assert_eq!(compared, 20 * 6 * 50 * 6);
    }

    /// B-splines (our `nurbs` module's), extrusions and surfaces of revolution are not taken
    /// here.
    #[test]
    fn bsplines_and_swept_surfaces_are_not_taken() {
        use truck_stepio::r#in::alias::SweptCurve;
        use truck_stepio::r#in::alias::re_exports::{BSplineSurface, ExtrudedCurve};
        let b = BSplineSurface::new(
            (KnotVec::bezier_knot(1), KnotVec::bezier_knot(1)),
            vec![
                vec![Point3::new(0.0, 0.0, 0.0), Point3::new(0.0, 1.0, 0.0)],
                vec![Point3::new(1.0, 0.0, 0.0), Point3::new(1.0, 1.0, 0.0)],
            ],
        );
        assert!(Analytic::of(&TruckSurface::BSplineSurface(Box::new(b))).is_none());
        let line = truck_stepio::r#in::alias::Curve3D::Line(Line(
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
        ));
        let e = ExtrudedCurve::by_extrusion(line.clone(), Vector3::unit_z());
        let s = TruckSurface::SweptCurve(Box::new(SweptCurve::ExtrudedCurve(e)));
        assert!(Analytic::of(&s).is_none());
        let r = Processor::new(RevolutedCurve::by_revolution(
            line,
            Point3::new(0.0, 1.0, 0.0),
            Vector3::unit_x(),
        ));
        let s = TruckSurface::SweptCurve(Box::new(SweptCurve::RevolutedCurve(r)));
        assert!(Analytic::of(&s).is_none());
    }
}
