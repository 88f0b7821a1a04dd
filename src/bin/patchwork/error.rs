//! Every error the `patchwork` command reports (exit code 2, `error: <message>`).
//!
//! The library's errors pass through unchanged (their messages already name the file); the
//! command's own variants name the flag and carry the value that was refused.

use std::path::PathBuf;
use std::process::ExitStatus;

use glam::DVec3;
use thiserror::Error;

use patchwork::check::CheckError;
use patchwork::export::ExportError;
use patchwork::io::LoadError;
use patchwork::io::depth::DepthError;
use patchwork::io::gltf_out::GltfWriteError;
use patchwork::io::png::WriteError;
use patchwork::render::RenderError;
use patchwork::render::pick::PickError;
#[cfg(feature = "viewer")]
use patchwork::viewer::ViewerError;

#[derive(Debug, Error)]
pub enum CliError {
    #[error(transparent)]
    Load(#[from] LoadError),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error("--pick: {0}")]
    Pick(#[from] PickError),
    #[error(transparent)]
    Check(#[from] CheckError),
    #[error(transparent)]
    Write(#[from] WriteError),
    #[error(transparent)]
    Gltf(#[from] GltfWriteError),
    #[error(transparent)]
    Export(#[from] ExportError),
    #[error(transparent)]
    Depth(#[from] DepthError),
    /// `--section` refused (not six finite numbers, a zero normal, more than 3 planes).
    #[error("--section: {0}")]
    Section(#[from] patchwork::render::SectionError),
    #[error(transparent)]
    #[cfg(feature = "viewer")]
    Viewer(#[from] ViewerError),

    /// A number outside its range: `--fov must be between 0.5 and 179 degrees, got 0`.
    #[error("{flag} must be {range}, got {value}")]
    OutOfRange {
        flag: &'static str,
        value: f64,
        range: &'static str,
    },
    /// `--budget-ms must be a positive number, not 0`.
    #[error("{flag} must be a positive number, not {value}")]
    NotPositive { flag: &'static str, value: f64 },
    /// `--distance must be a number ≥ 0, not -1`.
    #[error("{flag} must be a number ≥ 0, not {value}")]
    Negative { flag: &'static str, value: f64 },
    /// A count below its minimum: `--frames must be at least 2`.
    #[error("{flag} must be at least {min}")]
    TooFew {
        flag: &'static str,
        value: usize,
        min: usize,
    },
    /// `--only` / `--hide` with a pattern that names no instance.
    #[error(
        "{}: no part matches {pattern:?} (`patchwork stats --list-parts FILE` lists them)",
        .path.display()
    )]
    NoSuchPart { path: PathBuf, pattern: String },
    /// `--only` / `--hide` left nothing to draw.
    #[error("{}: --only / --hide leave no part with faces", .path.display())]
    NothingSelected { path: PathBuf },
    /// `export -o` with an extension that names no format we write.
    #[error("{}: unknown export format (write .glb, .gltf or .stl)", .path.display())]
    ExportFormat { path: PathBuf },
    /// A flag value that is not one of its choices.
    #[error("{flag}: {value:?} is not one of {choices}")]
    BadChoice {
        flag: &'static str,
        value: String,
        choices: &'static str,
    },
    /// `export --unit` on a model whose format states no unit.
    #[error(
        "{}: the format states no length unit, so --unit cannot convert it (use --unit model)",
        .path.display()
    )]
    UnitUnknown { path: PathBuf },
    #[error(transparent)]
    Stl(#[from] patchwork::io::stl_out::StlWriteError),
    /// `render --ref`: the reference image cannot be used.
    #[error("{}: reference image: {reason}", .path.display())]
    Reference { path: PathBuf, reason: String },
    #[error("--up must not be the zero vector")]
    ZeroUp,
    #[error("--eye and --target must differ")]
    EyeAtTarget { eye: DVec3 },
    #[error("--up must not be parallel to the viewing direction")]
    UpAlongView { up: DVec3, direction: DVec3 },
    /// `bench` without a benchmark flag.
    #[error("say which benchmark: --flythrough or --scale")]
    NoBenchmark,
    /// `bench --flythrough` needs exactly one model.
    #[error(
        "reading a model from stdin (`-`) needs --format EXT (step, iges, bpt, glb, obj, ply, stl, …)"
    )]
    StdinFormat,
    #[error("--format {0:?}: expected a file extension such as step, glb or step.gz")]
    BadFormat(String),
    #[error("{reason}")]
    Stdin { reason: String },
    #[error(transparent)]
    Merge(#[from] patchwork::model::merge::MergeError),
    #[error(transparent)]
    Shard(#[from] crate::shard::ShardError),
    #[error(transparent)]
    MergeShards(#[from] crate::cmd::merge::MergeError),
    /// A file's error as a shard recorded it (`merge`), reported as the unsharded run did.
    #[error("{0}")]
    Recorded(String),
    /// `check --files-from` with an empty list and no file given.
    #[error("{}: lists no model file", .list.display())]
    NoFiles { list: PathBuf },
    #[error("{failed} of {total} files failed (each error above)")]
    FilesFailed { failed: usize, total: usize },
    #[error("bench --flythrough takes one model file, got {0}")]
    FlythroughFiles(usize),
    #[error(transparent)]
    Scale(#[from] patchwork::drive::scale::ScaleError),
    /// A `bench --scale` point whose child process failed or answered nothing readable.
    #[error("bench --scale: {point}: {reason}")]
    ScalePoint { point: String, reason: String },
    #[cfg(feature = "viewer")]
    #[error("--keys: unknown key {key:?}")]
    UnknownKey { key: String },
    #[cfg(feature = "viewer")]
    #[error("--keys: {keys} keys for {frames} frames")]
    TooManyKeys { keys: usize, frames: usize },

    /// A file or folder the command itself handles (not through the library).
    #[error("{}: {source}", .path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// An output folder that cannot be created (`implode`).
    #[error("{}: cannot create the folder: {source}", .path.display())]
    CreateDir {
        path: PathBuf,
        source: std::io::Error,
    },
    /// `ffmpeg` was found but could not be started.
    #[error("ffmpeg: {0}")]
    FfmpegStart(#[source] std::io::Error),
    /// `ffmpeg` ran and failed.
    #[error("ffmpeg failed ({status}); the PNGs are in {}", .dir.display())]
    FfmpegFailed { status: ExitStatus, dir: PathBuf },
    /// `implode` made or found fewer frames than asked for: it never reports such a set as
    /// written.
    #[error("implode: {made} of {frames} frames written; the output is incomplete")]
    ShortRun { frames: usize, made: usize },
    /// An output folder named like a file: `implode -o anim.gif`.
    #[error("{}: -o names the output folder (frames, the GIF and frames.csv go inside it), not a .{extension} file; try -o {}", .path.display(), .suggestion.display())]
    OutputNotFolder {
        path: PathBuf,
        extension: String,
        suggestion: PathBuf,
    },
}
