//! Poles of a trimmed face's parameter space: lines that the surface maps to one point (a
//! sphere's poles, a cone's apex, a B-spline side collapsed to a point, a circle swept about
//! its diameter), and the parameter-space image of a trim loop that runs through one.
//!
//! A trim loop that runs into a pole has a well-defined 3D polyline but no well-defined
//! parameter there: the free parameter of the pole point is whatever the projection left. In
//! parameter space the loop has to run *along* the pole line, from the free parameter it came
//! in with to the one it leaves with; `expand_poles` replaces every pole point by that
//! segment:
//! - **which way** — along a periodic free direction the two ends are only known modulo the
//!   period; the segment runs so that the face lies on its left (or right, when the face's
//!   sense is against the surface's: [`TrimmedFace::domain_left`]), i.e. it spans the face's
//!   whole opening angle at the pole (a cap bounded by a circle and a seam to its pole gets the
//!   full period);
//! - **which sheet** — a sphere (and a circle swept about its diameter) covers itself twice:
//!   past a pole, `(u + P/2, 2c − v)` is the same point as `(u, v)`. A projection that went on
//!   past the pole is folded back ([`TrimmedFace::fold`]), so the loop stays on the side of the
//!   pole line it came from. The two sheets have opposite normals, so the face's side of its
//!   loop is only known on the sheet the file meant: a loop through a pole closes in parameter
//!   space only there, and a loop that would run around the surface is folded onto the other
//!   sheet.
//!
//! Used by the tessellator (`tessellate::trimmed`) and by the fidelity measure
//! (`check::fidelity`) for their loops; the segment along the pole maps to a single 3D point,
//! so neither a chord test nor a 3D distance sees it.
//!
//! What it does not do: a loop that crosses a pole *between* two polyline points (neither of
//! them at the pole) is not detected; a pole line is not searched for when a loop that runs
//! around the surface must be closed (the tessellator closes it along the surface's parameter
//! range).

use glam::{DVec2, DVec3};

use super::trimmed::{Interval, SurfaceEval, TrimmedFace, parameter_bounds};

/// Below this fraction of a face's typical speed, a parameter derivative counts as vanished:
/// the point is a pole ([`TrimmedFace::pole_at`]).
pub(crate) const POLE_SPEED: f64 = 1e-6;

/// Fraction of a period under which the two ends of a pole segment count as the same
/// parameter (the loop goes once around the pole).
const SAME_END: f64 = 1e-9;

/// A line of parameter space that the surface maps to a single point: `free` is the
/// parameter that runs along it (0 = u, the line `v = at`; 1 = v, the line `u = at`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pole {
    pub free: usize,
    pub at: f64,
}

/// A point of a loop in parameter space, as [`expand_poles`] needs it.
pub(crate) trait LoopPoint: Copy {
    fn uv(&self) -> DVec2;
    fn with_uv(self, uv: DVec2) -> Self;
    /// This point, as the start of a segment that runs along a pole line (to the next point).
    fn along_pole(self) -> Self {
        self
    }
}

impl TrimmedFace {
    /// The pole through `uv`, if the surface collapses to a point along one parameter there:
    /// the derivative along that parameter is below [`POLE_SPEED`] × `speed` (a typical speed
    /// of the face).
    pub(crate) fn pole_at(&self, uv: DVec2, speed: f64) -> Option<Pole> {
        let (su, sv) = self.derivs(uv);
        let (lu, lv) = (su.length(), sv.length());
        let tiny = POLE_SPEED * speed;
        if !(lu.is_finite() && lv.is_finite() && tiny > 0.0) {
            return None;
        }
        if lu <= tiny && lv > tiny {
            Some(Pole { free: 0, at: uv.y })
        } else if lv <= tiny && lu > tiny {
            Some(Pole { free: 1, at: uv.x })
        } else {
            None
        }
    }

    /// The other parameter of the point at `uv` across the pole line `pole`, on a surface
    /// of revolution whose profile runs through the axis symmetrically (a sphere, a circle
    /// swept about its diameter): `(u + P/2, 2c − v)` for a line `v = c` along the periodic
    /// `u` (P its period), and likewise with the roles swapped. `None` when the free
    /// direction is not periodic or that parameter is another point.
    pub fn fold(&self, uv: DVec2, pole: Pole) -> Option<DVec2> {
        self.folds_across(pole)
            .then(|| self.folded(uv, pole))
            .flatten()
    }

    /// `(u + P/2, 2c − v)` (or with the roles swapped), without asking whether it is the
    /// same point.
    fn folded(&self, uv: DVec2, pole: Pole) -> Option<DVec2> {
        let (pu, pv) = self.periods();
        let period = if pole.free == 0 { pu } else { pv }.filter(|p| *p > 0.0)?;
        let fixed = 1 - pole.free;
        let mut other = uv;
        other[pole.free] += 0.5 * period;
        other[fixed] = 2.0 * pole.at - uv[fixed];
        Some(other)
    }

    /// The length of each parameter direction: its period, else its finite range, else 1.
    fn parameter_spans(&self) -> DVec2 {
        let (pu, pv) = self.periods();
        let (ru, rv) = parameter_bounds(&self.surface);
        let span = |period: Option<f64>, range: Interval| {
            period
                .or(range.map(|(a, b)| b - a))
                .filter(|l| l.is_finite() && *l > 0.0)
                .unwrap_or(1.0)
        };
        DVec2::new(span(pu, ru), span(pv, rv))
    }

    /// Whether the surface is symmetric across the pole line (every parameter and its fold
    /// one point), tested off the line: on it every parameter is the pole anyway.
    fn folds_across(&self, pole: Pole) -> bool {
        let fixed = 1 - pole.free;
        let spans = self.parameter_spans();
        let off = 0.1 * spans[fixed];
        let mut checked = false;
        for k in 0..3 {
            let mut uv = DVec2::ZERO;
            uv[pole.free] = spans[pole.free] * k as f64 / 3.0;
            uv[fixed] = pole.at + off;
            let Some(other) = self.folded(uv, pole) else {
                return false;
            };
            let (p, q) = (self.point(uv), self.point(other));
            let mut at_pole = uv;
            at_pole[fixed] = pole.at;
            let scale = p.distance(self.point(at_pole));
            if !(p.is_finite() && q.is_finite() && scale > 0.0) {
                continue;
            }
            if p.distance(q) > 1e-6 * scale {
                return false;
            }
            checked = true;
        }
        checked
    }

    /// The pole `uv` lies on when a projection of `p` ended there off the surface: at a pole
    /// the derivative along the pole line vanishes, so a search from there cannot tell which
    /// way `p` lies (a dome's tip: every direction leaves the pole, one of them towards `p`).
    pub(super) fn stalled_at_pole(&self, uv: DVec2, p: DVec3) -> Option<Pole> {
        let (su, sv) = self.derivs(uv);
        let speed = su.length().max(sv.length());
        let gap = self.point(uv).distance(p);
        // (A NaN gap is no stall either.)
        if gap.is_nan() || gap <= 1e-9 * self.bounds.radius.max(1e-300) {
            return None;
        }
        self.pole_at(uv, speed)
    }

    /// Starts for a search for `p` spread around the pole at `uv`, a little off it on both
    /// sides (the search keeps a B-spline in its knot range).
    pub(super) fn around_pole(&self, uv: DVec2, pole: Pole) -> impl Iterator<Item = DVec2> {
        const STARTS: usize = 16;
        let (free, fixed) = (pole.free, 1 - pole.free);
        let (ru, rv) = parameter_bounds(&self.surface);
        let spans = self.parameter_spans();
        let start = if free == 0 { ru } else { rv }.map_or(0.0, |r| r.0);
        let step = 1e-3 * spans[fixed];
        (0..2 * STARTS).map(move |k| {
            let mut g = uv;
            g[free] = start + spans[free] * (k / 2) as f64 / STARTS as f64;
            g[fixed] += if k % 2 == 0 { step } else { -step };
            g
        })
    }
}

/// `uv` shifted by whole periods to be nearest to `near`.
pub(crate) fn unwrap_near(
    mut uv: DVec2,
    near: DVec2,
    (pu, pv): (Option<f64>, Option<f64>),
) -> DVec2 {
    if let Some(p) = pu.filter(|p| *p > 0.0) {
        uv.x -= ((uv.x - near.x) / p).round() * p;
    }
    if let Some(p) = pv.filter(|p| *p > 0.0) {
        uv.y -= ((uv.y - near.y) / p).round() * p;
    }
    uv
}

/// Whether a closed loop (first point not repeated, each point unwrapped next to the one
/// before) runs around a periodic direction: its last point lies a whole period or more from
/// its first.
pub(crate) fn winds(face: &TrimmedFace, lp: &[impl LoopPoint]) -> bool {
    let (Some(first), Some(last)) = (lp.first(), lp.last()) else {
        return false;
    };
    let d = last.uv() - first.uv();
    let (pu, pv) = face.periods();
    let turns = |x: f64, p: Option<f64>| p.is_some_and(|p| p > 0.0 && (x / p).round() != 0.0);
    turns(d.x, pu) || turns(d.y, pv)
}

/// Replaces the points of `lp` (a closed loop, first point not repeated, unwrapped point to
/// point) that lie on a pole by a segment along the pole line, folding the loop onto one sheet
/// and shifting what follows by whole periods so that the segment spans the face's opening at
/// the pole (see the module doc). The loop may come out rotated (it starts at a point that is
/// not a pole). Returns whether it passed through a pole.
pub(crate) fn expand_poles<T: LoopPoint>(face: &TrimmedFace, lp: &mut Vec<T>) -> bool {
    let n = lp.len();
    if n < 2 {
        return false;
    }
    let speed = lp
        .iter()
        .map(|b| {
            let (du, dv) = face.derivs(b.uv());
            du.length().max(dv.length())
        })
        .filter(|s| s.is_finite())
        .fold(0.0, f64::max);
    if speed <= 0.0 {
        return false;
    }
    let mut poles: Vec<Option<Pole>> = lp.iter().map(|b| face.pole_at(b.uv(), speed)).collect();
    if poles.iter().all(Option::is_none) {
        return false;
    }
    // Start at a point that is not a pole: it fixes the frame the rest is expressed in.
    let Some(start) = poles.iter().position(Option::is_none) else {
        return false;
    };
    lp.rotate_left(start);
    poles.rotate_left(start);
    let (out, fold) = expand(face, lp, &poles, face.domain_left);
    if let Some(pole) = fold
        && winds(face, &out)
    {
        let (other, _) = expand(face, lp, &poles, !face.domain_left);
        if !winds(face, &other)
            && let Some(folded) = other
                .iter()
                .map(|b| face.fold(b.uv(), pole).map(|uv| b.with_uv(uv)))
                .collect::<Option<Vec<_>>>()
        {
            *lp = folded;
            return true;
        }
    }
    *lp = out;
    true
}

/// The expansion of [`expand_poles`] with the face on the `left` of the loop (or right);
/// `lp` starts with a point that is not a pole. Also returns the first pole line across which
/// the surface folds onto itself (in the output's frame), if any.
fn expand<T: LoopPoint>(
    face: &TrimmedFace,
    lp: &[T],
    poles: &[Option<Pole>],
    left: bool,
) -> (Vec<T>, Option<Pole>) {
    let n = lp.len();
    let periods = face.periods();
    let period = |axis: usize| if axis == 0 { periods.0 } else { periods.1 }.filter(|p| *p > 0.0);
    // Every point's parameter is mapped by `a ⊙ uv + b` (folds across pole lines negate one
    // coordinate; turns around a pole add whole periods).
    let (mut a, mut b) = (DVec2::ONE, DVec2::ZERO);
    let mut foldable: Option<Pole> = None;
    let mut out: Vec<T> = Vec::with_capacity(n + 8);
    let mut i = 0;
    while i < n {
        let Some(pole) = poles[i] else {
            out.push(lp[i].with_uv(a * lp[i].uv() + b));
            i += 1;
            continue;
        };
        // A run of pole points i..j, then the point the loop leaves the pole with.
        let j = (i..n).find(|&k| poles[k].is_none()).unwrap_or(n);
        let raw_next = if j < n {
            lp[j].uv()
        } else {
            unwrap_near(lp[0].uv(), lp[n - 1].uv(), periods)
        };
        let (free, fixed) = (pole.free, 1 - pole.free);
        let Some(prev) = out.last().map(|p| p.uv()) else {
            // Unreachable: the loop starts at a point that is not a pole.
            i = j;
            continue;
        };
        // The pole line in the mapped frame.
        let c = (a * lp[i].uv() + b)[fixed];
        let line = Pole { free, at: c };
        let side_in = (prev[fixed] - c).signum();
        let mut next = a * raw_next + b;
        if foldable.is_none() && face.fold(next, line).is_some() {
            foldable = Some(line);
        }
        if side_in != 0.0 && (next[fixed] - c).signum() == -side_in {
            // The projection went on past the pole: fold it back when that is the same point.
            if let Some(folded) = face.fold(next, line) {
                let shift = folded[free] - next[free];
                a[fixed] = -a[fixed];
                b[fixed] = 2.0 * c - b[fixed];
                b[free] += shift;
                next = a * raw_next + b;
            }
        }
        let u_in = prev[free];
        let mut jump = next[free] - u_in;
        if let Some(p) = period(free) {
            // Run along the pole with the face on the side the loop keeps it: the normal
            // towards the face is `side_in` along `fixed`, and the face is on the left of a
            // direction d when d turned a quarter anticlockwise is that normal.
            let left_normal_sign = if free == 0 { side_in } else { -side_in };
            let forward = (left_normal_sign > 0.0) == left;
            let r = jump.rem_euclid(p);
            jump = if side_in == 0.0 {
                // No side to go by: the shorter way.
                if r > 0.5 * p { r - p } else { r }
            } else if forward {
                if r <= SAME_END * p { p } else { r }
            } else if r >= (1.0 - SAME_END) * p || r == 0.0 {
                -p
            } else {
                r - p
            };
        }
        b[free] += u_in + jump - next[free];
        let mut enter = prev;
        enter[fixed] = c;
        let mut leave = enter;
        leave[free] = u_in + jump;
        out.push(lp[i].with_uv(enter).along_pole());
        out.push(lp[j - 1].with_uv(leave));
        i = j;
    }
    (out, foldable)
}
