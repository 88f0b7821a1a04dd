//! Closing a trim loop that runs round its surface and out along a seam, for the fidelity
//! measure's boundary (`super::boundary`), as the tessellator closes it
//! (`tessellate::trimmed::loops`): at the seam's dead end ([`seam_dead_end`]).

use glam::{DVec2, DVec3};

use crate::model::seam::seam_dead_end;
use crate::model::trimmed::{SurfaceEval, TrimmedFace};

/// A loop that runs around the surface and out along a seam (an edge it uses both ways) to a
/// vertex no other edge meets ends at the seam's dead end: the tessellator closes it there
/// (`tessellate::trimmed::loops`), as Open CASCADE's parameter-space wire does. The loop
/// `out` (from its first point to `close`, that start a period on; `marks`: every point
/// projected, repeats too) is closed up its seam to that end, across the period there (a
/// boundary, sampled to `tol`) and down the seam's other side to the first point. `false`,
/// nothing added, for any other loop, and for one whose far end is one point (a cone's apex).
/// (Judged as running on to the end of its parameter range, the band of a spring's offset
/// pipe that gen-46-47 keeps read as the whole pipe.)
pub(super) fn seam_closure(
    face: &TrimmedFace,
    out: &mut Vec<(DVec3, DVec2, bool)>,
    marks: &[(DVec2, bool)],
    close: DVec2,
    periods: (Option<f64>, Option<f64>),
    tol: f64,
) -> bool {
    let Some(&first) = out.first() else {
        return false;
    };
    let turn = close - first.1;
    if turn.length() <= 1e-9 * (1.0 + first.1.length()) {
        return false;
    }
    // Around along `axis`; the seam runs along the other.
    let axis = usize::from(turn.y.abs() > turn.x.abs());
    let other = 1 - axis;
    // The dead end told from every point (a degenerate edge there is repeated points, dropped
    // from `out`), and its place in `out`: the first seam point there.
    let Some((_, far)) = seam_dead_end(marks.iter().map(|m| (m.0[other], m.1))) else {
        return false;
    };
    let Some(k) = out
        .iter()
        .enumerate()
        .filter(|(_, q)| q.2)
        .min_by(|a, b| {
            (a.1.1[other] - far)
                .abs()
                .total_cmp(&(b.1.1[other] - far).abs())
        })
        .map(|(k, _)| k)
    else {
        return false;
    };
    let at = |t: f64| {
        let mut uv = close;
        uv[other] = far;
        uv[axis] = close[axis] - t * turn[axis];
        (face.point(uv), uv)
    };
    // Sampled until every chord's middle lies within `tol` of the line (a fixed 32 steps
    // round gen-45-9's inner cone sagged 4.7 ε at 1e-3 of its radius, read as samples outside).
    let mut steps = 32;
    let across: Vec<(DVec3, DVec2)> = loop {
        let pts: Vec<(DVec3, DVec2)> = (0..=steps).map(|i| at(i as f64 / steps as f64)).collect();
        let sag = (0..steps)
            .map(|i| {
                at((i as f64 + 0.5) / steps as f64)
                    .0
                    .distance(0.5 * (pts[i].0 + pts[i + 1].0))
            })
            .fold(0.0, f64::max);
        if sag.is_nan() || sag <= tol || steps >= 1 << 14 {
            break pts;
        }
        steps *= 2;
    };
    let length: f64 = across.windows(2).map(|w| w[0].0.distance(w[1].0)).sum();
    if length.is_nan() || length <= 1e-9 * face.bounds.radius {
        // A cone's tip: its apex line is no boundary, and running round the surface the
        // loop is judged by the side of its circle, as before.
        return false;
    }
    // A loop that came back down its seam on the side it went up (the far end unwrapped
    // near `close`) ends where it left the far end: as the tessellator does, that return leg
    // is dropped (it would lie on the closing line), and the loop goes on across from there.
    let period = if axis == 0 { periods.0 } else { periods.1 };
    let back = k + 1 < out.len()
        && out[k + 1..].iter().all(|q| q.2)
        && period.is_some_and(|p| (out[k].1[axis] - close[axis]).abs() < 0.25 * p);
    if back {
        out.truncate(k + 1);
    } else {
        // Up the seam (no boundary).
        out.push((face.point(close), close, true));
    }
    // Across, down the other side (no boundary) to the start.
    for (i, &(p, uv)) in across.iter().enumerate().skip(usize::from(back)) {
        out.push((p, uv, i == steps));
    }
    out.push((first.0, first.1, false));
    true
}
