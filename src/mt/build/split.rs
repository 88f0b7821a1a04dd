//! Split vertices in the MT build (`super`, [`MtHierarchy::build_across_seams`]): a position
//! whose vertices differ by their normals (a crease, `model::creases`) is one vertex of the
//! builder's topology, and each collapse of it moves every vertex there onto one at the target
//! position, so the hierarchy's triangles keep the normals of their side of the crease.
//!
//! [`MtHierarchy::build_across_seams`]: super::MtHierarchy::build_across_seams

use glam::Vec3;

use super::{Builder, MtHierarchy};

impl MtHierarchy {
    /// [`MtHierarchy::build`] across seams: the vertices at one position (`position_of`: per
    /// vertex, the first vertex at its position, as `model::mesh::MeshPatch::position_of`
    /// has it; empty when no vertex is split) are one vertex of the surface being simplified,
    /// so a crease is not a border and may be collapsed along and across like any edge, the
    /// node errors (geometric) saying what that costs. The hierarchy's triangles still index
    /// the split vertices: a collapse moves each vertex at the removed position onto the
    /// vertex at the target position that a vanishing triangle pairs it with, else onto the
    /// one with the nearest normal (`normals`, one per vertex; the first without them), so a
    /// triangle keeps the normals of its side of the crease.
    pub fn build_across_seams(
        positions: &[Vec3],
        position_of: &[u32],
        normals: &[Vec3],
        triangles: &[[u32; 3]],
    ) -> MtHierarchy {
        let wedges = (position_of.len() == positions.len()).then(|| Wedges {
            rep: position_of.to_vec(),
            normals: normals.to_vec(),
        });
        Builder::new(positions, triangles, wedges).run()
    }
}

/// Vertices split at one position ([`MtHierarchy::build_across_seams`]).
pub(super) struct Wedges {
    /// Per vertex: the first vertex at its position (the one the builder's topology uses).
    pub(super) rep: Vec<u32>,
    pub(super) normals: Vec<Vec3>,
}

/// What the builder keeps of split vertices: the topology (`Builder::tris`) uses each
/// position's first vertex, and these the vertices the triangles really have.
pub(super) struct Split {
    pub(super) rep: Vec<u32>,
    pub(super) normals: Vec<Vec3>,
    /// Per first vertex of a position, every vertex there (empty for the others).
    pub(super) at: Vec<Vec<u32>>,
    /// Every triangle's own vertices (`Builder::tris` with each corner's split vertex).
    pub(super) tris: Vec<[u32; 3]>,
    /// Per vertex: the vertex its position's collapse moved it onto (itself until then).
    pub(super) target: Vec<u32>,
}

impl Split {
    /// The vertex at `to` that vertex `w` (at the removed position) moves onto: the one the
    /// triangles `around` (those of the removed position) that hold `to` pair it with, else
    /// the one with the nearest normal, else the first; `None` when two triangles pair it
    /// with different ones (the collapse would leave a triangle of zero area where
    /// substituting vertices, as multiresolution strips do, expects none).
    pub(super) fn target_of(
        &self,
        w: u32,
        to: u32,
        around: &[u32],
        topo: &[[u32; 3]],
    ) -> Option<u32> {
        let mut paired = None;
        for &t in around {
            let Some(j) = topo[t as usize].iter().position(|&x| x == to) else {
                continue;
            };
            let own = self.tris[t as usize];
            if !own.contains(&w) {
                continue;
            }
            match paired {
                None => paired = Some(own[j]),
                Some(p) if p != own[j] => return None,
                Some(_) => {}
            }
        }
        if paired.is_some() {
            return paired;
        }
        let at = &self.at[to as usize];
        let n = self.normals.get(w as usize).copied().unwrap_or(Vec3::ZERO);
        let mut best = (at[0], f32::NEG_INFINITY);
        for &x in at {
            let d = self.normals.get(x as usize).map_or(0.0, |m| m.dot(n));
            if d > best.1 {
                best = (x, d);
            }
        }
        Some(best.0)
    }
}
