//! Measuring rendered images: crack and growth pixels against a watertight reference
//! ([`crack`]), stress tessellations that open every shared border as far as the pixel error
//! allows ([`stress`]) and golden-image comparison with NVIDIA's FLIP ([`golden`]).

pub mod crack;
pub mod fidelity;
pub mod golden;
pub mod stress;

pub use crack::{CheckError, CheckOptions, CheckReport, CrackCounts, run_check};
