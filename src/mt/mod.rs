//! Multi-triangulation (MT) hierarchy of one mesh patch, after Holst and Schumann's reduced
//! MT hierarchies (the `holst-reduced-mt-hierarchy` paper, sections 2–3).
//!
//! The hierarchy is built by half-edge collapses ordered by the error they are expected to
//! have: Garland–Heckbert plane quadrics (plus constraint planes along the patch border so the
//! border keeps its shape) as a distance, raised lazily to a cheap estimate of the node error
//! (what it inherits, how far the original vertices it stands for are from its fan), so nodes
//! come roughly in the order of their errors. A half-edge collapse moves a vertex onto a neighbour, so no vertex is ever created:
//! the vertex buffer is the patch's own, built once. Every collapse is a **node**; every
//! triangle records the node that created it (0: the original mesh) and the node that removed
//! it (`NEVER`: still there at the coarsest level). Triangles sharing (creator, remover) form
//! the **arcs** of the DAG.
//!
//! **Node errors are certified two-sided Hausdorff bounds** (`bound`, issue 30 item 3): upper
//! bounds, not samples, of the distance between the fan a collapse creates and the original
//! surface. Original → fan: every piece of the original surface is given to one fan triangle
//! (the one whose farthest point from it is nearest) and measured against it exactly at its
//! corners (distance to a triangle is convex), split where that is loose; it stays with the
//! triangle until the triangle is removed, so every cut holding the triangle holds the bound.
//! Fan → original: the height of the surface over the fan triangle where it covers it, else
//! convex and Lipschitz bounds on parts of the triangle. Maxed with the errors of the nodes
//! whose triangles it removes — monotone along the DAG. A **cut** for ε draws the triangles
//! whose creator's error is ≤ ε and whose remover's is > ε: the nodes with error ≤ ε form a
//! closed set (monotonicity), so the cut is a valid triangulation of the patch within ε of the
//! original, two-sided. Patch borders collapse along themselves, corners too (the node error
//! measures what that costs); creases, where a patch's vertices are split by their normals,
//! are no border (`build_across_seams`); the gaps to neighbouring patches are covered by fat
//! borders like those of independently tessellated surfaces.
//!
//! The algorithms live in their own modules: `build` (half-edge collapses by quadric error,
//! Hausdorff node errors), `bound` (the certified distance bounds they use), `reduce` (Holst §4: arc collapse and the error adjustment) and
//! `cut` (Holst §3: cuts as per-arc index ranges, moved from frame to frame). This module
//! holds the hierarchy they share.

mod bound;
mod build;
mod cut;
pub mod group;
mod nearest;
mod reduce;

/// Triangles per arc the hierarchies of loaded meshes are reduced to (see the Table-1 bench
/// `mt_table` for the trade-off: larger arcs, fewer draw ranges, more triangles drawn).
pub const DEFAULT_ARC_SIZE: f64 = 5.0;

/// Largest ratio of node errors an arc collapse of a loaded mesh's hierarchy may merge
/// ([`MtHierarchy::reduce_within`]): measured on the bunny (`examples/mt_breakdown`), 1.1 keeps
/// its cuts within 1.5× of the unreduced hierarchy's triangles at every ε tried.
pub const MAX_MERGE_ERROR_RATIO: f64 = 1.1;

/// Remover of a triangle that is never removed.
pub const NEVER: u32 = u32::MAX;

/// The hierarchy of one patch.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtHierarchy {
    /// Every triangle that exists at some level, indices into the patch's vertices: the
    /// original ones first.
    pub triangles: Vec<[u32; 3]>,
    /// Node that created each triangle (0 = the original mesh).
    pub created_by: Vec<u32>,
    /// Node that removed each triangle, or [`NEVER`].
    pub removed_by: Vec<u32>,
    /// Error of every node (index 0 = the original mesh, error 0); monotone along the DAG.
    pub node_error: Vec<f64>,
    /// Node whose collapse moved each vertex away, or [`NEVER`].
    pub vertex_removed_by: Vec<u32>,
    /// Vertex each removed vertex was moved onto by its half-edge collapse (itself when never
    /// removed). The cut after a prefix of [`MtHierarchy::order`] is the original mesh with
    /// every removed vertex replaced by the end of its chain of targets, degenerate triangles
    /// dropped — what multiresolution strips (`strips::mts`) substitute in their sequences.
    pub vertex_target: Vec<u32>,
    /// Arcs: the triangles are sorted so that every arc's triangles are contiguous, arc `k`
    /// being `triangles[arc_start[k]..arc_start[k + 1]]`, created by `arc_nodes[k].0` and
    /// removed by `arc_nodes[k].1`. One static index range per arc.
    pub arc_start: Vec<u32>,
    pub arc_nodes: Vec<(u32, u32)>,
    /// The nodes in the order a coarsening cut applies them: by error, then by index — a
    /// linear extension of the DAG, because errors are monotone and indices topological.
    pub order: Vec<u32>,
    /// Position of every node in `order`.
    rank: Vec<u32>,
    /// Arcs every node creates (`out`) and removes (`into`), as compressed rows.
    out_start: Vec<u32>,
    out_arcs: Vec<u32>,
    in_start: Vec<u32>,
    in_arcs: Vec<u32>,
}

/// A cut kept from frame to frame (Holst §3: moving a cut applies or undoes only the nodes
/// between the old and the new error). The applied nodes are a prefix of
/// [`MtHierarchy::order`]; an arc is drawn when its creator is applied and its remover not.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CutState {
    applied: usize,
    active: Vec<bool>,
}

impl CutState {
    /// Number of applied nodes (the original mesh counts as one).
    pub fn applied(&self) -> usize {
        self.applied
    }
}

impl MtHierarchy {
    pub fn node_count(&self) -> usize {
        self.node_error.len()
    }

    /// Number of arcs (static index ranges).
    pub fn arc_count(&self) -> usize {
        self.arc_nodes.len()
    }
}

/// The stored fields of a hierarchy, everything else ([`MtHierarchy::order`], the arcs) being
/// derived from them: what a cache of built hierarchies (`io::mt_cache`) writes and reads.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtParts {
    pub triangles: Vec<[u32; 3]>,
    pub created_by: Vec<u32>,
    pub removed_by: Vec<u32>,
    pub node_error: Vec<f64>,
    pub vertex_removed_by: Vec<u32>,
    pub vertex_target: Vec<u32>,
}

impl MtHierarchy {
    /// The hierarchy without a single collapse: every cut is `triangles`, with error 0. What a
    /// mesh patch carries until its real hierarchy is built (the full-resolution mesh is
    /// within every ε), made in linear time.
    pub fn original(triangles: &[[u32; 3]], vertex_count: usize) -> MtHierarchy {
        let mut h = MtHierarchy {
            triangles: triangles.to_vec(),
            created_by: vec![0; triangles.len()],
            removed_by: vec![NEVER; triangles.len()],
            node_error: vec![0.0],
            vertex_removed_by: vec![NEVER; vertex_count],
            vertex_target: (0..vertex_count as u32).collect(),
            ..Default::default()
        };
        h.layout();
        h
    }

    /// Whether the hierarchy has no collapse (every cut is the original mesh): the one of
    /// [`MtHierarchy::original`], or a built one of a patch where nothing could collapse.
    pub fn is_original(&self) -> bool {
        self.node_error.len() <= 1
    }

    /// The stored fields (see [`MtParts`]).
    pub fn parts(&self) -> MtParts {
        MtParts {
            triangles: self.triangles.clone(),
            created_by: self.created_by.clone(),
            removed_by: self.removed_by.clone(),
            node_error: self.node_error.clone(),
            vertex_removed_by: self.vertex_removed_by.clone(),
            vertex_target: self.vertex_target.clone(),
        }
    }

    /// The hierarchy of stored fields for a patch of `vertex_count` vertices, after checking
    /// every invariant the cut algorithms rely on (lengths, index bounds, creators before
    /// removers, finite non-negative errors with node 0 at 0, errors monotone along every
    /// arc); the reason otherwise. Untrusted input (a cache file) cannot make it panic.
    pub(crate) fn from_parts(p: MtParts, vertex_count: usize) -> Result<MtHierarchy, String> {
        let (m, nodes) = (p.triangles.len(), p.node_error.len());
        if p.created_by.len() != m || p.removed_by.len() != m {
            return Err("creator / remover lists do not match the triangles".into());
        }
        if p.vertex_removed_by.len() != vertex_count || p.vertex_target.len() != vertex_count {
            return Err("vertex lists do not match the patch's vertices".into());
        }
        if nodes == 0 || p.node_error[0] != 0.0 {
            return Err("node 0 (the original mesh) missing or with an error".into());
        }
        if let Some(e) = p.node_error.iter().find(|e| !e.is_finite() || **e < 0.0) {
            return Err(format!(
                "node error {e} is not a finite non-negative number"
            ));
        }
        if p.triangles
            .iter()
            .flatten()
            .any(|&v| v as usize >= vertex_count)
        {
            return Err("a triangle's vertex is out of range".into());
        }
        for (&c, &r) in p.created_by.iter().zip(&p.removed_by) {
            if c as usize >= nodes || (r != NEVER && (r as usize >= nodes || r <= c)) {
                return Err(format!(
                    "arc ({c}, {r}) out of range or against the node order"
                ));
            }
            if r != NEVER && p.node_error[c as usize] > p.node_error[r as usize] {
                return Err(format!("errors not monotone along arc ({c}, {r})"));
            }
        }
        for (&n, &t) in p.vertex_removed_by.iter().zip(&p.vertex_target) {
            if (n != NEVER && n as usize >= nodes) || t as usize >= vertex_count {
                return Err("a vertex's remover or target is out of range".into());
            }
        }
        let mut h = MtHierarchy {
            triangles: p.triangles,
            created_by: p.created_by,
            removed_by: p.removed_by,
            node_error: p.node_error,
            vertex_removed_by: p.vertex_removed_by,
            vertex_target: p.vertex_target,
            ..Default::default()
        };
        h.layout();
        Ok(h)
    }
}

/// Meshes and measures shared by the tests of the hierarchy's modules.
#[cfg(test)]
pub(crate) mod fixtures {
    use std::collections::HashMap;

    use glam::{DVec3, Vec3};

    use super::build::samples;
    use crate::geom::point_triangle_distance;
    use crate::model::mesh::TriMesh;

    /// A bumpy n × n grid patch: z = 0.1 sin(x) cos(y).
    pub(super) fn bumpy(n: u32) -> TriMesh {
        let mut m = TriMesh::default();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 * 0.25, j as f32 * 0.25);
                m.positions.push(Vec3::new(x, y, 0.1 * x.sin() * y.cos()));
            }
        }
        let at = |i: u32, j: u32| j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                m.triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                m.triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        m
    }

    /// Largest distance from the points `points` picks on each triangle of one set to the
    /// other set, both ways: a two-sided Hausdorff distance over those points.
    fn two_sided(
        pos: &[DVec3],
        x: &[[u32; 3]],
        y: &[[u32; 3]],
        points: impl Fn([DVec3; 3]) -> Vec<DVec3>,
    ) -> f64 {
        let dist_to = |p: DVec3, tris: &[[u32; 3]]| {
            tris.iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| pos[i as usize]);
                    point_triangle_distance(p, a, b, c)
                })
                .fold(f64::INFINITY, f64::min)
        };
        let mut worst = 0.0f64;
        for (from, to) in [(x, y), (y, x)] {
            for t in from {
                for p in points(t.map(|i| pos[i as usize])) {
                    worst = worst.max(dist_to(p, to));
                }
            }
        }
        worst
    }

    /// Sampled two-sided Hausdorff distance between two triangle sets over `pos`.
    pub(super) fn sampled_hausdorff(pos: &[DVec3], x: &[[u32; 3]], y: &[[u32; 3]]) -> f64 {
        two_sided(pos, x, y, |[a, b, c]| {
            samples(a, b, c).into_iter().collect()
        })
    }

    /// Two-sided Hausdorff distance between two triangle sets over `pos`, measured densely:
    /// every triangle sampled on a barycentric grid of `k` steps per edge ((k+1)(k+2)/2
    /// points), independent of the 7 samples the build uses.
    pub(crate) fn dense_hausdorff(pos: &[DVec3], x: &[[u32; 3]], y: &[[u32; 3]], k: u32) -> f64 {
        two_sided(pos, x, y, |[a, b, c]| {
            (0..=k)
                .flat_map(|i| (0..=k - i).map(move |j| (i, j)))
                .map(|(i, j)| {
                    let (u, v) = (i as f64 / k as f64, j as f64 / k as f64);
                    a + (b - a) * u + (c - a) * v
                })
                .collect()
        })
    }

    pub(super) fn edges_used(tris: &[[u32; 3]]) -> HashMap<(u32, u32), u32> {
        let mut uses = HashMap::new();
        for t in tris {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        uses
    }
}
