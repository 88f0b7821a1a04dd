//! Several models in one scene (`render a.step b.glb`): each file a top-level part named
//! after it, placed as its file writes it, in one length unit.
//!
//! Placement: coordinates as written (no file is moved or turned; the scene's up axis is the
//! first file's). Units: the common unit is the first stated unit of a file whose patches
//! cannot be moved (Bézier and mesh patches are drawn where their points are: glTF states
//! metres), else the first stated unit (STEP and IGES: millimetres); a file in another unit
//! is scaled into it through its placements (trimmed faces only), and the merge says so. A
//! file with no stated unit (`.bpt`, OBJ, PLY, STL) is taken as written in the common unit.
//! What cannot be scaled (a mesh in another stated unit) is a [`MergeError`].

use glam::{DMat4, DVec3};
use thiserror::Error;

use super::{PatchSurface, Scene, Sphere};

/// One model to merge and the name its top-level part takes (its file's name).
#[derive(Debug)]
pub struct Named {
    pub name: String,
    pub scene: Scene,
}

/// The merged scene and what was done to get it (units converted).
#[derive(Debug)]
pub struct Merged {
    pub scene: Scene,
    pub notes: Vec<String>,
}

#[derive(Debug, Error, PartialEq)]
pub enum MergeError {
    #[error("nothing to merge")]
    Empty,
    #[error(
        "{name}: in {unit}, other files in {common}; its patches are drawn where their points \
         are and cannot be scaled (put it first)"
    )]
    CannotScale {
        name: String,
        unit: &'static str,
        common: &'static str,
    },
}

/// Metres per unit of the units readers state.
fn metres(unit: &str) -> Option<f64> {
    match unit {
        "m" => Some(1.0),
        "cm" => Some(0.01),
        "mm" => Some(0.001),
        "in" => Some(0.0254),
        "ft" => Some(0.3048),
        _ => None,
    }
}

fn movable(scene: &Scene) -> bool {
    scene
        .patches
        .iter()
        .all(|p| matches!(p.surface, PatchSurface::Trimmed(_)))
}

/// The files' scenes side by side in one (see the module doc). Patches, parts and instances
/// keep the files' order; every instance's name starts with its file's name (`a.step/…`, or
/// just `a.bpt` for a model of one unnamed instance), so `--only a.step` keeps one file.
pub fn merge(files: Vec<Named>) -> Result<Merged, MergeError> {
    let first = files.first().ok_or(MergeError::Empty)?;
    let common = files
        .iter()
        .find(|f| f.scene.unit.is_some() && !movable(&f.scene))
        .or_else(|| files.iter().find(|f| f.scene.unit.is_some()))
        .and_then(|f| f.scene.unit);
    let up = first.scene.up;
    let mut notes = Vec::new();
    let mut out = Scene {
        patches: Vec::new(),
        up,
        bounds: Sphere::EMPTY,
        bbox: (DVec3::ZERO, DVec3::ZERO),
        parts: Vec::new(),
        instances: Vec::new(),
        skipped: Vec::new(),
        warnings: Vec::new(),
        unit: common,
        mesh_groups: Vec::new(),
    };
    let mut boxes = Vec::new();
    for Named { name, scene } in files {
        let factor = match (scene.unit, common) {
            (Some(u), Some(c)) if u != c => match (metres(u), metres(c)) {
                (Some(a), Some(b)) if movable(&scene) => {
                    notes.push(format!("{name}: {u} scaled to {c} (×{})", a / b));
                    a / b
                }
                _ => {
                    return Err(MergeError::CannotScale {
                        name,
                        unit: u,
                        common: c,
                    });
                }
            },
            _ => 1.0,
        };
        let s = DMat4::from_scale(DVec3::splat(factor));
        let (part0, inst0, id0) = (
            out.parts.len() as u32,
            out.instances.len() as u32,
            out.patches.len() as u32,
        );
        for mut part in scene.parts {
            if part.name.is_empty() {
                part.name.clone_from(&name);
            }
            out.parts.push(part);
        }
        for mut inst in scene.instances {
            inst.name = if inst.name.is_empty() {
                name.clone()
            } else {
                format!("{name}/{}", inst.name)
            };
            inst.part += part0;
            inst.transform = s * inst.transform;
            out.instances.push(inst);
        }
        for mut p in scene.patches {
            p.id += id0;
            p.part += part0;
            p.instance += inst0;
            if factor != 1.0 {
                p.transform = s * p.transform;
                p.bounds = Sphere {
                    center: p.bounds.center * factor,
                    radius: p.bounds.radius * factor,
                };
            }
            out.patches.push(p);
        }
        out.skipped.extend(scene.skipped);
        out.warnings
            .extend(scene.warnings.into_iter().map(|w| format!("{name}: {w}")));
        boxes.push((scene.bbox.0 * factor, scene.bbox.1 * factor));
        if scene.up != up {
            notes.push(format!(
                "{name}: its up axis differs from the first file's; placed as written"
            ));
        }
    }
    let spheres: Vec<Sphere> = out.patches.iter().map(|p| p.bounds).collect();
    out.bounds = Sphere::union(&spheres);
    out.bbox = super::box_of(boxes.iter().flat_map(|b| [b.0, b.1])).unwrap_or_default();
    Ok(Merged { scene: out, notes })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{BezierPatch, UpAxis};

    fn square(at: f64) -> Scene {
        let p = |x: f64, y: f64| DVec3::new(at + x, y, 0.0);
        let b = BezierPatch::new(
            1,
            1,
            vec![p(0.0, 0.0), p(0.0, 1.0), p(1.0, 0.0), p(1.0, 1.0)],
        )
        .expect("a bilinear patch");
        Scene::from_bezier(vec![b], UpAxis::Z)
    }

    #[test]
    fn files_become_top_level_parts_side_by_side() {
        let m = merge(vec![
            Named {
                name: "a.bpt".into(),
                scene: square(0.0),
            },
            Named {
                name: "b.bpt".into(),
                scene: square(5.0),
            },
        ])
        .expect("merged");
        let s = m.scene;
        assert_eq!(s.patches.len(), 2);
        assert_eq!(
            (s.patches[1].id, s.patches[1].part, s.patches[1].instance),
            (1, 1, 1)
        );
        assert_eq!(s.parts[1].name, "b.bpt");
        assert_eq!(s.instances[0].name, "a.bpt");
        assert_eq!(s.bbox, (DVec3::ZERO, DVec3::new(6.0, 1.0, 0.0)));
        assert!(s.bounds.radius >= 3.0);
        assert!(m.notes.is_empty());
        assert_eq!(merge(Vec::new()).err(), Some(MergeError::Empty));
    }

    #[test]
    fn a_mesh_in_another_unit_cannot_be_scaled() {
        let mut a = square(0.0);
        a.unit = Some("mm");
        let mut b = square(5.0);
        b.unit = Some("m");
        let err = merge(vec![
            Named {
                name: "a".into(),
                scene: a,
            },
            Named {
                name: "b".into(),
                scene: b,
            },
        ])
        .err();
        // Neither can move: the first unit stated by an immovable file (mm) is common, and
        // b (m) cannot be scaled.
        assert!(
            matches!(err, Some(MergeError::CannotScale { .. })),
            "{err:?}"
        );
    }
}
