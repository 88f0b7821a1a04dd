//! STEP (ISO 10303-21) reader: faces of B-rep shells → trimmed patches, placed by the assembly.

pub mod p21;
pub mod structure;
