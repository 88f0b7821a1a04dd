//! Measuring rendered images: crack and growth pixels against a watertight reference
//! ([`crack`]), stress tessellations that open every shared border as far as the pixel error
//! allows ([`stress`]), golden-image comparison with NVIDIA's FLIP and patch-ID goldens
//! ([`golden`]), a CPU rasterizer of patch IDs as a reference independent of the GPU path
//! ([`raster`]), and tessellations measured against the trimmed faces ([`fidelity`]).

pub mod crack;
pub mod fidelity;
pub mod golden;
pub mod raster;
pub mod stress;

pub use crack::{CheckError, CheckOptions, CheckReport, CrackCounts, run_check};
