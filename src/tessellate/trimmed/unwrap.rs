//! Parameters across the seams of periodic surfaces: each point of a trim loop is shifted by
//! whole periods to lie next to the one before it ([`unwrap_near`]), and a polyline piece
//! whose shift is ambiguous is split on its curve until it is not ([`bridge`]).

use super::*;

/// Most halvings of one polyline piece by [`bridge`].
const MAX_BRIDGE_DEPTH: u32 = 8;

/// A step of parameters below this fraction of a period is not checked by [`bridge`]: its
/// shift could only be wrong if the curve swept more than 3/4 of a turn of parameter in one
/// piece. At 1/16 the checks cost 23 % of the KiCad boards' tessellation time at ½ px (their
/// small circles' pieces), and changed no mesh.
const BRIDGE_CHECKED: f64 = 0.25;

/// `uv` shifted by whole periods to be nearest to `prev` ([`crate::model::poles::unwrap_near`]
/// with the periods apart).
pub(super) fn unwrap_near(uv: DVec2, prev: DVec2, pu: Option<f64>, pv: Option<f64>) -> DVec2 {
    crate::model::poles::unwrap_near(uv, prev, (pu, pv))
}

/// How many periods a closed loop winds around, per direction.
pub(super) fn winding(lp: &[BPoint], pu: Option<f64>, pv: Option<f64>) -> (i64, i64) {
    let (Some(f), Some(l)) = (lp.first(), lp.last()) else {
        return (0, 0);
    };
    let d = l.uv - f.uv;
    let w = |d: f64, p: Option<f64>| match p {
        Some(p) if p > 0.0 => (d / p).round() as i64,
        _ => 0,
    };
    (w(d.x, pu), w(d.y, pv))
}

/// Points of edge `e` (`src`: its loop and index in the loop) added to `pts` between their
/// last point, at curve parameter `t0`, and the point at `t1`, projected to `raw1` (before
/// unwrapping), while the piece's end does not unwrap to the same parameters from its midpoint
/// as from its start. Only `loops::ROUND` bounds a piece's turn, in 3D: near a pole a short, nearly
/// straight piece can sweep more than half a period of parameter, and its end was then
/// unwrapped the other way round (generated model gen-4-33 at 2 % of its diagonal, T 8.98: a
/// sphere face's edge passing 0.06 rad from the pole swept u by −3.4 in one piece, read as
/// +2.9; the loop wound round the sphere once and the face was drawn as its complement,
/// 3.6 T off). Each half is checked the same way, at most [`MAX_BRIDGE_DEPTH`] times deep.
/// A piece from or to a pole is left alone: any parameter along the pole line is that point.
#[allow(clippy::too_many_arguments)]
pub(super) fn bridge(
    face: &TrimmedFace,
    e: &crate::model::trimmed::TrimEdge,
    src: (u32, u32),
    (t0, t1): (f64, f64),
    raw1: DVec2,
    depth: u32,
    far: f64,
    search: &mut LoopSearch,
    pts: &mut Vec<BPoint>,
) {
    let (pu, pv) = face.periods();
    let Some(uv0) = pts.last().map(|b| b.uv) else {
        return;
    };
    let direct = unwrap_near(raw1, uv0, pu, pv);
    let big = |d: f64, p: Option<f64>| p.is_some_and(|p| p > 0.0 && d.abs() > BRIDGE_CHECKED * p);
    let step = direct - uv0;
    if depth >= MAX_BRIDGE_DEPTH || !(big(step.x, pu) || big(step.y, pv)) {
        return;
    }
    // A pole's u (or v) is any: `expand_poles` runs the loop along the pole line there.
    let at_pole = |uv: DVec2| {
        let (su, sv) = face.derivs(uv);
        face.pole_at(uv, su.length().max(sv.length())).is_some()
    };
    if at_pole(uv0) || at_pole(direct) {
        return;
    }
    let tm = 0.5 * (t0 + t1);
    let pm = e.point(tm);
    let Some(raw_m) = face.project_along(pm, Some(uv0), far, search) else {
        return;
    };
    let mid = unwrap_near(raw_m, uv0, pu, pv);
    let via_mid = unwrap_near(raw1, mid, pu, pv);
    let same = |a: f64, b: f64, p: Option<f64>| p.is_none_or(|p| (a - b).abs() < 0.5 * p);
    if same(via_mid.x, direct.x, pu) && same(via_mid.y, direct.y, pv) {
        return;
    }
    bridge(face, e, src, (t0, tm), raw_m, depth + 1, far, search, pts);
    let uv = unwrap_near(raw_m, pts.last().map_or(uv0, |b| b.uv), pu, pv);
    pts.push(BPoint {
        p: pm,
        uv,
        src: Some((src.0, src.1, tm)),
    });
    bridge(face, e, src, (tm, t1), raw1, depth + 1, far, search, pts);
}
