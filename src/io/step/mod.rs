//! STEP (ISO 10303-21, AP203/AP214/AP242) reader: every `ADVANCED_FACE` of every B-rep shell
//! becomes a trimmed patch, placed by the product structure.
//!
//! Two passes over the file:
//! * [`p21`] — our own scanner of the exchange structure: syntax errors with line and entity
//!   number, and the entities truck does not model (products, assembly relations, placements,
//!   styles) read by [`structure`];
//! * truck-stepio — surfaces and curves (B-spline, NURBS, conics, elementary and swept
//!   surfaces) and the face/loop/edge topology of each shell.
//!
//! A face whose surface, curves or trimming cannot be used is listed in
//! [`crate::model::Scene::skipped`] with the reason and the rest is drawn; truck code that
//! can panic runs under [`crate::isolate::isolated`]. Every face is tessellated once at load
//! at a coarse tolerance: that gives its bounds and rejects faces that cannot be trimmed.

mod bspline_check;
mod chunks;
mod conic;
mod edge;
pub mod offset;
pub mod p21;
mod ref_check;
pub mod structure;
mod whole;

use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use truck_stepio::r#in::alias::re_exports::Point3;
use truck_stepio::r#in::ruststep::ast::Name;
use truck_stepio::r#in::ruststep::tables::{IntoOwned, PlaceHolder};
use truck_stepio::r#in::{EdgeCurveHolder, FaceSurfaceHolder, Table};

use super::LoadError;
use crate::isolate::isolated;
use crate::model::nurbs::{FastSurface, NurbsSurface};
use crate::model::trimmed::{CLOSED_TOL, LoopEdge, TrimEdge, TruckSurface};
use crate::model::{Sphere, TrimmedFace};
use edge::{
    EDGE_VERTEX_TOLERANCE, Fit, LOOSE_EDGE_FRACTION, LOOSE_UNCERTAINTY_FACTOR, convert_edge,
};
use whole::{is_sphere, seam_clear_of, whole_surface_loop};

/// A STEP file read: every face of the shells used, converted (not yet probed: see
/// [`crate::prep::step`]), with the product structure that places them.
#[derive(Debug)]
pub struct StepModel {
    pub path: std::path::PathBuf,
    pub structure: structure::Structure,
    /// Every face of the shells used, by entity id: converted, or why not.
    pub faces: Vec<(u64, Result<TrimmedFace, String>)>,
    /// Face entity ids per shell entity id.
    pub shell_faces: HashMap<u64, Vec<u64>>,
    pub warnings: Vec<String>,
}

/// Reads a STEP file from bytes (`path` is for messages): its structure and faces.
pub fn read(bytes: &[u8], path: &Path) -> Result<StepModel, LoadError> {
    read_with(bytes, path, &crate::util::NoProgress)
}

/// As [`read`], reporting the face conversion to `progress`. Faces are converted in parallel
/// (rayon); the result is the same as one thread's, in file order: faces by shell (shells by
/// entity id), each shell's faces as it lists them; every edge converted once, whichever face
/// reaches it first (an edge's conversion depends on the edge alone); the loose-edge warning
/// lists edges in the order one thread would have met them.
pub(crate) fn read_with(
    bytes: &[u8],
    path: &Path,
    progress: &dyn crate::util::Progress,
) -> Result<StepModel, LoadError> {
    let p = || path.to_path_buf();
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(LoadError::Empty { path: p() });
    }
    if let Some(offset) = bytes.iter().position(|&b| b == 0) {
        return Err(LoadError::NotText {
            path: p(),
            offset,
            what: "a NUL byte",
        });
    }
    // STEP strings may be Latin-1; only the structure (ASCII) matters here.
    let text = String::from_utf8_lossy(bytes);
    let file = p21::parse(&text).map_err(|e| LoadError::Parse {
        path: p(),
        line: e.line(),
        reason: e.reason(),
    })?;
    let structure = structure::analyse(&file);
    if structure.instances.is_empty() {
        return Err(LoadError::NoFaces {
            path: p(),
            reason: format!(
                "no B-rep shell (MANIFOLD_SOLID_BREP, BREP_WITH_VOIDS, SHELL_BASED_SURFACE_MODEL) among {} entities",
                file.entities.len()
            ),
        });
    }

    // truck's view of the same data section (parsed in parallel, see `chunks`).
    // ruststep's parser panics on some values our scanner accepts (an exponent past i64).
    // Only the text our scanner read and checked (`file.end`): the two parsers may disagree
    // on where the exchange structure ends (`END-ISO-10303-21 ;` with a space, say).
    let instances = isolated(|| chunks::entity_instances(&text[..file.end]))
        .unwrap_or_else(|panic| Err(format!("its parser failed ({panic})")))
        .map_err(|e| LoadError::Unreadable {
            path: p(),
            reason: format!("STEP syntax not accepted by truck-stepio: {e}"),
        })?;
    // B-splines whose knots truck would expand without bound, or whose control points are
    // not references (ruststep panics on them), are not given to truck at all.
    let mut refused = bspline_check::refused(&file);
    // Reference cycles and very deep chains overflow truck's recursive resolution (an abort).
    let tangled = ref_check::refused(&file);
    let mut table = Table::default();
    let mut unreadable: BTreeMap<String, usize> = BTreeMap::new();
    let mut unseen = 0usize;
    for inst in &instances {
        use truck_stepio::r#in::ruststep::ast::EntityInstance;
        let (id, name) = match inst {
            EntityInstance::Simple { id, record } => (*id, record.name.clone()),
            EntityInstance::Complex { id, .. } => (*id, "complex entity".to_owned()),
        };
        if refused.contains_key(&id) || tangled.contains_key(&id) {
            continue;
        }
        // Only what our scanner read and checked, as it read it: an instance the two parsers
        // see differently is not given to truck (its faces are skipped, naming it).
        let ours = file.get(id);
        let same = match (inst, ours) {
            (EntityInstance::Simple { record, .. }, Some(e)) => {
                !e.is_complex()
                    && e.record()
                        .is_some_and(|r| r.name.eq_ignore_ascii_case(&record.name))
            }
            (EntityInstance::Complex { .. }, Some(e)) => e.is_complex(),
            (_, None) => false,
        };
        if !same {
            unseen += 1;
            continue;
        }
        // ruststep panics ("Invalid key while deserializing PlaceHolder") where a value of
        // the wrong kind stands for a reference: such an entity is unreadable, not fatal.
        if !matches!(isolated(|| table.push_instance(inst)), Ok(Ok(_))) {
            *unreadable.entry(name).or_default() += 1;
        }
    }
    drop(instances);

    complete_placements(&mut table);
    untrim_swept_curves(&mut table, &file);
    let offsets = offset::resolve(&mut table, &file, structure.plane_angle_rad);
    let offsets_refused = &offsets.refused;

    let mut warnings = structure.warnings.clone();
    if !structure.unsupported.is_empty() {
        let list: Vec<String> = structure
            .unsupported
            .iter()
            .map(|(n, c)| format!("{n} ×{c}"))
            .collect();
        warnings.push(format!(
            "unsupported entities (not drawn): {}",
            list.join(", ")
        ));
    }
    if let Some((id, reason)) = refused.iter().next() {
        warnings.push(format!(
            "{} B-spline entities refused, their faces not drawn (#{id}: {reason}{})",
            refused.len(),
            if refused.len() > 1 { "; …" } else { "" }
        ));
    }
    if unseen > 0 {
        warnings.push(format!(
            "{unseen} entity instances truck-stepio's parser read differently from ours were ignored"
        ));
    }
    if let Some((id, reason)) = tangled.iter().next() {
        warnings.push(format!(
            "{} entities not read, their faces not drawn (#{id}: {reason}{})",
            tangled.len(),
            if tangled.len() > 1 { "; …" } else { "" }
        ));
    }
    if let Some((id, reason)) = offsets_refused.iter().next() {
        warnings.push(format!(
            "{} of {} OFFSET_SURFACE entities not read, their faces not drawn (#{id}: {reason}{})",
            offsets_refused.len(),
            offsets_refused.len() + offsets.replaced.len() + offsets.evaluated.len(),
            if offsets_refused.len() > 1 {
                "; …"
            } else {
                ""
            }
        ));
    }
    refused.extend(tangled);
    if !unreadable.is_empty() {
        let list: Vec<String> = unreadable
            .iter()
            .map(|(n, c)| format!("{n} ×{c}"))
            .collect();
        warnings.push(format!(
            "entities truck-stepio could not read: {}",
            list.join(", ")
        ));
    }

    // Faces of every shell used, converted once and shared by the shell's instances.
    let mut shells: Vec<u64> = structure.instances.iter().map(|i| i.shell).collect();
    shells.sort_unstable();
    shells.dedup();
    let vertex_loops: std::collections::HashSet<u64> = file
        .entities
        .iter()
        .filter(|e| e.has("VERTEX_LOOP"))
        .map(|e| e.id)
        .collect();
    let mut face_ids: HashMap<u64, Vec<u64>> = HashMap::new();
    // Every face of every shell, in order (a face listed by two shells is converted twice,
    // as each shell's).
    let mut jobs: Vec<u64> = Vec::new();
    for &shell in &shells {
        let ids = shell_faces(&file, shell);
        jobs.extend_from_slice(&ids);
        face_ids.insert(shell, ids);
    }
    let by_vertex = edge::vertex_edges(&table);
    let source = FaceSource {
        file: &file,
        table: &table,
        by_vertex: &by_vertex,
        vertex_loops: &vertex_loops,
        angle_rad: structure.plane_angle_rad,
        uncertainty: structure.uncertainty,
        offsets_refused,
        evaluated_offsets: &offsets.evaluated,
    };
    let edges = EdgeCache::default();
    let results: Vec<(Result<TrimmedFace, String>, Vec<u64>)> = {
        use rayon::prelude::*;
        let bar = crate::util::Bar::begin(progress, "faces read", jobs.len(), 200);
        jobs.par_iter()
            .map(|&f| {
                // The edges the face reached, kept even when its conversion panics.
                let mut reached = Vec::new();
                let r = isolated(|| convert_face(&source, f, &edges, &mut reached))
                    .and_then(|r| r)
                    .map_err(|e| e.to_string());
                bar.advance();
                (r, reached)
            })
            .collect()
    };
    // Loose and healed edges in the order one thread converting the faces in order would have
    // met them.
    let mut seen = std::collections::HashSet::new();
    let (mut loose, mut healed) = (Vec::new(), Vec::new());
    for e in results
        .iter()
        .flat_map(|(_, reached)| reached.iter().copied())
    {
        match seen.insert(e).then(|| edges.fit(e)).flatten() {
            Some(Fit::Loose) => loose.push(e),
            Some(Fit::Healed(off)) => healed.push((e, off)),
            _ => {}
        }
    }
    let converted: Vec<(u64, Result<TrimmedFace, String>)> = jobs
        .into_iter()
        .zip(results)
        .map(|(f, (r, _))| {
            let r = r.map_err(|e| match refused.get(&f) {
                // The face itself was not given to truck (it reaches a reference cycle).
                Some(why) => format!("refused: {why}"),
                None => name_refusals(e, &refused),
            });
            (f, r)
        })
        .collect();

    if !loose.is_empty() {
        let list: Vec<String> = loose.iter().take(5).map(|e| format!("#{e}")).collect();
        warnings.push(format!(
            "{} edges have vertices off their curve by more than {EDGE_VERTEX_TOLERANCE:e} of \
             their size, accepted within the file's tolerance (its uncertainty ×{LOOSE_UNCERTAINTY_FACTOR} \
             or {LOOSE_EDGE_FRACTION} of the edge) ({}{})",
            loose.len(),
            list.join(", "),
            if loose.len() > 5 { ", …" } else { "" }
        ));
    }

    if !healed.is_empty() {
        let list: Vec<String> = healed
            .iter()
            .take(5)
            .map(|(e, d)| format!("#{e} by {d:.3e}"))
            .collect();
        warnings.push(format!(
            "{} edges have vertices off their curve beyond the file's tolerance, healed as a \
             kernel does, each vertex moved to where its healed edges' curves meet (or its nearest \
             point of the curve) ({}{})",
            healed.len(),
            list.join(", "),
            if healed.len() > 5 { ", …" } else { "" }
        ));
    }
    Ok(StepModel {
        path: p(),
        structure,
        faces: converted,
        shell_faces: face_ids,
        warnings,
    })
}

/// A face's failure that is truck's lookup of an entity we refused, with our reason instead.
fn name_refusals(reason: String, refused: &BTreeMap<u64, String>) -> String {
    const LOOKUP: &str = "Lookup failed for #";
    let Some(at) = reason.find(LOOKUP) else {
        return reason;
    };
    let digits = &reason[at + LOOKUP.len()..];
    let end = digits
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(digits.len());
    match digits[..end]
        .parse::<u64>()
        .ok()
        .and_then(|id| refused.get(&id).map(|w| (id, w)))
    {
        Some((id, why)) => reason.replacen(
            &format!("{LOOKUP}{id}"),
            &format!("#{id} refused: {why}"),
            1,
        ),
        None => reason,
    }
}

/// Gives every `AXIS2_PLACEMENT_3D` without a usable reference direction (`$`, or parallel to
/// its axis) the one ISO 10303-42's `build_axes` implies (x, or y when the axis is x).
/// truck-stepio takes x regardless, which is NaN for a placement whose axis is x: every
/// circle, cylinder, cone… placed so lost its edges or faces (CATIA writes such placements).
fn complete_placements(table: &mut Table) {
    use truck_stepio::r#in::DirectionHolder;
    let ratios = |d: &Option<PlaceHolder<DirectionHolder>>, table: &Table| -> Option<DVec3> {
        let h = match d.as_ref()? {
            PlaceHolder::Ref(Name::Entity(id)) => table.direction.get(id)?,
            PlaceHolder::Owned(h) => h,
            _ => return None,
        };
        let r = &h.direction_ratios;
        let v = DVec3::new(*r.first()?, *r.get(1)?, r.get(2).copied().unwrap_or(0.0));
        v.try_normalize()
    };
    let fixes: Vec<(u64, DVec3)> = table
        .axis2_placement_3d
        .iter()
        .filter_map(|(&id, a)| {
            let z = ratios(&a.axis, table).unwrap_or(DVec3::Z);
            let x = ratios(&a.ref_direction, table);
            let usable = x.is_some_and(|x| x.cross(z).length() > 1e-9);
            if usable {
                return None;
            }
            let default = if z.cross(DVec3::X).length() > 1e-9 {
                DVec3::X
            } else {
                DVec3::Y
            };
            Some((id, default))
        })
        .collect();
    for (id, x) in fixes {
        if let Some(a) = table.axis2_placement_3d.get_mut(&id) {
            a.ref_direction = Some(PlaceHolder::Owned(DirectionHolder {
                label: String::new(),
                direction_ratios: vec![x.x, x.y, x.z],
            }));
        }
    }
}

/// A swept surface whose curve is a `TRIMMED_CURVE` (truck-stepio reads none) sweeps the
/// trimmed curve's basis instead: a face is trimmed by its own edges, so the surface may
/// extend past the trimming points.
fn untrim_swept_curves(table: &mut Table, file: &p21::P21File) {
    let basis = |p: &PlaceHolder<truck_stepio::r#in::CurveAnyHolder>| -> Option<u64> {
        let id = holder_ref(p)?;
        file.get(id)?.part("TRIMMED_CURVE")?.ref_at(1)
    };
    for s in table.surface_of_linear_extrusion.values_mut() {
        if let Some(b) = basis(&s.swept_curve) {
            s.swept_curve = PlaceHolder::Ref(Name::Entity(b));
        }
    }
    for s in table.surface_of_revolution.values_mut() {
        if let Some(b) = basis(&s.swept_curve) {
            s.swept_curve = PlaceHolder::Ref(Name::Entity(b));
        }
    }
}

/// Face entity ids of a shell (`CLOSED_SHELL(name, (faces…))`, also `OPEN_SHELL`,
/// `ORIENTED_CLOSED_SHELL(name, *, #shell, orientation)`).
fn shell_faces(file: &p21::P21File, shell: u64) -> Vec<u64> {
    let Some(e) = file.get(shell) else {
        return Vec::new();
    };
    let Some(rec) = e.parts.first() else {
        return Vec::new();
    };
    if rec.name.starts_with("ORIENTED_") {
        return rec
            .args
            .get(2)
            .and_then(p21::Param::as_ref)
            .map(|s| shell_faces(file, s))
            .unwrap_or_default();
    }
    rec.args
        .get(1)
        .and_then(p21::Param::as_list)
        .map(|l| l.iter().filter_map(p21::Param::as_ref).collect())
        .unwrap_or_default()
}

/// An edge converted, and how its vertices lie on its curve; or why it cannot be used.
type EdgeResult = Result<(Arc<TrimEdge>, Fit), String>;

/// Edges shared by the faces converted in parallel: each converted once, by the first face to
/// reach it (the others wait for it). A conversion that panicked leaves no result: the next
/// face to reach the edge tries again, as one thread would.
#[derive(Default)]
struct EdgeCache(std::sync::Mutex<HashMap<u64, Arc<std::sync::OnceLock<EdgeResult>>>>);

impl EdgeCache {
    fn cell(&self, id: u64) -> Arc<std::sync::OnceLock<EdgeResult>> {
        let mut map = self.0.lock().unwrap_or_else(|e| e.into_inner());
        map.entry(id).or_default().clone()
    }

    fn get(&self, id: u64, convert: impl FnOnce() -> EdgeResult) -> EdgeResult {
        self.cell(id).get_or_init(convert).clone()
    }

    fn fit(&self, id: u64) -> Option<Fit> {
        self.cell(id)
            .get()
            .and_then(|r| r.as_ref().ok())
            .map(|r| r.1)
    }
}

fn entity_ref<T: Clone>(p: &PlaceHolder<T>, table: &HashMap<u64, T>) -> Option<(u64, T)> {
    match p {
        PlaceHolder::Ref(Name::Entity(id)) => table.get(id).cloned().map(|t| (*id, t)),
        PlaceHolder::Owned(t) => Some((0, t.clone())),
        _ => None,
    }
}

/// One face with its surface and loops of edges (edges shared through `edges`).
/// What converting faces reads: the file twice (our scanner, truck's table) and what the
/// structure found (units, tolerance).
struct FaceSource<'a> {
    file: &'a p21::P21File,
    table: &'a Table,
    vertex_loops: &'a std::collections::HashSet<u64>,
    /// The edges at each vertex (healing moves a vertex alike for all of them).
    by_vertex: &'a edge::VertexEdges,
    /// Radians per file plane-angle unit.
    angle_rad: Option<f64>,
    /// The file's distance uncertainty (file units).
    uncertainty: Option<f64>,
    /// `OFFSET_SURFACE`s not replaced ([`offset::resolve`]), and why.
    offsets_refused: &'a BTreeMap<u64, String>,
    /// Offset surface → (its basis, distance) we evaluate (`offset::Offsets::evaluated`).
    evaluated_offsets: &'a BTreeMap<u64, (u64, f64)>,
}

/// Converts face `id`; `reached` gets every edge curve the face looks up, in order.
fn convert_face(
    src: &FaceSource<'_>,
    id: u64,
    edges: &EdgeCache,
    reached: &mut Vec<u64>,
) -> Result<TrimmedFace, String> {
    let FaceSource {
        file,
        table,
        vertex_loops,
        angle_rad,
        uncertainty,
        offsets_refused,
        evaluated_offsets,
        by_vertex,
    } = *src;
    let face: FaceSurfaceHolder = if let Some(f) = table.face_surface.get(&id) {
        f.clone()
    } else if let Some(of) = table.oriented_face.get(&id) {
        entity_ref(&of.face_element, &table.face_surface)
            .map(|(_, f)| f)
            .ok_or("oriented face without a readable face element")?
    } else {
        return Err(
            "not a face truck-stepio could read (ADVANCED_FACE / FACE_SURFACE expected)".into(),
        );
    };
    let geometry = holder_ref(&face.face_geometry);
    // An offset of a B-spline or swept basis: read on the basis, evaluated as the offset
    // (`offset`).
    let offset = geometry.and_then(|g| evaluated_offsets.get(&g).copied());
    let holder = match offset {
        Some((basis, _)) => PlaceHolder::Ref(Name::Entity(basis)),
        None => face.face_geometry.clone(),
    };
    let surface_any = holder.into_owned(table).map_err(|e| {
        match geometry.and_then(|g| Some((g, offsets_refused.get(&g)?))) {
            Some((g, why)) => format!("surface: OFFSET_SURFACE #{g}: {why}"),
            None => format!("surface: {e}"),
        }
    })?;
    let mut surface =
        TruckSurface::try_from(&surface_any).map_err(|e| format!("surface not supported: {e}"))?;
    // truck evaluates an unclamped B-spline wrongly at the end of its range.
    if let Some(clamped) = crate::model::knots::clamp_surface(&surface) {
        surface = clamped;
    }
    if let Some(rad) = angle_rad
        && (rad - 1.0).abs() > 1e-12
        && let Some(cone) = cone_from_file(file, id, rad)
    {
        // truck-stepio reads a CONICAL_SURFACE's semi-angle as radians whatever the file's
        // plane-angle unit (many writers use degrees).
        surface = cone;
    }
    if !surface_is_finite(&surface) {
        // truck-stepio leaves NaNs in a plane whose placement has no usable reference
        // direction; rebuild it from the placement as we read it.
        surface = plane_from_file(file, id).ok_or("the surface has non-finite parameters")?;
    }
    let mut loops = Vec::new();
    let mut vertex_bound = false;
    for b in &face.bounds {
        let (_, bound) =
            entity_ref(b, &table.face_bound).ok_or("face bound is not an EDGE_LOOP")?;
        let Some((_, lp)) = entity_ref(&bound.bound, &table.edge_loop) else {
            // A VERTEX_LOOP marks an apex or pole: a point, nothing to trim.
            if let PlaceHolder::Ref(Name::Entity(l)) = &bound.bound
                && vertex_loops.contains(l)
            {
                vertex_bound = true;
                continue;
            }
            return Err("face bound is not an EDGE_LOOP (POLY_LOOP is not supported)".into());
        };
        let mut out: Vec<LoopEdge> = Vec::new();
        for e in &lp.edge_list {
            let PlaceHolder::Ref(Name::Entity(eid)) = e else {
                return Err("inline edge in a loop".into());
            };
            let (ecid, forward) = if let Some(oe) = table.oriented_edge.get(eid) {
                match &oe.edge_element {
                    PlaceHolder::Ref(Name::Entity(i)) => (*i, oe.orientation),
                    _ => return Err(format!("oriented edge #{eid} without an edge curve")),
                }
            } else {
                (*eid, true)
            };
            reached.push(ecid);
            let (edge, _) = edges.get(ecid, || {
                let holder: &EdgeCurveHolder = table
                    .edge_curve
                    .get(&ecid)
                    .ok_or_else(|| format!("edge #{ecid} is not a readable EDGE_CURVE"))?;
                let (e, fit) = convert_edge(file, table, ecid, holder, uncertainty, by_vertex)?;
                Ok((Arc::new(e), fit))
            })?;
            out.push(LoopEdge {
                edge,
                forward,
                kind: Default::default(),
            });
        }
        if !bound.orientation {
            out.reverse();
            for le in out.iter_mut() {
                le.forward = !le.forward;
            }
        }
        if !out.is_empty() {
            loops.push(out);
        }
    }
    if loops.is_empty() && vertex_bound {
        // Only a VERTEX_LOOP (at a pole): the face is the whole closed surface, a sphere.
        // Bounded as a kernel bounds it: its seam meridian, once each way (ShapeFix adds the
        // seam and the degenerate pole edges; the poles are points here).
        loops = whole_surface_loop(&surface, id, 0.0).into_iter().collect();
    } else if (vertex_bound || is_sphere(&surface))
        && let Some(seam) = seam_clear_of(&surface, &loops)
        && (vertex_bound || seam.loops_are_holes(face.same_sense))
        && let Some(whole) = whole_surface_loop(&surface, id, seam.at)
    {
        // A VERTEX_LOOP at a pole beside edge loops none of which runs around the surface:
        // they are holes in the whole sphere (a sphere cut by small features), which reaches
        // the pole. Without the whole surface's loop the holes alone were drawn. Without a
        // VERTEX_LOOP, the loops' orientation says whether they are holes (a sphere cut by a
        // wedge, its edges at the poles filleted: generated model gen-3-15).
        loops.insert(0, whole);
    }
    if loops.is_empty() {
        return Err("the face has no edge loop".into());
    }
    let pts = crate::model::trimmed::loop_points(&loops);
    let closed =
        isolated(|| TrimmedFace::closed_directions(&surface, CLOSED_TOL)).unwrap_or((None, None));
    let fast = match offset {
        Some((_, distance)) => Some(Arc::new(match NurbsSurface::of(&surface) {
            Some(base) => FastSurface::Offset { base, distance },
            None => FastSurface::OffsetOfTruck {
                base: surface.clone(),
                distance,
            },
        })),
        None => TrimmedFace::fast_surface(&surface),
    };
    Ok(TrimmedFace {
        id,
        closed,
        surface,
        loops,
        domain_left: face.same_sense,
        bounds: Sphere::around(pts.iter().copied()),
        fast,
        loop_starts: Vec::new(),
    })
}

fn surface_is_finite(s: &TruckSurface) -> bool {
    use crate::model::trimmed::SurfaceEval;
    // At the ends and middle of its parameter range where it has one (a B-spline's knots
    // need not cover [0, 1]: generated model gen-49-41's v knots run 92.57..93.16, and its
    // face was skipped as having non-finite parameters), else of [0, 1].
    let (u, v) = crate::model::trimmed::parameter_bounds(s);
    let (u, v) = (u.unwrap_or((0.0, 1.0)), v.unwrap_or((0.0, 1.0)));
    [0.0, 0.5, 1.0].iter().all(|&t| {
        let uv = glam::DVec2::new(u.0 + t * (u.1 - u.0), v.0 + t * (v.1 - v.0));
        s.point(uv).is_finite()
    })
}

/// The surface entity of face `face`: `ADVANCED_FACE(name, bounds, #surface, sense)`, also
/// through an `ORIENTED_FACE(name, *, #face, orientation)`.
fn face_geometry(file: &p21::P21File, face: u64) -> Option<u64> {
    let mut f = file.get(face)?.record()?;
    if f.name == "ORIENTED_FACE" {
        f = file.get(f.ref_at(2)?)?.record()?;
    }
    f.ref_at(2)
}

/// The cone of face `face` (`ADVANCED_FACE(name, bounds, #CONICAL_SURFACE, sense)`) with its
/// semi-angle converted by `rad` radians per file unit, parametrised as truck-stepio does
/// (the line `(r, 0, 0) + t (tan α, 0, 1)` revolved about the placement's z axis, inverted).
fn cone_from_file(file: &p21::P21File, face: u64, rad: f64) -> Option<TruckSurface> {
    use truck_stepio::r#in::alias::ElementarySurface;
    use truck_stepio::r#in::alias::re_exports::{
        Invertible, Line, Matrix4, Processor, RevolutedCurve, Transformed, Vector3,
    };
    let cone = file.get(face_geometry(file, face)?)?;
    let rec = cone.part("CONICAL_SURFACE")?;
    let m = structure::placement(file, rec.ref_at(1)?)?;
    let radius = rec.f64_at(2)?;
    let angle = rec.f64_at(3)? * rad;
    if !(radius.is_finite() && angle.is_finite() && angle.abs() < std::f64::consts::FRAC_PI_2) {
        return None;
    }
    let p = Point3::new(radius, 0.0, 0.0);
    let v = Vector3::new(angle.tan(), 0.0, 1.0);
    let rev = RevolutedCurve::by_revolution(
        Line(p, p + v),
        Point3::new(0.0, 0.0, 0.0),
        Vector3::unit_z(),
    );
    let mut processor = Processor::new(rev);
    let c = m.to_cols_array();
    processor.transform_by(Matrix4::new(
        c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8], c[9], c[10], c[11], c[12], c[13],
        c[14], c[15],
    ));
    processor.invert();
    let s = TruckSurface::ElementarySurface(Box::new(ElementarySurface::ConicalSurface(processor)));
    surface_is_finite(&s).then_some(s)
}

/// The plane of face `face` (`ADVANCED_FACE(name, bounds, #PLANE, sense)`) from its placement.
fn plane_from_file(file: &p21::P21File, face: u64) -> Option<TruckSurface> {
    use truck_stepio::r#in::alias::ElementarySurface;
    use truck_stepio::r#in::alias::re_exports::Plane;
    let plane = file.get(face_geometry(file, face)?)?;
    let rec = plane.part("PLANE")?;
    let m = structure::placement(file, rec.ref_at(1)?)?;
    let o = m.w_axis.truncate();
    let (x, y) = (m.x_axis.truncate(), m.y_axis.truncate());
    let pt = |v: DVec3| Point3::new(v.x, v.y, v.z);
    let plane = Plane::new(pt(o), pt(o + x), pt(o + y));
    let s = TruckSurface::ElementarySurface(Box::new(ElementarySurface::Plane(plane)));
    surface_is_finite(&s).then_some(s)
}

fn holder_ref<T>(p: &PlaceHolder<T>) -> Option<u64> {
    match p {
        PlaceHolder::Ref(Name::Entity(id)) => Some(*id),
        _ => None,
    }
}
