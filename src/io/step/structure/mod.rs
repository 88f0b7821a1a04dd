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
//!    capped at [`MAX_DEPTH`] and the instance count at [`MAX_INSTANCES`].
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

use std::collections::{HashMap, HashSet};

use glam::{DMat4, DVec3};

use super::p21::{Entity, P21File, Param, Record};

/// Deepest assembly nesting followed (levels of links).
pub const MAX_DEPTH: usize = 64;

/// Most shell instances produced; a file that would give more is cut with a warning.
pub const MAX_INSTANCES: usize = 1_000_000;

/// Most representation groups visited in all, so that hostile sharing (each level using the
/// next one twice) cannot make the traversal exponential.
pub const MAX_VISITS: usize = 2_000_000;

/// Entity types, anywhere in the file, that describe geometry to draw but that the STEP
/// geometry reader does not read: faceted and tessellated B-reps, bounded-surface forms other
/// than faces, offset geometry, wireframes and point/curve sets, constructive solids.
pub const UNSUPPORTED_TYPES: &[&str] = &[
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
    "OFFSET_SURFACE",
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
pub const UNSUPPORTED_PREFIXES: &[&str] =
    &["TESSELLATED_", "TRIANGULATED_", "COMPLEX_TRIANGULATED_"];

/// Entity types counted as unsupported only in a role where the reader meets them:
/// `VERTEX_LOOP` as the loop of a `FACE_BOUND`/`FACE_OUTER_BOUND` (a degenerate face bound, e.g.
/// at a cone apex), and `TRIMMED_CURVE` as the curve of an `EDGE_CURVE`, directly or as the 3D
/// curve of a `SURFACE_CURVE`/`SEAM_CURVE`/`INTERSECTION_CURVE` (elsewhere, e.g. in a
/// `GEOMETRIC_CURVE_SET`, they are not counted).
pub const UNSUPPORTED_IN_ROLE: &[&str] = &["TRIMMED_CURVE", "VERTEX_LOOP"];

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
    /// Counts of entity types the geometry reader does not use ([`UNSUPPORTED_TYPES`],
    /// [`UNSUPPORTED_PREFIXES`], [`UNSUPPORTED_IN_ROLE`]), sorted by name.
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
        warnings,
    }
}

// ---------------------------------------------------------------------------------------------
// Products

/// Products, their representations and the assembly tree's roots.
#[derive(Debug, Default)]
struct Products {
    parts: Vec<PartInfo>,
    /// `PRODUCT_DEFINITION` → part index.
    pd_part: HashMap<u64, usize>,
    /// `PRODUCT_DEFINITION` → its shape representations (through `SHAPE_DEFINITION_REPRESENTATION`).
    pd_reps: HashMap<u64, Vec<u64>>,
    /// Representation → part index.
    rep_part: HashMap<u64, usize>,
    /// Product definitions that are the child of no `NEXT_ASSEMBLY_USAGE_OCCURRENCE`.
    roots: Vec<u64>,
}

fn is_product_definition(name: &str) -> bool {
    name == "PRODUCT_DEFINITION" || name == "PRODUCT_DEFINITION_WITH_ASSOCIATED_DOCUMENTS"
}

impl Products {
    fn read(file: &P21File) -> Self {
        let mut p = Products::default();
        let mut children = HashSet::new();
        for e in &file.entities {
            if let Some(pd) = e.parts.iter().find(|r| is_product_definition(&r.name)) {
                let name = product_name(file, pd).unwrap_or_else(|| format!("product #{}", e.id));
                p.pd_part.insert(e.id, p.parts.len());
                p.parts.push(PartInfo {
                    name,
                    product_definition: Some(e.id),
                });
            } else if let Some(nauo) = e.part("NEXT_ASSEMBLY_USAGE_OCCURRENCE")
                && let Some(child) = nauo.ref_at(4)
            {
                children.insert(child);
            }
        }
        for e in &file.entities {
            let Some(sdr) = e.part("SHAPE_DEFINITION_REPRESENTATION") else {
                continue;
            };
            let (Some(pds), Some(rep)) = (sdr.ref_at(0), sdr.ref_at(1)) else {
                continue;
            };
            let Some(pd) = file
                .get(pds)
                .and_then(|e| e.part("PRODUCT_DEFINITION_SHAPE"))
                .and_then(|r| r.ref_at(2))
            else {
                continue;
            };
            if let Some(&part) = p.pd_part.get(&pd) {
                p.pd_reps.entry(pd).or_default().push(rep);
                p.rep_part.entry(rep).or_insert(part);
            }
        }
        p.roots = p
            .parts
            .iter()
            .filter_map(|part| part.product_definition)
            .filter(|pd| !children.contains(pd))
            .collect();
        p
    }
}

/// `PRODUCT_DEFINITION` → formation → `PRODUCT(id, name, …)`: the name, or the id if the name
/// is blank.
fn product_name(file: &P21File, pd: &Record) -> Option<String> {
    let formation = file.get(pd.ref_at(2)?)?;
    let formation = formation
        .parts
        .iter()
        .find(|r| r.name.starts_with("PRODUCT_DEFINITION_FORMATION"))?;
    let product = file.get(formation.ref_at(2)?)?.part("PRODUCT")?;
    [product.str_at(1), product.str_at(0)]
        .into_iter()
        .flatten()
        .map(str::trim)
        .find(|s| !s.is_empty())
        .map(str::to_owned)
}

// ---------------------------------------------------------------------------------------------
// Representations and the links between them

/// A shell and the solid or surface model that owns it.
type OwnedShell = (u64, Option<u64>);

/// A placed child group.
#[derive(Debug, Clone)]
struct Link {
    child: usize,
    /// Child → parent.
    transform: DMat4,
    /// Occurrence name for [`ShellInstance::instance_name`] (may be empty).
    name: String,
    /// The part of the occurrence (`NEXT_ASSEMBLY_USAGE_OCCURRENCE` child), if known.
    part: Option<usize>,
}

/// Representations joined by identity links, placed as a whole.
#[derive(Debug, Default)]
struct Group {
    /// Member representations with the shells they hold: (rep, [(shell, solid)]).
    members: Vec<(u64, Vec<OwnedShell>)>,
    links: Vec<Link>,
}

#[derive(Debug, Default)]
struct Graph {
    groups: Vec<Group>,
    group_of: HashMap<u64, usize>,
    /// Groups that are the child of some link.
    child_groups: HashSet<usize>,
    /// Representation → part (from products).
    rep_part: HashMap<u64, usize>,
    /// Representation → its context.
    rep_context: HashMap<u64, u64>,
    /// Shell → owning solid / surface model.
    shell_owner: HashMap<u64, u64>,
    /// Shells owned by a `FACETED_BREP` (not drawn, not placed as loose shells).
    faceted_shells: HashSet<u64>,
}

/// The record that makes `e` a representation `(name, (items…), context)`.
fn rep_record(e: &Entity) -> Option<&Record> {
    e.parts.iter().find(|r| {
        (r.name == "REPRESENTATION"
            || (r.name.ends_with("SHAPE_REPRESENTATION")
                && r.name != "CONTEXT_DEPENDENT_SHAPE_REPRESENTATION"))
            && r.list_at(1).is_some()
    })
}

/// `CLOSED_SHELL`/`OPEN_SHELL` `id`, or the shell an `ORIENTED_…_SHELL` orients.
fn resolve_shell(file: &P21File, mut id: u64) -> Option<u64> {
    for _ in 0..4 {
        let e = file.get(id)?;
        if let Some(oriented) = e
            .parts
            .iter()
            .find(|r| r.name == "ORIENTED_CLOSED_SHELL" || r.name == "ORIENTED_OPEN_SHELL")
        {
            id = oriented.ref_at(2)?;
        } else if e.has("CLOSED_SHELL") || e.has("OPEN_SHELL") {
            return Some(id);
        } else {
            return None;
        }
    }
    None
}

/// Shells held by a representation item (with the item as owner when it is a solid or surface
/// model).
fn item_shells(file: &P21File, id: u64) -> Vec<OwnedShell> {
    let Some(e) = file.get(id) else {
        return Vec::new();
    };
    let refs: Vec<u64> = if let Some(r) = e.part("BREP_WITH_VOIDS") {
        let mut v: Vec<u64> = r.ref_at(1).into_iter().collect();
        v.extend(
            r.list_at(2)
                .unwrap_or_default()
                .iter()
                .filter_map(Param::as_ref),
        );
        v
    } else if let Some(r) = e.part("MANIFOLD_SOLID_BREP") {
        r.ref_at(1).into_iter().collect()
    } else if let Some(r) = e.part("SHELL_BASED_SURFACE_MODEL") {
        r.list_at(1)
            .unwrap_or_default()
            .iter()
            .filter_map(Param::as_ref)
            .collect()
    } else {
        return resolve_shell(file, id)
            .map(|s| (s, None))
            .into_iter()
            .collect();
    };
    refs.into_iter()
        .filter_map(|r| resolve_shell(file, r))
        .map(|s| (s, Some(id)))
        .collect()
}

/// Reports unreadable placements once each.
#[derive(Debug, Default)]
struct PlacementLog {
    bad: Vec<u64>,
}

impl PlacementLog {
    /// The matrix of placement `id`, or the identity (logged) if it cannot be read.
    fn matrix(&mut self, file: &P21File, id: Option<u64>) -> DMat4 {
        match id.and_then(|id| placement(file, id)) {
            Some(m) => m,
            None => {
                self.bad.push(id.unwrap_or(0));
                DMat4::IDENTITY
            }
        }
    }

    /// `M(to) · M(from)⁻¹`.
    fn between(&mut self, file: &P21File, from: Option<u64>, to: Option<u64>) -> DMat4 {
        let from_m = self.matrix(file, from);
        let to_m = self.matrix(file, to);
        match inverse(from_m) {
            Some(inv) => to_m * inv,
            None => {
                self.bad.push(from.unwrap_or(0));
                to_m
            }
        }
    }
}

impl Graph {
    fn build(file: &P21File, products: &Products, warnings: &mut Vec<String>) -> Self {
        let mut g = Graph {
            rep_part: products.rep_part.clone(),
            ..Graph::default()
        };
        let mut log = PlacementLog::default();

        // Representations, in file order, with their shells and mapped items.
        let mut reps: Vec<u64> = Vec::new();
        let mut rep_shells: HashMap<u64, Vec<OwnedShell>> = HashMap::new();
        // (parent rep, child rep, transform, name, part)
        let mut directed: Vec<(u64, u64, DMat4, String, Option<usize>)> = Vec::new();
        let mut identity: HashMap<u64, Vec<u64>> = HashMap::new();
        for e in &file.entities {
            if let Some(r) = rep_record(e) {
                reps.push(e.id);
                if let Some(ctx) = r.ref_at(2) {
                    g.rep_context.insert(e.id, ctx);
                }
                let mut shells = Vec::new();
                for item in r
                    .list_at(1)
                    .unwrap_or_default()
                    .iter()
                    .filter_map(Param::as_ref)
                {
                    if let Some(mapped) = file.get(item).and_then(|i| i.part("MAPPED_ITEM")) {
                        let map = mapped.ref_at(1).and_then(|m| file.get(m));
                        let map = map.and_then(|m| m.part("REPRESENTATION_MAP"));
                        let Some(child) = map.and_then(|m| m.ref_at(1)) else {
                            warnings.push(format!(
                                "mapped item #{item} has no readable REPRESENTATION_MAP; skipped"
                            ));
                            continue;
                        };
                        let origin = map.and_then(|m| m.ref_at(0));
                        let m = log.between(file, origin, mapped.ref_at(2));
                        let name = mapped.str_at(0).unwrap_or("").trim().to_owned();
                        directed.push((e.id, child, m, name, None));
                    } else {
                        for s in item_shells(file, item) {
                            if !shells.contains(&s) {
                                shells.push(s);
                            }
                        }
                    }
                }
                rep_shells.insert(e.id, shells);
            }
            if e.has("MANIFOLD_SOLID_BREP")
                || e.has("BREP_WITH_VOIDS")
                || e.has("SHELL_BASED_SURFACE_MODEL")
            {
                for (s, owner) in item_shells(file, e.id) {
                    if let Some(o) = owner {
                        g.shell_owner.entry(s).or_insert(o);
                    }
                }
            } else if let Some(r) = e.part("FACETED_BREP")
                && let Some(s) = r.ref_at(1)
            {
                g.faceted_shells.insert(s);
            }
        }

        // Occurrence (NAUO) of each relationship, through CONTEXT_DEPENDENT_SHAPE_REPRESENTATION.
        let mut rel_occurrence: HashMap<u64, (String, Option<usize>)> = HashMap::new();
        for e in &file.entities {
            let Some(cdsr) = e.part("CONTEXT_DEPENDENT_SHAPE_REPRESENTATION") else {
                continue;
            };
            let nauo = cdsr
                .ref_at(1)
                .and_then(|pds| file.get(pds))
                .and_then(|pds| pds.part("PRODUCT_DEFINITION_SHAPE"))
                .and_then(|pds| pds.ref_at(2))
                .and_then(|n| file.get(n))
                .and_then(|n| n.part("NEXT_ASSEMBLY_USAGE_OCCURRENCE"));
            if let (Some(rel), Some(nauo)) = (cdsr.ref_at(0), nauo) {
                let name = [nauo.str_at(1), nauo.str_at(0)]
                    .into_iter()
                    .flatten()
                    .map(str::trim)
                    .find(|s| !s.is_empty())
                    .unwrap_or("")
                    .to_owned();
                let part = nauo
                    .ref_at(4)
                    .and_then(|pd| products.pd_part.get(&pd).copied());
                rel_occurrence.insert(rel, (name, part));
            }
        }

        // Relationships between representations.
        let mut reversed = 0;
        for e in &file.entities {
            let Some(rel) = e.parts.iter().find(|r| {
                r.name.contains("REPRESENTATION_RELATIONSHIP")
                    && r.ref_at(2).is_some()
                    && r.ref_at(3).is_some()
            }) else {
                continue;
            };
            let (Some(rep1), Some(rep2)) = (rel.ref_at(2), rel.ref_at(3)) else {
                continue;
            };
            if !rep_shells.contains_key(&rep1) || !rep_shells.contains_key(&rep2) {
                continue;
            }
            let with_transformation = e
                .parts
                .iter()
                .find(|r| r.name.ends_with("RELATIONSHIP_WITH_TRANSFORMATION"));
            match with_transformation {
                None => {
                    identity.entry(rep1).or_default().push(rep2);
                    identity.entry(rep2).or_default().push(rep1);
                }
                Some(t) => {
                    let t = t.args.last().and_then(Param::as_ref);
                    let m = transformation(file, t, &mut log);
                    let (name, part) = rel_occurrence.get(&e.id).cloned().unwrap_or_default();
                    // Some writers swap rep_1 and rep_2: the occurrence's child product says
                    // which representation is the component's (OCCT's
                    // `STEPConstruct_Assembly::CheckSRRReversesNAUO`); the transformation then
                    // maps rep_2 into rep_1 and is inverted.
                    let is_child =
                        |rep: u64| part.is_some() && g.rep_part.get(&rep) == part.as_ref();
                    if !is_child(rep1) && is_child(rep2) {
                        let inverted = inverse(m).unwrap_or_else(|| {
                            log.bad.push(e.id);
                            DMat4::IDENTITY
                        });
                        reversed += 1;
                        directed.push((rep1, rep2, inverted, name, part));
                    } else {
                        directed.push((rep2, rep1, m, name, part));
                    }
                }
            }
        }

        if reversed > 0 {
            warnings.push(format!(
                "{reversed} assembly relationships list the parent before the component \
                 (rep_1/rep_2 swapped); read as their occurrence says"
            ));
        }

        // Groups: connected components of the identity links, members in file order.
        for &rep in &reps {
            if g.group_of.contains_key(&rep) {
                continue;
            }
            let index = g.groups.len();
            let mut members = vec![rep];
            g.group_of.insert(rep, index);
            let mut k = 0;
            while let Some(&m) = members.get(k) {
                k += 1;
                for &other in identity.get(&m).map_or(&[][..], Vec::as_slice) {
                    if let std::collections::hash_map::Entry::Vacant(v) = g.group_of.entry(other) {
                        v.insert(index);
                        members.push(other);
                    }
                }
            }
            g.groups.push(Group {
                members: members
                    .into_iter()
                    .map(|m| (m, rep_shells.remove(&m).unwrap_or_default()))
                    .collect(),
                links: Vec::new(),
            });
        }
        for (parent, child, transform, name, part) in directed {
            let (Some(&pg), Some(&cg)) = (g.group_of.get(&parent), g.group_of.get(&child)) else {
                if !g.group_of.contains_key(&child) {
                    warnings.push(format!(
                        "#{child} is placed as a representation but is not one; skipped"
                    ));
                }
                continue;
            };
            g.child_groups.insert(cg);
            if let Some(group) = g.groups.get_mut(pg) {
                group.links.push(Link {
                    child: cg,
                    transform,
                    name,
                    part,
                });
            }
        }

        if !log.bad.is_empty() {
            log.bad.sort_unstable();
            log.bad.dedup();
            let list: Vec<String> = log.bad.iter().take(8).map(|id| format!("#{id}")).collect();
            warnings.push(format!(
                "{} placements or transformations could not be read ({}{}); identity used",
                log.bad.len(),
                list.join(", "),
                if log.bad.len() > 8 { ", …" } else { "" }
            ));
        }
        g
    }
}

/// Child → parent matrix of the transformation of a relationship.
fn transformation(file: &P21File, id: Option<u64>, log: &mut PlacementLog) -> DMat4 {
    let Some(e) = id.and_then(|id| file.get(id)) else {
        return log.matrix(file, None);
    };
    if let Some(idt) = e.part("ITEM_DEFINED_TRANSFORMATION") {
        log.between(file, idt.ref_at(2), idt.ref_at(3))
    } else {
        log.matrix(file, Some(e.id))
    }
}

// ---------------------------------------------------------------------------------------------
// Traversal

#[derive(Debug, Default)]
struct Walk {
    instances: Vec<ShellInstance>,
    parts: Vec<PartInfo>,
    /// Product-less shell → its `shell #id` part.
    shell_parts: HashMap<u64, usize>,
    visited_groups: HashSet<usize>,
    /// Shells placed from the products (pass 1): not emitted again by later passes.
    placed: HashSet<u64>,
    /// Shells skipped because of `placed`.
    repeated: usize,
    on_path: Vec<usize>,
    names: Vec<String>,
    cycles: usize,
    too_deep: usize,
    visits: usize,
    truncated: bool,
}

impl Walk {
    fn walk(
        &mut self,
        graph: &Graph,
        group: usize,
        transform: DMat4,
        part: Option<usize>,
        depth: usize,
    ) {
        if self.on_path.contains(&group) {
            self.cycles += 1;
            return;
        }
        if depth > MAX_DEPTH {
            self.too_deep += 1;
            return;
        }
        if self.visits >= MAX_VISITS {
            self.truncated = true;
            return;
        }
        self.visits += 1;
        let Some(g) = graph.groups.get(group) else {
            return;
        };
        self.visited_groups.insert(group);
        self.on_path.push(group);

        // The group's part: its first member with a product, else what the caller passed.
        let group_part = g
            .members
            .iter()
            .find_map(|(rep, _)| graph.rep_part.get(rep).copied())
            .or(part);
        let name = self
            .names
            .iter()
            .filter(|n| !n.is_empty())
            .cloned()
            .collect::<Vec<_>>()
            .join("/");
        for (rep, shells) in &g.members {
            let rep_part = graph.rep_part.get(rep).copied().or(group_part);
            for &(shell, solid) in shells {
                if self.placed.contains(&shell) {
                    self.repeated += 1;
                    continue;
                }
                if self.instances.len() >= MAX_INSTANCES {
                    self.truncated = true;
                    break;
                }
                let part = match rep_part {
                    Some(p) => p,
                    None => self.shell_part(shell),
                };
                self.instances.push(ShellInstance {
                    shell,
                    solid,
                    representation: Some(*rep),
                    transform,
                    part,
                    instance_name: name.clone(),
                });
            }
        }
        for link in &g.links {
            if self.truncated {
                break;
            }
            self.names.push(link.name.clone());
            self.walk(
                graph,
                link.child,
                transform * link.transform,
                link.part.or(group_part),
                depth + 1,
            );
            self.names.pop();
        }
        self.on_path.pop();
    }

    /// The `shell #id` part of a shell that belongs to no product.
    fn shell_part(&mut self, shell: u64) -> usize {
        let next = self.parts.len();
        let index = *self.shell_parts.entry(shell).or_insert(next);
        if index == next {
            self.parts.push(PartInfo {
                name: format!("shell #{shell}"),
                product_definition: None,
            });
        }
        index
    }
}

// ---------------------------------------------------------------------------------------------
// Placements

/// A point or direction `(name, (x, y[, z]))` as a vector; `None` if not finite.
fn vector(file: &P21File, id: u64, record: &str) -> Option<DVec3> {
    let r = file.get(id)?.part(record)?;
    let c = r.list_at(1)?;
    let x = c.first()?.as_f64()?;
    let y = c.get(1)?.as_f64()?;
    let z = c.get(2).and_then(Param::as_f64).unwrap_or(0.0);
    let v = DVec3::new(x, y, z);
    v.is_finite().then_some(v)
}

/// Optional direction attribute: `Some(None)` for `$` or an unreadable direction.
fn direction(file: &P21File, r: &Record, i: usize) -> Option<DVec3> {
    r.ref_at(i)
        .and_then(|id| vector(file, id, "DIRECTION"))
        .and_then(|d| d.try_normalize())
}

/// A unit vector perpendicular to `z` (unit), as close to `hint` as possible.
fn perpendicular(z: DVec3, hint: Option<DVec3>) -> DVec3 {
    let project = |v: DVec3| (v - v.dot(z) * z).try_normalize();
    hint.and_then(project)
        .or_else(|| project(DVec3::X))
        .or_else(|| project(DVec3::Y))
        .unwrap_or(DVec3::X)
}

/// Object → parent matrix of an `AXIS2_PLACEMENT_3D` or `CARTESIAN_TRANSFORMATION_OPERATOR_3D`.
pub fn placement(file: &P21File, id: u64) -> Option<DMat4> {
    let e = file.get(id)?;
    let m = if let Some(r) = e.part("AXIS2_PLACEMENT_3D") {
        let origin = vector(file, r.ref_at(1)?, "CARTESIAN_POINT")?;
        let z = direction(file, r, 2).unwrap_or(DVec3::Z);
        let x = perpendicular(z, direction(file, r, 3));
        let y = z.cross(x);
        DMat4::from_cols(
            x.extend(0.0),
            y.extend(0.0),
            z.extend(0.0),
            origin.extend(1.0),
        )
    } else if let Some(r) = e
        .parts
        .iter()
        .find(|r| r.name == "CARTESIAN_TRANSFORMATION_OPERATOR_3D")
    {
        // (name, [description,] axis1, axis2, local_origin, scale, axis3)
        let k = if r.args.len() >= 7 { 1 } else { 0 };
        let origin = vector(file, r.ref_at(k + 3)?, "CARTESIAN_POINT")?;
        let scale = r.f64_at(k + 4).unwrap_or(1.0);
        let scale = if scale.is_finite() && scale > 0.0 {
            scale
        } else {
            1.0
        };
        let z = direction(file, r, k + 5).unwrap_or(DVec3::Z);
        let x = perpendicular(z, direction(file, r, k + 1));
        let y_hint = direction(file, r, k + 2).unwrap_or_else(|| z.cross(x));
        let y = (y_hint - y_hint.dot(z) * z - y_hint.dot(x) * x)
            .try_normalize()
            .unwrap_or_else(|| z.cross(x));
        DMat4::from_cols(
            (x * scale).extend(0.0),
            (y * scale).extend(0.0),
            (z * scale).extend(0.0),
            origin.extend(1.0),
        )
    } else {
        return None;
    };
    m.is_finite().then_some(m)
}

/// Inverse of an affine matrix, if it is safely invertible.
fn inverse(m: DMat4) -> Option<DMat4> {
    let det = m.determinant();
    if !det.is_finite() || det.abs() < 1e-12 {
        return None;
    }
    let inv = m.inverse();
    inv.is_finite().then_some(inv)
}

// ---------------------------------------------------------------------------------------------
// Colours

/// Colours of `STYLED_ITEM`s, then `OVER_RIDING_STYLED_ITEM`s on top.
fn colours(file: &P21File) -> HashMap<u64, [f32; 3]> {
    let mut colours = HashMap::new();
    for overriding in [false, true] {
        for e in &file.entities {
            let Some(r) = e.parts.iter().find(|r| {
                let is_override = r.name == "OVER_RIDING_STYLED_ITEM"
                    || r.name == "CONTEXT_DEPENDENT_OVER_RIDING_STYLED_ITEM";
                (is_override || r.name == "STYLED_ITEM") && is_override == overriding
            }) else {
                continue;
            };
            // Complex instances carry the attributes on the STYLED_ITEM record.
            let r = e
                .parts
                .iter()
                .find(|r| r.list_at(1).is_some() && r.ref_at(2).is_some())
                .unwrap_or(r);
            let (Some(styles), Some(item)) = (r.list_at(1), r.ref_at(2)) else {
                continue;
            };
            if let Some(c) = style_colour(file, styles) {
                colours.insert(item, c);
            }
        }
    }
    colours
}

/// Most entities visited when looking for the colour of one styled item.
const STYLE_BUDGET: usize = 256;

/// The colour a list of presentation styles gives: the first surface colour found, else the
/// first other (curve, point, text) colour.
fn style_colour(file: &P21File, styles: &[Param]) -> Option<[f32; 3]> {
    let mut stack: Vec<(u64, usize, bool)> = Vec::new();
    push_refs(styles, 0, false, &mut stack);
    let mut seen = HashSet::new();
    let mut other = None;
    while let Some((id, depth, surface)) = stack.pop() {
        if seen.len() >= STYLE_BUDGET || !seen.insert((id, surface)) {
            continue;
        }
        let Some(e) = file.get(id) else {
            continue;
        };
        if let Some(c) = colour_value(e) {
            if surface {
                return Some(c);
            }
            other.get_or_insert(c);
            continue;
        }
        // Only styles and colours are followed, never back into geometry or representations.
        if depth >= 12
            || !e
                .parts
                .iter()
                .any(|r| r.name.contains("STYLE") || r.name.contains("COLOUR"))
        {
            continue;
        }
        let surface = surface
            || e.parts.iter().any(|r| {
                r.name.starts_with("SURFACE_STYLE")
                    || r.name == "SURFACE_SIDE_STYLE"
                    || r.name.starts_with("FILL_AREA_STYLE")
            });
        for r in e.parts.iter().rev() {
            push_refs(&r.args, depth + 1, surface, &mut stack);
        }
    }
    other
}

/// Pushes the references in `params` (and nested lists) so that the first is popped first.
fn push_refs(params: &[Param], depth: usize, surface: bool, stack: &mut Vec<(u64, usize, bool)>) {
    for p in params.iter().rev() {
        match p {
            Param::Ref(id) => stack.push((*id, depth, surface)),
            Param::List(items) => push_refs(items, depth, surface, stack),
            Param::Typed(_, inner) => push_refs(std::slice::from_ref(inner), depth, surface, stack),
            _ => {}
        }
    }
}

/// The RGB of a `COLOUR_RGB` or `DRAUGHTING_PRE_DEFINED_COLOUR` entity.
fn colour_value(e: &Entity) -> Option<[f32; 3]> {
    if let Some(r) = e.part("COLOUR_RGB") {
        let k = if r.args.len() >= 4 { 1 } else { 0 };
        let mut c = [0.0f32; 3];
        for (i, v) in c.iter_mut().enumerate() {
            let x = r.f64_at(k + i)?;
            if !x.is_finite() {
                return None;
            }
            *v = x.clamp(0.0, 1.0) as f32;
        }
        return Some(c);
    }
    let r = e.part("DRAUGHTING_PRE_DEFINED_COLOUR")?;
    let name = r.str_at(0)?.trim().to_ascii_lowercase();
    Some(match name.as_str() {
        "red" => [1.0, 0.0, 0.0],
        "green" => [0.0, 1.0, 0.0],
        "blue" => [0.0, 0.0, 1.0],
        "yellow" => [1.0, 1.0, 0.0],
        "magenta" => [1.0, 0.0, 1.0],
        "cyan" => [0.0, 1.0, 1.0],
        "black" => [0.0, 0.0, 0.0],
        "white" => [1.0, 1.0, 1.0],
        _ => return None,
    })
}

// ---------------------------------------------------------------------------------------------
// Unsupported geometry

fn unsupported(file: &P21File) -> Vec<(String, usize)> {
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

// ---------------------------------------------------------------------------------------------
// Units

/// Millimetres per file length unit, from the contexts of the representations holding the
/// placed shells (or, if they name none, of any context in the file).
fn length_unit(
    file: &P21File,
    graph: &Graph,
    instances: &[ShellInstance],
    warnings: &mut Vec<String>,
) -> Option<f64> {
    let mut contexts: Vec<u64> = Vec::new();
    for i in instances {
        if let Some(&ctx) = i.representation.and_then(|r| graph.rep_context.get(&r))
            && !contexts.contains(&ctx)
        {
            contexts.push(ctx);
        }
    }
    let mut units = distinct_length_units(file, &contexts);
    if units.is_empty() {
        let all: Vec<u64> = file
            .entities
            .iter()
            .filter(|e| e.has("GLOBAL_UNIT_ASSIGNED_CONTEXT"))
            .map(|e| e.id)
            .collect();
        units = distinct_length_units(file, &all);
    }
    if units.len() > 1 {
        let list: Vec<String> = units.iter().map(|u| format!("{u} mm")).collect();
        warnings.push(format!(
            "representations use different length units ({}); not converted, {} assumed",
            list.join(", "),
            list.first().map_or("", String::as_str)
        ));
    }
    units.first().copied()
}

/// The different length units (in mm) of `contexts`, in order of first use.
fn distinct_length_units(file: &P21File, contexts: &[u64]) -> Vec<f64> {
    let mut units: Vec<f64> = Vec::new();
    for &ctx in contexts {
        if let Some(mm) = context_length_mm(file, ctx)
            && !units.iter().any(|u| (u - mm).abs() <= 1e-9 * mm)
        {
            units.push(mm);
        }
    }
    units
}

fn context_length_mm(file: &P21File, ctx: u64) -> Option<f64> {
    let units = file
        .get(ctx)?
        .part("GLOBAL_UNIT_ASSIGNED_CONTEXT")?
        .list_at(0)?;
    units
        .iter()
        .filter_map(Param::as_ref)
        .find_map(|u| unit_mm(file, u, 0))
}

/// What a unit measures: its SI name, the record that marks a conversion-based unit of that
/// kind, and what one SI unit is in the scale wanted.
type UnitKind = (&'static str, &'static str, f64);
/// Lengths in millimetres.
const LENGTH_MM: UnitKind = ("METRE", "LENGTH_UNIT", 1000.0);
/// Plane angles in radians.
const ANGLE_RAD: UnitKind = ("RADIAN", "PLANE_ANGLE_UNIT", 1.0);

/// Millimetres in length unit `id` (`None` if it is not a length unit).
fn unit_mm(file: &P21File, id: u64, depth: usize) -> Option<f64> {
    unit_value(file, id, LENGTH_MM, depth)
}

/// One unit `id` of `kind` in `kind`'s scale (`None` if it is not such a unit): an `SI_UNIT`
/// with its prefix, or a `CONVERSION_BASED_UNIT` through its measure.
fn unit_value(file: &P21File, id: u64, kind: UnitKind, depth: usize) -> Option<f64> {
    let (si_name, marker, si_scale) = kind;
    if depth > 8 {
        return None;
    }
    let e = file.get(id)?;
    let value = if let Some(si) = e.part("SI_UNIT") {
        // Complex form SI_UNIT(prefix, name); simple form SI_UNIT(dimensions, prefix, name).
        let n = si.args.len();
        if n < 2 || si.args.get(n - 1)?.as_enum()? != si_name {
            return None;
        }
        let prefix = match si.args.get(n - 2)?.as_enum() {
            None => 1.0,
            Some(p) => si_prefix(p)?,
        };
        si_scale * prefix
    } else if let Some(cbu) = e.part("CONVERSION_BASED_UNIT") {
        if !e.has(marker) {
            return None;
        }
        let factor = file.get(cbu.ref_at(1)?)?;
        let measure = factor
            .parts
            .iter()
            .find(|r| r.f64_at(0).is_some() && r.ref_at(1).is_some())?;
        measure.f64_at(0)? * unit_value(file, measure.ref_at(1)?, kind, depth + 1)?
    } else {
        return None;
    };
    (value.is_finite() && value > 0.0).then_some(value)
}

/// Radians in the plane-angle unit of the first context that names one.
fn plane_angle_unit(file: &P21File) -> Option<f64> {
    file.entities
        .iter()
        .filter_map(|e| e.part("GLOBAL_UNIT_ASSIGNED_CONTEXT"))
        .filter_map(|r| r.list_at(0))
        .flat_map(|units| units.iter().filter_map(Param::as_ref))
        .find_map(|u| unit_value(file, u, ANGLE_RAD, 0))
}

/// The largest distance uncertainty any context declares (file length units).
fn uncertainty(file: &P21File) -> Option<f64> {
    file.entities
        .iter()
        .filter_map(|e| e.part("UNCERTAINTY_MEASURE_WITH_UNIT"))
        .filter_map(|r| r.f64_at(0))
        .filter(|u| u.is_finite() && *u > 0.0)
        .reduce(f64::max)
}

fn si_prefix(p: &str) -> Option<f64> {
    Some(match p {
        "EXA" => 1e18,
        "PETA" => 1e15,
        "TERA" => 1e12,
        "GIGA" => 1e9,
        "MEGA" => 1e6,
        "KILO" => 1e3,
        "HECTO" => 1e2,
        "DECA" => 1e1,
        "DECI" => 1e-1,
        "CENTI" => 1e-2,
        "MILLI" => 1e-3,
        "MICRO" => 1e-6,
        "NANO" => 1e-9,
        "PICO" => 1e-12,
        "FEMTO" => 1e-15,
        "ATTO" => 1e-18,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::step::p21::parse;

    const MODELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/models/");

    fn model(name: &str) -> Structure {
        let text = std::fs::read_to_string(format!("{MODELS}{name}")).expect("model readable");
        analyse(&parse(&text).expect("model parses"))
    }

    fn step(data: &str) -> Structure {
        let text = format!(
            "ISO-10303-21;\nHEADER;\nFILE_SCHEMA(('TEST'));\nENDSEC;\nDATA;\n{data}\nENDSEC;\n\
             END-ISO-10303-21;\n"
        );
        analyse(&parse(&text).expect("test file parses"))
    }

    fn assert_close(a: DMat4, b: DMat4) {
        assert!(a.abs_diff_eq(b, 1e-12), "\n{a}\n!=\n{b}");
    }

    fn assert_rigid(m: DMat4) {
        let r = glam::DMat3::from_mat4(m);
        assert!(
            (r.transpose() * r).abs_diff_eq(glam::DMat3::IDENTITY, 1e-9),
            "{m}"
        );
        assert!((r.determinant() - 1.0).abs() < 1e-9, "{m}");
        assert_eq!(m.row(3), glam::DVec4::W);
    }

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
    fn ctc_colours_and_unsupported_wireframe() {
        let s = model("nist_ctc_01_asme1_rd.stp");
        let steel = s.colors.get(&101).expect("solid colour");
        assert!((steel[0] - 0.596_063_2).abs() < 1e-6 && (steel[2] - 0.686_259_25).abs() < 1e-6);
        assert_eq!(s.instances[0].solid, Some(101));
        assert_eq!(
            s.unsupported,
            [
                ("GEOMETRIC_CURVE_SET".to_owned(), 1),
                ("VERTEX_LOOP".to_owned(), 2)
            ]
        );
    }

    /// Rep #10 holds a mapped item placing rep #20 (one solid) by target #30 and origin #33.
    const MAPPED: &str = "
        #1=CARTESIAN_POINT('',(0.,0.,0.));
        #2=CARTESIAN_POINT('',(1.,0.,0.));
        #3=CARTESIAN_POINT('',(10.,20.,30.));
        #4=DIRECTION('',(0.,0.,1.));
        #5=DIRECTION('',(0.,1.,0.));
        #10=SHAPE_REPRESENTATION('asm',(#11,#40),#99);
        #11=AXIS2_PLACEMENT_3D('',#1,$,$);
        #20=ADVANCED_BREP_SHAPE_REPRESENTATION('part',(#21,#33),#99);
        #21=MANIFOLD_SOLID_BREP('s',#22);
        #22=CLOSED_SHELL('',());
        #30=AXIS2_PLACEMENT_3D('',#3,#4,#5);
        #33=AXIS2_PLACEMENT_3D('',#2,$,$);
        #40=MAPPED_ITEM('m1',#41,#30);
        #41=REPRESENTATION_MAP(#33,#20);
        #99=(GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNIT_ASSIGNED_CONTEXT((#98))
             REPRESENTATION_CONTEXT('',''));
        #98=(LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT($,.METRE.));";

    #[test]
    fn mapped_item_gives_target_times_inverse_origin() {
        let s = step(MAPPED);
        assert_eq!(s.instances.len(), 1);
        let i = &s.instances[0];
        assert_eq!(
            (i.shell, i.solid, i.representation),
            (22, Some(21), Some(20))
        );
        // Rz(90°) about (10,20,30) after moving (1,0,0) to the origin.
        let expected = DMat4::from_cols_array(&[
            0.0, 1.0, 0.0, 0.0, //
            -1.0, 0.0, 0.0, 0.0, //
            0.0, 0.0, 1.0, 0.0, //
            10.0, 19.0, 30.0, 1.0,
        ]);
        assert_close(i.transform, expected);
        assert_eq!(i.instance_name, "m1");
        assert_eq!(s.parts[i.part].name, "shell #22");
        assert_eq!(s.length_unit_mm, Some(1000.0));
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }

    /// Assembly product #100 (rep #10 with placements #11, #12) uses component #200 (rep #20,
    /// placement #23) twice, by relationships #50 and #60 with item-defined transformations.
    const ASSEMBLY: &str = "
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
    fn assert_assembly_placements(s: &Structure) {
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

    /// A writer that lists the assembly's representation as rep_1 and the component's as
    /// rep_2 (with the items swapped too): the occurrence says which is the component.
    #[test]
    fn swapped_relationship_reads_as_its_occurrence_says() {
        let swapped = ASSEMBLY
            .replace(
                "#50=(REPRESENTATION_RELATIONSHIP('','',#20,#10)",
                "#50=(REPRESENTATION_RELATIONSHIP('','',#10,#20)",
            )
            .replace(
                "#51=ITEM_DEFINED_TRANSFORMATION('','',#23,#12)",
                "#51=ITEM_DEFINED_TRANSFORMATION('','',#12,#23)",
            );
        assert_ne!(swapped, ASSEMBLY);
        let s = step(&swapped);
        assert_assembly_placements(&s);
        assert!(
            s.warnings.iter().any(|w| w.contains("swapped")),
            "{:?}",
            s.warnings
        );
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
    fn item_defined_transformation_places_child_in_parent() {
        let s = step(ASSEMBLY);
        assert_eq!(s.instances.len(), 2, "{:?}", s.instances);
        assert_eq!(s.parts.len(), 2);
        assert_eq!(
            s.parts[0].name, "asm-id",
            "blank PRODUCT name falls back to the id"
        );
        let first = &s.instances[0];
        assert_eq!(s.parts[first.part].name, "widget");
        assert_eq!(first.instance_name, "comp_1");
        assert_eq!(first.representation, Some(21));
        // M(#12) · M(#23)⁻¹: axes x=(0,1,0), y=(0,0,1), z=(1,0,0), origin (5,0,0) − 2·z.
        let expected = DMat4::from_cols_array(&[
            0.0, 1.0, 0.0, 0.0, //
            0.0, 0.0, 1.0, 0.0, //
            1.0, 0.0, 0.0, 0.0, //
            3.0, 0.0, 0.0, 1.0,
        ]);
        assert_close(first.transform, expected);
        let second = &s.instances[1];
        assert_eq!(
            second.instance_name, "2",
            "blank NAUO name falls back to its id"
        );
        assert_close(
            second.transform,
            DMat4::from_translation(DVec3::new(0.0, 7.0, 0.0)),
        );
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert_eq!(s.length_unit_mm, None);
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
    fn representation_without_products_keeps_voids_and_identity_links() {
        let s = step(
            "#1=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#2),$);\
             #2=BREP_WITH_VOIDS('',#3,(#4));#3=CLOSED_SHELL('',());\
             #4=ORIENTED_CLOSED_SHELL('',*,#5,.F.);#5=CLOSED_SHELL('',());\
             #6=SHAPE_REPRESENTATION('',(),$);\
             #7=SHAPE_REPRESENTATION_RELATIONSHIP('','',#6,#1);",
        );
        let got: Vec<OwnedShell> = s.instances.iter().map(|i| (i.shell, i.solid)).collect();
        assert_eq!(got, [(3, Some(2)), (5, Some(2))]);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }

    #[test]
    fn cycles_terminate_with_a_warning() {
        // #10 maps #20, #20 maps #10, and a transform relation #20 → #10 too.
        let s = step(
            "#1=CARTESIAN_POINT('',(0.,0.,0.));#2=CARTESIAN_POINT('',(1.,0.,0.));\
             #3=AXIS2_PLACEMENT_3D('',#1,$,$);#4=AXIS2_PLACEMENT_3D('',#2,$,$);\
             #10=SHAPE_REPRESENTATION('',(#11,#12),$);#11=MANIFOLD_SOLID_BREP('',#13);\
             #13=CLOSED_SHELL('',());#12=MAPPED_ITEM('',#14,#4);#14=REPRESENTATION_MAP(#3,#20);\
             #20=SHAPE_REPRESENTATION('',(#21,#22),$);#21=MANIFOLD_SOLID_BREP('',#23);\
             #23=CLOSED_SHELL('',());#22=MAPPED_ITEM('',#24,#4);#24=REPRESENTATION_MAP(#3,#10);\
             #30=(REPRESENTATION_RELATIONSHIP('','',#10,#20)\
                  REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION(#31)\
                  SHAPE_REPRESENTATION_RELATIONSHIP());\
             #31=ITEM_DEFINED_TRANSFORMATION('','',#3,#4);",
        );
        assert!(!s.instances.is_empty());
        for shell in [13, 23] {
            assert!(s.instances.iter().any(|i| i.shell == shell));
        }
        assert!(s.instances.len() <= 4, "{}", s.instances.len());
        assert!(
            s.warnings.iter().any(|w| w.contains("cycles")),
            "{:?}",
            s.warnings
        );
    }

    #[test]
    fn exponential_sharing_is_capped() {
        // Each level maps the next one twice: 2^70 paths, cut by depth and instance limits.
        let mut data = String::from(
            "#1=CARTESIAN_POINT('',(0.,0.,0.));#2=AXIS2_PLACEMENT_3D('',#1,$,$);\
             #3=CLOSED_SHELL('',());",
        );
        for level in 0..70u64 {
            let rep = 1000 + 10 * level;
            let next = rep + 10;
            if level == 69 {
                data += &format!("#{rep}=SHAPE_REPRESENTATION('',(#3),$);");
            } else {
                data += &format!(
                    "#{rep}=SHAPE_REPRESENTATION('',(#{a},#{b}),$);\
                     #{a}=MAPPED_ITEM('',#{m},#2);#{b}=MAPPED_ITEM('',#{m},#2);\
                     #{m}=REPRESENTATION_MAP(#2,#{next});",
                    a = rep + 1,
                    b = rep + 2,
                    m = rep + 3
                );
            }
        }
        let start = std::time::Instant::now();
        let s = step(&data);
        assert!(start.elapsed().as_secs() < 30);
        assert!(!s.instances.is_empty() && s.instances.len() <= MAX_INSTANCES);
        assert!(!s.warnings.is_empty());
    }

    #[test]
    fn degenerate_placements_stay_finite_and_rigid() {
        let file = parse(
            "ISO-10303-21;HEADER;ENDSEC;DATA;\
             #1=CARTESIAN_POINT('',(1.,2.));#2=DIRECTION('',(0.,0.,0.));\
             #3=DIRECTION('',(0.,0.,5.));#4=DIRECTION('',(1.,0.,0.));\
             #10=AXIS2_PLACEMENT_3D('',#1,#2,#3);#11=AXIS2_PLACEMENT_3D('',#1,#3,#3);\
             #12=AXIS2_PLACEMENT_3D('',#1,#4,$);#13=AXIS2_PLACEMENT_3D('',#99,$,$);\
             #14=CARTESIAN_TRANSFORMATION_OPERATOR_3D('','',$,$,#1,2.,$);ENDSEC;",
        )
        .expect("parses");
        for id in [10, 11, 12] {
            let m = placement(&file, id).expect("readable");
            assert_rigid(m);
            assert_eq!(m.w_axis, glam::DVec4::new(1.0, 2.0, 0.0, 1.0));
        }
        assert_eq!(placement(&file, 13), None);
        let m = placement(&file, 14).expect("operator");
        assert_close(
            m,
            DMat4::from_scale_rotation_translation(
                DVec3::splat(2.0),
                glam::DQuat::IDENTITY,
                DVec3::new(1.0, 2.0, 0.0),
            ),
        );
    }

    #[test]
    fn colours_prefer_surface_and_overrides() {
        let s = step(
            "#1=COLOUR_RGB('',0.1,0.2,0.3);#2=DRAUGHTING_PRE_DEFINED_COLOUR('yellow');\
             #3=CURVE_STYLE('',$,$,#2);\
             #4=SURFACE_STYLE_USAGE(.BOTH.,#5);#5=SURFACE_SIDE_STYLE('',(#6));\
             #6=SURFACE_STYLE_FILL_AREA(#7);#7=FILL_AREA_STYLE('',(#8));\
             #8=FILL_AREA_STYLE_COLOUR('',#1);\
             #9=PRESENTATION_STYLE_ASSIGNMENT((#3,#4));\
             #10=STYLED_ITEM('',(#9),#100);\
             #11=STYLED_ITEM('',(#12),#101);#12=PRESENTATION_STYLE_ASSIGNMENT((#3));\
             #13=OVER_RIDING_STYLED_ITEM('',(#12),#100,#10);\
             #14=STYLED_ITEM('',(#15),#102);#15=PRESENTATION_STYLE_ASSIGNMENT((#16));\
             #16=SURFACE_STYLE_USAGE(.BOTH.,#17);#17=SURFACE_SIDE_STYLE('',(#18));\
             #18=SURFACE_STYLE_FILL_AREA(#19);#19=FILL_AREA_STYLE('',(#20));\
             #20=FILL_AREA_STYLE_COLOUR('',#21);#21=COLOUR_RGB('',2.,-1.,0.5);",
        );
        assert_eq!(
            s.colors.get(&101),
            Some(&[1.0, 1.0, 0.0]),
            "curve colour when alone"
        );
        assert_eq!(s.colors.get(&100), Some(&[1.0, 1.0, 0.0]), "override wins");
        assert_eq!(s.colors.get(&102), Some(&[1.0, 0.0, 0.5]), "clamped");
        let s = step(
            "#1=COLOUR_RGB('',0.1,0.2,0.3);#2=DRAUGHTING_PRE_DEFINED_COLOUR('yellow');\
             #3=CURVE_STYLE('',$,$,#2);#4=SURFACE_STYLE_USAGE(.BOTH.,#5);\
             #5=SURFACE_SIDE_STYLE('',(#6));#6=SURFACE_STYLE_FILL_AREA(#7);\
             #7=FILL_AREA_STYLE('',(#8));#8=FILL_AREA_STYLE_COLOUR('',#1);\
             #9=PRESENTATION_STYLE_ASSIGNMENT((#3,#4));#10=STYLED_ITEM('',(#9),#100);",
        );
        assert_eq!(
            s.colors.get(&100),
            Some(&[0.1, 0.2, 0.3]),
            "surface before curve"
        );
    }

    #[test]
    fn unsupported_geometry_in_role() {
        let s = step(
            "#1=EDGE_CURVE('',#9,#9,#2,.T.);#2=TRIMMED_CURVE('',#9,(),(),.T.,.UNSPECIFIED.);\
             #3=TRIMMED_CURVE('',#9,(),(),.T.,.UNSPECIFIED.);\
             #4=EDGE_CURVE('',#9,#9,#5,.T.);#5=SURFACE_CURVE('',#6,(),.CURVE_3D.);\
             #6=TRIMMED_CURVE('',#9,(),(),.T.,.UNSPECIFIED.);\
             #7=FACE_BOUND('',#8,.T.);#8=VERTEX_LOOP('',#9);#9=VERTEX_POINT('',$);\
             #10=TESSELLATED_SHELL('',(),$);#11=(BOUNDED_SURFACE() OFFSET_SURFACE('',#9,1.,.F.));",
        );
        assert_eq!(
            s.unsupported,
            [
                ("OFFSET_SURFACE".to_owned(), 1),
                ("TESSELLATED_SHELL".to_owned(), 1),
                ("TRIMMED_CURVE".to_owned(), 2),
                ("VERTEX_LOOP".to_owned(), 1),
            ]
        );
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
