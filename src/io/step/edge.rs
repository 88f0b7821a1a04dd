//! An `EDGE_CURVE` converted to a [`TrimEdge`]: its exact 3D curve, and its vertices located on
//! it — within the file's tolerance, or healed as a kernel heals them.

use truck_stepio::r#in::alias::re_exports::Point3;
use truck_stepio::r#in::ruststep::ast::Name;
use truck_stepio::r#in::ruststep::tables::{IntoOwned, PlaceHolder};
use truck_stepio::r#in::{CurveAnyHolder, EdgeCurve, EdgeCurveHolder, Table};

use super::{holder_ref, p21};
use glam::DVec3;

use crate::model::trimmed::{Curve3D, TrimEdge, nearest_on_curve, to_dvec};

/// How an edge's vertices lie on its curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Fit {
    /// Within [`EDGE_VERTEX_TOLERANCE`] of the coordinates' size.
    Exact,
    /// Within the file's tolerance (its uncertainty ×[`LOOSE_UNCERTAINTY_FACTOR`] or
    /// [`LOOSE_EDGE_FRACTION`] of the edge).
    Loose,
    /// Farther: located on the curve by their nearest points, the largest move this far.
    Healed(f64),
}

/// How far (relative to the coordinates' size) an edge's vertices may lie from its curve.
pub(super) const EDGE_VERTEX_TOLERANCE: f64 = 1e-4;
/// Vertices farther than that are still accepted within this many times the file's
/// uncertainty ...
pub(super) const LOOSE_UNCERTAINTY_FACTOR: f64 = 10.0;
/// ... or within this fraction of the edge's chord.
pub(super) const LOOSE_EDGE_FRACTION: f64 = 0.02;

/// Most edges at one vertex that [`healed_vertex`] weighs.
const MAX_HEAL_EDGES: usize = 8;

/// The `EDGE_CURVE`s that start or end at each `VERTEX_POINT`: a vertex off its curves is
/// healed to one point for all of them ([`healed_vertex`]).
pub(super) type VertexEdges = std::collections::HashMap<u64, Vec<u64>>;

/// [`VertexEdges`] of `table`.
pub(super) fn vertex_edges(table: &Table) -> VertexEdges {
    let mut map = VertexEdges::new();
    for (&id, h) in &table.edge_curve {
        for v in [holder_ref(&h.edge_start), holder_ref(&h.edge_end)]
            .into_iter()
            .flatten()
        {
            let list = map.entry(v).or_default();
            if !list.contains(&id) {
                list.push(id);
            }
        }
    }
    for list in map.values_mut() {
        list.sort_unstable();
    }
    map
}

/// The 3D curves of edge `id`: its `SURFACE_CURVE`'s exact 3D curve (when it has one) and
/// the curve truck reads, with the edge as truck owns it.
type Curves = (Option<Curve3D>, Result<Curve3D, String>, EdgeCurve);

fn edge_curves(
    file: &p21::P21File,
    table: &Table,
    id: u64,
    holder: &EdgeCurveHolder,
) -> Result<Curves, String> {
    // truck-stepio follows a SURFACE_CURVE's preferred representation, which may be a
    // parameter-space curve (its parameters need not match truck's surface, and it only
    // approximates the edge); the 3D curve of a SURFACE_CURVE / SEAM_CURVE is exact: use it.
    let curve_3d = holder_ref(&holder.edge_geometry)
        .and_then(|g| file.get(g))
        .and_then(p21::Entity::record)
        .filter(|r| r.name == "SURFACE_CURVE" || r.name == "SEAM_CURVE")
        .and_then(|r| r.ref_at(1));
    let ec = match holder.clone().into_owned(table) {
        Ok(ec) => ec,
        // A SURFACE_CURVE with a pcurve truck cannot read (on a surface it lacks): the edge is
        // its 3D curve.
        Err(e) => match curve_3d {
            Some(c3d) => {
                let mut h = holder.clone();
                h.edge_geometry = PlaceHolder::Ref(Name::Entity(c3d));
                h.into_owned(table)
                    .map_err(|_| format!("edge #{id}: {e}"))?
            }
            None => return Err(format!("edge #{id}: {e}")),
        },
    };
    let exact = curve_3d.and_then(|c3d| {
        let geometry = PlaceHolder::<CurveAnyHolder>::Ref(Name::Entity(c3d))
            .into_owned(table)
            .ok()?;
        super::conic::parse_curve3d(&EdgeCurve {
            edge_geometry: geometry,
            ..ec.clone()
        })
        .ok()
    });
    let truck_curve = super::conic::parse_curve3d(&ec)
        .map_err(|e| format!("edge #{id}: curve not supported: {e}"));
    Ok((exact, truck_curve, ec))
}

/// Where a vertex off its curves is healed to, for every edge at it alike: of the nearest
/// points to `at` on the curves that pass farther than `tol` from it (the edges that need
/// healing; the others keep the vertex), the one nearest to all those curves (least largest
/// distance; the nearest to the vertex breaks ties). Healing each edge by itself put one
/// vertex at two places: OCCT's offset of a box (generated model 1-78) left a vertex 20 off
/// a corner, the nearest point of one circle was the corner and of the other a point 3/4 of
/// the way round it, whose arc then ran through the solid.
fn healed_vertex(
    file: &p21::P21File,
    table: &Table,
    vertex: u64,
    at: DVec3,
    tol: f64,
    by_vertex: &VertexEdges,
) -> Option<DVec3> {
    let near = |c: &Curve3D, p: DVec3| nearest_on_curve(c, p).map(|q| q.distance(p));
    // A vertex of a real model has a handful of edges; a hostile file's vertex may have
    // thousands: the first few are enough to place it (the search is quadratic in them).
    let curves: Vec<Curve3D> = by_vertex
        .get(&vertex)?
        .iter()
        .take(MAX_HEAL_EDGES)
        .filter_map(|e| {
            let (exact, truck, _) = edge_curves(file, table, *e, table.edge_curve.get(e)?).ok()?;
            exact.or(truck.ok())
        })
        .filter(|c| near(c, at).is_some_and(|d| d > tol))
        .collect();
    curves
        .iter()
        .filter_map(|c| nearest_on_curve(c, at))
        .map(|q| {
            let worst = curves
                .iter()
                .map(|c| near(c, q).unwrap_or(f64::INFINITY))
                .fold(0.0, f64::max);
            (worst, q.distance(at), q)
        })
        .filter(|k| k.0.is_finite())
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)))
        .map(|k| k.2)
}

pub(super) fn convert_edge(
    file: &p21::P21File,
    table: &Table,
    id: u64,
    holder: &EdgeCurveHolder,
    uncertainty: Option<f64>,
    by_vertex: &VertexEdges,
) -> Result<(TrimEdge, Fit), String> {
    let (exact, truck_curve, ec) = edge_curves(file, table, id, holder)?;
    let start = to_dvec(Point3::from(&ec.edge_start.vertex_geometry));
    let end = to_dvec(Point3::from(&ec.edge_end.vertex_geometry));
    // Closed when it starts and ends at one VERTEX_POINT (as a kernel decides), or at one
    // position: two vertices a hair apart bound a tiny edge, not a whole circle.
    let closed = match (holder_ref(&holder.edge_start), holder_ref(&holder.edge_end)) {
        (Some(a), Some(b)) => a == b || start == end,
        _ => start == end,
    };
    let size = start.length().max(end.length()).max(start.distance(end));
    let tol = EDGE_VERTEX_TOLERANCE * (1.0 + size);
    // What a kernel accepts (OCCT raises a vertex's tolerance until it covers its edges): the
    // file's own uncertainty, generously, or a small fraction of the edge.
    let loose_tol = (LOOSE_UNCERTAINTY_FACTOR * uncertainty.unwrap_or(0.0))
        .max(LOOSE_EDGE_FRACTION * start.distance(end).max(tol));
    for t in [tol, loose_tol] {
        if let Some(curve) = exact.clone()
            && let Some(e) = TrimEdge::new(id, curve, start, end, closed, t)
        {
            return Ok((e, if t > tol { Fit::Loose } else { Fit::Exact }));
        }
        if let Ok(curve) = truck_curve.clone()
            && let Some(e) = TrimEdge::new(id, curve, start, end, closed, t)
        {
            return Ok((e, if t > tol { Fit::Loose } else { Fit::Exact }));
        }
    }
    // Healed as a kernel does (OCCT's reader locates a vertex on its edge's curve and grows
    // the vertex's tolerance to the distance): each vertex moved to the point of its edges'
    // curves nearest to all of them ([`healed_vertex`]), then onto this curve; the loops
    // close across the gap in parameter space, as they are drawn.
    let towards = |v: &PlaceHolder<_>, p: DVec3| {
        holder_ref(v)
            .and_then(|v| healed_vertex(file, table, v, p, loose_tol, by_vertex))
            .unwrap_or(p)
    };
    let (start_to, end_to) = (
        towards(&holder.edge_start, start),
        towards(&holder.edge_end, end),
    );
    let candidates = exact.into_iter().chain(truck_curve.clone().ok());
    let healed = candidates
        .filter_map(|curve| {
            let s = nearest_on_curve(&curve, start_to)?;
            let e = if closed {
                s
            } else {
                nearest_on_curve(&curve, end_to)?
            };
            // Two vertices apart that land on one point bound no edge.
            if !closed && s.distance(e) <= tol && start.distance(end) > tol {
                return None;
            }
            let off = s.distance(start).max(e.distance(end));
            Some((TrimEdge::new(id, curve, s, e, closed, tol)?, off))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1));
    if let Some((e, off)) = healed {
        return Ok((e, Fit::Healed(off)));
    }
    truck_curve?;
    Err(format!(
        "edge #{id}: its vertices are not on its curve (farther than the file's tolerance, \
         {loose_tol:e}) and cannot be located on it"
    ))
}
