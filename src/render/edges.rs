//! The model's edges as a frame draws them: ~1 px lines along the border polylines the fat
//! borders are expanded from (`vs_edge` in `shaders/scene.wgsl`), so they follow the frame's
//! level of detail and need no geometry of their own. Each border point carries, in its
//! colour's alpha byte, the edge bits of its segment to the next point
//! (`super::fat_border::edge_bits`, from `PatchMesh::border_kinds`); a draw selects the
//! segments whose bits meet its [`Edges`] mode. [`segments`] is the CPU twin of that choice.
//!
//! Depth: a line lies on its own patch's triangles, and a neighbour's may be up to its ε in
//! front of it, so each end is pulled [`EDGE_PULL`] × ε towards the viewer along its ray (it
//! projects where it was) and depth-tested without writing depth. A surface more than that in
//! front of an edge hides it; fat borders, pushed back by ε, never do.

use glam::Vec3;

use super::Edges;
use super::fat_border::{BorderPoint, EDGE_BITS, INFO_CLOSING};

/// How far an edge line is pulled towards the viewer, × its patch's ε (`EDGE_PULL` in WGSL).
pub const EDGE_PULL: f32 = 2.0;

/// Whether the segment from point `s` to the next is drawn in mode `edges` (`edge_drawn`).
pub fn drawn(points: &[BorderPoint], s: usize, edges: Edges) -> bool {
    let p = &points[s];
    p.info & INFO_CLOSING == 0 && (p.color[3] & EDGE_BITS & edges.bits()) != 0
}

/// The segments (world end points, before the pull) drawn in mode `edges`, in draw order.
pub fn segments(points: &[BorderPoint], edges: Edges) -> Vec<[Vec3; 2]> {
    (0..points.len().saturating_sub(1))
        .filter(|&s| drawn(points, s, edges))
        .map(|s| [Vec3::from(points[s].cur), Vec3::from(points[s + 1].cur)])
        .collect()
}
