//! Readers (files → [`Model`], prepared into a [`crate::model::Scene`] by [`crate::prep`])
//! and writers (PNG, glTF, depth).
//!
//! [`read`] picks the reader by file extension (case-insensitive):
//!
//! | extension | reader        | up axis |
//! |-----------|---------------|---------|
//! | `.bpt`    | [`bpt::read`] | z       |
//! | `.step`, `.stp` | [`step::read`] | z (CAD convention) |
//! | `.step.gz`, `.stp.gz` | gzip, then [`step::read`] | z |
//! | `.iges`, `.igs` (also `.gz`) | [`iges::read`] | z |
//!
//! Every reader reports failures as a [`LoadError`] that names the file and, where the problem
//! is at a place in the file, the 1-based line, so that its message reads like
//! `models/x.bpt:17: expected a number for the y coordinate of control point 3 of patch 2,
//! found "abc"`. Readers never panic on malformed input.

pub mod atomic;
pub mod bpt;
pub mod depth;
pub mod gltf_out;
pub mod iges;
pub mod mesh;
pub mod mt_cache;
pub mod png;
pub mod step;
pub mod stl;
pub mod stl_out;

use std::path::{Path, PathBuf};

use crate::model::bezier::PatchError;

/// Why a model file could not be loaded.
///
/// Lines are 1-based; patch and control-point numbers are 0-based indices, as in
/// [`crate::model::Scene::patches`] (patch `id`) and [`PatchError`].
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

    /// An IGES file that breaks the format (line, or entity by its DE number: see
    /// [`iges::IgesError`]).
    #[error("{}: {source}", .path.display())]
    Iges {
        path: PathBuf,
        source: iges::IgesError,
    },

    /// No reader for this file extension (`extension` is empty when there is none).
    #[error(
        "{}: unsupported model format {extension:?} (patchwork reads .bpt, .step, .stp, .step.gz, .stp.gz, .iges, .igs, .iges.gz, .igs.gz, .glb, .gltf, .obj, .ply and .stl files)",
        .path.display()
    )]
    UnsupportedFormat { path: PathBuf, extension: String },
    /// A format whose reader this build left out (a Cargo feature, on by default).
    #[error("{}: {format} files need patchwork built with the `{feature}` feature", .path.display())]
    NotBuiltIn {
        path: PathBuf,
        format: &'static str,
        feature: &'static str,
    },
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
            | LoadError::Iges { path, .. }
            | LoadError::Patch { path, .. }
            | LoadError::UnsupportedFormat { path, .. }
            | LoadError::NotBuiltIn { path, .. } => path,
        }
    }

    /// The 1-based line the error points at, if it points at one.
    pub fn line(&self) -> Option<usize> {
        match self {
            LoadError::Parse { line, .. } | LoadError::Patch { line, .. } => Some(*line),
            LoadError::Iges {
                source: iges::IgesError::Section { line, .. },
                ..
            } => Some(*line),
            _ => None,
        }
    }
}

/// Most bytes a compressed model may expand to.
pub(crate) const MAX_GUNZIPPED_BYTES: u64 = 4 << 30;

/// Without the `gzip` feature: an error naming it.
#[cfg(not(feature = "gzip"))]
fn read_gzip(path: &Path) -> Result<Vec<u8>, LoadError> {
    Err(LoadError::NotBuiltIn {
        path: path.to_path_buf(),
        format: "gzipped STEP or IGES",
        feature: "gzip",
    })
}

/// The decompressed bytes of a gzip file, at most [`MAX_GUNZIPPED_BYTES`].
#[cfg(feature = "gzip")]
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

fn is_iges(extension: &str) -> bool {
    extension.eq_ignore_ascii_case("iges") || extension.eq_ignore_ascii_case("igs")
}

/// What a model file holds, before load-time preparation ([`crate::prep`]).
#[derive(Debug)]
pub enum Model {
    /// Bézier patches (`.bpt`, z-up).
    Bezier(Vec<crate::model::BezierPatch>),
    /// A triangle mesh in world coordinates (`.glb`, `.gltf`, `.obj`, `.ply`, y-up).
    Mesh(mesh::TriMesh),
    /// A STEP file's faces and product structure (`.step`, `.stp`, also gzipped); an IGES
    /// file's faces (`.iges`, `.igs`, also gzipped) in the same form.
    Step(Box<step::StepModel>),
}

/// The length unit a format states for its coordinates: metres for glTF (`.glb`, `.gltf`);
/// `None` for formats that state none. STEP scenes carry theirs (millimetres) themselves.
pub(crate) fn stated_unit(path: &Path) -> Option<&'static str> {
    let extension = path.extension()?.to_string_lossy().to_ascii_lowercase();
    matches!(extension.as_str(), "glb" | "gltf").then_some("m")
}

/// Reads a model, choosing the reader by the file's extension (case-insensitive); any other
/// extension is [`LoadError::UnsupportedFormat`]. [`crate::prep::load`] turns it into a
/// scene.
pub fn read(path: &Path) -> Result<Model, LoadError> {
    read_with(path, &crate::util::NoProgress)
}

/// As [`read`], reporting long steps (a STEP file's faces) to `progress`.
pub(crate) fn read_with(
    path: &Path,
    progress: &dyn crate::util::Progress,
) -> Result<Model, LoadError> {
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
            let bytes = read_gzip(path)?;
            return Ok(Model::Step(Box::new(step::read_with(
                &bytes, path, progress,
            )?)));
        }
        if is_iges(&inner) {
            let bytes = read_gzip(path)?;
            return Ok(Model::Step(Box::new(iges::read(&bytes, path)?)));
        }
        return Err(LoadError::UnsupportedFormat {
            path: path.to_path_buf(),
            extension: format!("{inner}.gz"),
        });
    }
    if extension.eq_ignore_ascii_case("bpt") {
        Ok(Model::Bezier(bpt::read(path)?))
    } else if extension.eq_ignore_ascii_case("step") || extension.eq_ignore_ascii_case("stp") {
        let bytes = std::fs::read(path).map_err(|source| LoadError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(Model::Step(Box::new(step::read_with(
            &bytes, path, progress,
        )?)))
    } else if is_iges(&extension) {
        let bytes = std::fs::read(path).map_err(|source| LoadError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(Model::Step(Box::new(iges::read(&bytes, path)?)))
    } else {
        let m = if extension.eq_ignore_ascii_case("obj") {
            mesh::read_obj(path)?
        } else if extension.eq_ignore_ascii_case("stl") {
            stl::read(path)?
        } else if extension.eq_ignore_ascii_case("ply") {
            mesh::read_ply(path)?
        } else if extension.eq_ignore_ascii_case("glb") || extension.eq_ignore_ascii_case("gltf") {
            mesh::read_gltf(path)?
        } else {
            return Err(LoadError::UnsupportedFormat {
                path: path.to_path_buf(),
                extension,
            });
        };
        // Nothing drawable (all triangles without area) is an error, not a blank image.
        mesh::check_drawable(path, &m)?;
        Ok(Model::Mesh(m))
    }
}
