//! Trim loops in parameter space: edge polylines within ε/2, unwrapped across seams,
//! loops around periodic surfaces aligned, joined or closed, poles split along the pole line,
//! borders refined until the surface at every segment's parameter midpoint is within ε/2.

use super::*;

/// Margin on the pieces [`polyline_params`] predicts an edge needs.
const NEED_MARGIN: f64 = 1.01;

/// Curve parameters of an edge's polyline (from `t0` to `t1`), with chord deviation ≤ `tol`
/// at 3 samples per segment; returns also the largest deviation sampled.
///
/// The edge is first cut into `n0` segments — 8 for a closed edge, 1 for a straight line (its
/// chord is the edge: a midpoint only adds triangles, a rectangular pad's face had 6 instead
/// of 2), else 2 (so that an arc whose quarter points happen to lie near its chord is still
/// measured) — and each one's deviation `d` measured. A chord's deviation from a smooth curve
/// grows with the square of its length, so that segment needs about √(d / tol) pieces: the
/// polyline gets ⌈Σ √(d / tol)⌉ pieces (at least `n0`: one chord across a half circle of
/// radius below ε — its diameter — is within ε in 3D, but its parameter midpoint is the
/// axis, equally near both halves of the cylinder, and `check::fidelity` then judged
/// kicad-demo-tinytapeout's face #57784 2.3 ε off while OCCT measured 0.7 ε), spread in
/// proportion to each segment's √d. A circle gets the count its sagitta asks for (26 where
/// bisection from 8 doubled to 32; on the KiCad boards the borders were most of the triangles,
/// `benches/occt_faces.rs`). Every piece is then checked at its 3 samples and halved while it
/// deviates more than `tol`, as before.
///
/// A segment whose curve runs round its chord rather than along it (at its midpoint) is split
/// however near the chord its samples lie ([`across_chord`]): a helix of 8 turns in two segments of 4 had every
/// sample on its chord, and the thread's flank was drawn 6.2 T off its face. A B-spline edge
/// of more knot spans than `n0` is measured span by span instead ([`knot_spans`]; its pieces
/// are still at least `n0`), and no piece turns more than 140° ([`ROUND`]).
pub(super) fn polyline_params(e: &crate::model::trimmed::TrimEdge, tol: f64) -> (Vec<f64>, f64) {
    let n0 = match (&e.curve, e.is_closed()) {
        (_, true) => 8,
        (crate::model::trimmed::Curve3D::Line(_), false) => 1,
        _ => 2,
    };
    let measure = knot_spans(&e.curve, e.t0, e.t1).clamp(n0, MAX_MEASURED_SPANS);
    measured_params(|t| e.point(t), e.t0, e.t1, n0, measure, tol)
}

/// At most this many of a B-spline edge's knot spans are measured one by one
/// ([`knot_spans`]).
const MAX_MEASURED_SPANS: usize = 4096;

/// How many knot spans of a B-spline (or NURBS) curve lie between `t0` and `t1` (1 for any
/// other curve). An edge's polyline is planned from the deviation of each span
/// ([`measured_params`]): one polynomial span holds about a turn of a helix at most, and its
/// quarter-point samples show its bulge, where the two halves of a long helix can hide
/// theirs. A thread's edge of 8.36 turns (degree 11, 8 spans over its parameter 0..55.7), cut
/// in two, put every sample of each half within 3.19 of its chord and its tangent along it
/// (4.18 turns, the samples 1.05 turns apart), so the polyline was two chords across the
/// thread (generated model gen-35-41 at T 6.38, 2 % of its diagonal: OCCT's judge a 1.19 T,
/// `stats` 1.39 ε).
fn knot_spans(curve: &crate::model::trimmed::Curve3D, t0: f64, t1: f64) -> usize {
    use crate::model::trimmed::Curve3D;
    let knots: &[f64] = match curve {
        Curve3D::BSplineCurve(c) => c.knot_vec(),
        Curve3D::NurbsCurve(c) => c.knot_vec(),
        _ => return 1,
    };
    // Knots are sorted: each distinct value strictly inside the range starts a span.
    let (lo, hi) = (t0.min(t1), t0.max(t1));
    let inside = knots.iter().copied().filter(|&k| k > lo && k < hi);
    1 + inside
        .fold((0usize, f64::NAN), |(n, prev), k| {
            (n + usize::from(k != prev), k)
        })
        .0
}

/// Cosine of the largest angle between the curve's tangent at a segment's midpoint and the
/// chord for the segment to count as running along its chord ([`across_chord`]): 60°. On a
/// segment within the tolerance of a circle of radius r the tangent is at most
/// acos(1 − tol / r) off the chord: under 60° wherever r is over 2 tol.
const ALONG_CHORD_COS: f64 = 0.5;

/// Whether the curve at parameter `t` (in a segment with chord `pa..pb`) runs across the
/// chord: its tangent (a central difference over 10⁻³ of the segment `h`) more than 60° from
/// the chord's direction, on a chord longer than `tol`. Samples alone cannot tell a straight
/// segment from one across whole turns of a helix: there every sample lies on the chord.
fn across_chord(
    point: &impl Fn(f64) -> DVec3,
    t: f64,
    h: f64,
    pa: DVec3,
    pb: DVec3,
    tol: f64,
) -> bool {
    let chord = pb - pa;
    let len = chord.length();
    let tangent = point(t + 1e-3 * h) - point(t - 1e-3 * h);
    let scale = tangent.length() * len;
    len > tol && scale > 0.0 && tangent.dot(chord).abs() < ALONG_CHORD_COS * scale
}

/// How far from its chord, relative to the chord's length, a segment's curve may bulge
/// whatever the tolerance: an arc of θ bulges tan(θ/4)/2, so 0.35 keeps every segment of a
/// circle or helix under 140° of its turn. The loop's parameters are unwrapped across a seam
/// from point to point (to the nearest period), which takes a step of half a turn either way:
/// a helix of radius 4.7 at a tolerance of 6.45 (its polyline two half turns, each within
/// the tolerance of its diameter) was unwrapped as no turn at all, and its cylinder's loop,
/// found to wind round it once, was closed at the cylinder's nominal ends 1 000 mm away
/// (generated model gen-33-39 at 2 % of its diagonal: OCCT's judge a 74.9 T).
const ROUND: f64 = 0.35;

/// [`polyline_params`] for the curve `point` from `t0` to `t1`, cut into `n0` first.
#[cfg(test)]
fn curve_params(
    point: impl Fn(f64) -> DVec3,
    t0: f64,
    t1: f64,
    n0: usize,
    tol: f64,
) -> (Vec<f64>, f64) {
    measured_params(point, t0, t1, n0, n0, tol)
}

/// [`polyline_params`] for the curve `point` from `t0` to `t1`: its deviation measured on
/// `m` equal segments (at least `n0`), and at least `n0` pieces.
fn measured_params(
    point: impl Fn(f64) -> DVec3,
    t0: f64,
    t1: f64,
    n0: usize,
    m: usize,
    tol: f64,
) -> (Vec<f64>, f64) {
    let m = m.max(n0);
    // A segment across its chord at its midpoint counts as deviating by half the chord's
    // length (split; it asks for the pieces a deviation that large would). The midpoint's
    // tangent alone: at all three samples it cost 6-7 % of the corpus's tessellation time.
    // With the chord's length: a segment whose deviation is over `ROUND` of it is split
    // whatever the tolerance ([`ROUND`]).
    let deviation = |a: f64, b: f64| {
        let (pa, pb) = (point(a), point(b));
        let d = [0.25, 0.5, 0.75]
            .iter()
            .map(|f| dist_to_segment(point(a + (b - a) * f), pa, pb))
            .fold(0.0, f64::max);
        // Rounding of the coordinates' size is no bulge (a degenerate edge at one point).
        let chord = pa
            .distance(pb)
            .max(1e-12 * pa.abs().max(pb.abs()).max_element());
        match across_chord(&point, 0.5 * (a + b), b - a, pa, pb, tol) {
            true => (d.max(0.5 * chord), chord),
            false => (d, chord),
        }
    };
    let at = |i: usize, n: usize| t0 + (t1 - t0) * i as f64 / n as f64;
    // Pieces each initial segment asks for (a NaN deviation asks for none, as before).
    let need: Vec<f64> = (0..m)
        .map(|i| {
            let w = (deviation(at(i, m), at(i + 1, m)).0 / tol).sqrt();
            if w.is_finite() { w } else { 0.0 }
        })
        .collect();
    // A circle's sagitta grows a little slower than h² (1 − cos): counted from eighths, its
    // need comes out 0.6 % short, and every piece would then be halved.
    let pieces = ((NEED_MARGIN * need.iter().sum::<f64>()).ceil() as usize)
        .max(n0)
        .min(MAX_EDGE_SEGMENTS);
    // The pieces' ends: equal steps of the cumulative need, linear inside each initial
    // segment (a little need everywhere, so straight stretches of a curve still get spread).
    let weight: Vec<f64> = need.iter().map(|w| w + 1e-3).collect();
    let total: f64 = weight.iter().sum();
    let mut ends = Vec::with_capacity(pieces + 1);
    ends.push(t0);
    let (mut seg, mut below) = (0usize, 0.0f64);
    for k in 1..pieces {
        let target = total * k as f64 / pieces as f64;
        while seg + 1 < m && below + weight[seg] < target {
            below += weight[seg];
            seg += 1;
        }
        let f = ((target - below) / weight[seg]).clamp(0.0, 1.0);
        ends.push(at(seg, m) + (at(seg + 1, m) - at(seg, m)) * f);
    }
    ends.push(t1);
    let mut out = vec![t0];
    let mut worst = 0.0f64;
    // Stack of segments to examine, in reverse order so they pop in order.
    let mut stack: Vec<(f64, f64, usize)> =
        ends.windows(2).rev().map(|w| (w[0], w[1], 0)).collect();
    while let Some((a, b, depth)) = stack.pop() {
        let (dev, chord) = deviation(a, b);
        let round = dev > ROUND * chord;
        if (dev > tol || round) && depth < 24 && out.len() + stack.len() < MAX_EDGE_SEGMENTS {
            let m = 0.5 * (a + b);
            stack.push((m, b, depth + 1));
            stack.push((a, m, depth + 1));
        } else {
            worst = worst.max(dev);
            out.push(b);
        }
    }
    (out, worst)
}

pub(super) fn dist_to_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    if l2 == 0.0 {
        return p.distance(a);
    }
    let t = ((p - a).dot(ab) / l2).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// Shifts each loop by whole periods so that it lies next to the widest loop (the outer one).
/// Loops are unwrapped one by one from their own first point, so on a periodic surface a hole
/// can land a period away from the outer loop's window (an outer loop over u ∈ −2π..0 and a
/// slot at u ≈ π): the hole would then lie outside the domain and be filled.
pub(super) fn align_loops(face: &TrimmedFace, loops: &mut [Vec<BPoint>]) {
    let (pu, pv) = face.periods();
    if pu.is_none() && pv.is_none() {
        return;
    }
    let boxes: Vec<(DVec2, DVec2)> = loops
        .iter()
        .map(|lp| uv_box(std::slice::from_ref(lp)))
        .collect();
    let Some(outer) = boxes
        .iter()
        .max_by(|a, b| (a.1 - a.0).length().total_cmp(&(b.1 - b.0).length()))
        .map(|(lo, hi)| (*lo + *hi) * 0.5)
    else {
        return;
    };
    for (lp, (lo, hi)) in loops.iter_mut().zip(boxes) {
        let c = (lo + hi) * 0.5;
        let shift = |p: Option<f64>, d: f64| match p {
            Some(p) if p > 0.0 => (d / p).round() * p,
            _ => 0.0,
        };
        let delta = DVec2::new(shift(pu, outer.x - c.x), shift(pv, outer.y - c.y));
        if delta != DVec2::ZERO {
            for b in lp.iter_mut() {
                b.uv += delta;
            }
        }
    }
}

/// Joins or closes loops that run around a periodic surface, so that every loop is a closed
/// polygon in parameter space.
pub(super) fn close_wrapping_loops(
    face: &TrimmedFace,
    loops: &mut Vec<Vec<BPoint>>,
) -> Result<(), TrimError> {
    let s = face;
    let (pu, pv) = s.periods();
    let wrapping: Vec<usize> = (0..loops.len())
        .filter(|&i| winding(&loops[i], pu, pv) != (0, 0))
        .collect();
    match wrapping.len() {
        0 => Ok(()),
        1 => {
            let i = wrapping[0];
            let (wu, wv) = winding(&loops[i], pu, pv);
            let (ru, rv) = closing_bounds(&face.surface);
            let lp = &mut loops[i];
            let Some(first) = lp.first().copied() else {
                return Ok(());
            };
            // The loop runs from `first` to `first + w·P`; close it on the side of the domain.
            let end =
                first.uv + DVec2::new(wu as f64 * pu.unwrap_or(0.0), wv as f64 * pv.unwrap_or(0.0));
            // A loop that runs out along a seam (an edge it uses both ways) to a vertex no
            // other edge meets (the seam's dead end, beyond every other edge of the loop:
            // `model::seam`) is closed at that end, as Open CASCADE closes its
            // parameter-space wire: generated model gen-4-17,
            // a wide cone between a circle of radius 3.5 and a seam to radius 43.2, was drawn
            // as the disc inside the circle and a sliver along the seam; gen-46-47, the offset
            // of a spring's pipe (a NURBS of v range 0..34) between its end circle and a seam
            // to v 1.24, as the whole pipe, 28.9 mm past OCCT's part. Without such a seam, a
            // cone's loop is closed at its apex (truck reports a nominal range for cones; a
            // tip's seam ends at the apex, an oblique cut of a tip has none), any other at the
            // end of the range on the side of the domain.
            let on_seam = |b: &BPoint| {
                b.src.is_some_and(|(li, ei, _)| {
                    let edges = face.loops.get(li as usize);
                    let id = edges.and_then(|l| l.get(ei as usize)).map(|le| le.edge.id);
                    edges.is_some_and(|l| l.iter().filter(|le| Some(le.edge.id) == id).count() >= 2)
                })
            };
            // The seam's dead end along `u` (`along_u`) or `v`: its index and coordinate.
            let seam_end = |along_u: bool| {
                let along = |b: &BPoint| if along_u { b.uv.x } else { b.uv.y };
                crate::model::seam::seam_dead_end(lp.iter().map(|b| (along(b), on_seam(b))))
            };
            let apex = |along_u: bool| {
                let t0 = if along_u { first.uv.x } else { first.uv.y };
                singular_range(s, first.uv, along_u).map(|(a, b)| {
                    if (a - t0).abs() > (b - t0).abs() {
                        a
                    } else {
                        b
                    }
                })
            };
            let far = seam_end(wu == 0);
            let (a, b) = if wu != 0 {
                let v = match (far, rv) {
                    (Some((_, v)), _) => v,
                    // Running +u, the left side is +v.
                    (None, Some((_, vmax))) if (wu > 0) == face.domain_left => vmax,
                    (None, Some((vmin, _))) => vmin,
                    (None, None) => apex(false).ok_or(TrimError::UnboundedWrap)?,
                };
                (DVec2::new(end.x, v), DVec2::new(first.uv.x, v))
            } else {
                let u = match (far, ru) {
                    (Some((_, u)), _) => u,
                    // Running +v, the left side is −u.
                    (None, Some((umin, _))) if (wv > 0) == face.domain_left => umin,
                    (None, Some((_, umax))) => umax,
                    (None, None) => apex(true).ok_or(TrimError::UnboundedWrap)?,
                };
                (DVec2::new(u, end.y), DVec2::new(u, first.uv.y))
            };
            // A loop that comes back down its seam on the side it went up (both uses unwrapped
            // to one side of the period) ends where it left the seam's far end: that return
            // leg would lie on the closing line and cross it (gen-45-9's inner cone, once:
            // inside was then told by centroids, not parity). It is dropped, and the loop is
            // closed from the far end across the period and down the seam's other side.
            if let Some((k, _)) = far
                && k + 1 < lp.len()
                && lp[k + 1..].iter().all(on_seam)
                && (if wu != 0 {
                    pu.map(|p| (0, p))
                } else {
                    pv.map(|p| (1, p))
                })
                .is_some_and(|(x, p)| (lp[k].uv[x] - end[x]).abs() < 0.25 * p)
            {
                lp.truncate(k + 1);
                lp.push(BPoint {
                    p: s.point(b),
                    uv: b,
                    src: None,
                });
                return Ok(());
            }
            let mut add = |uv: DVec2| {
                lp.push(BPoint {
                    p: s.point(uv),
                    uv,
                    src: None,
                })
            };
            add(end);
            add(a);
            add(b);
            Ok(())
        }
        2 => {
            let (i, j) = (wrapping[0], wrapping[1]);
            let wi = winding(&loops[i], pu, pv);
            let period = DVec2::new(pu.unwrap_or(0.0), pv.unwrap_or(0.0));
            let shift_i = DVec2::new(wi.0 as f64, wi.1 as f64) * period;
            let b = loops.remove(j.max(i));
            let a = loops.remove(j.min(i));
            let (a, b) = if j > i { (a, b) } else { (b, a) };
            let (Some(a0), Some(b0)) = (a.first().copied(), b.first().copied()) else {
                return Ok(());
            };
            // Shift B so that its start is nearest to A's end (A's start + one turn).
            let a_end = a0.uv + shift_i;
            let dir = shift_i.normalize_or_zero();
            let along = (a_end - b0.uv).dot(dir) / period.dot(dir.abs()).max(1e-300);
            let k = along.round();
            let shift_b = dir * period.dot(dir.abs()) * k;
            let mut joined = a.clone();
            joined.push(BPoint {
                p: a0.p,
                uv: a_end,
                src: None,
            });
            for bp in &b {
                joined.push(BPoint {
                    uv: bp.uv + shift_b,
                    ..*bp
                });
            }
            joined.push(BPoint {
                p: b0.p,
                uv: b0.uv + shift_b - shift_i,
                src: None,
            });
            loops.push(joined);
            Ok(())
        }
        n => Err(TrimError::WrapCount(n)),
    }
}

/// The parameter range a loop running around the surface is closed along: none for a cone
/// (truck reports a nominal `0..1`; the loop is closed at the apex), else the surface's range
/// (a sphere's poles, a B-spline's knot range).
pub(super) fn closing_bounds(s: &TruckSurface) -> (Interval, Interval) {
    use truck_stepio::r#in::alias::ElementarySurface;
    match s {
        TruckSurface::ElementarySurface(e)
            if matches!(**e, ElementarySurface::ConicalSurface(_)) =>
        {
            (None, None)
        }
        _ => parameter_bounds(s),
    }
}

/// Where a surface with an unbounded parameter direction collapses to a point (a cone's
/// apex): searched along the other direction from `uv`. Returns the range between the apex and
/// the far side, or `None`.
pub(super) fn singular_range(s: &impl SurfaceEval, uv: DVec2, along_u: bool) -> Option<(f64, f64)> {
    // Speed in the periodic direction is linear in the other parameter on a cone: extrapolate.
    let at = |t: f64| {
        let q = if along_u {
            DVec2::new(t, uv.y)
        } else {
            DVec2::new(uv.x, t)
        };
        let (du, dv) = s.derivs(q);
        if along_u { dv.length() } else { du.length() }
    };
    let t0 = if along_u { uv.x } else { uv.y };
    let (a, b) = (at(t0), at(t0 + 1.0));
    let slope = b - a;
    if slope.abs() < 1e-300 {
        return None;
    }
    let apex = t0 - a / slope;
    apex.is_finite().then_some((apex.min(t0), apex.max(t0)))
}

/// Splits the segments of `lp` that run along a pole line (both ends the same 3D point, the
/// parameters apart: see `model::poles`) into steps of at most `step` (the interior grid's
/// steps in u and v), so that the triangles at the pole form a fan around it instead of
/// slivers spanning the whole opening angle (no chord test ever splits such a segment).
pub(super) fn split_poles(face: &TrimmedFace, lp: &mut Vec<BPoint>, step: DVec2) {
    let n = lp.len();
    if n < 2 {
        return;
    }
    let tiny = 1e-9 * face.bounds.radius.max(1e-300);
    let mut out: Vec<BPoint> = Vec::with_capacity(n);
    for k in 0..n {
        let (a, b) = (lp[k], lp[(k + 1) % n]);
        out.push(a);
        let d = b.uv - a.uv;
        if a.p.distance(b.p) > tiny || d.length() == 0.0 {
            continue;
        }
        // Along the pole: the surface at the middle is the pole point too.
        let mid = face.point(0.5 * (a.uv + b.uv));
        if mid.distance(a.p) > tiny.max(1e-7 * face.bounds.radius) {
            continue;
        }
        let pieces = (d.x.abs() / step.x.max(1e-300))
            .max(d.y.abs() / step.y.max(1e-300))
            .ceil()
            .clamp(1.0, 4096.0) as usize;
        for s in 1..pieces {
            out.push(BPoint {
                p: a.p,
                uv: a.uv + d * (s as f64 / pieces as f64),
                src: None,
            });
        }
    }
    *lp = out;
}

/// Splits border segments until the surface at the parameter midpoint is within `tol` of the
/// 3D chord midpoint (so the triangles along the border hold the tolerance too). With
/// `only_closing`, segments between two edge points are kept (shared-border mode).
pub(super) fn refine_border(
    face: &TrimmedFace,
    lp: &mut Vec<BPoint>,
    tol: f64,
    only_closing: bool,
) {
    let s = face;
    let mut k = 0;
    let mut budget = 8 * lp.len() + 256;
    while k < lp.len() && budget > 0 {
        let a = lp[k];
        let b = lp[(k + 1) % lp.len()];
        if only_closing && a.src.is_some() && b.src.is_some() {
            k += 1;
            continue;
        }
        let mid_uv = 0.5 * (a.uv + b.uv);
        let chord = 0.5 * (a.p + b.p);
        let on_surface = s.point(mid_uv);
        // A border point off the surface (a model whose edge curves miss their surface) keeps
        // its gap however finely the segment is split: allow the gaps of both ends.
        let gap = 0.5 * (s.point(a.uv).distance(a.p) + s.point(b.uv).distance(b.p));
        if on_surface.distance(chord) <= tol + gap || a.uv.distance(b.uv) < 1e-12 {
            k += 1;
            continue;
        }
        budget -= 1;
        let on_curve = curve_between(face, a, b);
        let m = match on_curve {
            Some((le, la, ea, t)) => {
                let p = le.edge.point(t);
                let (pu, pv) = s.periods();
                let uv = s
                    .project(p, Some(mid_uv))
                    .map(|uv| unwrap_near(uv, mid_uv, pu, pv))
                    .filter(|uv| uv.distance(mid_uv) < a.uv.distance(b.uv))
                    .unwrap_or(mid_uv);
                BPoint {
                    p,
                    uv,
                    src: Some((la, ea, t)),
                }
            }
            None => BPoint {
                p: on_surface,
                uv: mid_uv,
                src: None,
            },
        };
        lp.insert(k + 1, m);
    }
}

/// Where to split the border segment `a`–`b` on a trim curve: the edge and the parameter
/// halfway between the two ends on it, when both lie on one edge. The point at a vertex two
/// edges share carries the first edge's parameter only (the second's first point is dropped
/// as its repeat), so a segment from a vertex to the next edge's first sample, or from an
/// edge's last sample to the vertex it ends at, lies on that edge too. `None` for a closing
/// line (split on the surface). An edge of a single chord (a straight edge) whose ends are
/// both points of other edges is found as the edge after the one `a` ends. Without the vertex rule the stretch of a hyperbola from a
/// wide cone's base circle to its first sample was split on the surface, a straight line in
/// (u, v) 3 mm off the hyperbola: the face was drawn outside its trim (generated model
/// gen-1-42, 11 T from Open CASCADE).
pub(super) fn curve_between(
    face: &TrimmedFace,
    a: BPoint,
    b: BPoint,
) -> Option<(&LoopEdge, u32, u32, f64)> {
    let edge = |l: u32, e: u32| face.loops.get(l as usize)?.get(e as usize);
    let at = |p: DVec3, q: DVec3| p.distance(q) <= 1e-9 * (1.0 + p.length());
    // An edge's first and last point in the loop's direction, with their parameters.
    let first = |le: &LoopEdge| match le.forward {
        true => (le.edge.start, le.edge.t0),
        false => (le.edge.end, le.edge.t1),
    };
    let last = |le: &LoopEdge| match le.forward {
        true => (le.edge.end, le.edge.t1),
        false => (le.edge.start, le.edge.t0),
    };
    let (sa, sb) = (a.src?, b.src?);
    let (la, ea, ta) = sa;
    let (lb, eb, tb) = sb;
    let (le, l, e, t0, t1) = if (la, ea) == (lb, eb) {
        let le = edge(la, ea)?;
        // A closed edge alone in its loop: the segment closing it ends at its last parameter
        // (the first point stands for both ends).
        let tb = match tb == first(le).1 && ta != tb && at(last(le).0, b.p) {
            true => last(le).1,
            false => tb,
        };
        (le, la, ea, ta, tb)
    } else if let Some(le) = edge(lb, eb)
        && at(first(le).0, a.p)
    {
        (le, lb, eb, first(le).1, tb)
    } else if let Some(le) = edge(la, ea)
        && at(last(le).0, b.p)
    {
        (le, la, ea, ta, last(le).1)
    } else if let Some(n) = face.loops.get(la as usize).map(Vec::len)
        && let Some(le) = edge(la, (ea + 1) % n as u32)
        && at(first(le).0, a.p)
        && at(last(le).0, b.p)
    {
        // An edge of one chord whose both points are another's: its first the previous
        // edge's last, its last the loop's first point (a straight edge closing its loop).
        (le, la, (ea + 1) % n as u32, first(le).1, last(le).1)
    } else {
        return None;
    };
    (t0 != t1).then_some((le, l, e, 0.5 * (t0 + t1)))
}

impl TrimmedTessellator {
    /// The border of one loop: polylines of its edges within `tol`, projected to parameter
    /// space.
    pub(super) fn loop_points(
        &mut self,
        face: &TrimmedFace,
        li: usize,
        lp: &[LoopEdge],
        tol: f64,
        search: &mut LoopSearch,
        report: &mut TrimReport,
    ) -> Result<Vec<BPoint>, TrimError> {
        let s = face;
        let (pu, pv) = s.periods();
        let mut pts: Vec<BPoint> = Vec::new();
        for (k, le) in lp.iter().enumerate() {
            let e = &le.edge;
            let (ts, dev) = polyline_params(e, tol);
            report.trim_error = report.trim_error.max(dev);
            let n = ts.len();
            let ordered: Vec<f64> = if le.forward {
                ts
            } else {
                ts.into_iter().rev().collect()
            };
            let (first, last) = if le.forward {
                (e.start, e.end)
            } else {
                (e.end, e.start)
            };
            let mut t_prev = None;
            for (i, &t) in ordered.iter().enumerate() {
                let t_before = t_prev.replace(t);
                let p = if i == 0 {
                    first
                } else if i == n - 1 {
                    last
                } else {
                    e.point(t)
                };
                // Skip a point equal to the previous one (the shared vertex of two edges).
                if let Some(prev) = pts.last()
                    && prev.p.distance(p) <= 1e-12 * (1.0 + p.length())
                {
                    continue;
                }
                let far = 1e-3 * face.bounds.radius;
                // The loop's first point as an earlier tessellation found it: the same vertex
                // at every ε (checked, as is that its parameter still lands on it).
                let known = match (pts.is_empty(), face.loop_starts.get(li)) {
                    (true, Some(&Some((q, uv)))) if q == p && s.point(uv).distance(p) <= far => {
                        Some(uv)
                    }
                    _ => None,
                };
                // The loop's first point is projected from an interior point of its edge: a
                // vertex on the seam of a closed surface lies on both sides of it, and where
                // the surface is extended past its seam (a lofted side that a fillet grew, by
                // 5.4 of 70 in u on generated model gen-7-6) the nearest side was the
                // extension: the whole loop then followed it, up to 24 off the face.
                let hint = match pts.last() {
                    Some(b) => Some(b.uv),
                    None if known.is_some() => None,
                    None if ordered.len() >= 2 => {
                        let q = e.point(0.5 * (ordered[0] + ordered[1]));
                        s.project_along(q, None, far, search)
                    }
                    None => None,
                };
                // Loop points lie on the surface (within the model's gaps), whatever ε: a
                // nearest point farther than this is on another sheet (a thread's next turn,
                // 1.66 off at ε 1.66 on generated model gen-1-85: the loop then ran over
                // three turns and half the face was drawn outside its trim).
                let uv = match known {
                    Some(uv) => Some(uv),
                    None => s.project_along(p, hint, far, search),
                };
                let Some(mut uv) = uv else {
                    return Err(TrimError::Projection { edge: e.id });
                };
                if let Some(t0) = t_before {
                    let src = (li as u32, k as u32);
                    bridge(s, e, src, (t0, t), uv, 0, far, search, &mut pts);
                }
                if let Some(prev) = pts.last() {
                    uv = unwrap_near(uv, prev.uv, pu, pv);
                } else if let Some(start) = self.starts.get_mut(li) {
                    *start = Some((p, uv));
                }
                pts.push(BPoint {
                    p,
                    uv,
                    src: Some((li as u32, k as u32, t)),
                });
            }
        }
        // A loop through a pole runs along the pole line there.
        expand_poles(face, &mut pts);
        // The loop closes on its first point: drop a repeated last point.
        if pts.len() > 1
            && let (Some(f), Some(l)) = (pts.first(), pts.last())
            && f.p.distance(l.p) <= 1e-12 * (1.0 + f.p.length())
        {
            let l = pts[pts.len() - 1];
            let unwrapped = unwrap_near(l.uv, f.uv, pu, pv);
            if unwrapped.distance(f.uv) < 1e-9 * (1.0 + f.uv.length()) {
                pts.pop();
            }
        }
        Ok(pts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A helix of `turns` turns of radius `r` and pitch `pitch`, by turns.
    fn helix(r: f64, pitch: f64) -> impl Fn(f64) -> DVec3 {
        move |t: f64| {
            let a = std::f64::consts::TAU * t;
            DVec3::new(r * a.cos(), r * a.sin(), pitch * t)
        }
    }

    /// Largest distance from the curve (densely sampled) to the polyline through `ts`.
    fn gap(point: &impl Fn(f64) -> DVec3, ts: &[f64]) -> f64 {
        let (a, b) = (ts[0], ts[ts.len() - 1]);
        (0..=8000)
            .map(|i| {
                let p = point(a + (b - a) * i as f64 / 8000.0);
                ts.windows(2)
                    .map(|w| dist_to_segment(p, point(w[0]), point(w[1])))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    }

    /// A thread's edge of 8 turns (and 16) cut in two: every sample of each half (its
    /// quarter points and midpoint, whole turns along) lies on its chord. The tangents there
    /// run round it, so the halves are split and the polyline follows every turn (without
    /// `across_chord`: 2 chords, 5.9 off the helix).
    #[test]
    fn an_edge_across_whole_turns_of_a_helix_is_followed() {
        let (r, pitch, tol) = (5.863, 2.013, 0.38);
        let point = helix(r, pitch);
        for turns in [8.0, 16.0] {
            let (ts, dev) = curve_params(&point, 0.0, turns, 2, tol);
            let g = gap(&point, &ts);
            assert!(
                g <= 1.05 * tol,
                "{turns} turns: {g} off ({} points)",
                ts.len()
            );
            assert!(dev <= tol, "{turns} turns: deviation {dev}");
        }
        // A circle's chords within the tolerance are not split for their tangents: the
        // count its sagitta asks for, as before.
        let circle = helix(r, 0.0);
        let (ts, _) = curve_params(&circle, 0.0, 1.0, 8, tol);
        let sagitta = |n: usize| r * (1.0 - (std::f64::consts::PI / n as f64).cos());
        let need = (3..).find(|&n| sagitta(n) <= tol).unwrap_or(3);
        assert!(
            ts.len() - 1 <= 2 * need,
            "{} pieces for a circle needing {need}",
            ts.len() - 1
        );
    }

    /// One turn of a thread's root helix (generated model gen-33-39's, in mm) at a tolerance
    /// above its radius: each half turn is within the tolerance of its diameter, but the
    /// loop's parameters could not be unwrapped across such steps. Every piece turns under
    /// 140° ([`ROUND`]); with the rule off, 2 pieces of 180°.
    #[test]
    fn no_piece_turns_half_a_turn_whatever_the_tolerance() {
        let point = helix(4.7, 2.44);
        for tol in [6.45, 20.0, 1e3] {
            let (ts, _) = curve_params(&point, 0.0, 1.0, 2, tol);
            let widest = ts.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
            assert!(
                widest * 360.0 < 140.0,
                "tolerance {tol}: a piece of {:.0}° ({} pieces)",
                widest * 360.0,
                ts.len() - 1
            );
        }
        // A degenerate edge, its points one point up to rounding, is not split for that.
        let noise = |t: f64| DVec3::new(1e3 + 1e-13 * (97.0 * t).sin(), 5e2, 1e-14 * t.cos());
        let (ts, _) = curve_params(noise, 0.0, 10.0, 2, 1e-3);
        assert!(ts.len() <= 3, "{} pieces for a point", ts.len() - 1);
    }
}
