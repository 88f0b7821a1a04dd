//! Readers: files → [`crate::model::Scene`].
//!
//! [`load`] picks the reader by file extension (case-insensitive):
//!
//! | extension | reader        | up axis |
//! |-----------|---------------|---------|
//! | `.bpt`    | [`bpt::read`] | z       |
//! | `.step`, `.stp` | [`step::parse`] | z (CAD convention) |
//! | `.step.gz`, `.stp.gz` | gzip, then [`step::parse`] | z |
//!
//! Every reader reports failures as a [`LoadError`] that names the file and, where the problem
//! is at a place in the file, the 1-based line, so that its message reads like
//! `models/x.bpt:17: expected a number for the y coordinate of control point 3 of patch 2,
//! found "abc"`. Readers never panic on malformed input.

pub mod bpt;
pub mod depth;
pub mod export;
pub mod gltf_out;
pub mod mesh;
pub mod png;
pub mod step;

use std::path::{Path, PathBuf};

use crate::model::bezier::PatchError;
use crate::model::{Scene, UpAxis};

/// Why a model file could not be loaded.
///
/// Lines are 1-based; patch and control-point numbers are 0-based indices, as in
/// [`Scene::patches`] (patch `id`) and [`PatchError`].
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be read at all (missing, a directory, no permission…).
    #[error("{}: cannot read: {source}", .path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },

    /// The file is binary, not text: a NUL byte or bytes that are not UTF-8 at `offset`.
    #[error("{}: not a text file: {what} at byte offset {offset}", .path.display())]
    NotText {
        path: PathBuf,
        offset: usize,
        what: &'static str,
    },

    /// The file is empty or holds only whitespace.
    #[error("{}: the file is empty or holds only whitespace", .path.display())]
    Empty { path: PathBuf },

    /// The text does not follow the format: a token that is not a number, a negative or absurd
    /// count, an unexpected end of file (`line` = where the file ended), trailing data.
    #[error("{}:{line}: {reason}", .path.display())]
    Parse {
        path: PathBuf,
        line: usize,
        reason: String,
    },

    /// The file is well formed but declares no patches.
    #[error("{}: the file declares 0 patches", .path.display())]
    NoPatches { path: PathBuf },

    /// A patch was read but is not valid (degree above the maximum, a coordinate that is NaN or
    /// infinite, all control points equal). `line` is the line of the offending coordinate for
    /// a non-finite one, otherwise of the patch's `du dv` header.
    #[error("{}:{line}: invalid patch {patch}: {source}", .path.display())]
    Patch {
        path: PathBuf,
        line: usize,
        patch: usize,
        source: PatchError,
    },

    /// The file was read but holds nothing to draw: no B-rep faces, or none that could be
    /// used (`reason` says which, with the first faces' reasons).
    #[error("{}: nothing to draw: {reason}", .path.display())]
    NoFaces { path: PathBuf, reason: String },

    /// The file passed our checks but a library reading it refused it.
    #[error("{}: {reason}", .path.display())]
    Unreadable { path: PathBuf, reason: String },

    /// No reader for this file extension (`extension` is empty when there is none).
    #[error(
        "{}: unsupported model format {extension:?} (patchwork reads .bpt, .step, .stp, .step.gz, .stp.gz, .glb, .gltf, .obj and .ply files)",
        .path.display()
    )]
    UnsupportedFormat { path: PathBuf, extension: String },
}

impl LoadError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            LoadError::Io { path, .. }
            | LoadError::NotText { path, .. }
            | LoadError::Empty { path }
            | LoadError::Parse { path, .. }
            | LoadError::NoPatches { path }
            | LoadError::NoFaces { path, .. }
            | LoadError::Unreadable { path, .. }
            | LoadError::Patch { path, .. }
            | LoadError::UnsupportedFormat { path, .. } => path,
        }
    }

    /// The 1-based line the error points at, if it points at one.
    pub fn line(&self) -> Option<usize> {
        match self {
            LoadError::Parse { line, .. } | LoadError::Patch { line, .. } => Some(*line),
            _ => None,
        }
    }
}

/// A progress bar on a terminal for long loads (`n` ≥ 20 steps), hidden otherwise (and
/// indicatif draws nothing when stderr is not a terminal).
pub(crate) fn progress(n: usize, what: &str) -> indicatif::ProgressBar {
    if n < 20 {
        return indicatif::ProgressBar::hidden();
    }
    let pb = indicatif::ProgressBar::new(n as u64);
    pb.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{bar:40}} {{pos}}/{{len}} {what} {{elapsed}}"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    pb
}

/// Most bytes a compressed model may expand to.
pub const MAX_GUNZIPPED_BYTES: u64 = 4 << 30;

/// The decompressed bytes of a gzip file, at most [`MAX_GUNZIPPED_BYTES`].
fn read_gzip(path: &Path) -> Result<Vec<u8>, LoadError> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(|source| LoadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut bytes = Vec::new();
    flate2::read::MultiGzDecoder::new(std::io::BufReader::new(file))
        .take(MAX_GUNZIPPED_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| LoadError::Unreadable {
            path: path.to_path_buf(),
            reason: format!("not a readable gzip file: {e}"),
        })?;
    if bytes.len() as u64 > MAX_GUNZIPPED_BYTES {
        return Err(LoadError::Unreadable {
            path: path.to_path_buf(),
            reason: format!("expands to more than {MAX_GUNZIPPED_BYTES} bytes"),
        });
    }
    Ok(bytes)
}

/// Triangles per patch when a mesh is split into patches (the 1–2 k).
pub const DEFAULT_PATCH_TRIANGLES: usize = 1500;

/// Loads a model, choosing the reader by the file's extension (case-insensitive).
///
/// `.bpt` files (Newell's teaset format, z-up) give a scene with [`UpAxis::Z`]; any other
/// extension is [`LoadError::UnsupportedFormat`].
pub fn load(path: &Path) -> Result<Scene, LoadError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    if extension.eq_ignore_ascii_case("gz") {
        let inner = Path::new(path.file_stem().unwrap_or_default())
            .extension()
            .map(|e| e.to_string_lossy().into_owned())
            .unwrap_or_default();
        if inner.eq_ignore_ascii_case("step") || inner.eq_ignore_ascii_case("stp") {
            return step::parse(&read_gzip(path)?, path);
        }
        return Err(LoadError::UnsupportedFormat {
            path: path.to_path_buf(),
            extension: format!("{inner}.gz"),
        });
    }
    if extension.eq_ignore_ascii_case("bpt") {
        let patches = bpt::read(path)?;
        Ok(Scene::from_bezier(patches, UpAxis::Z))
    } else if extension.eq_ignore_ascii_case("step") || extension.eq_ignore_ascii_case("stp") {
        let bytes = std::fs::read(path).map_err(|source| LoadError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        step::parse(&bytes, path)
    } else if ["glb", "gltf", "obj", "ply"]
        .iter()
        .any(|e| extension.eq_ignore_ascii_case(e))
    {
        let mesh = if extension.eq_ignore_ascii_case("obj") {
            mesh::read_obj(path)?
        } else if extension.eq_ignore_ascii_case("ply") {
            mesh::read_ply(path)?
        } else {
            mesh::read_gltf(path)?
        };
        let patches = mesh.triangles.len().div_ceil(DEFAULT_PATCH_TRIANGLES);
        let pb = progress(patches, "patch hierarchies");
        let scene = Scene::from_mesh(
            mesh,
            DEFAULT_PATCH_TRIANGLES,
            crate::mt::DEFAULT_ARC_SIZE,
            UpAxis::Y,
            || pb.inc(1),
        );
        pb.finish_and_clear();
        Ok(scene)
    } else {
        Err(LoadError::UnsupportedFormat {
            path: path.to_path_buf(),
            extension,
        })
    }
}
