//! Measuring rendered images: crack and growth pixels against a watertight reference
//! ([`crack`]) and golden-image comparison with NVIDIA's FLIP ([`golden`]).

pub mod crack;
pub mod fidelity;
pub mod golden;

pub use crack::{CheckOptions, CheckReport, CrackCounts, run_check};
