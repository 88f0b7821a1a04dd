//! glTF binary export (placeholder, being written).
