//! Shared helpers for tests that render on a real adapter.
#![allow(dead_code)]

use std::path::PathBuf;

use patchwork::model::Scene;
use patchwork::render::Renderer;

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub fn teapot() -> Scene {
    let path = root().join("models/teapot.bpt");
    patchwork::io::load(&path).unwrap_or_else(|e| panic!("cannot load the teapot: {e}"))
}

/// A model shipped in `models/`.
pub fn load(name: &str) -> Scene {
    let path = root().join("models").join(name);
    patchwork::io::load(&path).unwrap_or_else(|e| panic!("cannot load {name}: {e}"))
}

/// A renderer on whatever adapter exists. Tests that render must fail — not skip — when
/// there is none; the message says what to install.
pub fn renderer() -> Renderer {
    match Renderer::new() {
        Ok(r) => r,
        Err(e) => panic!("this test renders on a graphics adapter and found none: {e}"),
    }
}

/// A scratch folder under target/ for test outputs.
pub fn scratch(name: &str) -> PathBuf {
    let dir = root().join("target").join("test-output").join(name);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    dir
}
