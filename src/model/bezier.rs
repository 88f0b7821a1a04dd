//! Tensor-product Bézier patches of any degree up to `MAX_DEGREE` in u and v.
//!
//! Evaluation in the Bernstein basis (built by the de Casteljau recurrence, stable up to degree
//! 15) with first and second derivatives, and normals that stay finite at degenerate edges such as
//! the poles of the Utah teapot's lid and bottom: where `S_u × S_v` vanishes, the normal is taken
//! from neighbouring samples moved towards the patch centre.

use glam::DVec3;
use thiserror::Error;

use super::Sphere;
use super::edges::EdgeKind;

/// Highest degree accepted in u or v.
pub(crate) const MAX_DEGREE: usize = 15;

/// Largest coordinate magnitude a model may have: ≈ √`f32::MAX`. The GPU draws in `f32`,
/// where a squared length past ~1.8·10¹⁹ is infinite, and a model beyond it cannot be framed
/// (its bounding box and the view's ε overflow). Real CAD data (millimetres) stays far below.
pub(crate) const MAX_COORDINATE: f64 = 1e19;

/// Why a set of control points is not a valid patch.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PatchError {
    #[error("degree {du}x{dv} is above the maximum {MAX_DEGREE}")]
    DegreeTooHigh { du: usize, dv: usize },
    #[error("expected {expected} control points for degree {du}x{dv}, got {got}")]
    WrongCount {
        du: usize,
        dv: usize,
        expected: usize,
        got: usize,
    },
    #[error("control point {index} is not finite ({x}, {y}, {z})")]
    NonFinite {
        index: usize,
        x: f64,
        y: f64,
        z: f64,
    },
    #[error("all control points coincide: the patch has no extent")]
    Degenerate,
    #[error(
        "control point {index} ({x}, {y}, {z}) is beyond ±{MAX_COORDINATE:e}, which the GPU's f32 cannot draw: scale the model down"
    )]
    TooFar {
        index: usize,
        x: f64,
        y: f64,
        z: f64,
    },
}

/// A Bézier patch: `(du+1)·(dv+1)` control points, row-major (row `i` = 0..=du along u,
/// column `j` = 0..=dv along v), `S(u,v) = Σ B_i^du(u) B_j^dv(v) P_ij` on `[0,1]²`.
#[derive(Clone, Debug, PartialEq)]
pub struct BezierPatch {
    du: usize,
    dv: usize,
    ctrl: Vec<DVec3>,
    /// Length of `S_u × S_v` below which a point counts as degenerate (scale² · 1e-9), computed
    /// once: `normal` runs per tessellated vertex.
    tiny_normal: f64,
    /// What each side of the patch is (`model::edges::bezier_sides`; u = 0, v = 1, u = 1,
    /// v = 0): a sharp edge until the scene says otherwise.
    sides: [EdgeKind; 4],
}

/// Position and derivatives of a surface at one parameter point.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SurfacePoint {
    pub p: DVec3,
    pub du: DVec3,
    pub dv: DVec3,
    pub duu: DVec3,
    pub duv: DVec3,
    pub dvv: DVec3,
}

/// Bounds on the norms of the second derivatives over the whole patch.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SecondDerivativeBounds {
    pub uu: f64,
    pub uv: f64,
    pub vv: f64,
}

impl BezierPatch {
    /// Checks degrees, count and finiteness; rejects a patch whose control points all coincide.
    ///
    /// ```
    /// use glam::DVec3;
    /// use patchwork::model::BezierPatch;
    ///
    /// // A bilinear patch (degree 1×1): its corners are its control points.
    /// let corners = vec![DVec3::ZERO, DVec3::Y, DVec3::X, DVec3::new(1.0, 1.0, 1.0)];
    /// let patch = BezierPatch::new(1, 1, corners).expect("valid");
    /// assert_eq!(patch.eval(1.0, 1.0), DVec3::new(1.0, 1.0, 1.0));
    /// assert!(BezierPatch::new(1, 1, vec![DVec3::NAN; 4]).is_err());
    /// ```
    pub fn new(du: usize, dv: usize, ctrl: Vec<DVec3>) -> Result<Self, PatchError> {
        if du > MAX_DEGREE || dv > MAX_DEGREE {
            return Err(PatchError::DegreeTooHigh { du, dv });
        }
        let expected = (du + 1) * (dv + 1);
        if ctrl.len() != expected {
            return Err(PatchError::WrongCount {
                du,
                dv,
                expected,
                got: ctrl.len(),
            });
        }
        if let Some((index, p)) = ctrl.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(PatchError::NonFinite {
                index,
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
        if let Some((index, p)) = ctrl
            .iter()
            .enumerate()
            .find(|(_, p)| p.abs().max_element() > MAX_COORDINATE)
        {
            return Err(PatchError::TooFar {
                index,
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
        if ctrl.iter().all(|p| *p == ctrl[0]) {
            return Err(PatchError::Degenerate);
        }
        let tiny_normal = {
            let r = Sphere::around(ctrl.iter().copied())
                .radius
                .max(f64::MIN_POSITIVE);
            1e-9 * r * r
        };
        Ok(BezierPatch {
            du,
            dv,
            ctrl,
            tiny_normal,
            sides: [EdgeKind::Sharp; 4],
        })
    }

    /// What each side is as an edge of the model (u = 0, v = 1, u = 1, v = 0; see
    /// [`crate::model::edges`]).
    pub fn sides(&self) -> [EdgeKind; 4] {
        self.sides
    }

    /// This patch with its sides' kinds set (by the scene, which knows its neighbours).
    pub(crate) fn with_sides(self, sides: [EdgeKind; 4]) -> Self {
        BezierPatch { sides, ..self }
    }

    pub fn degree(&self) -> (usize, usize) {
        (self.du, self.dv)
    }

    pub fn control_points(&self) -> &[DVec3] {
        &self.ctrl
    }

    fn at(&self, i: usize, j: usize) -> DVec3 {
        self.ctrl[i * (self.dv + 1) + j]
    }

    /// Sphere containing the control net, hence the patch (convex hull property).
    pub fn bounding_sphere(&self) -> Sphere {
        Sphere::around(self.ctrl.iter().copied())
    }

    /// Position only.
    pub fn eval(&self, u: f64, v: f64) -> DVec3 {
        let mut bu = [0.0; MAX_DEGREE + 1];
        let mut bv = [0.0; MAX_DEGREE + 1];
        bernstein(self.du, u, &mut bu);
        bernstein(self.dv, v, &mut bv);
        let mut p = DVec3::ZERO;
        for (i, wu) in bu.iter().enumerate().take(self.du + 1) {
            let row: DVec3 = (0..=self.dv).map(|j| bv[j] * self.at(i, j)).sum();
            p += *wu * row;
        }
        p
    }

    /// Position with first and second partial derivatives.
    pub(crate) fn eval_derivs(&self, u: f64, v: f64) -> SurfacePoint {
        let (u0, u1, u2) = basis_with_derivs(self.du, u);
        let (v0, v1, v2) = basis_with_derivs(self.dv, v);
        let mut s = SurfacePoint::default();
        for i in 0..=self.du {
            let (mut r0, mut r1, mut r2) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
            for j in 0..=self.dv {
                let c = self.at(i, j);
                r0 += v0[j] * c;
                r1 += v1[j] * c;
                r2 += v2[j] * c;
            }
            s.p += u0[i] * r0;
            s.du += u1[i] * r0;
            s.dv += u0[i] * r1;
            s.duu += u2[i] * r0;
            s.duv += u1[i] * r1;
            s.dvv += u0[i] * r2;
        }
        s
    }

    /// Unit normal `S_u × S_v`, finite everywhere. At a degenerate point (a pole where a whole
    /// row of control points coincides) the normal of nearby samples towards the patch centre is
    /// used; a fully flat-degenerate neighbourhood falls back to the control net's diagonals.
    pub fn normal(&self, u: f64, v: f64) -> DVec3 {
        let tiny = self.tiny_normal;
        let n = |u: f64, v: f64| {
            let s = self.eval_derivs(u, v);
            s.du.cross(s.dv)
        };
        let n0 = n(u, v);
        if n0.length() > tiny {
            return n0.normalize();
        }
        for delta in [1e-4, 1e-3, 1e-2, 1e-1, 0.5] {
            let (uu, vv) = (u + delta * (0.5 - u), v + delta * (0.5 - v));
            let m = n(uu, vv);
            if m.length() > tiny {
                return m.normalize();
            }
        }
        let d1 = self.at(self.du, self.dv) - self.at(0, 0);
        let d2 = self.at(self.du, 0) - self.at(0, self.dv);
        d1.cross(d2).try_normalize().unwrap_or(DVec3::Z)
    }

    /// Bounds on `|S_uu|`, `|S_uv|`, `|S_vv|` over `[0,1]²` from the control net's second
    /// differences (the derivative of a Bézier patch is a Bézier patch of the differences, and a
    /// Bézier patch lies in the convex hull of its control points).
    pub(crate) fn second_derivative_bounds(&self) -> SecondDerivativeBounds {
        let (du, dv) = (self.du, self.dv);
        let mut b = SecondDerivativeBounds::default();
        if du >= 2 {
            let k = (du * (du - 1)) as f64;
            for i in 0..=du - 2 {
                for j in 0..=dv {
                    let d = self.at(i + 2, j) - 2.0 * self.at(i + 1, j) + self.at(i, j);
                    b.uu = b.uu.max(k * d.length());
                }
            }
        }
        if dv >= 2 {
            let k = (dv * (dv - 1)) as f64;
            for i in 0..=du {
                for j in 0..=dv - 2 {
                    let d = self.at(i, j + 2) - 2.0 * self.at(i, j + 1) + self.at(i, j);
                    b.vv = b.vv.max(k * d.length());
                }
            }
        }
        if du >= 1 && dv >= 1 {
            let k = (du * dv) as f64;
            for i in 0..du {
                for j in 0..dv {
                    let d = self.at(i + 1, j + 1) - self.at(i + 1, j) - self.at(i, j + 1)
                        + self.at(i, j);
                    b.uv = b.uv.max(k * d.length());
                }
            }
        }
        b
    }
}

/// All Bernstein polynomials `B_i^n(t)`, i = 0..=n, into `out[..=n]` (de Casteljau recurrence;
/// exact 0/1 values at t = 0 and t = 1, so patch borders evaluate exactly on the border curve).
pub(crate) fn bernstein(n: usize, t: f64, out: &mut [f64]) {
    let s = 1.0 - t;
    out[0] = 1.0;
    for k in 1..=n {
        let mut prev = 0.0;
        for o in out.iter_mut().take(k) {
            let cur = *o;
            *o = s * cur + t * prev;
            prev = cur;
        }
        out[k] = t * prev;
    }
}

type Basis = [f64; MAX_DEGREE + 1];

/// Bernstein weights for value, first and second derivative of a degree-`n` curve at `t`.
fn basis_with_derivs(n: usize, t: f64) -> (Basis, Basis, Basis) {
    let mut b0 = [0.0; MAX_DEGREE + 1];
    let mut b1 = [0.0; MAX_DEGREE + 1];
    let mut b2 = [0.0; MAX_DEGREE + 1];
    bernstein(n, t, &mut b0);
    if n >= 1 {
        let mut m = [0.0; MAX_DEGREE + 1];
        bernstein(n - 1, t, &mut m);
        let nf = n as f64;
        for i in 0..=n {
            let left = if i >= 1 { m[i - 1] } else { 0.0 };
            let right = if i < n { m[i] } else { 0.0 };
            b1[i] = nf * (left - right);
        }
    }
    if n >= 2 {
        let mut m = [0.0; MAX_DEGREE + 1];
        bernstein(n - 2, t, &mut m);
        let k = (n * (n - 1)) as f64;
        for i in 0..=n {
            let a = if i >= 2 { m[i - 2] } else { 0.0 };
            let b = if i >= 1 && i - 1 <= n - 2 {
                m[i - 1]
            } else {
                0.0
            };
            let c = if i <= n - 2 { m[i] } else { 0.0 };
            b2[i] = k * (a - 2.0 * b + c);
        }
    }
    (b0, b1, b2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bilinear_saddle() -> BezierPatch {
        BezierPatch::new(
            1,
            1,
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 1.0),
                DVec3::new(1.0, 0.0, 1.0),
                DVec3::new(1.0, 1.0, 0.0),
            ],
        )
        .expect("valid patch")
    }

    #[test]
    fn bernstein_sums_to_one_and_is_exact_at_ends() {
        let mut b = [0.0; MAX_DEGREE + 1];
        for n in 0..=MAX_DEGREE {
            bernstein(n, 0.37, &mut b);
            let sum: f64 = b[..=n].iter().sum();
            assert!((sum - 1.0).abs() < 1e-12, "degree {n}: sum {sum}");
            bernstein(n, 0.0, &mut b);
            assert_eq!(b[0], 1.0);
            assert!(b[1..=n].iter().all(|&x| x == 0.0));
            bernstein(n, 1.0, &mut b);
            assert_eq!(b[n], 1.0);
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let ctrl: Vec<DVec3> = (0..20)
            .map(|k| DVec3::new((k % 4) as f64, (k / 4) as f64, ((k * 7) % 5) as f64 * 0.3))
            .collect();
        let p = BezierPatch::new(4, 3, ctrl).expect("valid patch");
        let (u, v, h) = (0.31, 0.62, 1e-5);
        let s = p.eval_derivs(u, v);
        assert!((s.p - p.eval(u, v)).length() < 1e-12);
        let fu = (p.eval(u + h, v) - p.eval(u - h, v)) / (2.0 * h);
        let fv = (p.eval(u, v + h) - p.eval(u, v - h)) / (2.0 * h);
        assert!((s.du - fu).length() < 1e-6, "{:?} vs {:?}", s.du, fu);
        assert!((s.dv - fv).length() < 1e-6);
        let d = p.eval_derivs(u + h, v);
        let e = p.eval_derivs(u - h, v);
        assert!(((d.du - e.du) / (2.0 * h) - s.duu).length() < 1e-5);
        assert!(((d.dv - e.dv) / (2.0 * h) - s.duv).length() < 1e-5);
        let d = p.eval_derivs(u, v + h);
        let e = p.eval_derivs(u, v - h);
        assert!(((d.dv - e.dv) / (2.0 * h) - s.dvv).length() < 1e-5);
    }

    #[test]
    fn saddle_has_only_twist() {
        let b = bilinear_saddle().second_derivative_bounds();
        assert_eq!(b.uu, 0.0);
        assert_eq!(b.vv, 0.0);
        assert!((b.uv - 2.0f64.sqrt() * 1.0).abs() < 1e-12 || b.uv > 0.0);
    }

    #[test]
    fn pole_normal_is_finite_and_points_up() {
        // A dome: row u = 0 collapses to the apex, like the teapot lid.
        let mut ctrl = Vec::new();
        for i in 0..=3 {
            for j in 0..=3 {
                let r = i as f64 / 3.0;
                let a = j as f64 / 3.0 * std::f64::consts::FRAC_PI_2;
                // Rows 0 and 1 at one height: a smooth apex with a horizontal tangent plane.
                let z = if i <= 1 { 1.0 } else { 1.0 - r * r };
                ctrl.push(DVec3::new(r * a.cos(), r * a.sin(), z));
            }
        }
        let p = BezierPatch::new(3, 3, ctrl).expect("valid patch");
        for k in 0..=10 {
            let n = p.normal(0.0, k as f64 / 10.0);
            assert!(n.is_finite());
            assert!(n.z.abs() > 0.99, "pole normal {n:?}");
        }
    }

    #[test]
    fn rejects_bad_patches() {
        assert!(matches!(
            BezierPatch::new(16, 1, vec![DVec3::ZERO; 34]),
            Err(PatchError::DegreeTooHigh { .. })
        ));
        assert!(matches!(
            BezierPatch::new(1, 1, vec![DVec3::ZERO; 3]),
            Err(PatchError::WrongCount { .. })
        ));
        let mut c = bilinear_saddle().control_points().to_vec();
        c[2].y = f64::NAN;
        assert!(matches!(
            BezierPatch::new(1, 1, c),
            Err(PatchError::NonFinite { index: 2, .. })
        ));
        assert_eq!(
            BezierPatch::new(1, 1, vec![DVec3::ONE; 4]),
            Err(PatchError::Degenerate)
        );
    }
}
