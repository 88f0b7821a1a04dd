//! The directory entry (DE) section of IGES 5.3 (§2.2.4.3): two 80-column lines per entity,
//! twenty 8-column fields (entity type, parameter data pointer, transformation matrix,
//! status number, colour, parameter line count, form…). An entity is named by the sequence
//! number of its first DE line (odd: 1, 3, 5, …), which is what other entities point to.
//!
//! [`IgesFile::params`] reads an entity's parameter data (its P lines, columns 1–64) on
//! demand; every pointer is checked against the section it points into.

use super::IgesError;
use super::sections::{Global, Param, Sections, field_int, parse_free};

/// One directory entry.
#[derive(Clone, Debug)]
pub struct Entry {
    /// DE number (sequence number of its first line).
    pub de: usize,
    pub entity_type: i64,
    /// First P line (1-based) and how many.
    pub pd_pointer: i64,
    pub pd_lines: i64,
    /// DE of the transformation matrix (124), 0 for none.
    pub transform: i64,
    /// Colour: 1–8 a standard colour, negative the DE of a colour definition (314).
    pub color: i64,
    pub form: i64,
    /// Status number digits 3–4: 0 independent, 1 physically dependent, 2 logically
    /// dependent, 3 both.
    pub subordinate: i64,
    /// Status number digits 5–6 (0 geometry, 5 2D parametric, …).
    pub entity_use: i64,
    /// File line of the entry's first line.
    pub line: usize,
}

impl Entry {
    /// Whether the entity exists only as part of another (not drawn on its own).
    pub(crate) fn physically_dependent(&self) -> bool {
        self.subordinate == 1 || self.subordinate == 3
    }
}

/// A parsed IGES file: the global parameters, the directory and the parameter lines.
#[derive(Debug)]
pub struct IgesFile<'a> {
    pub global: Global,
    pub entries: Vec<Entry>,
    parameter: Vec<(&'a [u8], usize)>,
}

impl<'a> IgesFile<'a> {
    /// Reads the directory of `sections`; a parameter data pointer outside the P section is an
    /// error naming the DE.
    pub fn new(sections: Sections<'a>) -> Result<IgesFile<'a>, IgesError> {
        let Sections {
            global,
            directory,
            parameter,
        } = sections;
        let mut entries = Vec::with_capacity(directory.len() / 2);
        for (k, pair) in directory.chunks_exact(2).enumerate() {
            let (a, line) = pair[0];
            let b = pair[1].0;
            let de = 2 * k + 1;
            let field = |l: &[u8], n: usize, what: &str| -> Result<i64, IgesError> {
                field_int(&l[8 * n..8 * n + 8]).ok_or_else(|| IgesError::BadParameter {
                    de,
                    index: 0,
                    reason: format!(
                        "directory field {what} is {:?}, not an integer",
                        String::from_utf8_lossy(&l[8 * n..8 * n + 8])
                    ),
                })
            };
            let entity_type = field(a, 0, "1 (entity type)")?;
            let status = &a[64..72];
            let digits = |r: std::ops::Range<usize>| field_int(&status[r]).unwrap_or(0);
            let entry = Entry {
                de,
                entity_type,
                pd_pointer: field(a, 1, "2 (parameter data)")?,
                transform: field(a, 6, "7 (transformation matrix)")?,
                color: field(b, 2, "13 (colour)")?,
                pd_lines: field(b, 3, "14 (parameter line count)")?,
                form: field(b, 4, "15 (form)")?,
                subordinate: digits(2..4),
                entity_use: digits(4..6),
                line,
            };
            let second = field(b, 0, "11 (entity type)")?;
            if second != entity_type {
                return Err(IgesError::BadParameter {
                    de,
                    index: 0,
                    reason: format!(
                        "its two directory lines give entity types {entity_type} and {second}"
                    ),
                });
            }
            let n = parameter.len() as i64;
            if entity_type != 0 && (entry.pd_pointer < 1 || entry.pd_pointer > n) {
                return Err(IgesError::BadPointer {
                    de,
                    what: "parameter data pointer".into(),
                    target: entry.pd_pointer,
                    reason: format!("the P section has lines 1 to {n}"),
                });
            }
            entries.push(entry);
        }
        Ok(IgesFile {
            global,
            entries,
            parameter,
        })
    }

    /// The entry of DE `de`, or why a pointer to it is bad (`from`, `what`: who points).
    pub fn entry(&self, de: i64, from: usize, what: &str) -> Result<&Entry, IgesError> {
        let bad = |reason: String| IgesError::BadPointer {
            de: from,
            what: what.into(),
            target: de,
            reason,
        };
        if de < 1 || de % 2 == 0 {
            return Err(bad("a DE pointer is a positive odd number".into()));
        }
        self.entries
            .get(((de - 1) / 2) as usize)
            .ok_or_else(|| bad(format!("the file has {} entities", self.entries.len())))
    }

    /// The parameters of entity `e` (index 0 is its entity type, as in the standard's
    /// numbering). The record runs over the entity's P lines; when its record delimiter is
    /// not there, over following lines that still name this DE in columns 66–72.
    pub fn params(&self, e: &Entry) -> Result<Vec<Param>, IgesError> {
        // The pointer was checked in `new`.
        let first = (e.pd_pointer.max(1) - 1) as usize;
        let stated = e.pd_lines.max(1) as usize;
        let mut text: Vec<u8> = Vec::new();
        let mut k = first;
        let g = &self.global;
        while let Some(&(l, _)) = self.parameter.get(k) {
            let back = field_int(&l[64..72]);
            if k >= first + stated && back != Some(e.de as i64) {
                break;
            }
            text.extend_from_slice(&l[..64]);
            k += 1;
            if k >= first + stated && text.contains(&g.record_delim) {
                break;
            }
        }
        let line = self.parameter.get(first).map_or(0, |x| x.1);
        let (params, _) = parse_free(&text, g.param_delim, g.record_delim).map_err(|reason| {
            if reason.contains("without its record delimiter") || reason.contains("runs past") {
                IgesError::Truncated {
                    de: e.de,
                    line,
                    reason,
                }
            } else {
                IgesError::BadParameter {
                    de: e.de,
                    index: 0,
                    reason: format!("parameter data at line {line}: {reason}"),
                }
            }
        })?;
        if params.first().and_then(Param::int) != Some(e.entity_type) {
            return Err(IgesError::BadParameter {
                de: e.de,
                index: 0,
                reason: format!(
                    "its parameter data (line {line}) starts with {:?}, not its entity type {}",
                    params.first(),
                    e.entity_type
                ),
            });
        }
        Ok(params)
    }
}
