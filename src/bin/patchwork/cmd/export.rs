//! `patchwork export`: the tessellation as binary glTF (assembled by
//! `patchwork::export::assemble`, written by `io::gltf_out::write_glb`).

use std::path::PathBuf;

use clap::Args;

use patchwork::export::{ExportOptions, Tolerance, assemble};
use patchwork::io::gltf_out::write_glb;
use patchwork::view;

use super::load_built;
use crate::args::pixel_error;
use crate::error::CliError;

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// Model file (.bpt, .step, .stp, .glb, .gltf, .obj, .ply, .stl).
    file: PathBuf,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    /// Output .glb file.
    #[arg(short, long)]
    output: PathBuf,
    /// Tessellate for the default view at this screen-space error (pixels, 1024x768).
    #[arg(long, default_value_t = view::DEFAULT_PIXEL_ERROR, conflicts_with = "tolerance")]
    pixel_error: f64,
    /// Tessellate to this absolute tolerance instead (model units: millimetres for STEP).
    #[arg(long)]
    tolerance: Option<f64>,
}

impl ExportArgs {
    fn tolerance(&self) -> Result<Tolerance, CliError> {
        match self.tolerance {
            Some(t) => {
                if !(t.is_finite() && t > 0.0) {
                    return Err(CliError::NotPositive {
                        flag: "--tolerance",
                        value: t,
                    });
                }
                Ok(Tolerance::Absolute(t))
            }
            None => Ok(Tolerance::PixelError(pixel_error(self.pixel_error)?)),
        }
    }
}

pub fn run(args: &ExportArgs) -> Result<(), CliError> {
    let scene = load_built(&args.file, &args.cache)?;
    let opts = ExportOptions {
        tolerance: args.tolerance()?,
        ..ExportOptions::default()
    };
    let doc = assemble(&scene, &opts)?;
    let stats = write_glb(&args.output, &doc)?;
    eprintln!(
        "{}: {} meshes, {} nodes, {} triangles, {} bytes",
        args.output.display(),
        stats.meshes,
        stats.nodes,
        stats.triangles,
        stats.bytes
    );
    Ok(())
}
