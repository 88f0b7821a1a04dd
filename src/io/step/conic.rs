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
    Invertible, Processor, Transformed, TrimmedCurve, UnitHyperbola, UnitParabola,
};
use truck_stepio::r#in::alias::re_exports::{Matrix4, Point3};
use truck_stepio::r#in::alias::{Conic3D, Curve3D};
use truck_stepio::r#in::{Axis2Placement, Conic, CurveAny, EdgeCurve};

use crate::model::trimmed::{conic_parameter, to_dvec};

/// The edge's curve as truck's `parse_curve3d` builds it (inverted when its sense disagrees
/// with the curve's), except that a hyperbola or a parabola is built here, its parameters by
/// [`conic_parameter`].
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
    let frame = |position: &Axis2Placement| Matrix4::try_from(position).map_err(|e| e.to_string());
    // The unit conic placed, over `range`.
    let placed = |range: (f64, f64)| -> Option<Result<Curve3D, String>> {
        Some(match conic.as_ref() {
            Conic::Hyperbola(h) => {
                let (a, b) = (h.semi_axis, h.semi_imag_axis);
                frame(&h.position).map(|m| {
                    let m = m * Matrix4::from_nonuniform_scale(a, b, a.min(b));
                    let unit = TrimmedCurve::new(UnitHyperbola::new(), range);
                    Curve3D::Conic(Conic3D::Hyperbola(Processor::new(unit).transformed(m)))
                })
            }
            Conic::Parabola(pb) => frame(&pb.position).map(|m| {
                let m = m * Matrix4::from_scale(pb.focal_dist);
                let unit = TrimmedCurve::new(UnitParabola::new(), range);
                Curve3D::Conic(Conic3D::Parabola(Processor::new(unit).transformed(m)))
            }),
            _ => return None,
        })
    };
    let unit = match placed((0.0, 1.0))? {
        Ok(c) => c,
        Err(e) => return Some(Err(e)),
    };
    let p = Point3::from(&ec.edge_start.vertex_geometry);
    let q = Point3::from(&ec.edge_end.vertex_geometry);
    let param = |p: Point3| conic_parameter(&unit, to_dvec(p));
    let (u, v) = match (param(p), param(q)) {
        (Some(u), Some(v)) if u != v => (u, v),
        (Some(_), Some(_)) => {
            return Some(Err("its vertices are at one parameter of the conic".into()));
        }
        _ => {
            return Some(Err(
                "the conic is degenerate or its vertices are not finite on it".into(),
            ));
        }
    };
    // Run from the edge's start to its end as truck's curves do; `TrimEdge::new` finds
    // which end is which.
    Some(placed((u.min(v), u.max(v)))?.map(|mut c| {
        if !ec.same_sense {
            c.invert();
        }
        c
    }))
}
