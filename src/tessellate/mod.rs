//! Independent per-patch tessellation under an object-space tolerance.
//!
//! Every patch is tessellated on its own, from its own ε: neighbours get different
//! resolutions, so their shared borders do not match (T-junctions). The gaps are not stitched;
//! they are covered by fat borders at draw time (see `render::fat_border`).

pub mod bezier;

pub use bezier::{BezierTessellator, MAX_SEGMENTS, Resolution};

use glam::Vec3;
use rayon::prelude::*;

use crate::model::Scene;
use crate::view::View;

/// What is drawn for one patch: triangles, the closed border loops, and the error achieved.
#[derive(Clone, Debug, Default)]
pub struct PatchMesh {
    pub patch_id: u32,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Closed border loops as indices into `positions` (first vertex not repeated at the end);
    /// consecutive duplicates (collapsed edges at poles) are removed.
    pub borders: Vec<Vec<u32>>,
    /// Tolerance asked for, object units.
    pub eps_target: f64,
    /// Measured maximum distance between surface and triangles (sampled), object units.
    pub error: f64,
    /// Grid resolution used.
    pub resolution: Resolution,
}

impl PatchMesh {
    /// Error the fat borders of this patch must cover: the larger of target and achieved.
    pub fn eps_border(&self) -> f64 {
        self.eps_target.max(self.error)
    }

    pub fn border_vertex_count(&self) -> usize {
        self.borders.iter().map(Vec::len).sum()
    }
}

/// Tessellates every patch of `scene` for `view` at `pixel_error`, in parallel.
pub fn tessellate_scene(scene: &Scene, view: &View, pixel_error: f64) -> Vec<PatchMesh> {
    scene
        .patches
        .par_iter()
        .map_init(BezierTessellator::new, |t, patch| {
            let eps = view.eps_obj(&patch.bounds, pixel_error);
            let mut mesh = PatchMesh::default();
            t.tessellate(&patch.surface, eps, &mut mesh);
            mesh.patch_id = patch.id;
            mesh
        })
        .collect()
}

/// Tessellates every patch on one shared uniform `n × n` parameter grid (no error control).
/// Patches sharing a border curve with the same parameterisation then share border vertices,
/// which the crack check uses as its watertight reference.
pub fn tessellate_scene_uniform(scene: &Scene, n: u32) -> Vec<PatchMesh> {
    scene
        .patches
        .par_iter()
        .map_init(BezierTessellator::new, |t, patch| {
            let mut mesh = PatchMesh::default();
            t.tessellate_grid(&patch.surface, Resolution { nu: n, nv: n }, 0.0, &mut mesh);
            mesh.patch_id = patch.id;
            mesh
        })
        .collect()
}

/// Totals over a set of patch meshes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MeshStats {
    pub patches: usize,
    pub triangles: usize,
    pub vertices: usize,
    pub border_vertices: usize,
    pub eps_min: f64,
    pub eps_max: f64,
    /// Largest measured error relative to its patch's target (≤ 1 when every patch holds).
    pub worst_error_ratio: f64,
}

impl MeshStats {
    pub fn of(meshes: &[PatchMesh]) -> MeshStats {
        let mut s = MeshStats {
            patches: meshes.len(),
            eps_min: f64::INFINITY,
            eps_max: 0.0,
            ..MeshStats::default()
        };
        for m in meshes {
            s.triangles += m.triangles.len();
            s.vertices += m.positions.len();
            s.border_vertices += m.border_vertex_count();
            s.eps_min = s.eps_min.min(m.eps_target);
            s.eps_max = s.eps_max.max(m.eps_target);
            if m.eps_target > 0.0 {
                s.worst_error_ratio = s.worst_error_ratio.max(m.error / m.eps_target);
            }
        }
        if meshes.is_empty() {
            s.eps_min = 0.0;
        }
        s
    }
}
