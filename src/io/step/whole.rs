//! Faces bounded by a sphere's vertex loops (a `VERTEX_LOOP` at each pole, as kernels write a
//! whole sphere): the loop of the whole surface, its seam placed clear of the face's holes.

use std::sync::Arc;

use crate::model::trimmed::{LoopEdge, TruckSurface};

/// Ids of the seam edges made for whole faces (above any STEP entity id a file can hold in
/// f64-exact integers: `WHOLE_FACE_EDGE + 4 · face + side`).
const WHOLE_FACE_EDGE: u64 = 1 << 56;

/// Where a sphere's seam can run clear of holes: the u of the middle of the widest gap
/// between the loops' points seen around the sphere's axis (its poles are the ends of its v
/// range; 16 points per edge). `None` when a loop runs around the axis (it bounds a cap, not
/// a hole) or the surface has no v range.
pub(super) fn seam_clear_of(surface: &TruckSurface, loops: &[Vec<LoopEdge>]) -> Option<f64> {
    use crate::model::trimmed::{SurfaceEval, parameter_bounds};
    use glam::DVec2;
    let tau = std::f64::consts::TAU;
    let (v0, v1) = parameter_bounds(surface).1?;
    let (south, north) = (
        surface.point(DVec2::new(0.0, v0)),
        surface.point(DVec2::new(0.0, v1)),
    );
    let centre = 0.5 * (south + north);
    let axis = (north - south).try_normalize()?;
    let mid = 0.5 * (v0 + v1);
    let x = (surface.point(DVec2::new(0.0, mid)) - centre)
        .reject_from_normalized(axis)
        .try_normalize()?;
    let mut y = axis.cross(x);
    // u runs with the angle about the axis or against it.
    if (surface.point(DVec2::new(0.1, mid)) - centre).dot(y) < 0.0 {
        y = -y;
    }
    let size = north.distance(south);
    let mut all = Vec::new();
    for lp in loops {
        let mut angles = Vec::new();
        for le in lp {
            let e = &le.edge;
            for k in 0..16 {
                let f = k as f64 / 16.0;
                let f = if le.forward { f } else { 1.0 - f };
                let d = e.point(e.t0 + (e.t1 - e.t0) * f) - centre;
                // A point on the axis (a pole) has no angle.
                if d.reject_from_normalized(axis).length() > 1e-9 * size {
                    angles.push(d.dot(y).atan2(d.dot(x)).rem_euclid(tau));
                }
            }
        }
        let first = *angles.first()?;
        let turn: f64 = angles
            .iter()
            .zip(angles.iter().skip(1).chain(std::iter::once(&first)))
            .map(|(a, b)| {
                let d = (b - a).rem_euclid(tau);
                if d > 0.5 * tau { d - tau } else { d }
            })
            .sum();
        if (turn / tau).round() != 0.0 {
            return None;
        }
        all.extend(angles);
    }
    all.sort_by(f64::total_cmp);
    let first = *all.first()?;
    let (gap, at) = all
        .iter()
        .zip(all.iter().skip(1).chain(std::iter::once(&(first + tau))))
        .map(|(a, b)| (b - a, 0.5 * (a + b)))
        .max_by(|a, b| a.0.total_cmp(&b.0))?;
    (gap > 0.0).then_some(at.rem_euclid(tau))
}

/// The loop bounding the whole of a sphere (face `face`): its parameter rectangle without the
/// sides that are poles (points), i.e. the seam meridian at u = `seam` (and `seam` + 2π) up
/// and down again. `None` for any other surface (a face bounded only by vertex loops
/// elsewhere stays refused).
pub(super) fn whole_surface_loop(
    surface: &TruckSurface,
    face: u64,
    seam: f64,
) -> Option<Vec<LoopEdge>> {
    use crate::model::trimmed::{SurfaceEval, parameter_bounds, parameter_rectangle};
    use truck_stepio::r#in::alias::ElementarySurface;
    let TruckSurface::ElementarySurface(e) = surface else {
        return None;
    };
    if !matches!(**e, ElementarySurface::Sphere(_)) {
        return None;
    }
    let (ru, rv) = parameter_bounds(surface);
    let pu = surface.periods().0;
    let (u0, u1) = ru.or(pu.map(|p| (0.0, p)))?;
    let (u0, u1) = (u0 + seam, u1 + seam);
    let (v0, v1) = rv?;
    let rect = parameter_rectangle(
        surface,
        (u0, u1, v0, v1),
        (pu.is_some(), false),
        WHOLE_FACE_EDGE + 4 * face.min(1 << 50),
    );
    let size = rect
        .iter()
        .map(|e| e.start.distance(e.point(0.5)))
        .fold(0.0, f64::max);
    let lp: Vec<LoopEdge> = rect
        .into_iter()
        .filter(|e| e.point(0.5).distance(e.start) > 1e-9 * size)
        .map(|e| LoopEdge {
            edge: Arc::new(e),
            forward: true,
            kind: Default::default(),
        })
        .collect();
    (lp.len() == 2).then_some(lp)
}
