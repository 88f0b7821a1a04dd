//! How far a trimmed face's tessellation lies from the **trimmed** face, measured
//! independently of the tessellator's own refinement.
//!
//! The tessellator ([`crate::tessellate::TrimmedTessellator`]) measures its error at 7 points
//! per triangle against the *untrimmed* surface at the parameters it refined; a triangle over
//! a wrong trim region, or between those points, goes unseen. Here every triangle is sampled
//! on a barycentric grid of [`SAMPLES_PER_SIDE`] steps (28 points, 4× the refinement's), and
//! each sample `p` is judged against the face itself:
//!
//! 1. `p` is projected onto the surface from scratch (no parameter from the tessellator), at
//!    `uv`, with `d = |S(uv) − p|`;
//! 2. the trim loops are rebuilt from the exact edge curves, sampled until their chords are
//!    within ε/16, projected into parameter space and unwrapped across periodic seams;
//! 3. `uv` is inside the face by the even-odd rule over the loops when every loop closes in
//!    parameter space; when a loop runs around a periodic surface (and would need closing
//!    along a pole or the parameter range), by the side of the nearest boundary segment
//!    instead (the STEP convention: the face lies to the left of its loops when its sense
//!    agrees with the surface's, [`TrimmedFace::domain_left`]); seams are no boundary;
//! 4. the sample's error is `d` inside, and its 3D distance to the boundary curves outside
//!    (the nearest point of the trimmed face then lies on its boundary).
//!
//! Where a loop runs through a pole (a sphere's, a cone's apex, a B-spline side collapsed to a
//! point) it runs along the pole line in parameter space (`model::poles`, a segment that is no
//! boundary in 3D), and where the surface covers itself twice (a sphere, a circle swept about
//! its diameter) a sample is judged on the sheet the loops lie on.
//!
//! That is the distance from the mesh to the face; a mesh can be close to its face everywhere
//! and still leave part of the face out (a sphere cap whose triangles at the pole are slivers
//! spanning the whole opening angle). So the face is sampled too — a grid over its loops'
//! parameter box, the samples inside the trim, at most [`MAX_FACE_SAMPLES`] of them and no
//! closer than ε/2 — and each face point's distance to the mesh (nearest triangle, through a
//! grid of cells) is the geometry missing there ([`FaceFidelity::missing`]).
//!
//! The worst sample over the face (either way) is returned with its position, so `stats` can
//! name faces. What it does not do: samples are points, not a proof (a spike between samples
//! 1/6 of a triangle side apart is missed, and so is a hole between face samples); a surface
//! read wrongly (both the tessellator and this measure evaluate the same surface) is the
//! business of the checks against the file's own edges and of the Open CASCADE cross-check in
//! `tools/occt_fidelity.py`.

use glam::{DMat4, DVec2, DVec3};

use crate::model::poles::{self, Pole};
use crate::model::trimmed::{SurfaceEval, TrimmedFace, TruckSurface};
use crate::tessellate::PatchMesh;

/// Barycentric steps per triangle side: (n+1)(n+2)/2 samples per triangle.
pub const SAMPLES_PER_SIDE: usize = 6;
/// Trim loops are rebuilt to this fraction of ε.
pub const LOOP_FRACTION: f64 = 1.0 / 16.0;
/// Most samples per face (larger meshes are sampled with fewer steps per side).
pub const MAX_SAMPLES: usize = 400_000;
/// Most samples of the face itself (for [`FaceFidelity::missing`]) per face.
pub const MAX_FACE_SAMPLES: usize = 4096;

/// The measured distance of one face's tessellation to the trimmed face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceFidelity {
    /// STEP entity id of the face.
    pub face: u64,
    /// Surface type (`plane`, `cylinder`, `cone`, `sphere`, `torus`, `swept`, `b-spline`,
    /// `nurbs`).
    pub surface: &'static str,
    /// Tolerance the mesh was built for (face units).
    pub eps: f64,
    /// Largest error over all samples (face units).
    pub error: f64,
    /// Largest distance to the untrimmed surface over the samples inside the trim.
    pub surface_error: f64,
    /// Samples outside the trim by more than ε.
    pub outside: usize,
    /// Samples taken.
    pub samples: usize,
    /// Largest distance from a sample of the trimmed face to the mesh: geometry the mesh
    /// leaves out (face units; part of `error`).
    pub missing: f64,
    /// Samples of the face farther than ε from the mesh.
    pub uncovered: usize,
    /// Samples of the face taken.
    pub face_samples: usize,
    /// Where the worst sample is, on the mesh or on the face (face units).
    pub worst_at: DVec3,
}

impl FaceFidelity {
    /// `error / eps`.
    pub fn ratio(&self) -> f64 {
        self.error / self.eps.max(f64::MIN_POSITIVE)
    }
}

/// Surface type name of a face.
pub fn surface_kind(s: &TruckSurface) -> &'static str {
    use truck_stepio::r#in::alias::ElementarySurface as E;
    match s {
        TruckSurface::ElementarySurface(e) => match e.as_ref() {
            E::Plane(_) => "plane",
            E::Sphere(_) => "sphere",
            E::CylindricalSurface(_) => "cylinder",
            E::ToroidalSurface(_) => "torus",
            E::ConicalSurface(_) => "cone",
        },
        TruckSurface::SweptCurve(_) => "swept",
        TruckSurface::BSplineSurface(_) => "b-spline",
        TruckSurface::NurbsSurface(_) => "nurbs",
    }
}

/// Tessellates every patch of `scene` for `view` at `pixel_error` as the renderer does and
/// measures each trimmed one against its face. Sorted worst first, with the patch id.
pub fn measure_scene(
    scene: &crate::model::Scene,
    view: &crate::view::View,
    pixel_error: f64,
) -> Vec<(u32, FaceFidelity)> {
    let meshes = crate::tessellate::tessellate_scene(scene, view, pixel_error);
    measure_meshes(scene, &meshes)
}

/// Measures `meshes` (one per patch of `scene`, in order, in world coordinates, each built
/// for its `eps_target`) against their trimmed faces, on rayon. Sorted worst first.
pub fn measure_meshes(
    scene: &crate::model::Scene,
    meshes: &[PatchMesh],
) -> Vec<(u32, FaceFidelity)> {
    use rayon::prelude::*;
    let mut out: Vec<(u32, FaceFidelity)> = scene
        .patches
        .par_iter()
        .zip(meshes.par_iter())
        .filter_map(|(p, mesh)| {
            let crate::model::PatchSurface::Trimmed(face) = &p.surface else {
                return None;
            };
            measure_placed(face, &p.transform, mesh, mesh.eps_target).map(|f| (p.id, f))
        })
        .collect();
    out.sort_by(|a, b| b.1.ratio().total_cmp(&a.1.ratio()));
    out
}

/// Measures `mesh` (in world coordinates, placed by `transform`) against `face` for the
/// world tolerance `eps`. Returns `None` for an empty mesh.
pub fn measure_placed(
    face: &TrimmedFace,
    transform: &DMat4,
    mesh: &PatchMesh,
    eps: f64,
) -> Option<FaceFidelity> {
    let det = transform.determinant();
    if !det.is_finite() || det.abs() < 1e-300 {
        return None;
    }
    let inverse = transform.inverse();
    let scale = crate::model::transform_scale(transform).max(1e-300);
    let local: Vec<DVec3> = mesh
        .positions
        .iter()
        .map(|p| inverse.transform_point3(p.as_dvec3()))
        .collect();
    measure(face, &local, &mesh.triangles, eps / scale)
}

/// Measures triangles `triangles` over `positions` (face units) against `face` for
/// tolerance `eps` (face units).
pub fn measure(
    face: &TrimmedFace,
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    eps: f64,
) -> Option<FaceFidelity> {
    if triangles.is_empty() || !(eps.is_finite() && eps > 0.0) {
        return None;
    }
    let boundary = Boundary::build(face, eps * LOOP_FRACTION);
    let mut n = SAMPLES_PER_SIDE;
    while n > 1 && triangles.len() * (n + 1) * (n + 2) / 2 > MAX_SAMPLES {
        n -= 1;
    }
    let mut out = FaceFidelity {
        face: face.id,
        surface: surface_kind(&face.surface),
        eps,
        error: 0.0,
        surface_error: 0.0,
        outside: 0,
        samples: 0,
        missing: 0.0,
        uncovered: 0,
        face_samples: 0,
        worst_at: DVec3::ZERO,
    };
    let mut vertex_uv: Vec<Option<DVec2>> = vec![None; positions.len()];
    for t in triangles {
        let Some(corners) = t
            .map(|i| positions.get(i as usize).copied())
            .into_iter()
            .collect::<Option<Vec<_>>>()
        else {
            continue;
        };
        // A hint per triangle: the projection of its first corner (cached per vertex).
        let hint = match vertex_uv.get(t[0] as usize).copied().flatten() {
            Some(uv) => uv,
            None => {
                let uv = face.project(corners[0], None).unwrap_or_default();
                if let Some(c) = vertex_uv.get_mut(t[0] as usize) {
                    *c = Some(uv);
                }
                uv
            }
        };
        let mut prev = hint;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (a, b) = (i as f64 / n as f64, j as f64 / n as f64);
                let p = corners[0] * (1.0 - a - b) + corners[1] * a + corners[2] * b;
                // From the previous sample, and from scratch when that lands far off (a
                // search can end at a cone's apex or across a seam).
                let near = face.project(p, Some(prev));
                let off = |uv: &DVec2| face.point(*uv).distance(p);
                let uv = match near {
                    Some(uv) if off(&uv) <= 0.25 * eps => Some(uv),
                    _ => [near, face.project(p, None), face.project(p, Some(hint))]
                        .into_iter()
                        .flatten()
                        .min_by(|a, b| off(a).total_cmp(&off(b))),
                };
                out.samples += 1;
                let Some(uv) = uv else {
                    // No foot point: judged by the boundary alone.
                    let d = boundary.distance_3d(p);
                    record(&mut out, d, p);
                    continue;
                };
                prev = uv;
                let d = face.point(uv).distance(p);
                let err = if boundary.inside(face, boundary.on_sheet(face, uv)) {
                    out.surface_error = out.surface_error.max(d);
                    d
                } else {
                    let db = boundary.distance_3d(p).min(f64::MAX);
                    if db > eps {
                        out.outside += 1;
                    }
                    db
                };
                record(&mut out, err, p);
            }
        }
    }
    cover(face, &boundary, positions, triangles, eps, &mut out);
    Some(out)
}

/// The face's own samples against the mesh: [`FaceFidelity::missing`].
fn cover(
    face: &TrimmedFace,
    boundary: &Boundary,
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    eps: f64,
    out: &mut FaceFidelity,
) {
    let Some((lo, hi)) = boundary.parameter_box(face) else {
        return;
    };
    let size = (hi - lo) * boundary.metric;
    if !(size.x.is_finite() && size.y.is_finite()) {
        return;
    }
    let area = size.x.max(eps) * size.y.max(eps);
    let h = (0.5 * eps).max((area / MAX_FACE_SAMPLES as f64).sqrt());
    let steps = |len: f64| ((len / h).ceil() as usize).clamp(1, MAX_FACE_SAMPLES);
    let (nu, nv) = (steps(size.x), steps(size.y));
    let (nu, nv) = if nu * nv > 2 * MAX_FACE_SAMPLES {
        let f = ((nu * nv) as f64 / MAX_FACE_SAMPLES as f64).sqrt();
        (
            ((nu as f64 / f) as usize).max(1),
            ((nv as f64 / f) as usize).max(1),
        )
    } else {
        (nu, nv)
    };
    let grid = TriangleGrid::new(positions, triangles);
    for i in 0..nu {
        for j in 0..nv {
            let uv = lo
                + (hi - lo)
                    * DVec2::new((i as f64 + 0.5) / nu as f64, (j as f64 + 0.5) / nv as f64);
            if !boundary.inside_strictly(face, uv) {
                continue;
            }
            let q = face.point(uv);
            if !q.is_finite() {
                continue;
            }
            let d = grid.distance(q);
            out.face_samples += 1;
            out.missing = out.missing.max(d);
            if d > eps {
                out.uncovered += 1;
            }
            record(out, d, q);
        }
    }
}

/// A mesh's triangles binned in a grid of cubic cells (each triangle in every cell its box
/// overlaps), for nearest-triangle distances.
struct TriangleGrid<'a> {
    positions: &'a [DVec3],
    triangles: &'a [[u32; 3]],
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// Per cell, the range of `items` holding its triangles.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl<'a> TriangleGrid<'a> {
    /// Most cells per axis.
    const MAX_DIM: usize = 32;

    fn new(positions: &'a [DVec3], triangles: &'a [[u32; 3]]) -> TriangleGrid<'a> {
        let corners = |t: &[u32; 3]| t.map(|i| positions[i as usize]);
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for t in triangles {
            for p in corners(t) {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        let extent = (hi - lo).max_element();
        let cell = if extent.is_finite() && extent > 0.0 {
            // About one triangle per occupied cell, for a mesh that is a surface.
            let per_axis = (triangles.len() as f64).sqrt().ceil().max(1.0);
            extent / per_axis.min(Self::MAX_DIM as f64)
        } else {
            1.0
        };
        let dim = |d: f64| ((d / cell).floor() as usize + 1).clamp(1, Self::MAX_DIM);
        let size = hi - lo;
        let dims = if lo.is_finite() {
            [dim(size.x), dim(size.y), dim(size.z)]
        } else {
            [1, 1, 1]
        };
        let mut grid = TriangleGrid {
            positions,
            triangles,
            lo: if lo.is_finite() { lo } else { DVec3::ZERO },
            cell,
            dims,
            start: Vec::new(),
            items: Vec::new(),
        };
        let n = dims[0] * dims[1] * dims[2];
        let mut count = vec![0u32; n + 1];
        let cells_of = |g: &TriangleGrid<'_>, t: &[u32; 3]| {
            let c = corners(t);
            let a = g.cell_of(c[0].min(c[1]).min(c[2]));
            let b = g.cell_of(c[0].max(c[1]).max(c[2]));
            (a, b)
        };
        for t in triangles {
            let (a, b) = cells_of(&grid, t);
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        count[grid.index([x, y, z]) + 1] += 1;
                    }
                }
            }
        }
        for k in 1..=n {
            count[k] += count[k - 1];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[n] as usize];
        for (ti, t) in triangles.iter().enumerate() {
            let (a, b) = cells_of(&grid, t);
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        let c = grid.index([x, y, z]);
                        items[fill[c] as usize] = ti as u32;
                        fill[c] += 1;
                    }
                }
            }
        }
        grid.start = count;
        grid.items = items;
        grid
    }

    fn cell_of(&self, p: DVec3) -> [usize; 3] {
        let c = (p - self.lo) / self.cell;
        let f = |x: f64, d: usize| {
            if x.is_nan() {
                0
            } else {
                (x.floor().max(0.0) as usize).min(d - 1)
            }
        };
        [
            f(c.x, self.dims[0]),
            f(c.y, self.dims[1]),
            f(c.z, self.dims[2]),
        ]
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[0] * self.dims[1] + c[1]) * self.dims[2] + c[2]
    }

    fn triangle_distance(&self, q: DVec3, t: u32) -> f64 {
        let [a, b, c] = self.triangles[t as usize].map(|i| self.positions[i as usize]);
        crate::geom::point_triangle_distance(q, a, b, c)
    }

    /// Distance from `q` to the nearest triangle: cells in rings around `q`'s cell until no
    /// triangle outside the rings can be nearer.
    fn distance(&self, q: DVec3) -> f64 {
        let c = self.cell_of(q);
        let mut best = f64::INFINITY;
        let max_k = *self.dims.iter().max().unwrap_or(&1);
        for k in 0..=max_k {
            // A ring as large as the mesh: every triangle once instead.
            if (2 * k + 1).pow(3) > self.triangles.len() {
                return (0..self.triangles.len() as u32)
                    .map(|t| self.triangle_distance(q, t))
                    .fold(best, f64::min);
            }
            let range = |i: usize| (c[i].saturating_sub(k), (c[i] + k).min(self.dims[i] - 1));
            let (rx, ry, rz) = (range(0), range(1), range(2));
            for x in rx.0..=rx.1 {
                for y in ry.0..=ry.1 {
                    for z in rz.0..=rz.1 {
                        let ring = x.abs_diff(c[0]).max(y.abs_diff(c[1])).max(z.abs_diff(c[2]));
                        if ring != k {
                            continue;
                        }
                        let cell = self.index([x, y, z]);
                        let (s, e) = (self.start[cell] as usize, self.start[cell + 1] as usize);
                        for &t in &self.items[s..e] {
                            best = best.min(self.triangle_distance(q, t));
                        }
                    }
                }
            }
            // Untested triangles lie outside the rings' box: at least this far, across its
            // faces inside the grid (nothing lies beyond the grid's own faces).
            let mut bound = f64::INFINITY;
            for (i, (a, b)) in [rx, ry, rz].into_iter().enumerate() {
                if a > 0 {
                    bound = bound.min(q[i] - (self.lo[i] + a as f64 * self.cell));
                }
                if b + 1 < self.dims[i] {
                    bound = bound.min(self.lo[i] + (b + 1) as f64 * self.cell - q[i]);
                }
            }
            if best <= bound.max(0.0) || bound == f64::INFINITY {
                return best;
            }
        }
        best
    }
}

fn record(out: &mut FaceFidelity, err: f64, p: DVec3) {
    if err > out.error || !err.is_finite() {
        out.error = if err.is_finite() { err } else { f64::INFINITY };
        out.worst_at = p;
    }
}

/// The face's trim loops, rebuilt from the edge curves: 3D polylines and their unwrapped
/// parameter-space images.
#[derive(Debug, Default)]
struct Boundary {
    /// Per loop: (3D point, parameter, whether the segment from here to the next point runs
    /// along a seam), closed (the first point repeated, unwrapped).
    loops: Vec<Vec<(DVec3, DVec2, bool)>>,
    periods: (Option<f64>, Option<f64>),
    /// Scales of u and v that make parameter distances roughly 3D distances.
    metric: DVec2,
    /// An odd number of loops runs around the periodic direction (or both directions are
    /// periodic): even-odd has no ray out of the domain, the side test decides.
    wraps: bool,
    /// Pole lines across which the surface folds onto itself, with the side (±1 along the
    /// fixed parameter) the loops lie on.
    sheets: Vec<(Pole, f64)>,
}

impl poles::LoopPoint for (DVec3, DVec2, bool) {
    fn uv(&self) -> DVec2 {
        self.1
    }

    fn with_uv(self, uv: DVec2) -> Self {
        (self.0, uv, self.2)
    }

    fn along_pole(self) -> Self {
        (self.0, self.1, true)
    }
}

/// The pole lines a loop expanded by [`poles::expand_poles`] runs along, where the surface
/// folds across them, with the side of the line the loop lies on.
fn sheet_sides(face: &TrimmedFace, lp: &[(DVec3, DVec2, bool)]) -> Vec<(Pole, f64)> {
    let n = lp.len();
    let mut out: Vec<(Pole, f64)> = Vec::new();
    for k in 0..n {
        let (a, b) = (lp[k], lp[(k + 1) % n]);
        if !a.2 || a.0.distance(b.0) > 0.0 {
            continue;
        }
        let d = b.1 - a.1;
        let free = if d.x.abs() >= d.y.abs() { 0 } else { 1 };
        let pole = Pole {
            free,
            at: a.1[1 - free],
        };
        if face.fold(a.1, pole).is_none() || out.iter().any(|(p, _)| *p == pole) {
            continue;
        }
        // The side of the neighbours that leave the line.
        let off = lp
            .iter()
            .map(|q| q.1[1 - free] - pole.at)
            .max_by(|x, y| x.abs().total_cmp(&y.abs()))
            .unwrap_or(0.0);
        if off != 0.0 {
            out.push((pole, off.signum()));
        }
    }
    out
}

impl Boundary {
    fn build(face: &TrimmedFace, tol: f64) -> Boundary {
        let periods = face.periods();
        let mut loops = Vec::new();
        let mut sheets = Vec::new();
        let mut speeds = DVec2::ZERO;
        let mut count = 0.0;
        // A seam (an edge the face uses twice, once each way) is no boundary: the face lies
        // on both of its sides.
        let mut uses: std::collections::HashMap<u64, usize> = std::collections::HashMap::new();
        for le in face.loops.iter().flatten() {
            *uses.entry(le.edge.id).or_default() += 1;
        }
        for lp in &face.loops {
            let mut pts: Vec<(DVec3, bool)> = Vec::new();
            for le in lp {
                let e = &le.edge;
                let (a, b) = if le.forward {
                    (e.t0, e.t1)
                } else {
                    (e.t1, e.t0)
                };
                let mut ts = vec![a, b];
                // Split until every chord is within `tol` of the curve at its midpoint.
                let mut k = 0;
                while k + 1 < ts.len() && ts.len() < 1 << 14 {
                    let (t0, t1) = (ts[k], ts[k + 1]);
                    let (p0, p1) = (e.point(t0), e.point(t1));
                    let tm = 0.5 * (t0 + t1);
                    let pm = e.point(tm);
                    let chord = (p0 + p1) * 0.5;
                    // Always split the first few times (a closed edge starts and ends at one
                    // point).
                    if pm.distance(chord) > tol || ts.len() < 9 {
                        ts.insert(k + 1, tm);
                    } else {
                        k += 1;
                    }
                }
                // The edge's own start vertex, then curve points; its end is the next edge's
                // start.
                let first = if le.forward { e.start } else { e.end };
                let seam = uses.get(&e.id).is_some_and(|&n| n > 1);
                let n = ts.len();
                for (i, &t) in ts.iter().enumerate().take(n - 1) {
                    pts.push((if i == 0 { first } else { e.point(t) }, seam));
                }
            }
            if pts.len() < 2 {
                continue;
            }
            let mut out: Vec<(DVec3, DVec2, bool)> = Vec::with_capacity(pts.len() + 1);
            let mut prev: Option<DVec2> = None;
            for &(p, seam) in &pts {
                let Some(mut uv) = face.project(p, prev).or_else(|| face.project(p, None)) else {
                    continue;
                };
                if let Some(q) = prev {
                    uv = unwrap_near(uv, q, periods);
                    if uv.distance_squared(q) == 0.0 {
                        continue;
                    }
                }
                let (su, sv) = face.derivs(uv);
                if su.is_finite() && sv.is_finite() {
                    speeds += DVec2::new(su.length(), sv.length());
                    count += 1.0;
                }
                out.push((p, uv, seam));
                prev = Some(uv);
            }
            // Through a pole the loop runs along the pole line (no boundary in 3D: a segment
            // flagged like a seam), on the sheet where the face lies on its `domain_left`.
            if poles::expand_poles(face, &mut out) {
                sheets.extend(sheet_sides(face, &out));
            }
            if let (Some(&first), Some(&(_, last, _))) = (out.first(), out.last()) {
                out.push((first.0, unwrap_near(first.1, last, periods), false));
                loops.push(out);
            }
        }
        let metric = if count > 0.0 {
            (speeds / count).max(DVec2::splat(1e-12))
        } else {
            DVec2::ONE
        };
        let wrapping = loops
            .iter()
            .filter(|lp| {
                let (Some(a), Some(b)) = (lp.first(), lp.last()) else {
                    return false;
                };
                a.1.distance(b.1) > 1e-9 * (1.0 + a.1.length())
            })
            .count();
        // Even-odd needs a ray that leaves the domain: along a direction that is not periodic,
        // and an even number of loops running around the periodic one.
        let wraps = wrapping % 2 == 1 || (periods.0.is_some() && periods.1.is_some());

        Boundary {
            loops,
            periods,
            metric,
            wraps,
            sheets,
        }
    }

    /// `uv` moved onto the sheet the loops lie on, where the surface covers itself twice (a
    /// sample's projection may land on either).
    fn on_sheet(&self, face: &TrimmedFace, mut uv: DVec2) -> DVec2 {
        for &(pole, side) in &self.sheets {
            let fixed = 1 - pole.free;
            let period = if fixed == 0 {
                self.periods.0
            } else {
                self.periods.1
            };
            if let Some(p) = period.filter(|p| *p > 0.0) {
                // Next to the middle of the sheet (half a period wide between two poles).
                let mid = pole.at + side * 0.25 * p;
                uv[fixed] -= ((uv[fixed] - mid) / p).round() * p;
            }
            if (uv[fixed] - pole.at) * side < 0.0
                && let Some(folded) = face.fold(uv, pole)
            {
                uv = folded;
            }
        }
        uv
    }

    /// Whether `uv` lies in the trimmed domain: by the side of the nearest boundary segment,
    /// and, when the loops allow it, by even-odd too (outside only when both say so).
    fn inside(&self, face: &TrimmedFace, uv: DVec2) -> bool {
        if self.wraps {
            return self.inside_by_side(face, uv);
        }
        // Files do not always orient their loops consistently (even-odd does not care) and
        // sampled loops can graze a sample (a ray through a vertex): a sample counts as
        // outside only when the side of its nearest boundary agrees.
        self.inside_by_parity(uv) || self.inside_by_side(face, uv)
    }

    /// Even-odd over the loops (meaningful when no loop runs around the surface).
    fn inside_by_parity(&self, uv: DVec2) -> bool {
        // The ray runs along `r`, crossings are found on `c` (taken modulo its period, if any).
        let (pu, pv) = self.periods;
        let (c, r, period) = if pu.is_some() { (0, 1, pu) } else { (1, 0, pv) };
        let mut odd = false;
        for lp in &self.loops {
            for w in lp.windows(2) {
                let (a, b) = (w[0].1, w[1].1);
                let mut qc = uv[c];
                if let Some(p) = period.filter(|p| *p > 0.0) {
                    qc += ((0.5 * (a[c] + b[c]) - qc) / p).round() * p;
                }
                if (a[c] > qc) != (b[c] > qc) {
                    let t = (qc - a[c]) / (b[c] - a[c]);
                    if a[r] + t * (b[r] - a[r]) > uv[r] {
                        odd = !odd;
                    }
                }
            }
        }
        odd
    }

    /// Whether `uv` lies in the trimmed domain by every test that applies (for the face's
    /// own samples: a point near a boundary that only one test puts inside is left out).
    fn inside_strictly(&self, face: &TrimmedFace, uv: DVec2) -> bool {
        self.inside_by_side(face, uv) && (self.wraps || self.inside_by_parity(uv))
    }

    /// The parameter box of the loops; where a loop runs around the surface, extended along
    /// the other direction to the end of a sphere's or B-spline's parameter range (the face
    /// reaches a pole or the end of the surface there).
    fn parameter_box(&self, face: &TrimmedFace) -> Option<(DVec2, DVec2)> {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for (_, uv, _) in self.loops.iter().flatten() {
            lo = lo.min(*uv);
            hi = hi.max(*uv);
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        if self.wraps && matches!(surface_kind(&face.surface), "sphere" | "b-spline" | "nurbs") {
            let (ru, rv) = crate::model::trimmed::parameter_bounds(&face.surface);
            for (axis, range, period) in [(0, ru, self.periods.0), (1, rv, self.periods.1)] {
                if let (Some((a, b)), None) = (range, period) {
                    lo[axis] = lo[axis].min(a);
                    hi[axis] = hi[axis].max(b);
                }
            }
        }
        Some((lo, hi))
    }

    /// Smallest 3D distance from `p` to the boundary polylines.
    fn distance_3d(&self, p: DVec3) -> f64 {
        let mut best = f64::INFINITY;
        for lp in &self.loops {
            for w in lp.windows(2).filter(|w| !w[0].2) {
                best = best.min(dist_to_segment(p, w[0].0, w[1].0));
            }
        }
        best
    }

    /// Whether `uv` lies on the face's side of the nearest boundary segment.
    fn inside_by_side(&self, face: &TrimmedFace, uv: DVec2) -> bool {
        let scale = self.metric;
        // Nearest segment: (distance², loop, segment, parameter along it, uv shifted).
        let mut best: Option<(f64, usize, usize, f64, DVec2)> = None;
        for (li, lp) in self.loops.iter().enumerate() {
            for (si, w) in lp.windows(2).enumerate() {
                if w[0].2 {
                    continue;
                }
                let (a, b) = (w[0].1, w[1].1);
                let q = unwrap_near(uv, 0.5 * (a + b), self.periods);
                let (a2, b2, q2) = (a * scale, b * scale, q * scale);
                let ab = b2 - a2;
                let t = ((q2 - a2).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
                let d2 = (a2 + ab * t).distance_squared(q2);
                if best.is_none_or(|b| d2 < b.0) {
                    best = Some((d2, li, si, t, q));
                }
            }
        }
        let Some((_, li, si, t, q)) = best else {
            return true;
        };
        let lp = &self.loops[li];
        let seg = |k: usize| {
            let k = k % (lp.len() - 1);
            (lp[k].1 * scale, lp[k + 1].1 * scale, lp[k].2)
        };
        let cross = |d: DVec2, r: DVec2| d.x * r.y - d.y * r.x;
        let (a, b, _) = seg(si);
        let q = q * scale;
        let left = if t > 0.0 && t < 1.0 {
            cross(b - a, q - a) > 0.0
        } else {
            // At a vertex: the two segments meeting there decide.
            let (k_in, k_out) = if t <= 0.0 {
                (si + lp.len() - 2, si)
            } else {
                (si, si + 1)
            };
            // Directions do not depend on which period a segment was unwrapped to; `q` was
            // shifted next to segment `si`, whose end point `v` is.
            let v = if t <= 0.0 { a } else { b };
            let (a_in, b_in, seam_in) = seg(k_in);
            let (a_out, b_out, seam_out) = seg(k_out);
            let (d_in, d_out) = (b_in - a_in, b_out - a_out);
            let l1 = cross(d_in, q - v) > 0.0;
            let l2 = cross(d_out, q - v) > 0.0;
            if seam_in {
                // The boundary goes on across the seam, one period away: straight on.
                l2
            } else if seam_out {
                l1
            } else if cross(d_in, d_out) >= 0.0 {
                l1 && l2
            } else {
                l1 || l2
            }
        };
        left == face.domain_left
    }
}

/// `uv` shifted by whole periods to lie nearest `near`.
fn unwrap_near(mut uv: DVec2, near: DVec2, periods: (Option<f64>, Option<f64>)) -> DVec2 {
    if let Some(p) = periods.0.filter(|p| *p > 0.0) {
        uv.x += ((near.x - uv.x) / p).round() * p;
    }
    if let Some(p) = periods.1.filter(|p| *p > 0.0) {
        uv.y += ((near.y - uv.y) / p).round() * p;
    }
    uv
}

fn dist_to_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
    (a + ab * t).distance(p)
}
