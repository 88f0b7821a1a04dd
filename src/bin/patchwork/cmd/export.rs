//! `patchwork export`: the tessellation as binary glTF (assembled by
//! `patchwork::export::assemble`, written by `io::gltf_out::write_glb`).

use std::path::{Path, PathBuf};

use clap::Args;
use serde_json::json;

use patchwork::export::{ExportOptions, Tolerance, assemble_reporting, metres_per_unit};
use patchwork::io::gltf_out::{write_glb, write_gltf};
use patchwork::io::stl_out::write_stl;
use patchwork::model::{Scene, UpAxis};
use patchwork::view;

use crate::args::pixel_error;
use crate::error::CliError;
use crate::out::{self, data};
use patchwork::prep::Hierarchies;

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// Model files (.bpt, .step, .stp, .iges, .glb, .gltf, .obj, .ply, .stl; `-` reads stdin,
    /// with --format); several are drawn as one scene, each file a top-level part.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    #[command(flatten)]
    parts: crate::args::PartArgs,
    /// Output file, its format by extension: .glb (binary glTF), .gltf (text glTF with a .bin
    /// beside it) or .stl (binary STL).
    #[arg(short, long)]
    output: PathBuf,
    /// Unit of the file's coordinates: m, cm, mm, in, ft, or `model` (the model's own numbers).
    /// Default: metres for glTF (as the glTF specification says), millimetres for STL; a
    /// model whose format states no unit (.bpt, OBJ, PLY, STL) is written in its own numbers.
    #[arg(long)]
    unit: Option<String>,
    /// The file's up axis: y, z, or `model` (the model's own axes). Default: y for glTF (as its
    /// specification says), z for STL.
    #[arg(long)]
    up: Option<String>,
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

/// The output formats, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Glb,
    Gltf,
    Stl,
}

impl Format {
    fn of(path: &Path) -> Result<Format, CliError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "glb" => Ok(Format::Glb),
            "gltf" => Ok(Format::Gltf),
            "stl" => Ok(Format::Stl),
            _ => Err(CliError::ExportFormat {
                path: path.to_owned(),
            }),
        }
    }
}

/// The file's up axis and unit scale from the flags and the format's conventions.
fn frame(
    args: &ExportArgs,
    format: Format,
    scene: &Scene,
) -> Result<(Option<UpAxis>, f64, String), CliError> {
    let up = match (args.up.as_deref(), format) {
        (Some("y" | "Y"), _) | (None, Format::Glb | Format::Gltf) => Some(UpAxis::Y),
        (Some("z" | "Z"), _) | (None, Format::Stl) => Some(UpAxis::Z),
        (Some("model"), _) => None,
        (Some(other), _) => {
            return Err(CliError::BadChoice {
                flag: "--up",
                value: other.to_owned(),
                choices: "y, z or model",
            });
        }
    };
    let asked = args.unit.as_deref().unwrap_or(match format {
        Format::Glb | Format::Gltf => "m",
        Format::Stl => "mm",
    });
    if asked == "model" {
        return Ok((up, 1.0, scene.unit.unwrap_or("model units").to_owned()));
    }
    let target = metres_per_unit(asked).ok_or_else(|| CliError::BadChoice {
        flag: "--unit",
        value: asked.to_owned(),
        choices: "m, cm, mm, in, ft or model",
    })?;
    match scene.unit.and_then(metres_per_unit) {
        Some(model) => Ok((up, model / target, asked.to_owned())),
        None if args.unit.is_some() => Err(CliError::UnitUnknown {
            path: super::shown(&args.files),
        }),
        // The format states no unit: its numbers are written as they are.
        None => Ok((up, 1.0, "model units".to_owned())),
    }
}

pub fn run(args: &ExportArgs) -> Result<(), CliError> {
    let format = Format::of(&args.output)?;
    let tolerance = args.tolerance()?;
    let file = super::shown(&args.files);
    // Export draws a mesh's coarse patch groups where they pay: build them too.
    let mut options = args.cache.options(Hierarchies::Build);
    options.groups = true;
    let loaded = super::load_all(&args.files, &options)?;
    let scene = args.parts.apply(loaded.scene, &file)?;
    let (up, scale, unit) = frame(args, format, &scene)?;
    let opts = ExportOptions {
        tolerance,
        up,
        scale,
        // The file's name; several files: their names joined (each a group below it).
        root_name: args
            .files
            .iter()
            .filter_map(|f| f.file_name())
            .map(|n| n.to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join(" + "),
        ..ExportOptions::default()
    };
    let (doc, left_out) = assemble_reporting(&scene, &opts)?;
    // Faces whose tessellation failed are missing from the file: said, never silent.
    let lines: Vec<String> = (left_out.iter())
        .map(|l| format!("{} (part {}): {}", l.patch, l.part, l.reason))
        .collect();
    super::warn_list(
        &format!(
            "{} face(s) could not be tessellated and are left out of {}",
            left_out.len(),
            args.output.display()
        ),
        &lines,
    );
    let (meshes, nodes, triangles, bytes) = match format {
        Format::Glb | Format::Gltf => {
            let stats = if format == Format::Glb {
                write_glb(&args.output, &doc)?
            } else {
                write_gltf(&args.output, &doc)?
            };
            (stats.meshes, stats.nodes, stats.triangles, stats.bytes)
        }
        Format::Stl => {
            let stats = write_stl(&args.output, &doc)?;
            (
                doc.meshes.len(),
                doc.nodes.len(),
                stats.triangles,
                stats.bytes,
            )
        }
    };
    let up_name = match up {
        Some(UpAxis::Y) => "y",
        Some(UpAxis::Z) => "z",
        None => "the model's",
    };
    out::emit(&json!({
        "output": args.output.display().to_string(),
        "meshes": meshes,
        "nodes": nodes,
        "groups": doc.groups.len(),
        "triangles": triangles,
        "bytes": bytes,
        "unit": unit,
        "up": up_name,
        "left_out": left_out.iter().map(|l| json!({
            "patch": l.patch,
            "part": l.part,
            "reason": l.reason,
        })).collect::<Vec<_>>(),
    }));
    data!(
        "{}: {meshes} meshes, {nodes} nodes, {} groups, {triangles} triangles, {bytes} bytes; \
         {unit}, {up_name} up",
        args.output.display(),
        doc.groups.len(),
    );
    Ok(())
}
