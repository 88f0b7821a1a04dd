//! One module per command: its flags, and `run`, which checks them, calls the library and
//! prints. What several commands print the same way is here.

pub mod bench;
pub mod check;
pub mod export;
pub mod implode;
pub mod render;
pub mod stats;
#[cfg(feature = "viewer")]
pub mod view;

use std::path::Path;

use indicatif::{ProgressBar, ProgressStyle};

use patchwork::model::Scene;
use patchwork::prep::{Hierarchies, LoadOptions, Loaded};
use patchwork::tessellate::PatchMesh;

use crate::args::CacheArgs;
use crate::error::CliError;
use crate::out::note;

/// Loads a model as `options` say and tells the user (stderr) what was left out and why, and
/// what went wrong with the hierarchy cache.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Loaded, CliError> {
    let loaded = patchwork::prep::load_with_options(path, options, &Bar::default())?;
    let scene = &loaded.scene;
    for w in scene.warnings.iter().chain(&loaded.warnings) {
        note!("warning: {}: {w}", path.display());
    }
    if !scene.skipped.is_empty() {
        note!(
            "warning: {}: {} face(s) skipped:",
            path.display(),
            scene.skipped.len()
        );
        for s in &scene.skipped {
            note!("  face #{}: {}", s.face, s.reason);
        }
    }
    Ok(loaded)
}

/// Loads a model with every hierarchy built (or read from the cache `cache` names).
pub fn load_built(path: &Path, cache: &CacheArgs) -> Result<Scene, CliError> {
    Ok(load(path, &cache.options(Hierarchies::Build))?.scene)
}

/// Reports patches whose tessellation failed (their faces are not drawn in this frame).
pub fn report_failures(meshes: &[PatchMesh]) {
    let failed: Vec<&str> = meshes.iter().filter_map(|m| m.failure.as_deref()).collect();
    if !failed.is_empty() {
        note!(
            "warning: {} patch(es) could not be tessellated:",
            failed.len()
        );
        for f in failed.iter().take(10) {
            note!("  {f}");
        }
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
