//! Independent per-patch tessellation under an object-space tolerance.
//!
//! Every patch is tessellated on its own, from its own ε: neighbours get different
//! resolutions, so their shared borders do not match (T-junctions). The gaps are not stitched;
//! they are covered by fat borders at draw time (see `render::fat_border`).

pub mod bezier;
pub mod trimmed;

pub(crate) use bezier::Resolution;
pub use bezier::{BezierTessellator, MAX_SEGMENTS};
pub use trimmed::TrimmedTessellator;

use glam::{DMat3, DVec3, Vec3};
use rayon::prelude::*;

use crate::isolate::isolated;
use crate::model::edges::EdgeKind;
use crate::model::{Patch, PatchSurface, Scene};
use crate::mt::CutState;
use crate::view::View;

/// What is drawn for one patch: triangles, the closed border loops, and the error achieved.
#[derive(Clone, Debug, Default)]
pub struct PatchMesh {
    pub patch_id: u32,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Closed border loops as indices into `positions` (first vertex not repeated at the end);
    /// consecutive duplicates (collapsed edges at poles) are removed.
    pub borders: Vec<Vec<u32>>,
    /// Per border loop, per vertex k: what the loop runs along from vertex k to the next
    /// (an edge of the model, sharp or smooth, or none: [`EdgeKind`]); what `--edges` draws.
    /// Empty when not known: every segment is then a sharp edge.
    pub border_kinds: Vec<Vec<EdgeKind>>,
    /// Tolerance asked for, object units.
    pub eps_target: f64,
    /// Measured maximum distance between surface and triangles (sampled), object units.
    pub error: f64,
    /// Grid resolution used.
    pub resolution: Resolution,
    /// Trimmed faces: largest sampled distance between a trim curve and its polyline.
    pub trim_error: f64,
    /// Largest measured distance between the border loops and the patch's true border
    /// (object units), when the tessellator measures it (Bézier patches: the border is a
    /// polyline through points of the boundary curves); `None`: not measured, the fat
    /// borders cover the whole [`PatchMesh::eps_border`].
    pub border_error: Option<f64>,
    /// Why the patch could not be tessellated (its mesh is then empty).
    pub failure: Option<String>,
    /// The patch's own colour (a STEP part or face style), drawn by `lit` shading; `None`
    /// draws the renderer's default colour.
    pub color: Option<[f32; 3]>,
    /// For a mesh patch drawn as a cut of its hierarchy: the cut as ranges of the
    /// hierarchy's triangles, which the renderer draws from index buffers built once per
    /// patch (`triangles` holds the same triangles for CPU work).
    pub arcs: Option<CutRanges>,
    /// This mesh is a placement of a tessellation other patches share (instanced parts,
    /// `lod::shared`): its geometry is the shared mesh's, moved by the placement, and is not
    /// held here — `positions`, `normals`, `triangles` and `borders` stay empty (the frame
    /// loop keeps one copy per shared tessellation, not one per placement). The renderer
    /// draws the shared mesh with the placement; [`PatchMesh::world`] makes the world-space
    /// copy for whoever needs its vertices on the CPU.
    pub instance: Option<Instance>,
    /// Set when the patch's refinement stopped at its work budget before its measured
    /// error reached ε (`error` is then what it reached): no input makes one face work without
    /// bound, and `stats` says which faces stopped short.
    pub stopped: Option<Stop>,
}

/// The work budget a tessellator stopped at, short of ε.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The trimmed tessellator's vertex budget, from the face's area over ε² (its screen
    /// area in pixel errors squared; `tessellate::trimmed`'s `vertex_budget`), at most
    /// 400 000 (the count given).
    Vertices(usize),
    /// The trimmed tessellator's rounds of error-driven refinement (the count given).
    Rounds(usize),
    /// A Bézier grid of [`MAX_SEGMENTS`] steps per direction.
    Segments(u32),
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::Vertices(n) => write!(f, "its vertex budget ({n})"),
            Stop::Rounds(n) => write!(f, "{n} rounds of refinement"),
            Stop::Segments(n) => write!(f, "a grid of {n} x {n} steps"),
        }
    }
}

/// A mesh that is `shared` moved by `transform` ([`PatchMesh::world`]: vertex for vertex
/// what tessellating the placed patch itself gives, or for translated Bézier copies within
/// f32 rounding of it), with its own patch id and colour and its error raised by
/// `error_added` (world units). Only similarities (rotation, reflection,
/// uniform scale, translation: [`is_similarity`]) are instances, so lengths scale evenly,
/// normals turn with the transform and the shared mesh's errors are already the placement's
/// ([`shared_surface`] keys on the scale).
#[derive(Clone, Debug)]
pub struct Instance {
    pub shared: std::sync::Arc<PatchMesh>,
    pub transform: glam::DMat4,
    pub error_added: f64,
}

/// Whether `m` is affine and a similarity: orthogonal axes of one length (within 1e-9
/// relative), no projective part.
pub fn is_similarity(m: &glam::DMat4) -> bool {
    let [x, y, z] = [m.x_axis, m.y_axis, m.z_axis].map(|a| a.truncate());
    let l = x.length();
    let tol = 1e-9 * l * l;
    let finite = m.to_cols_array().iter().all(|v| v.is_finite());
    finite
        && l > 0.0
        && m.row(3) == glam::DVec4::new(0.0, 0.0, 0.0, 1.0)
        && (y.length_squared() - l * l).abs() <= tol
        && (z.length_squared() - l * l).abs() <= tol
        && x.dot(y).abs() <= tol
        && x.dot(z).abs() <= tol
        && y.dot(z).abs() <= tol
}

/// A cut as ranges `[first, count]` of its patch's [`crate::mt::MtHierarchy::triangles`].
#[derive(Clone, Debug)]
pub struct CutRanges {
    pub patch: std::sync::Arc<crate::model::mesh::MeshPatch>,
    pub ranges: Vec<[u32; 2]>,
    /// Nodes of the hierarchy's order the cut applies (the original mesh counts as one): the
    /// cut's level for multiresolution / repaired strips.
    pub applied: usize,
    /// The mesh's positions are not the patch's (an animation moved them): the patch's
    /// static buffers cannot draw it, so it is uploaded.
    pub moved: bool,
}

/// Smallest fat-border half-width, as a fraction of [`PatchMesh::eps_border`]
/// ([`PatchMesh::border_width`]).
pub(crate) const MIN_BORDER_WIDTH: f64 = 0.25;

impl PatchMesh {
    /// Error the fat borders of this patch must cover: the larger of target and achieved.
    pub fn eps_border(&self) -> f64 {
        self.eps_target.max(self.error)
    }

    /// Half-width of this patch's fat borders across the view: its measured
    /// [`PatchMesh::border_error`] when known, at least `MIN_BORDER_WIDTH` × and at most
    /// [`PatchMesh::eps_border`]; the push-back away from the viewer stays `eps_border`.
    ///
    /// Why the border's own error is enough (Balázs et al. 2004, §3 ask for ε, a bound on the
    /// whole patch): the crack between two neighbours lies between their border polylines,
    /// which are within `b_a` and `b_b` of the common boundary curve; a point of the crack is
    /// then within `b_a` of the first polyline or within `b_b` of the second, so each fat
    /// border needs only its own patch's border error. Where a patch's surface needs a fine
    /// grid but its border is nearly straight, fat borders get much thinner than ε and stick
    /// out of silhouettes by that much less (issue 17 item 8). The floor keeps a band over the
    /// T-junction slivers of borders that are exactly straight.
    pub fn border_width(&self) -> f64 {
        let full = self.eps_border();
        match self.border_error {
            Some(b) if b.is_finite() => b.clamp(MIN_BORDER_WIDTH * full, full),
            _ => full,
        }
    }

    /// Border vertices (an instance's: its shared mesh's).
    pub fn border_vertex_count(&self) -> usize {
        self.geometry().borders.iter().map(Vec::len).sum()
    }

    /// Triangles drawn for this patch (an instance's: its shared mesh's).
    pub fn triangle_count(&self) -> usize {
        self.geometry().triangles.len()
    }

    /// The mesh that holds this patch's triangles, border loops and (unmoved) vertices: the
    /// shared mesh of an instance, else this one. Indices are the same either way.
    pub fn geometry(&self) -> &PatchMesh {
        self.instance.as_ref().map_or(self, |i| i.shared.as_ref())
    }

    /// This patch's mesh in world space: itself, or for an instance (which holds no geometry
    /// of its own) its shared mesh moved by the placement, with the instance's id, colour and
    /// errors — what tessellating the patch on its own gives ([`place`]; a translated Bézier
    /// copy within f32 rounding). The copy is no instance.
    pub fn world(&self) -> std::borrow::Cow<'_, PatchMesh> {
        let Some(inst) = &self.instance else {
            return std::borrow::Cow::Borrowed(self);
        };
        let shared = inst.shared.as_ref();
        let mut out = PatchMesh {
            patch_id: self.patch_id,
            positions: shared.positions.clone(),
            normals: shared.normals.clone(),
            triangles: shared.triangles.clone(),
            borders: shared.borders.clone(),
            border_kinds: shared.border_kinds.clone(),
            eps_target: self.eps_target,
            error: self.error,
            resolution: self.resolution,
            trim_error: self.trim_error,
            border_error: self.border_error,
            failure: self.failure.clone(),
            color: self.color,
            arcs: None,
            instance: None,
            stopped: self.stopped,
        };
        place(&mut out, &inst.transform);
        std::borrow::Cow::Owned(out)
    }

    /// Bytes this mesh holds: the struct and its arrays' capacities (positions, normals,
    /// triangles, border loops, the failure message, a cut's ranges; the allocator's
    /// per-allocation overhead and the hierarchy a cut refers to — the scene's — not counted).
    pub fn mem_bytes(&self) -> usize {
        use std::mem::size_of;
        fn cap<T>(v: &Vec<T>) -> usize {
            v.capacity() * size_of::<T>()
        }
        // (An instance's shared mesh is counted once, by whoever holds it: not here.)
        size_of::<PatchMesh>()
            + cap(&self.positions)
            + cap(&self.normals)
            + cap(&self.triangles)
            + cap(&self.borders)
            + self.borders.iter().map(cap).sum::<usize>()
            + cap(&self.border_kinds)
            + self.border_kinds.iter().map(cap).sum::<usize>()
            + self.failure.as_ref().map_or(0, String::capacity)
            + self.arcs.as_ref().map_or(0, |a| cap(&a.ranges))
    }
}

/// Both tessellators with their scratch buffers, one set per worker thread.
#[derive(Debug, Default)]
pub struct Tessellators {
    pub bezier: BezierTessellator,
    pub trimmed: TrimmedTessellator,
}

impl Tessellators {
    pub fn new() -> Self {
        Self::default()
    }

    /// Tessellates one patch to world tolerance `eps`, in world coordinates. A trimmed face
    /// that fails (or panics inside truck) gives an empty mesh with `failure` set.
    pub fn patch(&mut self, patch: &Patch, eps: f64, out: &mut PatchMesh) {
        self.patch_with(patch, eps, false, out)
    }

    /// As [`Tessellators::patch`], for a frame loop: a mesh patch's cut is moved from `cut`
    /// (the patch's previous cut, kept by the caller: per-view state, not the scene's) to
    /// `eps`, and left there for the next call (Holst §3, frame coherence).
    pub(crate) fn patch_from(
        &mut self,
        patch: &Patch,
        eps: f64,
        cut: &mut Option<CutState>,
        out: &mut PatchMesh,
    ) {
        self.dispatch(patch, eps, false, Some(cut), true, out)
    }

    /// As [`Tessellators::patch`] for a patch whose surface other placements share
    /// ([`shared_surface`]): the tessellation in the surface's own coordinates (errors in
    /// world units), which [`placed`] copies to each placement — a part placed k times is
    /// tessellated once per level.
    pub fn unplaced(&mut self, patch: &Patch, eps: f64, out: &mut PatchMesh) {
        self.dispatch(patch, eps, false, None, false, out)
    }

    /// As [`Tessellators::patch`]; `shared_borders` keeps trim polylines to what depends on
    /// the curve and ε alone, so faces tessellated with the same ε share border vertices
    /// (used for watertight references).
    pub fn patch_with(
        &mut self,
        patch: &Patch,
        eps: f64,
        shared_borders: bool,
        out: &mut PatchMesh,
    ) {
        self.dispatch(patch, eps, shared_borders, None, true, out)
    }

    fn dispatch(
        &mut self,
        patch: &Patch,
        eps: f64,
        shared_borders: bool,
        cut: Option<&mut Option<CutState>>,
        place_it: bool,
        out: &mut PatchMesh,
    ) {
        out.patch_id = patch.id;
        out.color = patch.color;
        out.failure = None;
        out.trim_error = 0.0;
        out.border_error = None;
        out.arcs = None;
        out.instance = None;
        out.stopped = None;
        match &patch.surface {
            PatchSurface::Bezier(b) => self.bezier.tessellate(b, eps, out),
            PatchSurface::Mesh(m) => mesh_patch(m, eps, shared_borders, cut, out),
            PatchSurface::Trimmed(face) => {
                let scale = patch.scale().max(1e-300);
                let local = eps / scale;
                let t = &mut self.trimmed;
                let result = isolated(|| t.tessellate_with(face, local, shared_borders, out));
                match result {
                    Ok(Ok(report)) => {
                        out.trim_error = report.trim_error * scale;
                        out.error *= scale;
                        out.eps_target = eps;
                        if place_it {
                            place(out, &patch.transform);
                        }
                    }
                    Ok(Err(e)) => fail(out, eps, format!("face #{}: {e}", face.id)),
                    Err(e) => {
                        // The scratch state may be inconsistent after a panic.
                        self.trimmed = TrimmedTessellator::new();
                        fail(out, eps, format!("face #{}: {e}", face.id))
                    }
                }
            }
        }
    }
}

/// A mesh patch: the cut of its MT hierarchy for `eps` (the original triangles with
/// `original`, as the watertight crack-check reference wants), its border loops and the
/// achieved error. The cut is moved from `cut` when given (the patch's previous cut, frame
/// coherence), else from the finest cut.
fn mesh_patch(
    m: &std::sync::Arc<crate::model::mesh::MeshPatch>,
    eps: f64,
    original: bool,
    cut: Option<&mut Option<CutState>>,
    out: &mut PatchMesh,
) {
    out.positions.clear();
    out.positions.extend_from_slice(&m.positions);
    out.normals.clear();
    out.normals.extend_from_slice(&m.normals);
    if original || m.hierarchy.node_count() == 0 {
        out.triangles.clear();
        out.triangles.extend_from_slice(&m.triangles);
        out.borders = m.borders.clone();
        out.border_kinds = m.border_kinds.clone();
        out.error = 0.0;
    } else {
        let h = &m.hierarchy;
        let mut fresh = None;
        let state = cut
            .unwrap_or(&mut fresh)
            .get_or_insert_with(|| h.finest_cut());
        h.move_cut(state, eps);
        let mut ranges = Vec::new();
        out.error = h.cut_ranges(state, &mut ranges);
        out.triangles.clear();
        for &[first, count] in &ranges {
            out.triangles
                .extend_from_slice(&h.triangles[first as usize..(first + count) as usize]);
        }
        // Built across creases, the cut's borders are the outline's; its creases are drawn
        // as edges of their own.
        let (rings, kinds) = match m.position_of.is_empty() {
            true => (&m.borders, &m.border_kinds),
            false => (&m.outline, &m.outline_kinds),
        };
        h.cut_borders(state, rings, &mut out.borders);
        cut_border_kinds(h, state, rings, kinds, &mut out.border_kinds);
        if !m.position_of.is_empty() {
            crease_edges(
                &out.triangles,
                &m.position_of,
                &mut out.borders,
                &mut out.border_kinds,
            );
        }
        out.arcs = Some(CutRanges {
            patch: m.clone(),
            ranges,
            applied: state.applied(),
            moved: false,
        });
    }
    out.eps_target = eps;
    out.resolution = Resolution { nu: 1, nv: 1 };
}

/// A closed border loop from its vertices, each with the kind of its segment to the next:
/// consecutive vertices at one position (a side collapsed to a pole, a vertex two edges
/// share) kept once — the first of each run, with the kind of the run's last segment, the
/// one that leaves it — and trailing vertices at the first one's position dropped.
pub(crate) fn dedup_ring(
    ring: &[(u32, EdgeKind)],
    positions: &[Vec3],
) -> (Vec<u32>, Vec<EdgeKind>) {
    let at = |v: u32| positions[v as usize];
    let mut ids: Vec<u32> = Vec::with_capacity(ring.len());
    let mut kinds: Vec<EdgeKind> = Vec::with_capacity(ring.len());
    for &(v, kind) in ring {
        match (ids.last(), kinds.last_mut()) {
            (Some(&last), Some(k)) if at(last) == at(v) => *k = kind,
            _ => {
                ids.push(v);
                kinds.push(kind);
            }
        }
    }
    while ids.len() > 1 && at(ids[0]) == at(ids[ids.len() - 1]) {
        ids.pop();
        kinds.pop();
    }
    (ids, kinds)
}

/// The kinds of the border segments of a cut (the loops `cut_borders` gives): a border
/// vertex the cut collapsed joins its two segments into one, which is the strongest edge
/// it replaces (a crease shortened onto a cut stays a crease).
fn cut_border_kinds(
    h: &crate::mt::MtHierarchy,
    state: &CutState,
    rings: &[Vec<u32>],
    ring_kinds: &[Vec<EdgeKind>],
    out: &mut Vec<Vec<EdgeKind>>,
) {
    out.clear();
    for (ring, kinds) in rings.iter().zip(ring_kinds) {
        let n = ring.len();
        let alive: Vec<usize> = (0..n).filter(|&k| h.vertex_alive(state, ring[k])).collect();
        if alive.len() < 2 {
            continue;
        }
        out.push(
            alive
                .iter()
                .zip(alive.iter().cycle().skip(1))
                .map(|(&k, &next)| {
                    let span = match (next + n - k) % n {
                        0 => n,
                        s => s,
                    };
                    (0..span)
                        .map(|s| kinds[(k + s) % n])
                        .max()
                        .unwrap_or_default()
                })
                .collect(),
        );
    }
}

/// The creases of a cut built across them (`MtHierarchy::build_across_seams`): each edge
/// whose two triangles have different vertices at one of its ends (`position_of`: the first
/// vertex at each vertex's position), appended to `borders` as a loop of its two ends, both
/// segments sharp: drawn once per side, as the two border loops of a crease inside a patch
/// were, with a fat border (not needed: the cut is one surface across it).
fn crease_edges(
    triangles: &[[u32; 3]],
    position_of: &[u32],
    borders: &mut Vec<Vec<u32>>,
    kinds: &mut Vec<Vec<EdgeKind>>,
) {
    let at = |v: u32| position_of.get(v as usize).copied().unwrap_or(v);
    let mut first: crate::util::IntMap<(u32, u32), (u32, u32)> = Default::default();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let key = (at(a).min(at(b)), at(a).max(at(b)));
            // The vertices at the key's ends, in the key's order.
            let own = if at(a) <= at(b) { (a, b) } else { (b, a) };
            match first.remove(&key) {
                None => {
                    first.insert(key, own);
                }
                Some(other) if other != own => {
                    borders.push(vec![own.0, own.1]);
                    kinds.push(vec![EdgeKind::Sharp; 2]);
                }
                Some(_) => {}
            }
        }
    }
}

fn fail(out: &mut PatchMesh, eps: f64, why: String) {
    out.positions.clear();
    out.normals.clear();
    out.triangles.clear();
    out.borders.clear();
    out.border_kinds.clear();
    out.error = 0.0;
    out.eps_target = eps;
    out.failure = Some(why);
}

/// What a patch's tessellation at a given ε depends on when other placements can share it:
/// its surface (by address: a trimmed face is shared by every placement of its part) and how
/// much its placement scales lengths (ε is divided by it). `None` for Bézier and mesh patches,
/// whose tessellation is their own.
pub fn shared_surface(patch: &Patch) -> Option<(usize, u64)> {
    match &patch.surface {
        PatchSurface::Trimmed(face) => Some((
            std::sync::Arc::as_ptr(face) as usize,
            patch.scale().to_bits(),
        )),
        PatchSurface::Bezier(_) | PatchSurface::Mesh(_) => None,
    }
}

/// `patch`'s mesh from `unplaced` (from [`Tessellators::unplaced`] on a patch with the same
/// [`shared_surface`]), with its id and colour: when the placement is a similarity, an
/// [`Instance`] of `unplaced` holding no geometry of its own ([`PatchMesh::world`] gives
/// exactly what [`Tessellators::patch`] makes for `patch`); otherwise (or when the shared
/// tessellation failed) a moved copy.
pub fn placed(unplaced: &std::sync::Arc<PatchMesh>, patch: &Patch) -> PatchMesh {
    if unplaced.failure.is_none() && is_similarity(&patch.transform) {
        return instance_of(
            unplaced,
            Instance {
                shared: unplaced.clone(),
                transform: patch.transform,
                error_added: 0.0,
            },
            patch,
        );
    }
    let mut out = PatchMesh::clone(unplaced);
    out.patch_id = patch.id;
    out.color = patch.color;
    out.instance = None;
    if out.failure.is_none() {
        place(&mut out, &patch.transform);
    }
    out
}

/// The mesh of `patch` drawn as `instance`: no geometry of its own, the shared mesh's errors
/// (the error raised by the instance's `error_added`; a border moved off its curve by that
/// much has no measured border error: fat borders the whole ε wide, as the placed shader
/// draws them), `patch`'s id and colour.
pub(crate) fn instance_of(shared: &PatchMesh, instance: Instance, patch: &Patch) -> PatchMesh {
    PatchMesh {
        patch_id: patch.id,
        color: patch.color,
        eps_target: shared.eps_target,
        error: shared.error + instance.error_added,
        resolution: shared.resolution,
        trim_error: shared.trim_error,
        border_error: shared.border_error.filter(|_| instance.error_added <= 0.0),
        failure: None,
        stopped: shared.stopped,
        instance: Some(instance),
        ..PatchMesh::default()
    }
}

/// Moves a mesh from its patch's own coordinates into the scene by `m`: positions through
/// `m` (a pure translation adds it, in f64), normals through its inverse transpose,
/// normalized — unless its linear part is the identity (a translation keeps them as they are).
pub fn place(out: &mut PatchMesh, m: &glam::DMat4) {
    if *m == glam::DMat4::IDENTITY {
        return;
    }
    let linear = DMat3::from_mat4(*m);
    if linear == DMat3::IDENTITY {
        let t = m.w_axis.truncate();
        for p in out.positions.iter_mut() {
            *p = (p.as_dvec3() + t).as_vec3();
        }
        return;
    }
    let n = linear.inverse().transpose();
    for p in out.positions.iter_mut() {
        *p = m.transform_point3(p.as_dvec3()).as_vec3();
    }
    for v in out.normals.iter_mut() {
        let t: DVec3 = n * v.as_dvec3();
        *v = t.normalize_or_zero().as_vec3();
    }
}

/// Tessellates every patch of `scene` for `view` at `pixel_error`, in parallel.
pub fn tessellate_scene(scene: &Scene, view: &View, pixel_error: f64) -> Vec<PatchMesh> {
    scene
        .patches
        .par_iter()
        .map_init(Tessellators::new, |t, patch| {
            let eps = view.eps_obj(&patch.bounds, pixel_error);
            let mut mesh = PatchMesh::default();
            t.patch(patch, eps, &mut mesh);
            mesh
        })
        .collect()
}

/// Tessellates every patch of `scene` to one world tolerance `tol` (view-independent, as a
/// CAD exporter or a benchmark asks).
pub fn tessellate_scene_tolerance(scene: &Scene, tol: f64) -> Vec<PatchMesh> {
    tessellate_scene_with(scene, tol, false)
}

/// As [`tessellate_scene_tolerance`]; see [`Tessellators::patch_with`] for `shared_borders`.
pub fn tessellate_scene_with(scene: &Scene, tol: f64, shared_borders: bool) -> Vec<PatchMesh> {
    scene
        .patches
        .par_iter()
        .map_init(Tessellators::new, |t, patch| {
            let mut mesh = PatchMesh::default();
            t.patch_with(patch, tol, shared_borders, &mut mesh);
            mesh
        })
        .collect()
}

/// Tessellates every Bézier patch on one shared uniform `n × n` parameter grid (no error
/// control). Patches sharing a border curve with the same parameterisation then share border
/// vertices, which the crack check uses as its watertight reference. Trimmed faces are not
/// on a common grid: they get an empty mesh here (see `check::crack::reference_meshes`).
pub(crate) fn tessellate_scene_uniform(scene: &Scene, n: u32) -> Vec<PatchMesh> {
    scene
        .patches
        .par_iter()
        .map_init(BezierTessellator::new, |t, patch| {
            let mut mesh = PatchMesh::default();
            if let PatchSurface::Bezier(b) = &patch.surface {
                t.tessellate_grid(b, Resolution { nu: n, nv: n }, 0.0, &mut mesh);
            }
            mesh.patch_id = patch.id;
            mesh
        })
        .collect()
}

/// Totals over a set of patch meshes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MeshStats {
    pub patches: usize,
    pub triangles: usize,
    pub vertices: usize,
    pub border_vertices: usize,
    pub eps_min: f64,
    pub eps_max: f64,
    /// Largest measured error relative to its patch's target (≤ 1 when every patch holds).
    pub worst_error_ratio: f64,
    /// Bytes the meshes hold ([`PatchMesh::mem_bytes`]).
    pub bytes: usize,
    /// Patches whose refinement stopped at its work budget short of ε
    /// ([`PatchMesh::stopped`]) ...
    pub stopped: usize,
    /// ... and the worst of them: patch id, error / ε reached, the budget.
    pub worst_stopped: Option<(u32, f64, Stop)>,
}

impl MeshStats {
    pub fn of(meshes: &[PatchMesh]) -> MeshStats {
        let mut s = MeshStats {
            patches: meshes.len(),
            eps_min: f64::INFINITY,
            eps_max: 0.0,
            ..MeshStats::default()
        };
        for m in meshes {
            s.triangles += m.triangle_count();
            s.vertices += m.geometry().positions.len();
            s.border_vertices += m.border_vertex_count();
            s.bytes += m.mem_bytes();
            s.eps_min = s.eps_min.min(m.eps_target);
            s.eps_max = s.eps_max.max(m.eps_target);
            if m.eps_target > 0.0 {
                s.worst_error_ratio = s.worst_error_ratio.max(m.error / m.eps_target);
            }
            if let Some(stop) = m.stopped {
                s.stopped += 1;
                let ratio = m.error / m.eps_target.max(f64::MIN_POSITIVE);
                if s.worst_stopped.is_none_or(|(_, r, _)| ratio > r) {
                    s.worst_stopped = Some((m.patch_id, ratio, stop));
                }
            }
        }
        if meshes.is_empty() {
            s.eps_min = 0.0;
        }
        s
    }
}
