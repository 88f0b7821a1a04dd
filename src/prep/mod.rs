//! Load-time preparation, the stage between reading a file ([`crate::io`]) and everything that
//! uses a scene: a mesh is welded, split into patches and given its MT hierarchies
//! ([`crate::mt`]); a STEP model's faces are probed and placed ([`step`]). The scene that
//! comes out is immutable: per-view state lives in the frame loop and the renderer.
//!
//! Long steps report to a [`Progress`] the caller passes (the binary draws a bar); the
//! library itself prints nothing.

pub mod partition;
pub mod step;

use std::path::Path;

use std::sync::Arc;

use glam::DMat4;

pub use partition::partition;

use crate::io::{LoadError, Model};
use crate::model::mesh::TriMesh;
use crate::model::{Patch, PatchSurface, Scene, Sphere, UpAxis, bounding_box};

/// Triangles per patch when a mesh is split into patches (the 1–2 k).
pub const DEFAULT_PATCH_TRIANGLES: usize = 1500;

use crate::util::Bar;
pub use crate::util::{NoProgress, Progress};

/// Reads and prepares a model (see [`crate::io::read`] for the formats).
pub fn load(path: &Path) -> Result<Scene, LoadError> {
    load_with(path, &NoProgress)
}

/// As [`load`], reporting long steps to `progress`.
pub fn load_with(path: &Path, progress: &dyn Progress) -> Result<Scene, LoadError> {
    prepare(crate::io::read_with(path, progress)?, progress)
}

/// Prepares a model read by [`crate::io::read`].
pub fn prepare(model: Model, progress: &dyn Progress) -> Result<Scene, LoadError> {
    Ok(match model {
        Model::Bezier(patches) => Scene::from_bezier(patches, UpAxis::Z),
        Model::Mesh(mesh) => mesh_scene(
            mesh,
            DEFAULT_PATCH_TRIANGLES,
            crate::mt::DEFAULT_ARC_SIZE,
            UpAxis::Y,
            progress,
        ),
        Model::Step(model) => step::assemble(*model, progress)?,
    })
}

/// Builds a scene from a triangle mesh: welded, split into patches of about
/// `patch_triangles` triangles ([`partition`]), each with its MT hierarchy reduced
/// to `arc_size` triangles per arc (built on rayon, reported to `progress`).
pub fn mesh_scene(
    mut m: TriMesh,
    patch_triangles: usize,
    arc_size: f64,
    up: UpAxis,
    progress: &dyn Progress,
) -> Scene {
    let dropped = m.weld();
    let mut warnings = Vec::new();
    if dropped > 0 {
        warnings.push(format!(
            "{dropped} degenerate triangles dropped after welding"
        ));
    }
    let bbox = bounding_box(m.positions.iter().map(|p| p.as_dvec3())).unwrap_or_default();
    let mut parts = partition(&m, patch_triangles);
    {
        use rayon::prelude::*;
        let bar = Bar::begin(progress, "patch hierarchies", parts.len(), 20);
        parts.par_iter_mut().for_each(|p| {
            p.build_hierarchy(arc_size);
            bar.advance();
        });
    }
    let patches: Vec<Patch> = parts
        .into_iter()
        .enumerate()
        .map(|(i, p)| Patch {
            id: i as u32,
            bounds: Sphere::around(p.positions.iter().map(|v| v.as_dvec3())),
            surface: PatchSurface::Mesh(Arc::new(p)),
            transform: DMat4::IDENTITY,
            part: 0,
            color: None,
            instance: 0,
        })
        .collect();
    Scene::single_part(patches, up, bbox, warnings)
}
