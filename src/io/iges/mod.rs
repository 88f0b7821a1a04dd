//! IGES 5.3 reader: every trimmed surface (144) and every untrimmed B-spline surface (128)
//! that no trimmed surface uses becomes a [`TrimmedFace`](crate::model::trimmed::TrimmedFace), in the same [`StepModel`] the STEP
//! reader produces, so that probing, placement, tessellation, fat borders, the crack and
//! fidelity checks and export run unchanged.
//!
//! * [`sections`] — the fixed-format lines, the global section (delimiters, units), free-format
//!   parameters and Hollerith strings;
//! * [`directory`] — directory entries and each entity's parameter data;
//! * [`entities`] — curves (100, 102, 110, 126), surfaces (128), matrices (124), colours (314);
//! * [`faces`] — trim loops from curves on surfaces (142), faces (144, whole 128 patches),
//!   subfigures (308 placed by 408).
//!
//! Faces whose entities are bad (a pointer to no entity, a reference cycle, a missing
//! parameter, an unsupported surface) are skipped with their DE and reason; when none can be
//! used, the first face's [`IgesError`] is the error. Entities drawn by no face are counted
//! per type in one warning. Planes (108, 190) are read as surfaces of 144s; not read: the other
//! analytic surfaces (192–198), a bounded 108 on its own, the compressed and binary forms.

pub mod directory;
pub mod entities;
pub mod faces;
pub mod nurbs;
pub mod sections;

use std::collections::BTreeMap;
use std::path::Path;

use super::LoadError;
use super::step::StepModel;
use super::step::structure::{PartInfo, ShellInstance, Structure};

/// What is wrong with an IGES file, at the line or entity (DE number) where it is.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IgesError {
    /// The fixed-format structure: a line that is not 80 columns, a bad section letter or
    /// sequence number, section lengths the terminate section contradicts.
    #[error("line {line}: {reason}")]
    Section { line: usize, reason: String },
    /// A pointer (to a DE, or a DE's pointer into the P section) that leads nowhere.
    #[error("DE {de}: {what} {target} points nowhere: {reason}")]
    BadPointer {
        de: usize,
        what: String,
        target: i64,
        reason: String,
    },
    /// Entities that refer to each other in a circle (`path`: the DEs, the first repeated).
    #[error("DE {de}: reference cycle {path}")]
    Cycle { de: usize, path: String },
    /// An entity's parameter data ends before its record delimiter.
    #[error("DE {de}: parameter data truncated (from line {line}): {reason}")]
    Truncated {
        de: usize,
        line: usize,
        reason: String,
    },
    /// A parameter the entity needs is empty or absent (`index`: 1-based).
    #[error("DE {de}: parameter {index} ({what}) is missing")]
    MissingParameter {
        de: usize,
        index: usize,
        what: String,
    },
    /// A parameter or directory field of the wrong kind or out of range.
    #[error("DE {de}: parameter {index}: {reason}")]
    BadParameter {
        de: usize,
        index: usize,
        reason: String,
    },
    /// Well-formed data that makes no valid geometry (decreasing knots, open trim loop…).
    #[error("DE {de}: {reason}")]
    Invalid { de: usize, reason: String },
    /// An entity type the reader does not draw where a curve or surface is needed.
    #[error("DE {de}: entity type {entity_type} is not supported as {role}")]
    Unsupported {
        de: usize,
        entity_type: i64,
        role: String,
    },
}

impl IgesError {
    /// The DE number the error is about, if it is about an entity.
    pub fn de(&self) -> Option<usize> {
        match self {
            IgesError::Section { .. } => None,
            IgesError::BadPointer { de, .. }
            | IgesError::Cycle { de, .. }
            | IgesError::Truncated { de, .. }
            | IgesError::MissingParameter { de, .. }
            | IgesError::BadParameter { de, .. }
            | IgesError::Invalid { de, .. }
            | IgesError::Unsupported { de, .. } => Some(*de),
        }
    }
}

/// Entity types the reader uses (others are counted in a warning).
const USED_TYPES: &[i64] = &[
    0, 100, 102, 108, 110, 116, 123, 124, 126, 128, 142, 144, 190, 308, 314, 408,
];

/// Reads an IGES file from bytes (`path` is for messages).
pub fn read(bytes: &[u8], path: &Path) -> Result<StepModel, LoadError> {
    let p = || path.to_path_buf();
    let err = |source: IgesError| LoadError::Iges {
        path: path.to_path_buf(),
        source,
    };
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(LoadError::Empty { path: p() });
    }
    let file = directory::IgesFile::new(sections::split(bytes).map_err(err)?).map_err(err)?;
    let unit = file.global.unit_mm();
    let mut warnings = Vec::new();
    if unit.is_none() {
        warnings.push(format!(
            "unknown length unit (global parameters 14 = {:?}, 15 = {:?}): millimetres assumed",
            file.global.get(14),
            file.global.get(15)
        ));
    }
    let model = faces::collect(&file);
    let mut unsupported: BTreeMap<i64, usize> = BTreeMap::new();
    for e in &file.entries {
        if !USED_TYPES.contains(&e.entity_type) {
            *unsupported.entry(e.entity_type).or_default() += 1;
        }
    }
    if !unsupported.is_empty() {
        let list: Vec<String> = unsupported
            .iter()
            .map(|(t, c)| format!("type {t} ×{c}"))
            .collect();
        warnings.push(format!(
            "unsupported IGES entities (not drawn): {}",
            list.join(", ")
        ));
    }
    warnings.extend(model.warnings);
    if model.faces.iter().all(|(_, r)| r.is_err()) {
        return match model.first_error {
            Some(e) => Err(err(e)),
            None => Err(LoadError::NoFaces {
                path: p(),
                reason: format!(
                    "no trimmed (144) or B-spline (128) surface among {} entities",
                    file.entries.len()
                ),
            }),
        };
    }
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let structure = Structure {
        instances: model
            .shells
            .iter()
            .map(|(shell, transform, instance_name)| ShellInstance {
                shell: *shell,
                solid: None,
                representation: None,
                transform: *transform,
                part: 0,
                instance_name: instance_name.clone(),
            })
            .collect(),
        parts: vec![PartInfo {
            name,
            product_definition: None,
        }],
        colors: model.colors,
        length_unit_mm: Some(unit.unwrap_or(1.0)),
        uncertainty: file.global.get(19).real().filter(|r| *r > 0.0),
        ..Structure::default()
    };
    Ok(StepModel {
        path: p(),
        structure,
        faces: model
            .faces
            .into_iter()
            .map(|(id, r)| (id, r.map_err(|e| e.to_string())))
            .collect(),
        shell_faces: model.shell_faces,
        warnings,
    })
}
