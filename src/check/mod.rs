//! Measuring rendered images: crack and growth pixels against a watertight reference
//! ([`crack`]), golden-image comparison with NVIDIA's FLIP and patch-ID goldens ([`golden`]),
//! and a CPU rasterizer of patch IDs as a reference independent of the GPU path ([`raster`]).

pub mod crack;
pub mod golden;
pub mod raster;

pub use crack::{CheckOptions, CheckReport, CrackCounts, run_check};
