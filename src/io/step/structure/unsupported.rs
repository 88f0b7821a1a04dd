//! Geometry a STEP file holds that the geometry reader does not use, counted by entity type
//! so the loader can say what it did not draw: faceted and tessellated B-reps, constructive
//! solids, offset curves, wireframes and point/curve sets, and two types only in the role
//! where the reader meets them.

use std::collections::{HashMap, HashSet};

use crate::io::step::p21::P21File;

/// Entity types, anywhere in the file, that describe geometry to draw but that the STEP
/// geometry reader does not read: faceted and tessellated B-reps, bounded-surface forms other
/// than faces, offset curves (offset surfaces are read: `super::super::offset`), wireframes and point/curve sets, constructive solids.
pub(crate) const UNSUPPORTED_TYPES: &[&str] = &[
    "BLOCK",
    "BOOLEAN_RESULT",
    "BOXED_HALF_SPACE",
    "CSG_SOLID",
    "CURVE_BOUNDED_SURFACE",
    "DEGENERATE_TOROIDAL_SURFACE",
    "EDGE_BASED_WIREFRAME_MODEL",
    "EXTRUDED_AREA_SOLID",
    "EXTRUDED_FACE_SOLID",
    "FACETED_BREP",
    "GEOMETRIC_CURVE_SET",
    "GEOMETRIC_SET",
    "HALF_SPACE_SOLID",
    "OFFSET_CURVE_3D",
    "POLY_LOOP",
    "RECTANGULAR_COMPOSITE_SURFACE",
    "RECTANGULAR_TRIMMED_SURFACE",
    "REVOLVED_AREA_SOLID",
    "REVOLVED_FACE_SOLID",
    "RIGHT_ANGULAR_WEDGE",
    "RIGHT_CIRCULAR_CONE",
    "RIGHT_CIRCULAR_CYLINDER",
    "SHELL_BASED_WIREFRAME_MODEL",
    "SPHERE",
    "SURFACE_CURVE_SWEPT_AREA_SOLID",
    "SWEPT_DISK_SOLID",
    "TORUS",
];

/// Prefixes of unsupported entity types: the tessellated geometry of ISO 10303-42 edition 4
/// (`TESSELLATED_SHELL`, `TRIANGULATED_FACE`, `COMPLEX_TRIANGULATED_SURFACE_SET`, …).
pub(crate) const UNSUPPORTED_PREFIXES: &[&str] =
    &["TESSELLATED_", "TRIANGULATED_", "COMPLEX_TRIANGULATED_"];

/// Counts the unsupported entity types of `file`. Two are counted only in a role where the
/// reader meets them: `VERTEX_LOOP` as the loop of a `FACE_BOUND`/`FACE_OUTER_BOUND` (a degenerate face bound, e.g.
/// at a cone apex), and `TRIMMED_CURVE` as the curve of an `EDGE_CURVE`, directly or as the 3D
/// curve of a `SURFACE_CURVE`/`SEAM_CURVE`/`INTERSECTION_CURVE` (elsewhere, e.g. in a
/// `GEOMETRIC_CURVE_SET`, they are not counted).
pub(super) fn unsupported(file: &P21File) -> Vec<(String, usize)> {
    let mut counts: HashMap<&str, usize> = HashMap::new();
    let mut in_role: HashSet<(&'static str, u64)> = HashSet::new();
    let mut role = |id: Option<u64>, name: &'static str| {
        if let Some(id) = id
            && file.get(id).is_some_and(|e| e.has(name))
        {
            in_role.insert((name, id));
        }
    };
    for e in &file.entities {
        for r in &e.parts {
            let name = r.name.as_str();
            if UNSUPPORTED_TYPES.contains(&name)
                || UNSUPPORTED_PREFIXES.iter().any(|p| name.starts_with(p))
            {
                *counts.entry(name).or_default() += 1;
            }
            match name {
                "FACE_BOUND" | "FACE_OUTER_BOUND" => role(r.ref_at(1), "VERTEX_LOOP"),
                "EDGE_CURVE" => {
                    let curve = r.ref_at(3);
                    role(curve, "TRIMMED_CURVE");
                    let surface_curve = curve.and_then(|c| file.get(c)).and_then(|c| {
                        c.parts.iter().find(|p| {
                            matches!(
                                p.name.as_str(),
                                "SURFACE_CURVE" | "SEAM_CURVE" | "INTERSECTION_CURVE"
                            )
                        })
                    });
                    role(surface_curve.and_then(|s| s.ref_at(1)), "TRIMMED_CURVE");
                }
                _ => {}
            }
        }
    }
    for (name, _) in in_role {
        *counts.entry(name).or_default() += 1;
    }
    let mut list: Vec<(String, usize)> =
        counts.into_iter().map(|(n, c)| (n.to_owned(), c)).collect();
    list.sort();
    list
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::step;

    #[test]
    fn unsupported_geometry_in_role() {
        let s = step(
            "#1=EDGE_CURVE('',#9,#9,#2,.T.);#2=TRIMMED_CURVE('',#9,(),(),.T.,.UNSPECIFIED.);\
             #3=TRIMMED_CURVE('',#9,(),(),.T.,.UNSPECIFIED.);\
             #4=EDGE_CURVE('',#9,#9,#5,.T.);#5=SURFACE_CURVE('',#6,(),.CURVE_3D.);\
             #6=TRIMMED_CURVE('',#9,(),(),.T.,.UNSPECIFIED.);\
             #7=FACE_BOUND('',#8,.T.);#8=VERTEX_LOOP('',#9);#9=VERTEX_POINT('',$);\
             #10=TESSELLATED_SHELL('',(),$);#11=(BOUNDED_CURVE() OFFSET_CURVE_3D('',#9,1.,.F.,#9));",
        );
        assert_eq!(
            s.unsupported,
            [
                ("OFFSET_CURVE_3D".to_owned(), 1),
                ("TESSELLATED_SHELL".to_owned(), 1),
                ("TRIMMED_CURVE".to_owned(), 2),
                ("VERTEX_LOOP".to_owned(), 1),
            ]
        );
    }
}
