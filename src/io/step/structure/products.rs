//! Products of a STEP file: `PRODUCT_DEFINITION`s (the parts, named by their `PRODUCT`), their
//! shape representations through `SHAPE_DEFINITION_REPRESENTATION` → `PRODUCT_DEFINITION_SHAPE`,
//! and the roots of the assembly tree (product definitions that are the child of no
//! `NEXT_ASSEMBLY_USAGE_OCCURRENCE`) — the CAx-IF *Recommended Practices for AP203/AP214
//! Assembly Structure*, §2.

use std::collections::{HashMap, HashSet};

use super::PartInfo;
use crate::io::step::p21::{P21File, Record};

/// Products, their representations and the assembly tree's roots.
#[derive(Debug, Default)]
pub(super) struct Products {
    pub(super) parts: Vec<PartInfo>,
    /// `PRODUCT_DEFINITION` → part index.
    pub(super) pd_part: HashMap<u64, usize>,
    /// `PRODUCT_DEFINITION` → its shape representations (through `SHAPE_DEFINITION_REPRESENTATION`).
    pub(super) pd_reps: HashMap<u64, Vec<u64>>,
    /// Representation → part index.
    pub(super) rep_part: HashMap<u64, usize>,
    /// Product definitions that are the child of no `NEXT_ASSEMBLY_USAGE_OCCURRENCE`.
    pub(super) roots: Vec<u64>,
}

fn is_product_definition(name: &str) -> bool {
    name == "PRODUCT_DEFINITION" || name == "PRODUCT_DEFINITION_WITH_ASSOCIATED_DOCUMENTS"
}

impl Products {
    pub(super) fn read(file: &P21File) -> Self {
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
