//! Trimmed-face tessellation under a tolerance, after the on-the-fly NURBS tessellation of
//! Balázs, Guthe and Klein, "Fat Borders" (2004), §5: every face on its own, its border the
//! polyline of its trim curves, so neighbours need not agree and fat borders close the gaps.
//!
//! For a tolerance ε:
//! 1. **Trim polylines** — every edge curve is split until the chord deviates from the curve
//!    by at most ε/2 (3 samples per segment), from the edge's own start vertex, so a shared
//!    edge gives the same points to both faces when their ε agree. The vertices are the exact
//!    STEP vertices. Where spade finds two polylines crossing (a peninsula of the face
//!    narrower than ε), the face is tessellated again with its edges followed to ε/8, then
//!    ε/32, and the attempt with the fewest crossings kept.
//! 2. **Parameter space** — each point is projected onto the surface (nearest parameter, from
//!    the previous point), unwrapped across the seams of periodic surfaces; where a loop runs
//!    through a pole (a vanishing derivative) it runs along the pole line from the parameter
//!    it came in with to the one it leaves with, on one sheet of a surface that covers itself
//!    twice (`model::poles`). Loops that run around a periodic surface are joined to a second
//!    such loop, or closed along a pole / the parameter range. Segments along a pole are split
//!    into steps of the interior grid (a fan at the pole, not slivers across its opening), and
//!    every segment is split again until the surface at the middle of its parameter chord is
//!    within ε/2 of the 3D chord, so triangles along the border hold ε too.
//! 3. **Interior** — a grid whose steps follow from ε and the largest second derivatives
//!    sampled on the domain (`(M_uu h_u² + 2 M_uv h_u h_v + M_vv h_v²)/8 ≤ ε`), points
//!    strictly inside the trimmed domain and away from its border.
//! 4. **Constrained Delaunay** (spade) of grid and border in a parameter space scaled to the
//!    error metric — one unit per grid step, so a unit cell holds ε and triangles stretch along
//!    directions that do not curve (a cylinder's axis); a flat face is scaled by its mean
//!    speeds |S_u|, |S_v| instead. Triangles outside the domain are dropped (parity across
//!    the constraint edges; where constraints cross, by their centroids, a sliver's by its
//!    3D side: `domain::inside_faces`).
//! 5. **Measured error** — the distance between the surface and the triangle at 7 samples per
//!    triangle (centroid, edge midpoints, inner points); triangles above ε get their centroid
//!    inserted, for a few rounds. The maximum measured is returned with the mesh.

use glam::{DVec2, DVec3, Vec3};
use spade::handles::FixedVertexHandle;
use spade::{ConstrainedDelaunayTriangulation, HierarchyHintGenerator, Point2, Triangulation};

/// The triangulation: a point-location hierarchy finds where each point goes in O(log n)
/// steps whatever the insertion order (the default walk from the last point inserted is
/// linear on a scrambled order).
type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>, (), (), (), HierarchyHintGenerator<f64>>;

use super::{PatchMesh, Resolution, Stop};
use crate::model::edges::{EdgeKind, EdgeNormals, SAMPLES};
use crate::model::poles::{LoopPoint, expand_poles};
use crate::model::trimmed::{
    Interval, LoopEdge, LoopSearch, SurfaceEval, TrimmedFace, TruckSurface, parameter_bounds,
};

mod domain;
mod loops;
mod unwrap;

use domain::Domain;
use loops::*;
use unwrap::*;

/// Most segments one edge polyline may have.
const MAX_EDGE_SEGMENTS: usize = 1 << 14;
/// Most grid steps per direction.
const MAX_GRID: usize = 400;
/// Times a face whose trim polylines cross is tessellated again with them closer to its
/// edges (see [`TrimmedTessellator::tessellate_with`]).
const BORDER_RETRIES: usize = 2;
/// Vertices the attempts at a face may have built for it to be tried again for crossing trim
/// polylines: a retry follows every edge ~2× more closely and costs what the attempt did
/// again. The retries fix narrow peninsulas of ordinary faces (the repository's retried
/// faces have at most 2 033 vertices, the corpus's 234); a fuzzed face whose B-spline edge
/// zigzags across the cone it bounds (`tests/data/fuzz/trimmed/zigzag_edge_retried_4x`)
/// built 148 000 vertices at its first attempt, 17 000 on its border, and its retries took
/// it past the fuzz target's 10 s.
const RETRY_VERTICES: usize = 50_000;
/// Rounds of error-driven refinement.
const REFINE_ROUNDS: usize = 10;
/// Triangles are refined down to this fraction of ε: 7 samples find a triangle's largest
/// distance to within a few per cent only (bearing.iges face #2445: 0.998 ε by its samples,
/// 1.008 ε by `check::fidelity`'s dense ones).
pub(crate) const REFINE_TARGET: f64 = 0.95;
/// Most vertices per face.
const MAX_VERTICES: usize = 400_000;
/// Vertices per ε² of a face's area that refinement may reach: a triangulation of edges
/// ε/4 has about 18.5 (equilateral triangles of area √3/64 ε², two per vertex). A chord
/// of ε/4 strays ε/(128 r/ε) from a curve of radius r, so only detail of radius below
/// ε/128 (with ε from ½ px: 1/256 of a pixel) can need more.
const VERTICES_PER_EPS2: f64 = 18.5;
/// Refinement may always add this many vertices to the first triangulation, however small
/// the face (a face much smaller than ε² needs none; this is for area estimates that a
/// coarse first triangulation gets wrong).
const MIN_EXTRA_VERTICES: usize = 1024;

/// The vertex budget of a face of `area` at `eps` whose first triangulation has `initial`
/// vertices: its screen area in units of the pixel error squared (`area / eps²`, ε being
/// derived from the pixel error for the view) times [`VERTICES_PER_EPS2`], at least the
/// first triangulation and [`MIN_EXTRA_VERTICES`] more, at most [`MAX_VERTICES`]. A face
/// that needs more is detail below 1/128 of ε, or a surface that misbehaves (a fuzzed torus
/// whose minor radius vanishes): refinement stops there and says so (`Stop::Vertices`).
fn vertex_budget(area: f64, eps: f64, initial: usize) -> usize {
    let derived = VERTICES_PER_EPS2 * area / (eps * eps);
    let derived = if derived.is_finite() {
        derived.min(MAX_VERTICES as f64) as usize
    } else {
        MAX_VERTICES
    };
    derived.max(initial + MIN_EXTRA_VERTICES).min(MAX_VERTICES)
}

/// Why a face could not be tessellated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TrimError {
    #[error("the face has no boundary loop")]
    NoLoops,
    #[error("edge #{edge}: projecting its points onto the surface failed")]
    Projection { edge: u64 },
    #[error(
        "a loop runs around the periodic surface and the surface has no finite range to close it"
    )]
    UnboundedWrap,
    #[error("{0} loops run around the periodic surface; only 1 or 2 are supported")]
    WrapCount(usize),
    #[error("the trimmed domain is empty")]
    EmptyDomain,
    #[error("non-finite value while tessellating")]
    NotFinite,
}

/// A border point: 3D position (on the trim curve), parameter, and where it came from on its
/// edge (to split the segment on the curve), `None` for points of a closing line.
#[derive(Clone, Copy, Debug)]
struct BPoint {
    p: DVec3,
    uv: DVec2,
    src: Option<(u32, u32, f64)>,
}

impl LoopPoint for BPoint {
    fn uv(&self) -> DVec2 {
        self.uv
    }

    fn with_uv(self, uv: DVec2) -> Self {
        BPoint { uv, ..self }
    }
}

/// Reusable trimmed-face tessellator (keeps its scratch buffers).
#[derive(Debug, Default)]
pub struct TrimmedTessellator {
    loops: Vec<Vec<BPoint>>,
    uvs: Vec<DVec2>,
    pos: Vec<DVec3>,
    /// Each vertex's distance from the surface at its parameter: 0 inside, and on the border
    /// how far the face's own edge curve lies off its surface there.
    off: Vec<f64>,
    /// Per loop of the last face, its first point and parameter ([`TrimmedFace::loop_starts`]).
    starts: Vec<Option<(DVec3, DVec2)>>,
}

/// What the tessellator achieved besides the mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TrimReport {
    /// Largest sampled distance between a trim curve and its polyline.
    pub trim_error: f64,
    /// Edge constraints spade could not add (crossing trim polylines).
    pub crossing_constraints: usize,
    /// Largest distance of a border point (on the face's edge curves) from the face's
    /// surface: a file whose edges lie off their faces (an OCCT offset that failed, leaving
    /// edges 0.57 mm off a plane: generated model 1-32). No mesh through those points can be
    /// nearer the surface; the error refinement works to is what the mesh adds to it.
    pub edge_offset: f64,
    /// Attempts at the face this tessellation made: one, and one more per retry for crossing
    /// trim polylines (see [`TrimmedTessellator::tessellate`]; the kept one is repeated
    /// when it was not the last).
    pub attempts: usize,
}

impl TrimmedTessellator {
    pub fn new() -> Self {
        Self::default()
    }

    /// Tessellates `face` (in its own coordinates) to tolerance `eps`, into `out` (cleared).
    pub fn tessellate(
        &mut self,
        face: &TrimmedFace,
        eps: f64,
        out: &mut PatchMesh,
    ) -> Result<TrimReport, TrimError> {
        self.tessellate_with(face, eps, false, out)
    }

    /// As [`TrimmedTessellator::tessellate`]. With `shared_borders`, segments of edges are not
    /// split by the surface criterion of step 2 (which depends on the face), so two faces
    /// tessellated with the same ε share their border points exactly; only the closing segments
    /// this tessellator adds along a closed surface's bounds (shared with no other face) are.
    pub(crate) fn tessellate_with(
        &mut self,
        face: &TrimmedFace,
        eps: f64,
        shared_borders: bool,
        out: &mut PatchMesh,
    ) -> Result<TrimReport, TrimError> {
        let eps = if eps.is_finite() && eps > 0.0 {
            eps
        } else {
            face.bounds.radius.max(1e-9) * 1e-3
        };
        // No tessellation is more accurate than f32, which stores its vertices, at the
        // face's coordinates: ε is held there (`eps_target` says so). This also bounds the
        // work when a degenerate view asks for far less.
        let magnitude = face.bounds.center.abs().max_element() + face.bounds.radius;
        let eps = match magnitude.is_finite() {
            true => eps.max(f64::from(f32::EPSILON) * magnitude),
            false => eps,
        };
        let mut border_tol = 0.5 * eps;
        let mut result = self.attempt(face, eps, border_tol, shared_borders, out);
        let mut attempts = 1;
        let mut built = self.uvs.len();
        // Trim polylines that cross (a peninsula of a face narrower than ε) leave spade's
        // constraints out and the parity fill off; the face is tessellated again with its
        // edges followed more closely (`BORDER_RETRIES` times, a quarter of the tolerance
        // each), the attempt with the fewest crossings kept. As many crossings do not end the
        // retries: a crescent's corner 0.038 ε inside its arc (gen-36-31 at 5 %, face #1055)
        // still crossed at ε/8, clear at ε/32. Not with shared borders (the neighbour's too),
        // nor once the attempts have built `RETRY_VERTICES`.
        let mut best = border_tol;
        for _ in 0..BORDER_RETRIES {
            let crossings = match &result {
                Ok(r) if r.crossing_constraints > 0 && !shared_borders => r.crossing_constraints,
                _ => break,
            };
            if built >= RETRY_VERTICES {
                break;
            }
            border_tol *= 0.25;
            let mut trial = PatchMesh::default();
            let tried = self.attempt(face, eps, border_tol, shared_borders, &mut trial);
            attempts += 1;
            built += self.uvs.len();
            match tried {
                Ok(r) if r.crossing_constraints < crossings => {
                    std::mem::swap(out, &mut trial);
                    result = Ok(r);
                    best = border_tol;
                }
                Ok(_) => {}
                Err(_) => break,
            }
        }
        if best != border_tol {
            // The last attempt was not kept: the tessellator's state (`loops`, `starts`) is
            // the kept one's again.
            result = self.attempt(face, eps, best, shared_borders, out);
            attempts += 1;
        }
        result.map(|r| TrimReport { attempts, ..r })
    }

    /// One tessellation of `face` at `eps` (already checked), its trim polylines and border
    /// segments within `border_tol` (ε/2 unless spade found them crossing).
    fn attempt(
        &mut self,
        face: &TrimmedFace,
        eps: f64,
        border_tol: f64,
        shared_borders: bool,
        out: &mut PatchMesh,
    ) -> Result<TrimReport, TrimError> {
        out.positions.clear();
        out.normals.clear();
        out.triangles.clear();
        out.borders.clear();
        out.border_kinds.clear();
        out.eps_target = eps;
        out.error = 0.0;
        out.stopped = None;
        let s = face;
        let mut report = TrimReport::default();
        if face.loops.is_empty() {
            return Err(TrimError::NoLoops);
        }

        // 1 + 2: border polylines in 3D and parameter space.
        self.loops.clear();
        self.starts.clear();
        self.starts.resize(face.loops.len(), None);
        let mut search = LoopSearch::new();
        for (li, lp) in face.loops.iter().enumerate() {
            let pts = self.loop_points(face, li, lp, border_tol, &mut search, &mut report)?;
            if pts.len() >= 2 {
                self.loops.push(pts);
            }
        }
        let mut loops = std::mem::take(&mut self.loops);
        close_wrapping_loops(face, &mut loops)?;
        align_loops(face, &mut loops);
        if loops.iter().all(|l| l.len() < 2) {
            return Err(TrimError::EmptyDomain);
        }

        // 3: interior grid (its steps also split the border along poles).
        let (lo, hi) = uv_box(&loops);
        let (scale, steps) = grid_steps(s, lo, hi, eps);
        let grid_step = (hi - lo) / DVec2::new(steps.0 as f64, steps.1 as f64);
        for lp in loops.iter_mut() {
            split_poles(face, lp, grid_step);
            refine_border(face, lp, border_tol, shared_borders);
        }
        if loops.iter().all(|l| l.len() < 3) {
            return Err(TrimError::EmptyDomain);
        }
        let segs = segments(&loops);
        let domain = Domain::new(&segs);

        // 4: constrained Delaunay in scaled parameter space.
        let mut cdt = Cdt::new();
        self.uvs.clear();
        self.pos.clear();
        self.off.clear();
        // Border points in a scrambled order: inserted one after the other along a long,
        // nearly straight trim curve, every insertion flipped edges back along the whole
        // curve (quadratic: 7 600 points of a fuzzed face took 100 s inside spade). A fixed
        // permutation keeps the mesh reproducible.
        let mut border_ids: Vec<Vec<u32>> = loops.iter().map(|l| vec![0; l.len()]).collect();
        let order: Vec<(usize, usize)> = loops
            .iter()
            .enumerate()
            .flat_map(|(li, l)| (0..l.len()).map(move |k| (li, k)))
            .collect();
        for i in scrambled(order.len()) {
            let (li, k) = order[i];
            let b = loops[li][k];
            let h = self.insert(&mut cdt, scale, b.uv, Some(b.p), s)?;
            border_ids[li][k] = h.index() as u32;
        }
        report.edge_offset = self.off.iter().copied().fold(0.0, f64::max);
        for ids in &border_ids {
            for k in 0..ids.len() {
                let (a, b) = (ids[k], ids[(k + 1) % ids.len()]);
                if a == b {
                    continue;
                }
                let fa = FixedVertexHandle::from_index(a as usize);
                let fb = FixedVertexHandle::from_index(b as usize);
                if cdt.can_add_constraint(fa, fb) {
                    cdt.add_constraint(fa, fb);
                } else {
                    report.crossing_constraints += 1;
                }
            }
        }
        let (nu, nv) = steps;
        let du = (hi.x - lo.x) / nu as f64;
        let dv = (hi.y - lo.y) / nv as f64;
        if nu > 1 || nv > 1 {
            let near = border_cells(&segs, lo, du, dv, nu, nv);
            for i in 1..nu {
                for j in 1..nv {
                    // Skip grid points at corners of cells the border passes through.
                    let touched = near[(i - 1) * nv + (j - 1)]
                        || near[i * nv + (j - 1)]
                        || near[(i - 1) * nv + j]
                        || near[i * nv + j];
                    if touched {
                        continue;
                    }
                    let uv = DVec2::new(lo.x + i as f64 * du, lo.y + j as f64 * dv);
                    if domain.contains(uv) {
                        self.insert(&mut cdt, scale, uv, None, s)?;
                    }
                }
            }
        }
        out.resolution = Resolution {
            nu: nu as u32,
            nv: nv as u32,
        };

        // 5: error-driven refinement.
        let use_parity = report.crossing_constraints == 0;
        let mut tris = Vec::new();
        // The face's work budget, from its size against ε (set after the first round, when
        // its area is known): see [`vertex_budget`]. The measured error then tells the truth.
        let mut vertex_cap = MAX_VERTICES;
        // What earlier rounds found of the triangles still there (`domain::Memo`): whether
        // each is inside, and its error with its edges' (in key order).
        let mut inside_memo = domain::Memo::default();
        let mut error_memo: domain::Memo<(f64, [f64; 3])> = domain::Memo::default();
        for round in 0..=REFINE_ROUNDS {
            tris.clear();
            let inside_faces = domain::inside_faces(
                &cdt,
                &self.uvs,
                &self.pos,
                &domain,
                use_parity,
                s,
                scale,
                &mut inside_memo,
            );
            let mut worst = 0.0f64;
            let mut to_insert = Vec::new();
            let mut earlier = std::mem::take(&mut error_memo);
            for t in inside_faces {
                let (key, r) = domain::memo_key(t);
                let (e, by_key) = earlier.remove(&key).unwrap_or_else(|| {
                    let (e, off) = self.triangle_error(s, t);
                    (e, domain::edges_to_key(off, r))
                });
                error_memo.insert(key, (e, by_key));
                let chord_off = domain::edges_from_key(by_key, r);
                worst = worst.max(e);
                if e > REFINE_TARGET * eps || self.wraps(&cdt, t, chord_off, eps) {
                    let c = (self.uvs[t[0] as usize]
                        + self.uvs[t[1] as usize]
                        + self.uvs[t[2] as usize])
                        / 3.0;
                    to_insert.push(c);
                }
                tris.push(t);
            }
            out.error = worst;
            if to_insert.is_empty() {
                break;
            }
            if round == 0 {
                vertex_cap = vertex_budget(self.area(&tris), eps, self.uvs.len());
            }
            let stop = if round == REFINE_ROUNDS {
                Some(Stop::Rounds(REFINE_ROUNDS))
            } else {
                (self.uvs.len() + to_insert.len() > vertex_cap)
                    .then_some(Stop::Vertices(vertex_cap))
            };
            if let Some(stop) = stop {
                out.stopped = (worst > eps).then_some(stop);
                break;
            }
            for uv in to_insert {
                self.insert(&mut cdt, scale, uv, None, s)?;
            }
        }
        if tris.is_empty() {
            return Err(TrimError::EmptyDomain);
        }

        // Output: used vertices only.
        let mut remap = vec![u32::MAX; self.uvs.len()];
        let mut take = |i: u32, out: &mut PatchMesh| -> u32 {
            let r = &mut remap[i as usize];
            if *r == u32::MAX {
                *r = out.positions.len() as u32;
                out.positions.push(self.pos[i as usize].as_vec3());
                // Outward (the face's sense): section caps tell inside from outside by it.
                let n = normal_at(s, self.uvs[i as usize], lo, hi);
                out.normals.push(if face.domain_left { n } else { -n });
            }
            *r
        };
        for t in &tris {
            let tri = [take(t[0], out), take(t[1], out), take(t[2], out)];
            out.triangles.push(tri);
        }
        for (ids, lp) in border_ids.iter().zip(&loops) {
            // Each vertex with what its segment to the next runs along (`model::edges`).
            let ring: Vec<(u32, EdgeKind)> = (0..ids.len())
                .map(|k| {
                    let kind = curve_between(face, lp[k], lp[(k + 1) % lp.len()])
                        .map_or(EdgeKind::None, |(le, ..)| le.kind);
                    (take(ids[k], out), kind)
                })
                .collect();
            let (ring, kinds) = super::dedup_ring(&ring, &out.positions);
            if ring.len() >= 2 {
                out.borders.push(ring);
                out.border_kinds.push(kinds);
            }
        }
        if !out.positions.iter().all(|p| p.is_finite()) {
            return Err(TrimError::NotFinite);
        }
        self.loops = loops;
        Ok(report)
    }

    /// Per loop of the face last tessellated, its first point and that point's parameter
    /// (`None` where the loop has no point): what [`TrimmedFace::loop_starts`] keeps.
    pub fn loop_starts(&self) -> &[Option<(DVec3, DVec2)>] {
        &self.starts
    }

    /// The face's unit normals at the [`SAMPLES`] of each of its edges (per loop, per edge;
    /// `model::edges` compares them across the faces that share an edge), after a successful
    /// [`TrimmedTessellator::tessellate`] of `face`: each sample is found on the surface from
    /// the parameter of the nearest point of that edge's border polyline. `None` where the
    /// search fails or the surface has no normal (a pole).
    pub(crate) fn edge_normals(&self, face: &TrimmedFace) -> Vec<Vec<EdgeNormals>> {
        // The polyline's parameters (curve, surface) per edge of the face.
        let mut on_edge: std::collections::HashMap<(u32, u32), Vec<(f64, DVec2)>> =
            Default::default();
        for b in self.loops.iter().flatten() {
            if let Some((l, j, s)) = b.src {
                on_edge.entry((l, j)).or_default().push((s, b.uv));
            }
        }
        face.loops
            .iter()
            .enumerate()
            .map(|(li, lp)| {
                lp.iter()
                    .enumerate()
                    .map(|(k, le)| {
                        let e = &le.edge;
                        SAMPLES.map(|f| {
                            let t = e.t0 + f * (e.t1 - e.t0);
                            let hint = on_edge
                                .get(&(li as u32, k as u32))
                                .into_iter()
                                .flatten()
                                .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
                                .map(|&(_, uv)| uv);
                            let uv = face.project(e.point(t), hint)?;
                            let (su, sv) = face.derivs(uv);
                            let n = su.cross(sv).normalize_or_zero();
                            (n != DVec3::ZERO).then_some(n)
                        })
                    })
                    .collect()
            })
            .collect()
    }

    /// Inserts a parameter point (3D position given for border points, else evaluated).
    fn insert(
        &mut self,
        cdt: &mut Cdt,
        scale: DVec2,
        uv: DVec2,
        p: Option<DVec3>,
        s: &impl SurfaceEval,
    ) -> Result<FixedVertexHandle, TrimError> {
        // spade refuses non-zero coordinates below 2^-142: flush such dust to zero.
        let flush = |x: f64| if x.abs() < 1e-40 { 0.0 } else { x };
        let q = uv * scale;
        let q = DVec2::new(flush(q.x), flush(q.y));
        if !q.is_finite() {
            return Err(TrimError::NotFinite);
        }
        let h = cdt
            .insert(Point2::new(q.x, q.y))
            .map_err(|_| TrimError::NotFinite)?;
        if h.index() == self.uvs.len() {
            self.uvs.push(uv);
            let on = s.point(uv);
            let p = p.unwrap_or(on);
            let off = p.distance(on);
            self.pos.push(p);
            self.off.push(if off.is_finite() { off } else { 0.0 });
        }
        Ok(h)
    }

    /// Area of the triangles `tris` (3D, their vertices' positions).
    fn area(&self, tris: &[[u32; 3]]) -> f64 {
        tris.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.pos[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// Whether triangle `t` wraps round the surface: one of its inner edges (not a border
    /// constraint) has a 3D chord shorter than `chord_off`, the distance from the chord's
    /// middle to the surface at the middle of its parameters ([`Self::triangle_error`]), as an
    /// edge spanning over 253° of a circle does (and one between the two sides of a seam, whose
    /// chord is nothing). A surface thinner than ε does it: a tube of radius 0.335 at ε 1.03
    /// (seed 22 model 50 of `tools/cad_generator.py`) had no grid point inside, and its
    /// triangles ran from one side of its seam to the other, all on one line: within ε of the
    /// tube, yet of no area, nothing drawn, 1.4 ε from any drawn surface. Along a pole the
    /// surface is one point, the chord nothing and the distance nothing: a fan's slivers there
    /// do not wrap.
    fn wraps(&self, cdt: &Cdt, t: [u32; 3], chord_off: [f64; 3], eps: f64) -> bool {
        (0..3).any(|k| {
            let (i, j) = (t[k], t[(k + 1) % 3]);
            let chord = self.pos[i as usize].distance(self.pos[j as usize]);
            chord_off[k] > chord.max(1e-6 * eps)
                && !cdt.exists_constraint(
                    FixedVertexHandle::from_index(i as usize),
                    FixedVertexHandle::from_index(j as usize),
                )
        })
    }

    /// Largest distance surface ↔ triangle at 7 samples, beyond what its corners' own
    /// distances from the surface (`off`: border points on edge curves that lie off it)
    /// account for there — refinement cannot move the border; and the distance at each edge's
    /// middle (edges `t[k]`–`t[k + 1]`), as it is, for [`Self::wraps`].
    fn triangle_error(&self, s: &impl SurfaceEval, t: [u32; 3]) -> (f64, [f64; 3]) {
        let (u0, u1, u2) = (
            self.uvs[t[0] as usize],
            self.uvs[t[1] as usize],
            self.uvs[t[2] as usize],
        );
        let (p0, p1, p2) = (
            self.pos[t[0] as usize],
            self.pos[t[1] as usize],
            self.pos[t[2] as usize],
        );
        let o = t.map(|i| self.off[i as usize]);
        const B: [[f64; 3]; 7] = [
            [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
            [0.5, 0.5, 0.0],
            [0.0, 0.5, 0.5],
            [0.5, 0.0, 0.5],
            [2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0],
            [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
            [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0],
        ];
        let mut error = 0.0f64;
        let mut middles = [0.0; 3];
        for (k, b) in B.iter().enumerate() {
            let uv = u0 * b[0] + u1 * b[1] + u2 * b[2];
            let lin = p0 * b[0] + p1 * b[1] + p2 * b[2];
            let given = o[0] * b[0] + o[1] * b[1] + o[2] * b[2];
            let d = s.point(uv).distance(lin);
            if (1..=3).contains(&k) {
                middles[k - 1] = d;
            }
            error = error.max((d - given).max(0.0));
        }
        (error, middles)
    }
}

fn uv_box(loops: &[Vec<BPoint>]) -> (DVec2, DVec2) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for b in loops.iter().flatten() {
        lo = lo.min(b.uv);
        hi = hi.max(b.uv);
    }
    (lo, hi)
}

fn segments(loops: &[Vec<BPoint>]) -> Vec<(DVec2, DVec2)> {
    let mut segs = Vec::new();
    for lp in loops {
        for k in 0..lp.len() {
            segs.push((lp[k].uv, lp[(k + 1) % lp.len()].uv));
        }
    }
    segs
}

/// Grid cells (nu × nv over the box from `lo`) that a border segment passes through.
fn border_cells(
    segs: &[(DVec2, DVec2)],
    lo: DVec2,
    du: f64,
    dv: f64,
    nu: usize,
    nv: usize,
) -> Vec<bool> {
    let mut near = vec![false; nu * nv];
    let cell = |p: DVec2| {
        let i = (((p.x - lo.x) / du).floor() as i64).clamp(0, nu as i64 - 1) as usize;
        let j = (((p.y - lo.y) / dv).floor() as i64).clamp(0, nv as i64 - 1) as usize;
        i * nv + j
    };
    for &(a, b) in segs {
        let steps = (((b.x - a.x) / du).abs() + ((b.y - a.y) / dv).abs()).ceil() as usize * 2 + 1;
        let steps = steps.min(4 * (nu + nv));
        for k in 0..=steps {
            let p = a + (b - a) * (k as f64 / steps as f64);
            near[cell(p)] = true;
        }
    }
    near
}

/// A fixed permutation of `0..n` that spreads consecutive indices apart (a multiplicative
/// step coprime with `n`, near n·(√5 − 1)/2): points along a curve come in an order close
/// to random for Delaunay insertion, the same on every run.
fn scrambled(n: usize) -> impl Iterator<Item = usize> {
    let mut step = ((n as f64) * 0.618_033_988_75) as usize | 1;
    while n > 1 && gcd(step, n) != 1 {
        step += 2;
    }
    (0..n).map(move |i| (i * step) % n.max(1))
}

fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// Parameter scaling (mean speeds) and grid steps for tolerance `eps` over the box.
fn grid_steps(s: &impl SurfaceEval, lo: DVec2, hi: DVec2, eps: f64) -> (DVec2, (usize, usize)) {
    const N: usize = 9;
    let (mut muu, mut muv, mut mvv) = (0.0f64, 0.0f64, 0.0f64);
    let (mut su, mut sv, mut cnt) = (0.0, 0.0, 0.0);
    for i in 0..N {
        for j in 0..N {
            let uv = lo + (hi - lo) * DVec2::new(i as f64, j as f64) / (N - 1) as f64;
            let (a, b, c) = s.second_derivs(uv);
            if a.is_finite() && b.is_finite() && c.is_finite() {
                muu = muu.max(a.length());
                muv = muv.max(b.length());
                mvv = mvv.max(c.length());
            }
            let (du, dv) = s.derivs(uv);
            if du.is_finite() && dv.is_finite() {
                su += du.length();
                sv += dv.length();
                cnt += 1.0;
            }
        }
    }
    // Sampled maxima may miss a peak between samples: a safety factor; the measured error and
    // refinement catch the rest.
    let (muu, muv, mvv) = (muu * 1.25, muv * 1.25, mvv * 1.25);
    let size = hi - lo;
    let scale = if cnt > 0.0 {
        let (su, sv) = (su / cnt, sv / cnt);
        let f = |x: f64| if x > 1e-300 && x.is_finite() { x } else { 1.0 };
        DVec2::new(f(su), f(sv))
    } else {
        DVec2::ONE
    };
    // Choose hu = a/√Muu, hv = a/√Mvv with a² (2 + 2 Muv/√(Muu Mvv)) ≤ 8ε.
    let steps_for = |m: f64, len: f64, other: f64| -> usize {
        if m <= 1e-300 || len <= 0.0 {
            return 1;
        }
        let cross = if other > 1e-300 {
            muv / (m * other).sqrt()
        } else {
            0.0
        };
        let a2 = 8.0 * eps / (2.0 + 2.0 * cross);
        let h = (a2 / m).sqrt();
        ((len / h).ceil() as usize).clamp(1, MAX_GRID)
    };
    let nu = steps_for(muu, size.x, mvv);
    let nv = steps_for(mvv, size.y, muu);
    // Where the surface curves, measure in grid steps (the error metric: a unit cell holds ε),
    // so Delaunay triangles follow the curvature — long along a cylinder's straight direction.
    // A flat face keeps the 3D speeds (well-shaped triangles; any shape is exact there).
    let scale = if nu > 1 || nv > 1 {
        let f = |n: usize, len: f64, sp: f64| {
            if len > 1e-300 { n as f64 / len } else { sp }
        };
        DVec2::new(f(nu, size.x, scale.x), f(nv, size.y, scale.y))
    } else {
        scale
    };
    (scale, (nu, nv))
}

/// Unit normal (cross product of the parameter derivatives), nudged into the domain at poles.
fn normal_at(s: &impl SurfaceEval, uv: DVec2, lo: DVec2, hi: DVec2) -> Vec3 {
    let n = |uv: DVec2| {
        let (du, dv) = s.derivs(uv);
        du.cross(dv)
    };
    let mut v = n(uv);
    if v.length_squared() < 1e-24 || !v.is_finite() {
        let centre = 0.5 * (lo + hi);
        for f in [1e-6, 1e-4, 1e-2] {
            v = n(uv + (centre - uv) * f);
            if v.length_squared() >= 1e-24 && v.is_finite() {
                break;
            }
        }
    }
    let v = v.normalize_or_zero().as_vec3();
    if v == Vec3::ZERO { Vec3::Z } else { v }
}
