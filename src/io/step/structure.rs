//! STEP product structure (placeholder, being written).
