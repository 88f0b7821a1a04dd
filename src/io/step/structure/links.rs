//! Representations and the links between them (CAx-IF *Recommended Practices for AP203/AP214
//! Assembly Structure*, §2–3): the shells every representation holds (`MANIFOLD_SOLID_BREP`,
//! `BREP_WITH_VOIDS`, `SHELL_BASED_SURFACE_MODEL`, bare and oriented shells), identity links
//! (relationships without transformation) that join representations into groups, and directed
//! links that place a child group in its parent: `REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION`
//! by `M(item_2) · M(item_1)⁻¹` of its `ITEM_DEFINED_TRANSFORMATION` (read as the
//! `NEXT_ASSEMBLY_USAGE_OCCURRENCE` of its `CONTEXT_DEPENDENT_SHAPE_REPRESENTATION` says when a
//! writer swapped rep_1 and rep_2), and `MAPPED_ITEM` by `M(target) · M(origin)⁻¹`. Unreadable
//! placements become the identity and are reported once each.

use std::collections::{HashMap, HashSet};

use glam::DMat4;

use super::placements::{inverse, placement};
use super::products::Products;
use crate::io::step::p21::{Entity, P21File, Param, Record};

/// A shell and the solid or surface model that owns it.
pub(super) type OwnedShell = (u64, Option<u64>);

/// A placed child group.
#[derive(Debug, Clone)]
pub(super) struct Link {
    pub(super) child: usize,
    /// Child → parent.
    pub(super) transform: DMat4,
    /// Occurrence name for [`ShellInstance::instance_name`] (may be empty).
    pub(super) name: String,
    /// The part of the occurrence (`NEXT_ASSEMBLY_USAGE_OCCURRENCE` child), if known.
    pub(super) part: Option<usize>,
}

/// Representations joined by identity links, placed as a whole.
#[derive(Debug, Default)]
pub(super) struct Group {
    /// Member representations with the shells they hold: (rep, [(shell, solid)]).
    pub(super) members: Vec<(u64, Vec<OwnedShell>)>,
    pub(super) links: Vec<Link>,
}

#[derive(Debug, Default)]
pub(super) struct Graph {
    pub(super) groups: Vec<Group>,
    pub(super) group_of: HashMap<u64, usize>,
    /// Groups that are the child of some link.
    pub(super) child_groups: HashSet<usize>,
    /// Representation → part (from products).
    pub(super) rep_part: HashMap<u64, usize>,
    /// Representation → its context.
    pub(super) rep_context: HashMap<u64, u64>,
    /// Shell → owning solid / surface model.
    pub(super) shell_owner: HashMap<u64, u64>,
    /// Shells owned by a `FACETED_BREP` (not drawn, not placed as loose shells).
    pub(super) faceted_shells: HashSet<u64>,
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
    pub(super) fn build(file: &P21File, products: &Products, warnings: &mut Vec<String>) -> Self {
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

#[cfg(test)]
mod tests {
    use glam::{DMat4, DVec3};

    use super::super::fixtures::{ASSEMBLY, assert_assembly_placements, assert_close, step};
    use super::OwnedShell;

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
}
