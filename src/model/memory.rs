//! What a loaded scene holds in memory, estimated from its data structures: every `Vec`'s
//! capacity (or length where the capacity is private) times its element size, plus the structs
//! themselves. Shared surfaces (a trimmed face placed many times, a mesh patch) are counted
//! once, by pointer.
//!
//! Not counted: the allocator's own overhead per allocation (typically 8–16 bytes), the heap
//! inside truck's curves and surfaces (B-spline knots and control points of trimmed faces:
//! only their inline size is counted), and strings' and names' heap beyond their capacity. So
//! this is a lower bound of what the process holds for the scene; `patchwork stats` prints the
//! peak resident size beside it.

use std::collections::HashSet;
use std::mem::size_of;

use super::mesh::MeshPatch;
use super::trimmed::{LoopEdge, TrimEdge};
use super::{PatchSurface, Scene, TrimmedFace};

/// Bytes a scene holds, by kind (see the module doc for what is counted).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneMemory {
    /// The [`Patch`](crate::model::Patch) structs (`Scene::patches`' capacity × its size).
    pub patches: usize,
    /// The surfaces' own heap: Bézier control nets; each distinct trimmed face (struct,
    /// loops) and each distinct edge; each distinct mesh patch (vertices, triangles, borders,
    /// source maps, MT hierarchy).
    pub surfaces: usize,
    /// Parts, instances, skipped faces and warnings.
    pub other: usize,
}

impl SceneMemory {
    pub fn total(&self) -> usize {
        self.patches + self.surfaces + self.other
    }
}

/// `v`'s heap: capacity × element size.
fn vec_bytes<T>(v: &Vec<T>) -> usize {
    v.capacity() * size_of::<T>()
}

impl Scene {
    /// What the scene holds (see the module doc).
    pub fn memory(&self) -> SceneMemory {
        let mut faces: HashSet<*const TrimmedFace> = HashSet::new();
        let mut edges: HashSet<*const TrimEdge> = HashSet::new();
        let mut meshes: HashSet<*const MeshPatch> = HashSet::new();
        let mut surfaces = 0;
        for p in &self.patches {
            surfaces += match &p.surface {
                PatchSurface::Bezier(b) => std::mem::size_of_val(b.control_points()),
                PatchSurface::Trimmed(f) if faces.insert(std::sync::Arc::as_ptr(f)) => {
                    trimmed_face_bytes(f, &mut edges)
                }
                PatchSurface::Mesh(m) if meshes.insert(std::sync::Arc::as_ptr(m)) => {
                    mesh_patch_bytes(m)
                }
                _ => 0,
            };
        }
        let strings = |v: &[String]| v.iter().map(String::capacity).sum::<usize>();
        SceneMemory {
            patches: vec_bytes(&self.patches),
            surfaces,
            other: vec_bytes(&self.parts)
                + self.parts.iter().map(|p| p.name.capacity()).sum::<usize>()
                + vec_bytes(&self.instances)
                + self
                    .instances
                    .iter()
                    .map(|i| i.name.capacity())
                    .sum::<usize>()
                + vec_bytes(&self.skipped)
                + self
                    .skipped
                    .iter()
                    .map(|s| s.reason.capacity())
                    .sum::<usize>()
                + vec_bytes(&self.warnings)
                + strings(&self.warnings),
        }
    }
}

/// A trimmed face behind its `Arc` (two counters), its loops, its `fast` evaluation, and the
/// edges not seen yet.
fn trimmed_face_bytes(f: &TrimmedFace, edges: &mut HashSet<*const TrimEdge>) -> usize {
    let mut bytes = 2 * size_of::<usize>() + size_of::<TrimmedFace>() + vec_bytes(&f.loops);
    // Our evaluation's copy of a B-spline's knots and control points, behind its own `Arc`.
    if let Some(fast) = &f.fast {
        bytes +=
            2 * size_of::<usize>() + size_of::<super::nurbs::FastSurface>() + fast.heap_bytes();
    }
    for l in &f.loops {
        bytes += vec_bytes::<LoopEdge>(l);
        for e in l {
            if edges.insert(std::sync::Arc::as_ptr(&e.edge)) {
                bytes += 2 * size_of::<usize>() + size_of::<TrimEdge>();
            }
        }
    }
    bytes
}

/// A mesh patch behind its `Arc`: its arrays and its hierarchy's (the hierarchy's private
/// adjacency rows estimated from the node and arc counts: one rank and two row starts per
/// node, two arc entries per arc).
fn mesh_patch_bytes(m: &MeshPatch) -> usize {
    let h = &m.hierarchy;
    let private = (3 * h.node_count() + 2 + 2 * h.arc_count()) * size_of::<u32>();
    2 * size_of::<usize>()
        + size_of::<MeshPatch>()
        + vec_bytes(&m.positions)
        + vec_bytes(&m.normals)
        + vec_bytes(&m.triangles)
        + vec_bytes(&m.borders)
        + m.borders.iter().map(vec_bytes).sum::<usize>()
        + vec_bytes(&m.border_kinds)
        + m.border_kinds.iter().map(vec_bytes).sum::<usize>()
        + vec_bytes(&m.position_of)
        + vec_bytes(&m.outline)
        + m.outline.iter().map(vec_bytes).sum::<usize>()
        + vec_bytes(&m.outline_kinds)
        + m.outline_kinds.iter().map(vec_bytes).sum::<usize>()
        + vec_bytes(&m.source_triangles)
        + vec_bytes(&m.source_vertices)
        + vec_bytes(&h.triangles)
        + vec_bytes(&h.created_by)
        + vec_bytes(&h.removed_by)
        + vec_bytes(&h.node_error)
        + vec_bytes(&h.vertex_removed_by)
        + vec_bytes(&h.vertex_target)
        + vec_bytes(&h.arc_start)
        + vec_bytes(&h.arc_nodes)
        + vec_bytes(&h.order)
        + private
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::model::{BezierPatch, Patch, UpAxis};

    fn bilinear(dx: f64) -> BezierPatch {
        let c = vec![
            DVec3::new(dx, 0.0, 0.0),
            DVec3::new(dx, 1.0, 0.0),
            DVec3::new(dx + 1.0, 0.0, 0.0),
            DVec3::new(dx + 1.0, 1.0, 1.0),
        ];
        BezierPatch::new(1, 1, c).expect("valid")
    }

    #[test]
    fn bezier_scenes_count_structs_and_control_nets() {
        let one = Scene::from_bezier(vec![bilinear(0.0)], UpAxis::Z).memory();
        let three =
            Scene::from_bezier((0..3).map(|i| bilinear(i as f64)).collect(), UpAxis::Z).memory();
        // 4 control points of 24 bytes per patch.
        assert_eq!(one.surfaces, 96);
        assert_eq!(three.surfaces, 3 * 96);
        assert_eq!(three.patches, 3 * size_of::<Patch>());
        assert!(one.other > 0);
        assert_eq!(one.total(), one.patches + one.surfaces + one.other);
    }
}
