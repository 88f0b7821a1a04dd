//! Parameter data of the IGES 5.3 entities the reader draws (§4): 100 circular arc, 102
//! composite curve, 110 line, 124 transformation matrix, 126 rational B-spline curve, 128
//! rational B-spline surface, 314 colour definition. Each entity's own transformation
//! (directory field 7, a 124 that may itself point to another) is applied to its control
//! points, so curves and surfaces come out in their parent's coordinates.
//!
//! References are followed with a stack of the DEs being decoded: a DE met again while it is
//! being decoded is a [`IgesError::Cycle`]; nesting is bounded by `MAX_DEPTH`. Counts in the
//! parameters are checked against the parameters present before anything is allocated.

use glam::{DMat4, DVec3, DVec4};

use super::IgesError;
use super::directory::{Entry, IgesFile};
use super::nurbs::{Nurbs, NurbsPatch, SurfaceDef, check_bspline};
use super::sections::Param;

/// Most references followed from one entity (composite curves in composite curves, matrices
/// composed with matrices).
pub(crate) const MAX_DEPTH: usize = 64;

/// An entity's parameters, with typed access that names the DE and parameter on failure.
#[derive(Debug)]
pub struct Params {
    pub de: usize,
    pub p: Vec<Param>,
}

impl Params {
    fn missing(&self, index: usize, what: &str) -> IgesError {
        IgesError::MissingParameter {
            de: self.de,
            index,
            what: what.into(),
        }
    }

    pub fn real(&self, index: usize, what: &str) -> Result<f64, IgesError> {
        match self.p.get(index) {
            None | Some(Param::Empty) => Err(self.missing(index, what)),
            Some(p) => p.real().ok_or_else(|| IgesError::BadParameter {
                de: self.de,
                index,
                reason: format!("{what} is {p:?}, not a number"),
            }),
        }
    }

    /// A real with a default for an empty or absent parameter.
    pub(crate) fn real_or(&self, index: usize, default: f64) -> Result<f64, IgesError> {
        match self.p.get(index) {
            None | Some(Param::Empty) => Ok(default),
            Some(_) => self.real(index, "parameter"),
        }
    }

    pub fn int(&self, index: usize, what: &str) -> Result<i64, IgesError> {
        match self.p.get(index) {
            None | Some(Param::Empty) => Err(self.missing(index, what)),
            Some(p) => p.int().ok_or_else(|| IgesError::BadParameter {
                de: self.de,
                index,
                reason: format!("{what} is {p:?}, not an integer"),
            }),
        }
    }

    /// A count in `0..=limit` (`limit`: what the parameters present can hold).
    pub fn count(&self, index: usize, what: &str, limit: usize) -> Result<usize, IgesError> {
        let n = self.int(index, what)?;
        if n < 0 || n as u64 > limit as u64 {
            return Err(IgesError::BadParameter {
                de: self.de,
                index,
                reason: format!(
                    "{what} is {n}, but the entity has {} parameters",
                    self.p.len()
                ),
            });
        }
        Ok(n as usize)
    }

    /// Checks that parameters `1..=last` are present (an entity cut short).
    fn need(&self, last: usize, what: &str) -> Result<(), IgesError> {
        if last >= self.p.len() {
            return Err(self.missing(self.p.len(), what));
        }
        Ok(())
    }

    fn reals(&self, from: usize, n: usize, what: &str) -> Result<Vec<f64>, IgesError> {
        self.need(from + n - 1, what)?;
        (from..from + n).map(|i| self.real(i, what)).collect()
    }

    fn point(&self, from: usize, what: &str) -> Result<DVec3, IgesError> {
        Ok(DVec3::new(
            self.real(from, what)?,
            self.real(from + 1, what)?,
            self.real(from + 2, what)?,
        ))
    }
}

/// Decodes entities of one file, following references.
#[derive(Debug)]
pub struct Decoder<'f, 'a> {
    pub file: &'f IgesFile<'a>,
    stack: Vec<usize>,
    /// Boundaries given by both curves whose parameter-space curve strays from the
    /// model-space one (the model-space curve is used), and how many gave both.
    pub disagreeing: (usize, usize),
}

impl<'f, 'a> Decoder<'f, 'a> {
    pub fn new(file: &'f IgesFile<'a>) -> Self {
        Decoder {
            file,
            stack: Vec::new(),
            disagreeing: (0, 0),
        }
    }

    /// Runs `f` on the entry DE `de` (pointed to by `from` as `what`), with `de` on the stack.
    pub(crate) fn visit<T>(
        &mut self,
        de: i64,
        from: usize,
        what: &str,
        f: impl FnOnce(&mut Self, &Entry) -> Result<T, IgesError>,
    ) -> Result<T, IgesError> {
        let e = self.file.entry(de, from, what)?;
        if let Some(k) = self.stack.iter().position(|&d| d == e.de) {
            let path: Vec<String> = self.stack[k..]
                .iter()
                .chain([&e.de])
                .map(|d| d.to_string())
                .collect();
            return Err(IgesError::Cycle {
                de: e.de,
                path: path.join(" → "),
            });
        }
        if self.stack.len() >= MAX_DEPTH {
            return Err(IgesError::Invalid {
                de: e.de,
                reason: format!("references nested more than {MAX_DEPTH} deep"),
            });
        }
        self.stack.push(e.de);
        let r = f(self, e);
        self.stack.pop();
        r
    }

    /// Forgets the DEs being decoded (after a decoding that panicked, see
    /// [`crate::isolate::isolated`]).
    pub fn reset(&mut self) {
        self.stack.clear();
    }

    pub fn params(&self, e: &Entry) -> Result<Params, IgesError> {
        Ok(Params {
            de: e.de,
            p: self.file.params(e)?,
        })
    }

    /// The placement of entity `e`: its transformation matrix (field 7), composed with the
    /// matrices that matrix points to; the identity when there is none.
    pub fn placement(&mut self, e: &Entry) -> Result<DMat4, IgesError> {
        if e.transform == 0 {
            return Ok(DMat4::IDENTITY);
        }
        self.visit(
            e.transform,
            e.de,
            "transformation matrix (field 7)",
            |d, m| {
                expect_type(m, &[124])?;
                let p = d.params(m)?;
                let r = p.reals(1, 12, "matrix element")?;
                let own = DMat4::from_cols(
                    DVec4::new(r[0], r[4], r[8], 0.0),
                    DVec4::new(r[1], r[5], r[9], 0.0),
                    DVec4::new(r[2], r[6], r[10], 0.0),
                    DVec4::new(r[3], r[7], r[11], 1.0),
                );
                Ok(d.placement(m)? * own)
            },
        )
    }

    /// The curve DE `de` (pointed to by `from`) as B-spline segments with the DE each came
    /// from, in the pointing entity's coordinates.
    pub fn curve(
        &mut self,
        de: i64,
        from: usize,
        what: &str,
    ) -> Result<Vec<(usize, Nurbs)>, IgesError> {
        self.visit(de, from, what, |d, e| {
            let p = d.params(e)?;
            let segments = match e.entity_type {
                110 => vec![(e.de, Nurbs::line(p.point(1, "start")?, p.point(4, "end")?))],
                100 => vec![(e.de, arc(&p)?)],
                126 => vec![(e.de, bspline_curve(&p)?)],
                102 => {
                    let n = p.count(1, "number of curves", p.p.len())?;
                    p.need(1 + n, "curve pointer")?;
                    let mut out = Vec::new();
                    for i in 0..n {
                        let c = p.int(2 + i, "curve pointer")?;
                        out.extend(d.curve(c, e.de, "curve of the composite curve")?);
                    }
                    out
                }
                t => {
                    return Err(IgesError::Unsupported {
                        de: e.de,
                        entity_type: t,
                        role: "curve".into(),
                    });
                }
            };
            let m = d.placement(e)?;
            Ok(segments
                .into_iter()
                .map(|(de, c)| (de, c.transformed(&m)))
                .collect())
        })
    }

    /// The surface DE `de` (pointed to by `from`), in the pointing entity's coordinates.
    pub fn surface(&mut self, de: i64, from: usize) -> Result<SurfaceDef, IgesError> {
        self.visit(de, from, "surface", |d, e| {
            expect_type(e, &[128, 108, 190])?;
            let p = d.params(e)?;
            let s = match e.entity_type {
                128 => SurfaceDef::Nurbs(bspline_surface(&p)?),
                108 => {
                    // A x + B y + C z = D.
                    let n = p.point(1, "plane coefficient")?;
                    let dist = p.real(4, "plane coefficient D")?;
                    plane(e.de, n * dist / n.length_squared(), n, None)?
                }
                _ => {
                    // 190: a point (116), the normal and, for form 1, a reference direction (123).
                    let at = d.point(p.int(1, "location DELOC")?, e.de)?;
                    let n = d.direction(p.int(2, "normal DENRML")?, e.de)?;
                    let r = match p.int(3, "reference direction DEREFD").unwrap_or(0) {
                        0 => None,
                        r => Some(d.direction(r, e.de)?),
                    };
                    plane(e.de, at, n, r)?
                }
            };
            Ok(s.transformed(&d.placement(e)?))
        })
    }

    /// A point (116), in the pointing entity's coordinates.
    fn point(&mut self, de: i64, from: usize) -> Result<DVec3, IgesError> {
        self.visit(de, from, "point", |d, e| {
            expect_type(e, &[116])?;
            let q = d.params(e)?.point(1, "point")?;
            Ok(d.placement(e)?.transform_point3(q))
        })
    }

    /// A direction (123), in the pointing entity's coordinates.
    fn direction(&mut self, de: i64, from: usize) -> Result<DVec3, IgesError> {
        self.visit(de, from, "direction", |d, e| {
            expect_type(e, &[123])?;
            let v = d.params(e)?.point(1, "direction")?;
            Ok(d.placement(e)?.transform_vector3(v))
        })
    }

    /// The colour of entity `e`: a standard colour number, or a colour definition (314).
    pub fn color(&mut self, e: &Entry) -> Option<[f32; 3]> {
        const STANDARD: [[f32; 3]; 8] = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 0.0],
            [1.0, 0.0, 1.0],
            [0.0, 1.0, 1.0],
            [1.0, 1.0, 1.0],
        ];
        match e.color {
            1..=8 => Some(STANDARD[(e.color - 1) as usize]),
            c if c < 0 => self
                .visit(-c, e.de, "colour", |d, c| {
                    expect_type(c, &[314])?;
                    let p = d.params(c)?;
                    let v = p.reals(1, 3, "colour component")?;
                    Ok([0, 1, 2].map(|k| (v[k] / 100.0).clamp(0.0, 1.0) as f32))
                })
                .ok(),
            _ => None,
        }
    }
}

pub(crate) fn expect_type(e: &Entry, types: &[i64]) -> Result<(), IgesError> {
    if types.contains(&e.entity_type) {
        return Ok(());
    }
    let list: Vec<String> = types.iter().map(i64::to_string).collect();
    Err(IgesError::Unsupported {
        de: e.de,
        entity_type: e.entity_type,
        role: format!("entity of type {}", list.join(" or ")),
    })
}

/// 100: a circular arc in the plane z = ZT, counter-clockwise from its start to its end point
/// (a full circle when they coincide).
fn arc(p: &Params) -> Result<Nurbs, IgesError> {
    let z = p.real(1, "ZT")?;
    let c = DVec3::new(p.real(2, "centre x")?, p.real(3, "centre y")?, z);
    let s = DVec3::new(p.real(4, "start x")?, p.real(5, "start y")?, z);
    let t = DVec3::new(p.real(6, "end x")?, p.real(7, "end y")?, z);
    let r = s.distance(c);
    if !(r > 0.0 && r.is_finite()) {
        return Err(IgesError::Invalid {
            de: p.de,
            reason: "the arc has radius 0".into(),
        });
    }
    let a0 = (s.y - c.y).atan2(s.x - c.x);
    let a1 = (t.y - c.y).atan2(t.x - c.x);
    let tau = std::f64::consts::TAU;
    let mut sweep = (a1 - a0).rem_euclid(tau);
    if sweep <= 1e-12 * tau || s.distance(t) <= 1e-12 * r {
        sweep = tau;
    }
    Ok(Nurbs::arc(c, r, a0, sweep))
}

fn invalid(de: usize) -> impl Fn(String) -> IgesError {
    move |reason| IgesError::Invalid { de, reason }
}

/// 126: upper index K, degree M, 4 flags, knots, weights, control points, V0, V1.
fn bspline_curve(p: &Params) -> Result<Nurbs, IgesError> {
    let len = p.p.len();
    let k = p.count(1, "upper index K", len)?;
    let m = p.count(2, "degree M", len)?;
    let polynomial = p.int(5, "PROP3")? == 1;
    let n = k + 1;
    let knots = p.reals(7, n + m + 1, "knot")?;
    let w0 = 7 + n + m + 1;
    let weights = p.reals(w0, n, "weight")?;
    let c0 = w0 + n;
    p.need(c0 + 3 * n + 1, "control point or parameter range")?;
    let points = (0..n)
        .map(|i| p.point(c0 + 3 * i, "control point"))
        .collect::<Result<Vec<_>, _>>()?;
    let weights = (!polynomial && weights.iter().any(|w| *w != weights[0])).then_some(weights);
    check_bspline(m, &knots, n, weights.as_deref()).map_err(invalid(p.de))?;
    let (lo, hi) = (knots[m], knots[n]);
    let t0 = p.real_or(c0 + 3 * n, lo)?.clamp(lo, hi);
    let t1 = p.real_or(c0 + 3 * n + 1, hi)?.clamp(lo, hi);
    if t1 <= t0 {
        return Err(IgesError::Invalid {
            de: p.de,
            reason: format!("empty parameter range V0 = {t0}, V1 = {t1}"),
        });
    }
    Ok(Nurbs {
        degree: m,
        knots,
        points,
        weights,
        t0,
        t1,
    })
}

/// 128: upper indices K1, K2, degrees M1, M2, 5 flags, both knot vectors, weights and control
/// points (u fastest), U0, U1, V0, V1.
fn bspline_surface(p: &Params) -> Result<NurbsPatch, IgesError> {
    let len = p.p.len();
    let k1 = p.count(1, "upper index K1", len)?;
    let k2 = p.count(2, "upper index K2", len)?;
    let m1 = p.count(3, "degree M1", len)?;
    let m2 = p.count(4, "degree M2", len)?;
    let polynomial = p.int(7, "PROP3")? == 1;
    let (n1, n2) = (k1 + 1, k2 + 1);
    let count = n1
        .checked_mul(n2)
        .filter(|c| c.saturating_mul(4) < len)
        .ok_or_else(|| IgesError::BadParameter {
            de: p.de,
            index: 1,
            reason: format!("{n1} × {n2} control points, but the entity has {len} parameters"),
        })?;
    let ku = p.reals(10, n1 + m1 + 1, "u knot")?;
    let kv0 = 10 + n1 + m1 + 1;
    let kv = p.reals(kv0, n2 + m2 + 1, "v knot")?;
    let w0 = kv0 + n2 + m2 + 1;
    let w = p.reals(w0, count, "weight")?;
    let c0 = w0 + count;
    p.need(c0 + 3 * count - 1, "control point")?;
    let mut points = vec![Vec::with_capacity(n2); n1];
    let mut weights = vec![Vec::with_capacity(n2); n1];
    for j in 0..n2 {
        for i in 0..n1 {
            let idx = j * n1 + i;
            points[i].push(p.point(c0 + 3 * idx, "control point")?);
            weights[i].push(w[idx]);
        }
    }
    let rational = !polynomial && w.iter().any(|x| *x != w[0]);
    let flat: Vec<f64> = w;
    check_bspline(m1, &ku, n1, rational.then_some(flat.as_slice())).map_err(invalid(p.de))?;
    check_bspline(m2, &kv, n2, None).map_err(invalid(p.de))?;
    let r0 = c0 + 3 * count;
    let (ulo, uhi, vlo, vhi) = (ku[m1], ku[n1], kv[m2], kv[n2]);
    let u0 = p.real_or(r0, ulo)?.clamp(ulo, uhi);
    let u1 = p.real_or(r0 + 1, uhi)?.clamp(ulo, uhi);
    let v0 = p.real_or(r0 + 2, vlo)?.clamp(vlo, vhi);
    let v1 = p.real_or(r0 + 3, vhi)?.clamp(vlo, vhi);
    let range = if u1 > u0 && v1 > v0 {
        (u0, u1, v0, v1)
    } else {
        (ulo, uhi, vlo, vhi)
    };
    Ok(NurbsPatch {
        degrees: (m1, m2),
        knots: (ku, kv),
        points,
        weights: rational.then_some(weights),
        range,
    })
}

/// A plane through `origin` with normal `n`, its x axis `reference` made orthogonal to `n` (or
/// the coordinate axis least along `n`), y = n × x.
fn plane(
    de: usize,
    origin: DVec3,
    n: DVec3,
    reference: Option<DVec3>,
) -> Result<SurfaceDef, IgesError> {
    let bad = |what: &str| IgesError::Invalid {
        de,
        reason: format!("the plane's {what} is zero or not finite"),
    };
    let n = n.try_normalize().ok_or_else(|| bad("normal"))?;
    if !origin.is_finite() {
        return Err(bad("location"));
    }
    let guess = reference.unwrap_or_else(|| {
        let a = n.abs();
        if a.x <= a.y && a.x <= a.z {
            DVec3::X
        } else if a.y <= a.z {
            DVec3::Y
        } else {
            DVec3::Z
        }
    });
    let x = (guess - n * guess.dot(n))
        .try_normalize()
        .ok_or_else(|| bad("reference direction"))?;
    Ok(SurfaceDef::Plane {
        origin,
        x,
        y: n.cross(x),
    })
}
