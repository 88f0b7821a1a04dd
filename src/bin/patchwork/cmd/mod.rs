//! One module per command: its flags, and `run`, which checks them, calls the library and
//! prints. What several commands print the same way is here.

pub mod bench;
pub mod check;
pub mod export;
pub mod implode;
pub mod merge;
mod pick;
pub mod render;
pub mod stats;
#[cfg(feature = "viewer")]
pub mod view;

use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{Value, json};

use patchwork::model::Scene;
use patchwork::prep::{Hierarchies, LoadOptions, Loaded};
use patchwork::tessellate::PatchMesh;

use crate::args::CacheArgs;
use crate::error::CliError;
use crate::out::{self, data, note};

/// Runs `one` on every file in order (`stats a b c`, `check a b c`): `one` prints its text
/// block and returns whether the file passed and its JSON object. One file: that object,
/// and its error as the command's. Several: a `== FILE ==` line before each text block, one
/// JSON array (a file that failed as `{"file", "error"}`), every file tried; the exit code is
/// the worst (an error 2, else a failed check 1).
pub fn for_each_file(
    files: &[PathBuf],
    mut one: impl FnMut(&Path) -> Result<(bool, Value), CliError>,
) -> Result<bool, CliError> {
    if let [file] = files {
        let (passed, value) = one(file)?;
        out::emit(&value);
        return Ok(passed);
    }
    let (mut values, mut failed, mut passed) = (Vec::new(), 0, true);
    for (k, file) in files.iter().enumerate() {
        if k > 0 {
            data!();
        }
        data!("== {} ==", file.display());
        match one(file) {
            Ok((ok, value)) => {
                passed &= ok;
                values.push(value);
            }
            Err(e) => {
                eprintln!("error: {e}");
                failed += 1;
                values.push(json!({ "file": file.display().to_string(), "error": e.to_string() }));
            }
        }
    }
    out::emit(&Value::Array(values));
    if failed > 0 {
        return Err(CliError::FilesFailed {
            failed,
            total: files.len(),
        });
    }
    Ok(passed)
}

/// The format of a model read from stdin (`--format EXT`), set once by `main`.
static STDIN_FORMAT: std::sync::OnceLock<Option<String>> = std::sync::OnceLock::new();

pub fn set_stdin_format(format: Option<String>) {
    let _ = STDIN_FORMAT.set(format);
}

/// Loads a model as `options` say and tells the user (stderr) what was left out and why, and
/// what went wrong with the hierarchy cache. `-` reads the model from stdin ([`load_stdin`]).
pub fn load(path: &Path, options: &LoadOptions) -> Result<Loaded, CliError> {
    if path == Path::new("-") {
        return load_stdin(options);
    }
    load_file(path, path, options)
}

/// `-`: stdin's bytes written to `stdin.EXT` (EXT from `--format`, required) in a temporary
/// folder (removed when loaded, or by the SIGINT/SIGTERM handler), then read by the reader
/// for EXT like any file; messages say `<stdin>` for that file.
fn load_stdin(options: &LoadOptions) -> Result<Loaded, CliError> {
    use std::io::Read;
    let format = STDIN_FORMAT.get().cloned().flatten();
    let Some(ext) = format.as_deref().map(|f| f.trim_start_matches('.')) else {
        return Err(CliError::StdinFormat);
    };
    if ext.is_empty() || !ext.chars().all(|c| c.is_ascii_alphanumeric() || c == '.') {
        return Err(CliError::BadFormat(ext.to_owned()));
    }
    let base = std::env::temp_dir().join("patchwork-stdin");
    let dir = patchwork::io::atomic::TempDir::beside(&base)
        .map_err(|source| CliError::CreateDir { path: base, source })?;
    let file = dir.path().join(format!("stdin.{ext}"));
    let mut bytes = Vec::new();
    std::io::stdin()
        .read_to_end(&mut bytes)
        .map_err(|source| CliError::Io {
            path: PathBuf::from("<stdin>"),
            source,
        })?;
    std::fs::write(&file, &bytes).map_err(|source| CliError::Io {
        path: file.clone(),
        source,
    })?;
    let shown = Path::new("<stdin>");
    load_file(&file, shown, options).map_err(|e| CliError::Stdin {
        reason: e
            .to_string()
            .replace(&file.display().to_string(), "<stdin>"),
    })
}

/// Loads `path`, naming it `shown` in warnings.
fn load_file(path: &Path, shown: &Path, options: &LoadOptions) -> Result<Loaded, CliError> {
    let loaded = patchwork::prep::load_with_options(path, options, &Bar::default())?;
    let scene = &loaded.scene;
    for w in scene.warnings.iter().chain(&loaded.warnings) {
        note!("warning: {}: {w}", shown.display());
    }
    if !scene.skipped.is_empty() {
        note!(
            "warning: {}: {} face(s) skipped:",
            shown.display(),
            scene.skipped.len()
        );
        for s in &scene.skipped {
            note!("  face #{}: {}", s.face, s.reason);
        }
    }
    Ok(loaded)
}

/// Loads `files` as [`load`] does; several are merged into one scene ([`patchwork::model::
/// merge`]: each file a top-level part named after it, as written, in one unit; what was
/// converted is said on stderr) without pending hierarchies (drawn from the cache or at full
/// resolution).
pub fn load_all(files: &[PathBuf], options: &LoadOptions) -> Result<Loaded, CliError> {
    if let [file] = files {
        return load(file, options);
    }
    let mut named = Vec::with_capacity(files.len());
    for file in files {
        let name = file.file_name().map_or_else(
            || file.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        named.push(patchwork::model::merge::Named {
            name,
            scene: load(file, options)?.scene,
        });
    }
    let merged = patchwork::model::merge::merge(named)?;
    for n in &merged.notes {
        note!("note: {n}");
    }
    Ok(Loaded {
        scene: merged.scene,
        pending: None,
        warnings: Vec::new(),
    })
}

/// The files as one name for messages (`a.step + b.glb`).
pub fn shown(files: &[PathBuf]) -> PathBuf {
    let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    PathBuf::from(names.join(" + "))
}

/// Loads a model with every hierarchy built (or read from the cache `cache` names).
pub fn load_built(path: &Path, cache: &CacheArgs) -> Result<Scene, CliError> {
    Ok(load(path, &cache.options(Hierarchies::Build))?.scene)
}

/// Reports patches whose tessellation failed (their faces are not drawn in this frame).
pub fn report_failures(meshes: &[PatchMesh]) {
    let failed: Vec<&str> = meshes.iter().filter_map(|m| m.failure.as_deref()).collect();
    warn_list(
        &format!("{} patch(es) could not be tessellated", failed.len()),
        &failed,
    );
}

/// A warning `heading:` on stderr with the first ten `items` below it (and how many more);
/// nothing when there are none.
pub fn warn_list(heading: &str, items: &[impl std::fmt::Display]) {
    if items.is_empty() {
        return;
    }
    note!("warning: {heading}:");
    for item in items.iter().take(10) {
        note!("  {item}");
    }
    if items.len() > 10 {
        note!("  … and {} more", items.len() - 10);
    }
}

/// A progress bar over `n` `what`s (views, frames) on stderr.
pub fn progress(n: usize, what: &str) -> ProgressBar {
    if !crate::out::diagnostics() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(n as u64);
    pb.set_style(
        ProgressStyle::with_template(&format!("{{bar:40}} {{pos}}/{{len}} {what} {{elapsed}}"))
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb
}

/// Load progress drawn as a bar on stderr (indicatif draws nothing when stderr is not a
/// terminal); the library reports, the binary draws.
#[derive(Debug, Default)]
pub struct Bar(std::sync::Mutex<Option<ProgressBar>>);

impl patchwork::prep::Progress for Bar {
    fn begin(&self, what: &str, total: usize) {
        let mut slot = self.0.lock().unwrap_or_else(|e| e.into_inner());
        *slot = Some(progress(total, what));
    }

    fn advance(&self) {
        if let Some(pb) = self.0.lock().unwrap_or_else(|e| e.into_inner()).as_ref() {
            pb.inc(1);
        }
    }

    fn end(&self) {
        if let Some(pb) = self.0.lock().unwrap_or_else(|e| e.into_inner()).take() {
            pb.finish_and_clear();
        }
    }
}
