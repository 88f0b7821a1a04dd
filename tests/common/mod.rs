//! Shared helpers for tests that render on a real adapter.
#![allow(dead_code)]

use std::path::PathBuf;

use glam::DVec3;
use patchwork::model::Scene;
use patchwork::render::Renderer;
use patchwork::view::{self, View};

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub fn teapot() -> Scene {
    let path = root().join("models/teapot.bpt");
    patchwork::prep::load(&path).unwrap_or_else(|e| panic!("cannot load the teapot: {e}"))
}

/// A model shipped in `models/`.
pub fn load(name: &str) -> Scene {
    let path = root().join("models").join(name);
    patchwork::prep::load(&path).unwrap_or_else(|e| panic!("cannot load {name}: {e}"))
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

/// The golden views' camera: 400×300, framing the scene from `dir`
/// (default three-quarter view).
pub fn golden_view(scene: &Scene, dir: Option<DVec3>) -> View {
    let up = scene.up.vector();
    let fov = view::DEFAULT_FOV_Y_DEG.to_radians();
    let size = (400, 300);
    match dir {
        None => View::framing(&scene.bounds, up, fov, size),
        Some(d) => View::framing_from(&scene.bounds, up, d, fov, size),
    }
}

/// The CLI's default camera for `scene` at 1024×768 (`View::framing`, the default field of
/// view), as `stats` measures fidelity.
pub fn framing(scene: &Scene) -> View {
    View::framing(
        &scene.bounds,
        scene.up.vector(),
        view::DEFAULT_FOV_Y_DEG.to_radians(),
        (1024, 768),
    )
}
