//! Faces of an IGES file (IGES 5.3 §4.34 trimmed surface 144, §4.32 curve on a parametric
//! surface 142, §4.74/§4.137 subfigures 308/408): a 144's surface with its outer boundary
//! (or the whole parameter rectangle when N1 = 0) and inner boundaries, each a closed loop of
//! [`TrimEdge`]s; a 128 that no 144 uses is a whole patch.
//!
//! A 142 may give its boundary twice: as a curve in the surface's parameter space (BPTR) and in
//! model space (CPTR). The parameter-space curve, lifted onto the surface, lies on the surface
//! exactly; it is used when it agrees with the model-space curve (every sample within
//! `AGREEMENT` of the loop's size) or when it is the only one, else the model-space curve.
//! Degenerate segments (a side collapsed at a pole) are dropped; consecutive segments are
//! oriented head to tail and their shared vertices made identical; a gap larger than
//! `MAX_GAP` of the loop's size makes the face invalid.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use glam::{DMat4, DVec3};
use truck_stepio::r#in::alias::re_exports::PCurve;
use truck_stepio::r#in::alias::{Curve3D, Surface};

use super::IgesError;
use super::directory::{Entry, IgesFile};
use super::entities::{Decoder, expect_type};
use super::nurbs::Nurbs;
use crate::isolate::isolated;
use crate::model::trimmed::{CLOSED_TOL, LoopEdge, TrimEdge};
use crate::model::{Sphere, TrimmedFace};

/// How far (relative to the loop's size) a lifted parameter-space curve may stray from the
/// model-space curve and still be used.
pub(crate) const AGREEMENT: f64 = 1e-3;
/// Largest gap between consecutive boundary segments, relative to the loop's size.
pub(crate) const MAX_GAP: f64 = 2e-3;
/// Edge ids of the sides of a whole parameter rectangle (face ids are DE numbers, far below).
const RECT_EDGE_ID: u64 = 1 << 40;
/// Most nested subfigure instances followed.
const MAX_SUBFIGURE_DEPTH: usize = 16;

/// The faces of a file and how they are placed.
#[derive(Debug)]
pub struct Collected {
    /// Faces by DE, converted or why not.
    pub faces: Vec<(u64, Result<TrimmedFace, IgesError>)>,
    /// Shells placed: (shell id — 0 for the top level, else the 308's DE —, transform, name).
    pub shells: Vec<(u64, DMat4, String)>,
    pub shell_faces: HashMap<u64, Vec<u64>>,
    pub colors: HashMap<u64, [f32; 3]>,
    pub warnings: Vec<String>,
    /// The first face's error, in file order.
    pub first_error: Option<IgesError>,
}

/// Finds, converts and places every face of `file`.
pub fn collect(file: &IgesFile<'_>) -> Collected {
    let mut d = Decoder::new(file);
    let mut trimmed_surfaces: HashSet<usize> = HashSet::new();
    let mut subfigure_members: HashSet<usize> = HashSet::new();
    for e in &file.entries {
        let Ok(p) = d.params(e) else { continue };
        match e.entity_type {
            144 => {
                if let Ok(s) = p.int(1, "surface")
                    && let Ok(s) = file.entry(s, e.de, "surface")
                {
                    trimmed_surfaces.insert(s.de);
                }
            }
            308 => {
                let n = p.count(3, "number of entities", p.p.len()).unwrap_or(0);
                for i in 0..n {
                    if let Ok(m) = p.int(4 + i, "entity") {
                        subfigure_members.insert(m as usize);
                    }
                }
            }
            _ => {}
        }
    }
    let is_face = |e: &Entry| {
        e.entity_type == 144 || e.entity_type == 128 && !trimmed_surfaces.contains(&e.de)
    };

    let mut out = Collected {
        faces: Vec::new(),
        shells: Vec::new(),
        shell_faces: HashMap::new(),
        colors: HashMap::new(),
        warnings: Vec::new(),
        first_error: None,
    };
    let mut converted: HashSet<usize> = HashSet::new();
    let mut convert = |d: &mut Decoder<'_, '_>, out: &mut Collected, e: &Entry| {
        if !converted.insert(e.de) {
            return;
        }
        // truck code evaluates the curves and surfaces: a panic there skips the face.
        let r = isolated(|| face(d, e)).unwrap_or_else(|reason| {
            d.reset();
            Err(IgesError::Invalid {
                de: e.de,
                reason: format!("the geometry library {reason}"),
            })
        });
        if let Err(err) = &r
            && out.first_error.is_none()
        {
            out.first_error = Some(err.clone());
        }
        if let Some(c) = d.color(e) {
            out.colors.insert(e.de as u64, c);
        }
        out.faces.push((e.de as u64, r));
    };

    let top: Vec<&Entry> = file
        .entries
        .iter()
        .filter(|e| is_face(e) && !e.physically_dependent() && !subfigure_members.contains(&e.de))
        .collect();
    if !top.is_empty() {
        out.shells.push((0, DMat4::IDENTITY, String::new()));
        out.shell_faces
            .insert(0, top.iter().map(|e| e.de as u64).collect());
        for e in top {
            convert(&mut d, &mut out, e);
        }
    }

    // Subfigure instances (408) of definitions (308): one shell per definition.
    let mut stack: Vec<(usize, DMat4, String, usize)> = file
        .entries
        .iter()
        .filter(|e| e.entity_type == 408 && !e.physically_dependent())
        .map(|e| (e.de, DMat4::IDENTITY, String::new(), 0))
        .collect();
    stack.reverse();
    while let Some((de, parent, name, depth)) = stack.pop() {
        let placed = instance(&mut d, de, parent, &name);
        let (def, transform, name) = match placed {
            Ok(x) => x,
            Err(e) => {
                out.warnings
                    .push(format!("subfigure instance skipped: {e}"));
                continue;
            }
        };
        let Ok(def_entry) = file.entry(def as i64, de, "subfigure definition") else {
            continue;
        };
        let members = d
            .params(def_entry)
            .map(|p| {
                let n = p.count(3, "number of entities", p.p.len()).unwrap_or(0);
                (0..n)
                    .filter_map(|i| p.int(4 + i, "entity").ok())
                    .collect::<Vec<i64>>()
            })
            .unwrap_or_default();
        let mut faces = Vec::new();
        for m in members {
            let Ok(me) = file.entry(m, def, "subfigure member") else {
                continue;
            };
            if is_face(me) {
                faces.push(me.de as u64);
                convert(&mut d, &mut out, me);
            } else if me.entity_type == 408 {
                if depth + 1 >= MAX_SUBFIGURE_DEPTH {
                    out.warnings.push(format!(
                        "DE {}: subfigures nested more than {MAX_SUBFIGURE_DEPTH} deep",
                        me.de
                    ));
                } else {
                    stack.push((me.de, transform, name.clone(), depth + 1));
                }
            }
        }
        if !faces.is_empty() {
            out.shell_faces.entry(def as u64).or_insert(faces);
            out.shells.push((def as u64, transform, name));
        }
    }
    if d.disagreeing.0 > 0 {
        out.warnings.push(format!(
            "{} of {} boundaries (142) drawn by their model-space curve: their parameter-space \
             curve strays from it by more than {AGREEMENT} of the loop's size",
            d.disagreeing.0, d.disagreeing.1
        ));
    }
    out
}

/// A 408's definition (308 DE), its transform composed with `parent`, and its name path.
fn instance(
    d: &mut Decoder<'_, '_>,
    de: usize,
    parent: DMat4,
    name: &str,
) -> Result<(usize, DMat4, String), IgesError> {
    let e = d.file.entry(de as i64, de, "subfigure instance")?;
    let p = d.params(e)?;
    let def = p.int(1, "subfigure definition")?;
    let def_entry = d.file.entry(def, de, "subfigure definition")?;
    expect_type(def_entry, &[308])?;
    let at = DVec3::new(p.real_or(2, 0.0)?, p.real_or(3, 0.0)?, p.real_or(4, 0.0)?);
    let scale = p.real_or(5, 1.0)?;
    if !(scale.is_finite() && scale > 0.0) {
        return Err(IgesError::Invalid {
            de,
            reason: format!("scale {scale}"),
        });
    }
    let m = parent
        * d.placement(e)?
        * DMat4::from_translation(at)
        * DMat4::from_scale(DVec3::splat(scale));
    let dname = d
        .params(def_entry)
        .ok()
        .and_then(|p| p.p.get(2).and_then(|s| s.string().map(str::to_owned)))
        .unwrap_or_else(|| format!("DE {}", def_entry.de));
    let name = if name.is_empty() {
        dname
    } else {
        format!("{name}/{dname}")
    };
    Ok((def_entry.de, m, name))
}

/// Converts face entity `e` (a 144, or a 128 drawn whole).
pub fn face(d: &mut Decoder<'_, '_>, e: &Entry) -> Result<TrimmedFace, IgesError> {
    let (surface, range, loops) = if e.entity_type == 128 {
        let patch = d.surface(e.de as i64, e.de)?;
        let surface = patch
            .surface()
            .map_err(|reason| IgesError::Invalid { de: e.de, reason })?;
        (surface, patch.range(), Vec::new())
    } else {
        d.visit(e.de as i64, e.de, "trimmed surface", |d, e| {
            let p = d.params(e)?;
            let m = d.placement(e)?;
            let patch = d.surface(p.int(1, "surface PTS")?, e.de)?.transformed(&m);
            let surface = patch
                .surface()
                .map_err(|reason| IgesError::Invalid { de: e.de, reason })?;
            let n1 = p.int(2, "N1")?;
            let n2 = p.count(3, "number of inner boundaries N2", p.p.len())?;
            let mut loops = Vec::new();
            let outer = p.int(4, "outer boundary PTO")?;
            if n1 != 0 && outer != 0 {
                loops.push((trim_loop(d, outer, e.de, &surface, &m)?, true));
            }
            for i in 0..n2 {
                let b = p.int(5 + i, "inner boundary PTI")?;
                loops.push((trim_loop(d, b, e.de, &surface, &m)?, false));
            }
            Ok((surface, patch.range(), loops))
        })?
    };
    let closed =
        isolated(|| TrimmedFace::closed_directions(&surface, CLOSED_TOL)).unwrap_or((None, None));
    let mut loops = loops;
    if loops.is_empty() || !loops.iter().any(|l| l.1) {
        // No outer boundary: the whole parameter rectangle.
        let range = range.ok_or_else(|| IgesError::Invalid {
            de: e.de,
            reason: "an unbounded plane without an outer boundary".into(),
        })?;
        let seams = (closed.0.is_some(), closed.1.is_some());
        let rect = crate::model::trimmed::parameter_rectangle(&surface, range, seams, RECT_EDGE_ID);
        loops.insert(0, (chain(rect, e.de)?, true));
    }
    let loops: Vec<Vec<LoopEdge>> = loops.into_iter().map(|l| l.0).collect();
    let pts = crate::model::trimmed::loop_points(&loops);
    if pts.iter().any(|p| !p.is_finite()) {
        return Err(IgesError::Invalid {
            de: e.de,
            reason: "a boundary point is not finite".into(),
        });
    }
    let fast = TrimmedFace::fast_surface(&surface);
    Ok(TrimmedFace {
        id: e.de as u64,
        closed,
        surface,
        loops,
        domain_left: true,
        bounds: Sphere::around(pts.iter().copied()),
        fast,
        loop_starts: Vec::new(),
    })
}

/// The loop of boundary entity `de` (a 142) on `surface`, in the face's coordinates (`m`: the
/// face's placement).
fn trim_loop(
    d: &mut Decoder<'_, '_>,
    de: i64,
    from: usize,
    surface: &Surface,
    m: &DMat4,
) -> Result<Vec<LoopEdge>, IgesError> {
    d.visit(de, from, "boundary", |d, c| {
        expect_type(c, &[142])?;
        let p = d.params(c)?;
        let bptr = p.int(3, "parameter-space curve BPTR").unwrap_or(0);
        let cptr = p.int(4, "model-space curve CPTR").unwrap_or(0);
        let total = *m * d.placement(c)?;
        let model = (cptr != 0).then(|| {
            d.curve(cptr, c.de, "model-space curve (CPTR)").map(|segs| {
                segs.into_iter()
                    .map(|(de, n)| (de, n.transformed(&total)))
                    .collect::<Vec<_>>()
            })
        });
        let param = (bptr != 0).then(|| d.curve(bptr, c.de, "parameter-space curve (BPTR)"));
        let model_edges = match model {
            Some(Ok(segs)) => Some(edges_3d(&segs)?),
            Some(Err(e)) if !matches!(param, Some(Ok(_))) => return Err(e),
            _ => None,
        };
        let lifted = match param {
            Some(Ok(segs)) => lift(&segs, surface).ok(),
            Some(Err(e)) if model_edges.is_none() => return Err(e),
            _ => None,
        };
        let edges = match (lifted, model_edges) {
            (Some(l), Some(m)) => {
                d.disagreeing.1 += 1;
                if agrees(&l, &m) {
                    l
                } else {
                    d.disagreeing.0 += 1;
                    m
                }
            }
            (Some(l), None) => l,
            (None, Some(m)) => m,
            (None, None) => {
                return Err(IgesError::MissingParameter {
                    de: c.de,
                    index: 4,
                    what: "a usable curve (BPTR and CPTR give none)".into(),
                });
            }
        };
        chain(edges, c.de)
    })
}

fn edge(id: usize, curve: Curve3D, t0: f64, t1: f64) -> TrimEdge {
    use truck_stepio::r#in::alias::re_exports::ParametricCurve;
    let at = |t: f64| crate::model::trimmed::to_dvec(curve.subs(t));
    let (start, end) = (at(t0), at(t1));
    TrimEdge {
        id: id as u64,
        curve,
        t0,
        t1,
        start,
        end,
        wrap: None,
    }
}

fn edges_3d(segs: &[(usize, Nurbs)]) -> Result<Vec<TrimEdge>, IgesError> {
    segs.iter()
        .map(|(de, n)| {
            let c = n
                .curve3d()
                .map_err(|reason| IgesError::Invalid { de: *de, reason })?;
            Ok(edge(*de, c, n.t0, n.t1))
        })
        .collect()
}

/// Parameter-space segments lifted onto `surface`.
fn lift(segs: &[(usize, Nurbs)], surface: &Surface) -> Result<Vec<TrimEdge>, IgesError> {
    segs.iter()
        .map(|(de, n)| {
            let c2 = n
                .curve2d()
                .map_err(|reason| IgesError::Invalid { de: *de, reason })?;
            let c = Curve3D::PCurve(PCurve::new(Box::new(c2), Box::new(surface.clone())));
            Ok(edge(*de, c, n.t0, n.t1))
        })
        .collect()
}

fn samples(e: &TrimEdge, n: usize) -> impl Iterator<Item = DVec3> + '_ {
    (0..=n).map(move |k| e.point(e.t0 + (e.t1 - e.t0) * k as f64 / n as f64))
}

fn size_of(edges: &[TrimEdge]) -> f64 {
    let pts: Vec<DVec3> = edges.iter().flat_map(|e| samples(e, 4)).collect();
    crate::model::bounding_box(pts.iter().copied()).map_or(0.0, |(lo, hi)| lo.distance(hi))
}

/// Whether every sample of the lifted curve lies near the model-space curve's polyline.
fn agrees(lifted: &[TrimEdge], model: &[TrimEdge]) -> bool {
    let size = size_of(model);
    if !(size.is_finite() && size > 0.0) {
        return false;
    }
    let tol = AGREEMENT * size;
    let poly: Vec<Vec<DVec3>> = model.iter().map(|e| samples(e, 32).collect()).collect();
    let near = |p: DVec3| {
        poly.iter().any(|pl| {
            pl.windows(2)
                .any(|w| p.distance(crate::geom::closest_point_on_segment(p, w[0], w[1])) <= tol)
        })
    };
    lifted.iter().all(|e| samples(e, 8).all(near))
}

/// Orients segments head to tail, drops degenerate ones, closes the loop exactly.
fn chain(edges: Vec<TrimEdge>, de: usize) -> Result<Vec<LoopEdge>, IgesError> {
    let size = size_of(&edges);
    if !(size.is_finite() && size > 0.0) {
        return Err(IgesError::Invalid {
            de,
            reason: "the trim loop has no extent".into(),
        });
    }
    let mut edges: Vec<TrimEdge> = edges
        .into_iter()
        .filter(|e| {
            let pts: Vec<DVec3> = samples(e, 8).collect();
            pts.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>() > 1e-9 * size
        })
        .collect();
    let n = edges.len();
    if n == 0 {
        return Err(IgesError::Invalid {
            de,
            reason: "the trim loop is empty".into(),
        });
    }
    let mut forward = vec![true; n];
    if n > 1 {
        let near = |p: DVec3, e: &TrimEdge| p.distance(e.start).min(p.distance(e.end));
        forward[0] = near(edges[0].end, &edges[1]) <= near(edges[0].start, &edges[1]);
    }
    let head = |e: &TrimEdge, f: bool| if f { e.end } else { e.start };
    for i in 1..n {
        let prev = head(&edges[i - 1], forward[i - 1]);
        forward[i] = edges[i].start.distance(prev) <= edges[i].end.distance(prev);
    }
    for i in 0..n {
        let j = (i + 1) % n;
        let h = head(&edges[i], forward[i]);
        let tail = if forward[j] {
            &mut edges[j].start
        } else {
            &mut edges[j].end
        };
        let gap = tail.distance(h);
        if gap > MAX_GAP * size {
            return Err(IgesError::Invalid {
                de,
                reason: format!(
                    "the trim loop is open: a gap of {gap:.3e} after curve DE {}",
                    edges[i].id
                ),
            });
        }
        *tail = h;
    }
    Ok(edges
        .into_iter()
        .zip(forward)
        .map(|(e, forward)| LoopEdge {
            edge: Arc::new(e),
            forward,
            kind: Default::default(),
        })
        .collect())
}
