//! STEP product structure: which B-rep shells to draw, where, for which part, in which colour,
//! in which length unit, and which geometry the file holds that the reader does not use.
//!
//! Follows the AP203 / AP214 conventions of ISO 10303-203 and -214 (and their AP242 successor)
//! as written down in the CAx-IF *Recommended Practices for AP203/AP214 Assembly Structure*
//! (§2: "Assembly structure", §3: "Transformation of components", both the
//! `REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION` and the `MAPPED_ITEM` forms) and the
//! *Recommended Practices for Model Styling and Organization* (colours through
//! `STYLED_ITEM` → `PRESENTATION_STYLE_ASSIGNMENT` → … → `COLOUR_RGB`). Placements follow
//! ISO 10303-42 (`axis2_placement_3d`, `build_axes`, `cartesian_transformation_operator_3d`).
//!
//! # What [`analyse`] does
//!
//! 1. Representations (any entity with a record `REPRESENTATION` or `…SHAPE_REPRESENTATION`,
//!    except `CONTEXT_DEPENDENT_SHAPE_REPRESENTATION`) and their items: `MANIFOLD_SOLID_BREP`,
//!    `BREP_WITH_VOIDS` (outer and void shells), `SHELL_BASED_SURFACE_MODEL`, bare
//!    `CLOSED_SHELL`/`OPEN_SHELL`, and `MAPPED_ITEM`s. `ORIENTED_CLOSED_SHELL`s are resolved to
//!    the shell they orient (the orientation flag is dropped).
//! 2. Links between representations: relationships without transformation are identity links,
//!    taken as undirected — representations joined by them form one *group* that is placed as a
//!    whole; relationships with transformation place `rep_1` (child) into `rep_2` (parent) by
//!    `M(item_2) · M(item_1)⁻¹` of their `ITEM_DEFINED_TRANSFORMATION` (or by a
//!    `CARTESIAN_TRANSFORMATION_OPERATOR_3D`); a `MAPPED_ITEM` places the mapped representation
//!    by `M(target) · M(origin)⁻¹`.
//! 3. Traversal from the root products (product definitions that are no child of a
//!    `NEXT_ASSEMBLY_USAGE_OCCURRENCE`), or, in a file without products, from the groups that
//!    are no child of any link. One [`ShellInstance`] per shell and path: a part used twice in an
//!    assembly gives two instances. Cycles are cut where they close (with a warning), depth is
//!    capped at `MAX_DEPTH` and the instance count at `MAX_INSTANCES`.
//! 4. Geometry never lost: groups never reached are walked from the identity, then shells in no
//!    representation are placed at the identity, each time with a warning.
//!
//! # Guarantees and limits
//!
//! Never panics; every matrix is finite (unreadable placements become the identity, with a
//! warning). Transforms are rigid when the file's placements are (a
//! `CARTESIAN_TRANSFORMATION_OPERATOR_3D` may scale). Units are not converted: all transforms
//! are in file units and [`Structure::length_unit_mm`] says what one unit is; a file whose
//! representations use different length units gets a warning, not a conversion. Instance
//! names come from `NEXT_ASSEMBLY_USAGE_OCCURRENCE`s (through
//! `CONTEXT_DEPENDENT_SHAPE_REPRESENTATION`) and `MAPPED_ITEM` names. Colours are per styled
//! entity; layers, invisibility and transparency are not read.
//!
//! # Modules
//!
//! `products` (product definitions and their shape representations), `links` (representations,
//! their shells and the relationships and mapped items that place them), `walk` (the traversal
//! of step 3), `placements` (ISO 10303-42 placements as matrices), `styles` (colours),
//! `units` (length and plane-angle units, the distance uncertainty) and `unsupported` (counts
//! of geometry the reader does not use). This module holds the result types and [`analyse`],
//! which runs the steps.

mod links;
mod placements;
mod products;
mod styles;
mod units;
mod unsupported;
mod walk;

use std::collections::{HashMap, HashSet};

use glam::DMat4;

use super::p21::P21File;
use links::Graph;
pub use placements::placement;
use products::Products;
use styles::colours;
use units::{length_unit, plane_angle_unit, uncertainty};
use unsupported::unsupported;
use walk::Walk;

/// Deepest assembly nesting followed (levels of links).
pub(crate) const MAX_DEPTH: usize = 64;

/// Most shell instances produced; a file that would give more is cut with a warning.
pub(crate) const MAX_INSTANCES: usize = 1_000_000;

/// Most representation groups visited in all, so that hostile sharing (each level using the
/// next one twice) cannot make the traversal exponential.
pub(crate) const MAX_VISITS: usize = 2_000_000;

/// Product structure of a STEP file; see the module documentation.
#[derive(Debug, Clone, Default)]
pub struct Structure {
    /// Every placed shell: which shell entity, in which world placement, for which part.
    pub instances: Vec<ShellInstance>,
    /// Parts (products) by index; [`ShellInstance::part`] indexes this. All product
    /// definitions come first, in file order, then one `shell #id` part per shell that belongs
    /// to no product.
    pub parts: Vec<PartInfo>,
    /// Colour of styled items (faces, shells, solids, …) by entity id, RGB in 0..=1 as in the
    /// file (clamped).
    pub colors: HashMap<u64, [f32; 3]>,
    /// Counts of entity types the geometry reader does not use (`UNSUPPORTED_TYPES`,
    /// `UNSUPPORTED_PREFIXES`, `TRIMMED_CURVE` and `VERTEX_LOOP` in the roles `unsupported` looks at), sorted by name.
    pub unsupported: Vec<(String, usize)>,
    /// How many millimetres one file length unit is (`SI_UNIT(.MILLI.,.METRE.)` → 1,
    /// `CONVERSION_BASED_UNIT('INCH', …)` → 25.4), from the contexts of the representations
    /// that hold the shells; `None` if the file does not say.
    pub length_unit_mm: Option<f64>,
    /// How many radians one file plane-angle unit is (`SI_UNIT($,.RADIAN.)` → 1,
    /// `CONVERSION_BASED_UNIT('DEGREE', …)` → π/180); `None` if the file does not say. Angles
    /// in the geometry (a `CONICAL_SURFACE`'s semi-angle) are in this unit.
    pub plane_angle_rad: Option<f64>,
    /// The file's distance uncertainty (`UNCERTAINTY_MEASURE_WITH_UNIT` of a
    /// `GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT`, the largest if several), in file length units: how
    /// far the writer's vertices may lie from their curves and surfaces.
    pub uncertainty: Option<f64>,
    /// `BREP_WITH_VOIDS` solids: their shells (outer and voids) make one solid.
    pub voided_solids: std::collections::HashSet<u64>,
    /// Human-readable notes (e.g. "2 shells not reached from any product; placed at identity").
    pub warnings: Vec<String>,
}

/// One shell placed in the world.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellInstance {
    /// Entity id of the `CLOSED_SHELL` / `OPEN_SHELL`.
    pub shell: u64,
    /// The `MANIFOLD_SOLID_BREP` / `BREP_WITH_VOIDS` / `SHELL_BASED_SURFACE_MODEL` that owns the
    /// shell, for colour lookup.
    pub solid: Option<u64>,
    /// The representation whose items hold the shell (`None` for a shell in no representation).
    pub representation: Option<u64>,
    /// Object → world, in file units.
    pub transform: DMat4,
    /// Index into [`Structure::parts`].
    pub part: usize,
    /// Names of the assembly occurrences (and named mapped items) along the path, joined by
    /// `/`; empty for a shell placed directly.
    pub instance_name: String,
}

/// A part (product).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PartInfo {
    /// `PRODUCT` name, or its id if the name is empty, or `shell #id` for a shell in no product.
    pub name: String,
    /// The `PRODUCT_DEFINITION` entity, if the part is a product.
    pub product_definition: Option<u64>,
}

/// Computes the product structure of a parsed file.
pub fn analyse(file: &P21File) -> Structure {
    let mut warnings = Vec::new();
    let products = Products::read(file);
    let graph = Graph::build(file, &products, &mut warnings);
    let mut walk = Walk {
        parts: products.parts.clone(),
        ..Walk::default()
    };

    // Pass 1: from the root products, or from the root groups when there are none.
    let has_products = !products.parts.is_empty();
    if has_products {
        for &pd in &products.roots {
            let part = products.pd_part.get(&pd).copied();
            for &rep in products.pd_reps.get(&pd).map_or(&[][..], Vec::as_slice) {
                // A group that some link places is left to its parent (or to pass 2), so that
                // it is not also drawn at the identity.
                if let Some(&g) = graph.group_of.get(&rep)
                    && !walk.visited_groups.contains(&g)
                    && !graph.child_groups.contains(&g)
                {
                    walk.walk(&graph, g, DMat4::IDENTITY, part, 0);
                }
            }
        }
    } else {
        for g in 0..graph.groups.len() {
            if !graph.child_groups.contains(&g) && !walk.visited_groups.contains(&g) {
                walk.walk(&graph, g, DMat4::IDENTITY, None, 0);
            }
        }
    }

    // Pass 2: groups not reached, roots first, then any left (children of unreached parents,
    // members of cycles with no way in).
    let before = walk.instances.len();
    // A shell the product structure placed is never drawn again from the identity (OCCT
    // transfers what the products reach): representations left over may repeat it.
    walk.placed = walk.instances.iter().map(|i| i.shell).collect();
    for children_too in [false, true] {
        for g in 0..graph.groups.len() {
            if !walk.visited_groups.contains(&g)
                && (children_too || !graph.child_groups.contains(&g))
            {
                walk.walk(&graph, g, DMat4::IDENTITY, None, 0);
            }
        }
    }
    let unreached = walk.instances.len() - before;
    if walk.repeated > 0 {
        warnings.push(format!(
            "{} shells of representations not reached from any product are placed by the \
             product structure already; not drawn again",
            walk.repeated
        ));
    }
    if unreached > 0 {
        warnings.push(format!(
            "{unreached} shells in representations not reached from any {}; placed from the \
             identity",
            if has_products {
                "product"
            } else {
                "root representation"
            }
        ));
    }

    // Pass 3: shells in no representation.
    let emitted: HashSet<u64> = walk.instances.iter().map(|i| i.shell).collect();
    let mut loose = 0;
    for e in &file.entities {
        if (e.has("CLOSED_SHELL") || e.has("OPEN_SHELL"))
            && !emitted.contains(&e.id)
            && !graph.faceted_shells.contains(&e.id)
        {
            let part = walk.shell_part(e.id);
            walk.instances.push(ShellInstance {
                shell: e.id,
                solid: graph.shell_owner.get(&e.id).copied(),
                representation: None,
                transform: DMat4::IDENTITY,
                part,
                instance_name: String::new(),
            });
            loose += 1;
        }
    }
    if loose > 0 {
        warnings.push(format!(
            "{loose} shells not reached from any product or representation; placed at identity"
        ));
    }

    if walk.cycles > 0 {
        warnings.push(format!(
            "{} cycles in the links between representations were cut",
            walk.cycles
        ));
    }
    if walk.too_deep > 0 {
        warnings.push(format!(
            "{} paths nested deeper than {MAX_DEPTH} levels were cut",
            walk.too_deep
        ));
    }
    if walk.truncated {
        warnings.push(format!(
            "more than {MAX_INSTANCES} shell instances or {MAX_VISITS} representation visits; \
             the traversal was cut"
        ));
    }

    let length_unit_mm = length_unit(file, &graph, &walk.instances, &mut warnings);
    Structure {
        instances: walk.instances,
        parts: walk.parts,
        colors: colours(file),
        unsupported: unsupported(file),
        length_unit_mm,
        plane_angle_rad: plane_angle_unit(file),
        uncertainty: uncertainty(file),
        voided_solids: file
            .entities
            .iter()
            .filter(|e| e.has("BREP_WITH_VOIDS"))
            .map(|e| e.id)
            .collect(),
        warnings,
    }
}

/// Files, fixtures and checks shared by the tests of the structure's modules.
#[cfg(test)]
mod fixtures {
    use glam::{DMat4, DVec3};

    use super::{Structure, analyse};
    use crate::io::step::p21::parse;

    pub(super) const MODELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/models/");

    pub(super) fn model(name: &str) -> Structure {
        let text = std::fs::read_to_string(format!("{MODELS}{name}")).expect("model readable");
        analyse(&parse(&text).expect("model parses"))
    }

    pub(super) fn step(data: &str) -> Structure {
        let text = format!(
            "ISO-10303-21;\nHEADER;\nFILE_SCHEMA(('TEST'));\nENDSEC;\nDATA;\n{data}\nENDSEC;\n\
             END-ISO-10303-21;\n"
        );
        analyse(&parse(&text).expect("test file parses"))
    }

    pub(super) fn assert_close(a: DMat4, b: DMat4) {
        assert!(a.abs_diff_eq(b, 1e-12), "\n{a}\n!=\n{b}");
    }

    pub(super) fn assert_rigid(m: DMat4) {
        let r = glam::DMat3::from_mat4(m);
        assert!(
            (r.transpose() * r).abs_diff_eq(glam::DMat3::IDENTITY, 1e-9),
            "{m}"
        );
        assert!((r.determinant() - 1.0).abs() < 1e-9, "{m}");
        assert_eq!(m.row(3), glam::DVec4::W);
    }

    /// Assembly product #100 (rep #10 with placements #11, #12) uses component #200 (rep #20,
    /// placement #23) twice, by relationships #50 and #60 with item-defined transformations.
    pub(super) const ASSEMBLY: &str = "
        #1=CARTESIAN_POINT('',(0.,0.,0.));
        #2=CARTESIAN_POINT('',(5.,0.,0.));
        #3=CARTESIAN_POINT('',(0.,0.,2.));
        #4=DIRECTION('',(1.,0.,0.));
        #5=DIRECTION('',(0.,1.,0.));
        #6=CARTESIAN_POINT('',(0.,7.,0.));
        #100=PRODUCT_DEFINITION('d','',#101,$);
        #101=PRODUCT_DEFINITION_FORMATION('','',#102);
        #102=PRODUCT('asm-id','',' ',());
        #103=SHAPE_DEFINITION_REPRESENTATION(#104,#10);
        #104=PRODUCT_DEFINITION_SHAPE('','',#100);
        #200=PRODUCT_DEFINITION('d','',#201,$);
        #201=PRODUCT_DEFINITION_FORMATION_WITH_SPECIFIED_SOURCE('','',#202,.MADE.);
        #202=PRODUCT('c','widget','',());
        #203=SHAPE_DEFINITION_REPRESENTATION(#204,#20);
        #204=PRODUCT_DEFINITION_SHAPE('','',#200);
        #10=SHAPE_REPRESENTATION('',(#11,#12,#13),$);
        #11=AXIS2_PLACEMENT_3D('',#1,$,$);
        #12=AXIS2_PLACEMENT_3D('',#2,#4,#5);
        #13=AXIS2_PLACEMENT_3D('',#6,$,$);
        #20=SHAPE_REPRESENTATION('',(#23),$);
        #21=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#24),$);
        #22=SHAPE_REPRESENTATION_RELATIONSHIP('','',#20,#21);
        #23=AXIS2_PLACEMENT_3D('',#3,$,$);
        #24=MANIFOLD_SOLID_BREP('',#25);
        #25=CLOSED_SHELL('',());
        #50=(REPRESENTATION_RELATIONSHIP('','',#20,#10)
             REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION(#51)
             SHAPE_REPRESENTATION_RELATIONSHIP());
        #51=ITEM_DEFINED_TRANSFORMATION('','',#23,#12);
        #52=CONTEXT_DEPENDENT_SHAPE_REPRESENTATION(#50,#53);
        #53=PRODUCT_DEFINITION_SHAPE('','',#54);
        #54=NEXT_ASSEMBLY_USAGE_OCCURRENCE('1','comp_1','',#100,#200,$);
        #60=(REPRESENTATION_RELATIONSHIP('','',#20,#10)
             REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION(#61)
             SHAPE_REPRESENTATION_RELATIONSHIP());
        #61=ITEM_DEFINED_TRANSFORMATION('','',#11,#13);
        #62=CONTEXT_DEPENDENT_SHAPE_REPRESENTATION(#60,#63);
        #63=PRODUCT_DEFINITION_SHAPE('','',#64);
        #64=NEXT_ASSEMBLY_USAGE_OCCURRENCE('2','','',#100,#200,$);";

    /// Both placements of [`ASSEMBLY`], whatever order a writer lists the representations in.
    pub(super) fn assert_assembly_placements(s: &Structure) {
        assert_eq!(s.instances.len(), 2, "{:?}", s.instances);
        let expected = DMat4::from_cols_array(&[
            0.0, 1.0, 0.0, 0.0, //
            0.0, 0.0, 1.0, 0.0, //
            1.0, 0.0, 0.0, 0.0, //
            3.0, 0.0, 0.0, 1.0,
        ]);
        assert_close(s.instances[0].transform, expected);
        assert_close(
            s.instances[1].transform,
            DMat4::from_translation(DVec3::new(0.0, 7.0, 0.0)),
        );
    }
}

#[cfg(test)]
mod tests {
    use glam::{DMat4, DVec3};

    use super::fixtures::{
        ASSEMBLY, MODELS, assert_assembly_placements, assert_close, assert_rigid, model, step,
    };
    use super::links::OwnedShell;
    use super::*;
    use crate::io::step::p21::parse;

    #[test]
    fn as1_assembly_places_every_occurrence() {
        let s = model("as1-oc-214.stp");
        // as1 = rod-assembly (nut ×2, rod) + l-bracket-assembly ×2 (l-bracket +
        // nut-bolt-assembly ×3 (bolt + nut)) + plate: 3 + 2·(1 + 3·2) + 1 = 18.
        assert_eq!(s.instances.len(), 18);
        assert_eq!(s.parts.len(), 9);
        let count = |shell| s.instances.iter().filter(|i| i.shell == shell).count();
        assert_eq!(
            count(64),
            8,
            "nut: 2 in the rod assembly + 2·3 in the bracket assemblies"
        );
        assert_eq!(count(1191), 6, "bolt");
        assert_eq!(count(760), 1, "rod");
        assert_eq!(count(1935), 2, "l-bracket");
        assert_eq!(count(3814), 1, "plate");
        for i in &s.instances {
            assert_rigid(i.transform);
        }
        let nuts: Vec<DMat4> = s
            .instances
            .iter()
            .filter(|i| i.shell == 64)
            .map(|i| i.transform)
            .collect();
        for (a, i) in nuts.iter().enumerate() {
            for j in &nuts[a + 1..] {
                assert!(!i.abs_diff_eq(*j, 1e-6), "two nuts in the same place");
            }
        }
        let nut = s.instances.iter().find(|i| i.shell == 64).expect("a nut");
        assert_eq!(s.parts[nut.part].name, "nut");
        assert_eq!(nut.solid, Some(63));
        assert_eq!(nut.instance_name, "rod-assembly_1/nut_1");
        let names: HashSet<&str> = s
            .instances
            .iter()
            .map(|i| i.instance_name.as_str())
            .collect();
        assert!(names.contains("l-bracket-assembly_2/nut-bolt-assembly_3/bolt_1"));
        assert_eq!(names.len(), 18, "every path has its own name");
        // nut_1: rod-assembly placed by #15 in as1, nut by #45 in rod-assembly.
        let file =
            parse(&std::fs::read_to_string(format!("{MODELS}as1-oc-214.stp")).expect("read"))
                .expect("parses");
        let p = |id| placement(&file, id).expect("placement");
        assert_close(nut.transform, p(15) * p(45));
        assert_eq!(s.length_unit_mm, Some(1.0));
        assert_eq!(s.colors.len(), 5);
        assert_eq!(s.colors.get(&63), Some(&[1.0, 0.0, 0.0]));
        assert_eq!(s.colors.get(&3813), Some(&[0.8, 1.0, 0.0]));
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert!(s.unsupported.is_empty(), "{:?}", s.unsupported);
    }

    #[test]
    fn single_part_files() {
        for (file, shell, product, colours, mm) in [
            ("NIST_MBE_PMI_3.stp", 13, "Document", 0, 25.4),
            ("NIST_MBE_PMI_11.stp", 13, "Document", 0, 1.0),
            (
                "nist_ctc_01_asme1_rd.stp",
                102,
                "nist_ctc_01_asme1_rd",
                101,
                1.0,
            ),
            ("screw.step", 13, "the product name", 0, 1.0),
        ] {
            let s = model(file);
            assert_eq!(s.instances.len(), 1, "{file}");
            let i = &s.instances[0];
            assert_eq!(i.shell, shell, "{file}");
            assert_eq!(i.transform, DMat4::IDENTITY, "{file}");
            assert_eq!(s.parts[i.part].name, product, "{file}");
            assert_eq!(s.parts.len(), 1, "{file}");
            assert_eq!(s.colors.len(), colours, "{file}");
            let unit = s.length_unit_mm.expect("unit");
            assert!((unit - mm).abs() < 1e-12, "{file}: {unit}");
            assert!(s.warnings.is_empty(), "{file}: {:?}", s.warnings);
        }
    }

    #[test]
    fn product_placed_without_occurrence_is_not_drawn_twice() {
        // No NEXT_ASSEMBLY_USAGE_OCCURRENCE, so both products are roots; the component (#200,
        // first in the file) is drawn only where relationship #50 places it.
        let s = step(
            "#200=PRODUCT_DEFINITION('d','',#201,$);#201=PRODUCT_DEFINITION_FORMATION('','',#202);
             #202=PRODUCT('c','widget','',());#203=SHAPE_DEFINITION_REPRESENTATION(#204,#20);
             #204=PRODUCT_DEFINITION_SHAPE('','',#200);
             #20=SHAPE_REPRESENTATION('',(#23,#24),$);#24=MANIFOLD_SOLID_BREP('',#25);
             #25=CLOSED_SHELL('',());#23=AXIS2_PLACEMENT_3D('',#1,$,$);
             #1=CARTESIAN_POINT('',(0.,0.,0.));#2=CARTESIAN_POINT('',(5.,0.,0.));
             #100=PRODUCT_DEFINITION('d','',#101,$);#101=PRODUCT_DEFINITION_FORMATION('','',#102);
             #102=PRODUCT('a','asm','',());#103=SHAPE_DEFINITION_REPRESENTATION(#104,#10);
             #104=PRODUCT_DEFINITION_SHAPE('','',#100);
             #10=SHAPE_REPRESENTATION('',(#12),$);#12=AXIS2_PLACEMENT_3D('',#2,$,$);
             #50=(REPRESENTATION_RELATIONSHIP('','',#20,#10)
                  REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION(#51)
                  SHAPE_REPRESENTATION_RELATIONSHIP());
             #51=ITEM_DEFINED_TRANSFORMATION('','',#23,#12);",
        );
        assert_eq!(s.instances.len(), 1, "{:?}", s.instances);
        let i = &s.instances[0];
        assert_close(
            i.transform,
            DMat4::from_translation(DVec3::new(5.0, 0.0, 0.0)),
        );
        assert_eq!(s.parts[i.part].name, "widget");
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }

    /// A second representation holding the component's solid, reached from no product (some
    /// writers add one): the solid is drawn where the products place it, not also at the
    /// identity.
    #[test]
    fn a_shell_placed_by_the_products_is_not_drawn_again_at_the_identity() {
        let extra =
            format!("{ASSEMBLY}\n        #30=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#24),$);");
        let s = step(&extra);
        assert_assembly_placements(&s);
        assert!(
            s.warnings.iter().any(|w| w.contains("not drawn again")),
            "{:?}",
            s.warnings
        );
    }

    #[test]
    fn unreached_shell_is_placed_at_identity_with_a_warning() {
        let s = step(&format!(
            "{ASSEMBLY}\n#300=CLOSED_SHELL('',());\n#301=OPEN_SHELL('',());"
        ));
        assert_eq!(s.instances.len(), 4);
        for (i, shell) in s.instances[2..].iter().zip([300, 301]) {
            assert_eq!(i.shell, shell);
            assert_eq!(i.transform, DMat4::IDENTITY);
            assert_eq!(s.parts[i.part].name, format!("shell #{shell}"));
        }
        assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
        assert!(
            s.warnings[0].starts_with("2 shells not reached"),
            "{:?}",
            s.warnings
        );
    }

    #[test]
    fn file_with_only_shells_gives_each_once() {
        let s = step(
            "#1=CLOSED_SHELL('',());#2=MANIFOLD_SOLID_BREP('',#1);\
             #3=SHELL_BASED_SURFACE_MODEL('',(#4,#5));#4=OPEN_SHELL('',());\
             #5=ORIENTED_CLOSED_SHELL('',*,#6,.F.);#6=CLOSED_SHELL('',());\
             #7=FACETED_BREP('',#8);#8=CLOSED_SHELL('',());",
        );
        let got: Vec<OwnedShell> = s.instances.iter().map(|i| (i.shell, i.solid)).collect();
        assert_eq!(got, [(1, Some(2)), (4, Some(3)), (6, Some(3))]);
        assert_eq!(s.unsupported, [("FACETED_BREP".to_owned(), 1)]);
    }

    #[test]
    fn analysis_time_of_the_largest_model() {
        let text = std::fs::read_to_string(format!("{MODELS}as1-oc-214.stp")).expect("read");
        let start = std::time::Instant::now();
        let file = parse(&text).expect("parses");
        let parsed = start.elapsed();
        let s = analyse(&file);
        eprintln!(
            "as1-oc-214.stp: parse {parsed:?}, parse + analyse {:?}",
            start.elapsed()
        );
        assert_eq!(s.instances.len(), 18);
    }
}
