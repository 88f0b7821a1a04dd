//! An edge on a `HYPERBOLA` or a `PARABOLA`, its vertices' parameters found in closed form.
//!
//! truck-stepio locates an edge's vertices on these conics with a polynomial root finder whose
//! Newton refinement has no iteration limit: a vertex some 10³ semi-axes from the conic's
//! centre (a mutated file, or a far healed vertex) never returned (fuzz input
//! `tests/data/fuzz/step/hyperbola_far_vertex.step`). It also reads a `PARABOLA` as a
//! hyperbola. Here the parameter of a point on the curve is exact — STEP's hyperbola is
//! `C + a·cosh λ·x + b·sinh λ·y`, so λ = asinh(y/b); its parabola `C + F·(λ²·x + 2λ·y)`, so
//! λ = y/(2F) — and a vertex off the curve is located or healed later, as on any curve
//! ([`crate::model::trimmed::TrimEdge::new`]).

use truck_geometry::prelude::{
    Invertible, Processor, SquareMatrix, Transform, Transformed, TrimmedCurve, UnitHyperbola,
    UnitParabola,
};
use truck_stepio::r#in::alias::re_exports::{Matrix4, Point3};
use truck_stepio::r#in::alias::{Conic3D, Curve3D};
use truck_stepio::r#in::{Axis2Placement, Conic, CurveAny, EdgeCurve};

/// The edge's curve as truck's `parse_curve3d` builds it (run from the edge's start to its
/// end, inverted when its sense disagrees with the curve's), except that a hyperbola or a
/// parabola is built here.
pub(super) fn parse_curve3d(ec: &EdgeCurve) -> Result<Curve3D, String> {
    match conic_curve(ec) {
        Some(c) => c,
        None => ec.parse_curve3d().map_err(|e| e.to_string()),
    }
}

/// `None` when the edge's curve is not a hyperbola or a parabola.
fn conic_curve(ec: &EdgeCurve) -> Option<Result<Curve3D, String>> {
    let CurveAny::Conic(conic) = &ec.edge_geometry else {
        return None;
    };
    let p = Point3::from(&ec.edge_start.vertex_geometry);
    let q = Point3::from(&ec.edge_end.vertex_geometry);
    let (p, q) = if ec.same_sense { (p, q) } else { (q, p) };
    let frame = |position: &Axis2Placement| Matrix4::try_from(position).map_err(|e| e.to_string());
    let curve = match conic.as_ref() {
        Conic::Hyperbola(h) => {
            let (a, b) = (h.semi_axis, h.semi_imag_axis);
            let build = || -> Result<Curve3D, String> {
                let mat = frame(&h.position)? * Matrix4::from_nonuniform_scale(a, b, a.min(b));
                let range = range(mat, p, q, |l| l.y.asinh())?;
                Ok(Curve3D::Conic(Conic3D::Hyperbola(
                    Processor::new(TrimmedCurve::new(UnitHyperbola::new(), range)).transformed(mat),
                )))
            };
            build()
        }
        Conic::Parabola(pb) => {
            let f = pb.focal_dist;
            let build = || -> Result<Curve3D, String> {
                let mat = frame(&pb.position)? * Matrix4::from_scale(f);
                let range = range(mat, p, q, |l| 0.5 * l.y)?;
                Ok(Curve3D::Conic(Conic3D::Parabola(
                    Processor::new(TrimmedCurve::new(UnitParabola::new(), range)).transformed(mat),
                )))
            };
            build()
        }
        _ => return None,
    };
    Some(curve.map(|mut c| {
        if !ec.same_sense {
            c.invert();
        }
        c
    }))
}

/// The parameter range between `p` and `q` (in increasing order) on the unit conic that
/// `mat` places, `param` giving a point's parameter in the unit conic's coordinates.
fn range(
    mat: Matrix4,
    p: Point3,
    q: Point3,
    param: impl Fn(Point3) -> f64,
) -> Result<(f64, f64), String> {
    let inv = mat
        .invert()
        .ok_or_else(|| "the conic's placement or size is degenerate".to_string())?;
    let (u, v) = (param(inv.transform_point(p)), param(inv.transform_point(q)));
    if !(u.is_finite() && v.is_finite()) {
        return Err("its vertices are not finite on the conic".to_string());
    }
    if u == v {
        return Err("its vertices are at one parameter of the conic".to_string());
    }
    Ok((u.min(v), u.max(v)))
}
