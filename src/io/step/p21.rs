//! ISO 10303-21 scanner (placeholder, being written).
