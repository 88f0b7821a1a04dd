//! Load-time preparation of a STEP model: every face tessellated coarsely once (the probe:
//! its bounds, its normals along its edges, and faces that cannot be trimmed are skipped with
//! their reason), its edges classified as sharp, smooth or seams by the faces that share
//! them (`model::edges`), then placed by the product structure — one patch per face and
//! placement, one [`Instance`] per placed shell, the scene in millimetres.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{DMat4, DVec3};
use rayon::prelude::*;

use crate::io::LoadError;
use crate::io::step::StepModel;
use crate::isolate::isolated;
use crate::model::bezier::MAX_COORDINATE;
use crate::model::edges::{EdgeNormals, EdgeUse, classify_shared};
use crate::model::{
    Instance, Part, Patch, PatchSurface, Scene, SkippedFace, Sphere, UpAxis, bounding_box,
    transform_scale, trimmed::TrimmedFace,
};
use crate::tessellate::{PatchMesh, TrimmedTessellator};
use crate::util::{Bar, Progress};

/// Coarse tolerance of the load-time tessellation, relative to a face's edge extent.
const PROBE_TOLERANCE: f64 = 0.02;

/// A face with its bounding box (own coordinates) and its normals along its edges.
type Probed = (TrimmedFace, (DVec3, DVec3), Vec<Vec<EdgeNormals>>);

/// Reads a STEP file from bytes (`path` is for messages) and prepares its scene.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Scene, LoadError> {
    assemble(crate::io::step::read(bytes, path)?, &super::NoProgress)
}

/// Probes every face of `model` and places them (see the module doc).
pub fn assemble(model: StepModel, progress: &dyn Progress) -> Result<Scene, LoadError> {
    // Probe tessellation: bounds, and faces that cannot be trimmed.
    let StepModel {
        path,
        structure,
        faces: converted,
        shell_faces: face_ids,
        mut warnings,
    } = model;
    let p = || path.clone();
    let pb = Bar::begin(progress, "faces probed", converted.len(), 200);
    let probed: Vec<(u64, Result<Probed, String>)> = converted
        .into_par_iter()
        .map_init(TrimmedTessellator::new, |t, (id, r)| {
            let out = r.and_then(|mut face| {
                let (bounds, bbox) = probe(t, &face)?;
                face.bounds = bounds;
                face.loop_starts = t.loop_starts().to_vec();
                let normals = t.edge_normals(&face);
                Ok((face, bbox, normals))
            });
            pb.advance();
            (id, out)
        })
        .collect();
    drop(pb);

    let mut probed = probed;
    classify_edges(&mut probed);
    let mut faces: HashMap<u64, (Arc<TrimmedFace>, (DVec3, DVec3))> = HashMap::new();
    let mut skipped = Vec::new();
    for (id, r) in probed {
        match r {
            Ok((face, bbox, _)) => {
                faces.insert(id, (Arc::new(face), bbox));
            }
            Err(reason) => skipped.push(SkippedFace { face: id, reason }),
        }
    }

    let parts: Vec<Part> = structure
        .parts
        .iter()
        .map(|p| Part {
            name: p.name.clone(),
        })
        .collect();
    // Scenes are in millimetres (the CAD default); files in other units are scaled.
    let unit = structure
        .length_unit_mm
        .filter(|u| u.is_finite() && *u > 0.0)
        .unwrap_or(1.0);
    if unit != 1.0 {
        warnings.push(format!("length unit is {unit} mm: scaled to millimetres"));
    }
    let mut patches = Vec::new();
    let mut corners = Vec::new();
    let mut instances = Vec::new();
    // One instance per placed solid, as a kernel reads it: the void shells of a
    // BREP_WITH_VOIDS placed with its outer shell join the outer shell's instance (the shells
    // of a SHELL_BASED_SURFACE_MODEL stay shapes of their own, as in OCCT).
    let mut solid_instance: HashMap<(u64, usize, String, [u64; 16]), u32> = HashMap::new();
    for inst in &structure.instances {
        let transform = DMat4::from_scale(DVec3::splat(unit)) * inst.transform;
        let scale = transform_scale(&transform);
        let key = inst
            .solid
            .filter(|s| structure.voided_solids.contains(s))
            .map(|solid| {
                (
                    solid,
                    inst.part,
                    inst.instance_name.clone(),
                    transform.to_cols_array().map(f64::to_bits),
                )
            });
        let instance = match key.as_ref().and_then(|k| solid_instance.get(k)) {
            Some(&i) => i,
            None => {
                let i = instances.len() as u32;
                instances.push(Instance {
                    name: inst.instance_name.clone(),
                    part: inst.part as u32,
                    transform,
                    shell: Some(inst.shell),
                });
                if let Some(k) = key {
                    solid_instance.insert(k, i);
                }
                i
            }
        };
        for fid in face_ids.get(&inst.shell).into_iter().flatten() {
            let Some((face, (lo, hi))) = faces.get(fid) else {
                continue;
            };
            let color = structure
                .colors
                .get(fid)
                .or_else(|| structure.colors.get(&inst.shell))
                .or_else(|| inst.solid.and_then(|s| structure.colors.get(&s)))
                .copied();
            let bounds = Sphere {
                center: transform.transform_point3(face.bounds.center),
                radius: face.bounds.radius * scale,
            };
            for k in 0..8 {
                let c = DVec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x },
                    if k & 2 == 0 { lo.y } else { hi.y },
                    if k & 4 == 0 { lo.z } else { hi.z },
                );
                corners.push(transform.transform_point3(c));
            }
            patches.push(Patch {
                id: patches.len() as u32,
                surface: PatchSurface::Trimmed(face.clone()),
                transform,
                bounds,
                part: inst.part as u32,
                color,
                instance,
            });
        }
    }
    if patches.is_empty() {
        let first: Vec<String> = skipped
            .iter()
            .take(3)
            .map(|s| format!("#{}: {}", s.face, s.reason))
            .collect();
        return Err(LoadError::NoFaces {
            path: p(),
            reason: if skipped.is_empty() {
                "its shells have no faces".to_owned()
            } else {
                format!(
                    "none of its {} faces could be used ({})",
                    skipped.len(),
                    first.join("; ")
                )
            },
        });
    }
    let spheres: Vec<Sphere> = patches.iter().map(|p| p.bounds).collect();
    Ok(Scene {
        bounds: Sphere::union(&spheres),
        bbox: bounding_box(corners).unwrap_or_default(),
        patches,
        up: UpAxis::Z,
        parts,
        instances,
        skipped,
        warnings,
        unit: Some("mm"),
        mesh_groups: Vec::new(),
    })
}

/// Sets the kind of every edge of the probed faces (`model::edges::classify_shared`): the
/// faces that use an edge (by its `EDGE_CURVE`) and their normals along it decide whether
/// it is sharp, smooth or a seam.
fn classify_edges(probed: &mut [(u64, Result<Probed, String>)]) {
    let mut uses = Vec::new();
    for (f, (_, r)) in probed.iter().enumerate() {
        let Ok((face, _, normals)) = r else {
            continue;
        };
        for (lp, ln) in face.loops.iter().zip(normals) {
            for (le, &n) in lp.iter().zip(ln) {
                uses.push(EdgeUse {
                    edge: le.edge.id,
                    face: f,
                    normals: n,
                });
            }
        }
    }
    let mut kinds = classify_shared(&uses).into_iter();
    for (_, r) in probed.iter_mut() {
        let Ok((face, _, _)) = r else {
            continue;
        };
        for le in face.loops.iter_mut().flatten() {
            le.kind = kinds.next().unwrap_or_default();
        }
    }
}

/// Coarse tessellation of a face: its bounding sphere (grown by the error) and box.
fn probe(
    t: &mut TrimmedTessellator,
    face: &TrimmedFace,
) -> Result<(Sphere, (DVec3, DVec3)), String> {
    let tol = (face.bounds.radius * PROBE_TOLERANCE).max(1e-9);
    let mut mesh = PatchMesh::default();
    isolated(|| t.tessellate(face, tol, &mut mesh))?.map_err(|e| e.to_string())?;
    let grow = mesh.error + tol;
    // As for Bézier patches and meshes: a face reaching past the GPU's f32 range (its
    // vertices overflowed to infinity, or its error did) can be neither drawn nor framed.
    let reach = mesh
        .positions
        .iter()
        .map(|p| match p.is_finite() {
            true => f64::from(p.abs().max_element()),
            false => f64::INFINITY,
        })
        .fold(0.0, f64::max)
        + grow;
    if reach.is_nan() || reach > MAX_COORDINATE {
        return Err(format!(
            "its points reach beyond ±{MAX_COORDINATE:e} (to {reach:e}), which the GPU's f32 cannot draw"
        ));
    }
    let pts = mesh.positions.iter().map(|p| p.as_dvec3());
    let s = Sphere::around(pts.clone());
    let (lo, hi) = bounding_box(pts).ok_or("no vertices")?;
    Ok((
        Sphere {
            center: s.center,
            radius: s.radius + grow,
        },
        (lo - DVec3::splat(grow), hi + DVec3::splat(grow)),
    ))
}
