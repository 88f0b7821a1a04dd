//! Faces bounded by a sphere's vertex loops (a `VERTEX_LOOP` at each pole, as kernels write a
//! whole sphere): the loop of the whole surface, its seam placed clear of the face's holes.

use std::sync::Arc;

use std::f64::consts::TAU;

use crate::model::trimmed::{LoopEdge, TruckSurface};

/// Ids of the seam edges made for whole faces (above any STEP entity id a file can hold in
/// f64-exact integers: `WHOLE_FACE_EDGE + 4 · face + side`).
const WHOLE_FACE_EDGE: u64 = 1 << 56;

/// A sphere's frame for angles about its axis: centre, axis (south to north pole, the way v
/// runs) and the directions of angle 0 and of a quarter turn the way u runs.
struct AxisFrame {
    centre: glam::DVec3,
    axis: glam::DVec3,
    x: glam::DVec3,
    y: glam::DVec3,
    size: f64,
}

impl AxisFrame {
    fn of(surface: &TruckSurface) -> Option<AxisFrame> {
        use crate::model::trimmed::{SurfaceEval, parameter_bounds};
        use glam::DVec2;
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
        Some(AxisFrame {
            centre,
            axis,
            x,
            y,
            size,
        })
    }

    /// A loop's points (16 per edge, in the loop's direction) as (angle about the axis in
    /// 0..2π, latitude), both increasing the way the surface's u and v do; points on the axis
    /// (a pole: no angle) are left out.
    fn loop_angles(&self, lp: &[LoopEdge]) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        for le in lp {
            let e = &le.edge;
            for k in 0..16 {
                let f = k as f64 / 16.0;
                let f = if le.forward { f } else { 1.0 - f };
                let d = e.point(e.t0 + (e.t1 - e.t0) * f) - self.centre;
                let across = d.reject_from_normalized(self.axis).length();
                if across > 1e-9 * self.size {
                    let angle = d.dot(self.y).atan2(d.dot(self.x)).rem_euclid(TAU);
                    out.push((angle, d.dot(self.axis).atan2(across)));
                }
            }
        }
        out
    }
}

/// Steps between consecutive angles of a closed loop, each taken the short way round.
fn angle_steps(angles: &[(f64, f64)]) -> impl Iterator<Item = f64> + '_ {
    angles
        .iter()
        .zip(angles.iter().skip(1).chain(angles.first()))
        .map(move |(a, b)| {
            let d = (b.0 - a.0).rem_euclid(TAU);
            if d > 0.5 * TAU { d - TAU } else { d }
        })
}

/// A sphere face's loops seen around its axis ([`seam_clear_of`]).
pub(super) struct ClearSeam {
    /// The u the seam can run at, clear of the loops.
    pub(super) at: f64,
    /// The loops' signed areas in (angle, latitude), added up; `None` where a loop runs
    /// through a pole (a point left out: a sphere's lune, generated models gen-1-9 and
    /// gen-1-12), whose way round along the pole in u is not known, or steps a quarter turn
    /// or more, which cannot be told from its other way round.
    signed_area: Option<f64>,
}

impl ClearSeam {
    /// Whether the loops are all holes by their orientation: the face lies outside them, on
    /// the rest of the sphere. Their signed areas in (angle, latitude), which run as the
    /// surface's (u, v), add up to the side the face is on: with the face left of its loops
    /// (`domain_left`), an outer loop runs counter-clockwise and outweighs its holes; here
    /// the sum says clockwise. Generated model gen-3-15: a sphere of 296° whose edges at the
    /// poles are fillets has one loop (the two meridians of its cut and the fillet arcs), and
    /// the even-odd rule alone drew the 64° wedge the loop encloses in (u, v), the complement
    /// of the face. `false` where the orientation is not read.
    pub(super) fn loops_are_holes(&self, domain_left: bool) -> bool {
        self.signed_area
            .is_some_and(|area| if domain_left { area < 0.0 } else { area > 0.0 })
    }
}

/// The signed area in (angle, latitude) of a loop that closes without running around the
/// axis, its angles unwrapped along it.
fn signed_area(pts: &[(f64, f64)]) -> f64 {
    let mut angle = pts.first().map_or(0.0, |p| p.0);
    let unwrapped: Vec<(f64, f64)> = std::iter::once(angle)
        .chain(angle_steps(pts).map(|d| {
            angle += d;
            angle
        }))
        .zip(pts.iter().map(|p| p.1))
        .take(pts.len())
        .collect();
    0.5 * unwrapped
        .iter()
        .zip(unwrapped.iter().skip(1).chain(unwrapped.first()))
        .map(|(a, b)| a.0 * b.1 - b.0 * a.1)
        .sum::<f64>()
}

/// Where a sphere's seam can run clear of holes: the u of the middle of the widest arc of
/// angles about the sphere's axis that no loop crosses (its poles are the ends of its v range;
/// 16 points per edge, each step between two of them covering the angles it sweeps the short
/// way round: beside a pole a step sweeps a radian or more, and the points alone left a gap
/// there that the loop crosses, generated model gen-43-42), and the loops' orientation. `None`
/// when a loop runs around the axis (it bounds a cap, not a hole), the surface has no v range
/// or the loops cross every angle.
pub(super) fn seam_clear_of(surface: &TruckSurface, loops: &[Vec<LoopEdge>]) -> Option<ClearSeam> {
    let frame = AxisFrame::of(surface)?;
    // The arcs of angle the loops sweep, as (start, length), start in 0..2π.
    let mut swept = Vec::new();
    let mut area = Some(0.0);
    for lp in loops {
        let angles = frame.loop_angles(lp);
        angles.first()?;
        let turn: f64 = angle_steps(&angles).sum();
        if (turn / TAU).round() != 0.0 {
            return None;
        }
        let clear =
            angles.len() == 16 * lp.len() && angle_steps(&angles).all(|d| d.abs() < 0.25 * TAU);
        area = area.filter(|_| clear).map(|a| a + signed_area(&angles));
        swept.extend(
            angles
                .iter()
                .zip(angle_steps(&angles))
                .map(|(a, d)| ((a.0 + d.min(0.0)).rem_euclid(TAU), d.abs())),
        );
    }
    let (gap, at) = widest_gap(&mut swept)?;
    (gap > 0.0).then(|| ClearSeam {
        at: at.rem_euclid(TAU),
        signed_area: area,
    })
}

/// The widest arc of the circle that none of the arcs `swept` ((start in 0..2π, length up to
/// π)) covers: its length (0 where they cover every angle) and the angle of its middle.
/// `None` when there are no arcs.
fn widest_gap(swept: &mut [(f64, f64)]) -> Option<(f64, f64)> {
    swept.sort_by(|a, b| a.0.total_cmp(&b.0));
    let first = swept.first()?.0;
    // Walking from the first start once round: `reach` is the farthest angle covered so far
    // (at first, by the arcs that wrap past 2π), and a start beyond it opens a gap from it.
    let mut reach = swept.iter().map(|a| a.0 + a.1 - TAU).fold(first, f64::max);
    let mut best = (0.0, first);
    for &(start, length) in swept.iter().chain(std::iter::once(&(first + TAU, 0.0))) {
        if start - reach > best.0 {
            best = (start - reach, 0.5 * (start + reach));
        }
        reach = reach.max(start + length);
    }
    Some(best)
}

/// Whether `surface` is a sphere (the one surface [`whole_surface_loop`] bounds).
pub(super) fn is_sphere(surface: &TruckSurface) -> bool {
    use truck_stepio::r#in::alias::ElementarySurface;
    matches!(surface, TruckSurface::ElementarySurface(e) if matches!(**e, ElementarySurface::Sphere(_)))
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
    if !is_sphere(surface) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_widest_gap_is_between_the_arcs_the_steps_sweep() {
        // Points at 0.1, 3.0 and 6.0 alone leave 3.0 between 3.0 and 6.0; the steps sweep
        // 3.0..4.5 and, past 2π, 6.0..0.8.
        let mut arcs = [(0.1, 0.1), (3.0, 1.5), (6.0, 1.1)];
        let (gap, at) = widest_gap(&mut arcs).expect("arcs were given");
        let tail = 6.0 + 1.1 - TAU;
        assert!((gap - (3.0 - tail)).abs() < 1e-12, "{gap}");
        assert!((at - 0.5 * (3.0 + tail)).abs() < 1e-12, "{at}");
        // Arcs covering every angle leave no gap.
        let mut all = [(0.0, 3.0), (2.5, 3.0), (5.0, 2.0)];
        assert_eq!(widest_gap(&mut all).map(|g| g.0), Some(0.0));
        assert!(widest_gap(&mut []).is_none());
    }
}
