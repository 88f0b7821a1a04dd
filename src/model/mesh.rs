//! Triangle meshes split into patches.
//!
//! A [`TriMesh`] is welded (vertices at the same position are one vertex, split again where
//! their normals differ: [`super::creases`]) and split by
//! [`partition`](fn@crate::prep::partition) into patches of about a target number of triangles by region growing over
//! edge-adjacent triangles (breadth first from a seed, so patches come out compact), tiny
//! leftover regions merged into a neighbour. Each [`MeshPatch`] keeps its own vertices and the
//! border loops (edges it does not share with another of its triangles) along which fat borders
//! are drawn — the setting of Holst's reduced MT hierarchies, where every patch is simplified
//! independently.

use std::collections::HashMap;

use glam::Vec3;

use super::creases;
use super::edges::EdgeKind;
use crate::util::IntMap;

/// An indexed triangle mesh in world coordinates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    /// The file's vertex normals, one per position (empty: the file gives none; a zero vector:
    /// none for that vertex). After [`TriMesh::weld`]: one per vertex, always (the file's, or
    /// computed with creases, [`crate::model::creases`]).
    pub normals: Vec<Vec3>,
    /// After [`TriMesh::weld`]: for every vertex, the index of its position among the distinct
    /// positions — vertices split by their normals (a crease) share it, and edges across a
    /// crease are adjacent through it. Empty: every vertex is its own position.
    pub position_ids: Vec<u32>,
    pub triangles: Vec<[u32; 3]>,
    /// Runs of triangles from one source object (a glTF node's primitive), in order; empty:
    /// the whole mesh is one unnamed, uncoloured part. Patches never cross a group.
    pub groups: Vec<TriGroup>,
    /// Names of the parts groups belong to ([`TriGroup::part`] indexes it).
    pub part_names: Vec<String>,
    /// What the reader could not keep (a missing material file, colours it cannot draw).
    pub warnings: Vec<String>,
}

/// Triangles `previous end .. end` of a [`TriMesh`]: one part's, in one colour.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TriGroup {
    /// Index into [`TriMesh::part_names`].
    pub part: u32,
    /// Base colour (sRGB, 0..1), when the file gives one.
    pub color: Option<[f32; 3]>,
    /// One past the group's last triangle.
    pub end: usize,
}

impl TriMesh {
    /// The group of every triangle (all 0 without groups; triangles past the last group's end
    /// belong to the last group).
    pub(crate) fn triangle_groups(&self) -> Vec<u32> {
        let mut out = vec![0u32; self.triangles.len()];
        let mut start = 0;
        for (g, group) in self.groups.iter().enumerate() {
            let end = group.end.min(out.len());
            out[start.min(end)..end].fill(g as u32);
            start = end;
        }
        if let Some(last) = self.groups.len().checked_sub(1) {
            let from = start.min(out.len());
            out[from..].fill(last as u32);
        }
        out
    }

    /// The group record of group index `g` (a default one without groups).
    pub fn group(&self, g: u32) -> TriGroup {
        self.groups.get(g as usize).copied().unwrap_or_default()
    }

    /// The position index of vertex `v` ([`TriMesh::position_ids`]).
    pub(crate) fn position_id(&self, v: u32) -> u32 {
        self.position_ids.get(v as usize).copied().unwrap_or(v)
    }

    /// Merges vertices at bit-identical positions (glTF splits vertices by normal and texture
    /// coordinate), drops triangles that become degenerate (two equal corners), gives every
    /// corner a normal — the file's ([`TriMesh::normals`]) where it has one, else the
    /// area-weighted normal of the faces around it within `creases::CREASE_ANGLE_DEG`
    /// (`creases::creased_normals`) — and splits each position into one vertex per distinct
    /// normal (`creases::wedges`; [`TriMesh::position_ids`] says which vertices share a
    /// position). Without creases or split normals the vertices are the distinct positions in
    /// the order they first occur. Returns how many triangles were dropped.
    pub fn weld(&mut self) -> usize {
        let mut index: HashMap<[u32; 3], u32> = HashMap::with_capacity(self.positions.len());
        let mut positions = Vec::with_capacity(self.positions.len());
        let remap: Vec<u32> = self
            .positions
            .iter()
            .map(|p| {
                // +0.0 and −0.0 are the same point.
                let key = [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f32::to_bits);
                *index.entry(key).or_insert_with(|| {
                    positions.push(*p);
                    (positions.len() - 1) as u32
                })
            })
            .collect();
        let before = self.triangles.len();
        let groups = self.triangle_groups();
        let mut kept_groups = Vec::with_capacity(before);
        // The file's vertex of every kept corner, for its normal.
        let mut sources: Vec<[u32; 3]> = Vec::with_capacity(before);
        let welded: Vec<[u32; 3]> = (self.triangles.iter().zip(&groups))
            .map(|(t, &g)| (t.map(|i| remap[i as usize]), *t, g))
            .filter(|(t, _, _)| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
            .map(|(t, source, g)| {
                kept_groups.push(g);
                sources.push(source);
                t
            })
            .collect();
        let authored = |v: u32| {
            self.normals
                .get(v as usize)
                .filter(|n| n.is_finite())
                .map_or(Vec3::ZERO, |n| n.normalize_or_zero())
        };
        let mut corner_normals: Vec<Vec3> =
            sources.iter().flatten().map(|&v| authored(v)).collect();
        if corner_normals.contains(&Vec3::ZERO) {
            let computed = creases::creased_normals(&positions, &welded, creases::CREASE_ANGLE_DEG);
            for (n, c) in corner_normals.iter_mut().zip(computed) {
                if *n == Vec3::ZERO {
                    *n = c;
                }
            }
        }
        let (triangles, position_ids, normals) =
            creases::wedges(positions.len(), &welded, &corner_normals);
        self.positions = position_ids
            .iter()
            .map(|&p| positions[p as usize])
            .collect();
        self.normals = normals;
        self.position_ids = position_ids;
        self.triangles = triangles;
        // Each group ends where its last kept triangle is.
        for (g, group) in self.groups.iter_mut().enumerate() {
            group.end = kept_groups.partition_point(|&k| k <= g as u32);
        }
        before - self.triangles.len()
    }
}

/// One patch of a mesh: its own vertices, triangles and closed border loops.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshPatch {
    pub positions: Vec<Vec3>,
    /// The mesh's vertex normals ([`TriMesh::weld`]: the file's, or area-weighted within the
    /// crease angle), so shading is continuous across patch borders and hard at creases.
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Closed border loops as indices into `positions` (first vertex not repeated).
    pub borders: Vec<Vec<u32>>,
    /// Per border loop, per vertex k: the edge from vertex k to the next is a crease or a
    /// boundary of the mesh (one triangle of the whole mesh uses it: sharp) or where the mesh
    /// was cut into patches (two do: no edge); see `model::edges`.
    pub border_kinds: Vec<Vec<EdgeKind>>,
    /// Where vertices are split by their normals (a crease, [`TriMesh::position_ids`]): per
    /// vertex, the patch's first vertex at its position; empty when no vertex is split.
    pub position_of: Vec<u32>,
    /// With split vertices, the border loops of the surface with each position one vertex
    /// (the patch's outline: where it meets other patches or the mesh ends, its creases
    /// inside) and their kinds, as [`MeshPatch::borders`]: the borders of the hierarchy's cuts
    /// (built across creases, [`crate::mt::MtHierarchy::build_across_seams`]). Empty without.
    pub outline: Vec<Vec<u32>>,
    pub outline_kinds: Vec<Vec<EdgeKind>>,
    /// Indices of the patch's triangles in the partitioned mesh.
    pub source_triangles: Vec<u32>,
    /// Index in the partitioned mesh of every patch vertex.
    pub source_vertices: Vec<u32>,
    /// The patch's multi-resolution hierarchy (empty until built, see
    /// [`MeshPatch::build_hierarchy`]).
    pub hierarchy: crate::mt::MtHierarchy,
}

/// A coarse group of a mesh's patches (issue 30; [`crate::mt::group`]): one patch made of
/// its members' original triangles with its own hierarchy, drawn instead of them where its
/// cut has no more triangles than theirs ([`crate::mt::group::select`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshGroup {
    pub patch: std::sync::Arc<MeshPatch>,
    /// What it stands for and the finest error at which it may be drawn (`f64::INFINITY`
    /// until its hierarchy is built).
    pub links: crate::mt::group::GroupLinks,
    /// Bounding sphere of its vertices.
    pub bounds: super::Sphere,
    /// 1: a group of patches, 2: a group of level-1 groups (and maybe lone patches), …
    pub level: u32,
}

impl MeshPatch {
    /// Builds the patch's MT hierarchy ([`crate::mt`]) and reduces it by arc collapses to
    /// `arc_size` triangles per arc on average (no reduction below 1.5), merging only nodes
    /// whose errors are within [`crate::mt::MAX_MERGE_ERROR_RATIO`] of each other.
    pub fn build_hierarchy(&mut self, arc_size: f64) {
        self.hierarchy = crate::mt::MtHierarchy::build_across_seams(
            &self.positions,
            &self.position_of,
            &self.normals,
            &self.triangles,
        );
        if arc_size >= 1.5 {
            self.hierarchy
                .reduce_within(arc_size, crate::mt::MAX_MERGE_ERROR_RATIO);
        }
    }
}

/// Edge key with the smaller index first.
pub(crate) fn edge(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// The mesh's own vertex normals (a welded mesh has the file's or creased ones, see
/// [`TriMesh::weld`]), else smooth ones ([`vertex_normals`]).
pub(crate) fn normals_or_smooth(mesh: &TriMesh) -> std::borrow::Cow<'_, [Vec3]> {
    match mesh.normals.len() == mesh.positions.len() {
        true => std::borrow::Cow::Borrowed(&mesh.normals),
        false => std::borrow::Cow::Owned(vertex_normals(mesh)),
    }
}

/// Area-weighted vertex normals of `mesh` (zero for unused vertices).
pub(crate) fn vertex_normals(mesh: &TriMesh) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        // The cross product's length is twice the area: area weighting for free.
        let n = (b - a).cross(c - a);
        for &i in t {
            normals[i as usize] += n;
        }
    }
    for n in normals.iter_mut() {
        *n = n.normalize_or_zero();
    }
    normals
}

/// The patch made of `triangles` of `mesh`: local vertices with their `normals` (one per mesh
/// vertex, e.g. [`vertex_normals`]) and border loops.
/// How many triangles of `triangles` use each edge ([`edge`] keys): what
/// [`MeshPatch::border_kinds`] are made from.
pub(crate) fn edge_uses(triangles: &[[u32; 3]]) -> IntMap<(u32, u32), u32> {
    let mut uses: IntMap<(u32, u32), u32> = IntMap::default();
    for t in triangles {
        for k in 0..3 {
            *uses.entry(edge(t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    uses
}

/// The patch of `mesh` made of `triangles`; `uses` are the whole mesh's [`edge_uses`].
pub(crate) fn extract(
    mesh: &TriMesh,
    normals: &[Vec3],
    triangles: &[u32],
    uses: &IntMap<(u32, u32), u32>,
) -> MeshPatch {
    let mut local: IntMap<u32, u32> = IntMap::default();
    let mut positions = Vec::new();
    let mut sources = Vec::new();
    let mut tris = Vec::with_capacity(triangles.len());
    for &t in triangles {
        let tri = mesh.triangles[t as usize].map(|v| {
            *local.entry(v).or_insert_with(|| {
                positions.push(mesh.positions[v as usize]);
                sources.push(v);
                (positions.len() - 1) as u32
            })
        });
        tris.push(tri);
    }
    let borders = border_loops(&tris);
    let kind = |a: u32, b: u32| match uses.get(&edge(sources[a as usize], sources[b as usize])) {
        Some(&n) if n >= 2 => EdgeKind::None,
        _ => EdgeKind::Sharp,
    };
    let border_kinds = borders
        .iter()
        .map(|ring| {
            (0..ring.len())
                .map(|k| kind(ring[k], ring[(k + 1) % ring.len()]))
                .collect()
        })
        .collect();
    // Split vertices: each position's first vertex, and the loops of the merged surface.
    let mut first: IntMap<u32, u32> = IntMap::default();
    let mut position_of: Vec<u32> = (sources.iter().enumerate())
        .map(|(v, &s)| *first.entry(mesh.position_id(s)).or_insert(v as u32))
        .collect();
    let (mut outline, mut outline_kinds) = (Vec::new(), Vec::new());
    if position_of.iter().enumerate().all(|(v, &r)| r == v as u32) {
        position_of.clear();
    } else {
        let merged: Vec<[u32; 3]> = (tris.iter())
            .map(|t| t.map(|v| position_of[v as usize]))
            .collect();
        // Each merged border edge's own vertices (the triangle's that has it).
        let mut own: IntMap<(u32, u32), (u32, u32)> = IntMap::default();
        for (t, m) in tris.iter().zip(&merged) {
            for k in 0..3 {
                own.insert((m[k], m[(k + 1) % 3]), (t[k], t[(k + 1) % 3]));
            }
        }
        for ring in border_loops(&merged) {
            let n = ring.len();
            let edges: Vec<(u32, u32)> = (0..n)
                .map(|k| {
                    let e = (ring[k], ring[(k + 1) % n]);
                    // An open chain closed where it ends: no triangle has its closing edge.
                    own.get(&e).copied().unwrap_or(e)
                })
                .collect();
            outline_kinds.push(edges.iter().map(|&(a, b)| kind(a, b)).collect());
            outline.push(edges.iter().map(|&(a, _)| a).collect());
        }
    }
    let normals = sources
        .iter()
        .map(|&v| normals.get(v as usize).copied().unwrap_or(Vec3::ZERO))
        .collect();
    MeshPatch {
        positions,
        normals,
        triangles: tris,
        borders,
        border_kinds,
        position_of,
        outline,
        outline_kinds,
        source_triangles: triangles.to_vec(),
        source_vertices: sources,
        hierarchy: Default::default(),
    }
}

/// Closed loops of the edges used by exactly one triangle, walked in the triangles' winding.
/// At a vertex where several border loops meet, each outgoing edge is used once.
pub fn border_loops(triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let uses = edge_uses(triangles);
    // Directed border edges a → b, by start vertex.
    let mut next: IntMap<u32, Vec<u32>> = IntMap::default();
    let mut starts = Vec::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if uses[&edge(a, b)] == 1 {
                next.entry(a).or_default().push(b);
                starts.push(a);
            }
        }
    }
    let mut loops = Vec::new();
    for s in starts {
        let Some(first) = next.get_mut(&s).and_then(|v| v.pop()) else {
            continue;
        };
        let mut ring = vec![s];
        let mut at = first;
        while at != s {
            ring.push(at);
            match next.get_mut(&at).and_then(|v| v.pop()) {
                Some(b) => at = b,
                // An open chain (inconsistent winding): close it where it ends.
                None => break,
            }
        }
        if ring.len() >= 2 {
            loops.push(ring);
        }
    }
    loops
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prep::partition;

    /// An n × n grid of quads (2 triangles each) in the plane z = 0.
    fn grid(n: u32) -> TriMesh {
        let mut m = TriMesh::default();
        for j in 0..=n {
            for i in 0..=n {
                m.positions.push(Vec3::new(i as f32, j as f32, 0.0));
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

    #[test]
    fn welding_merges_equal_positions_and_drops_degenerate_triangles() {
        let mut m = TriMesh {
            positions: vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Y,
                Vec3::X,                   // duplicate of 1
                Vec3::new(-0.0, 0.0, 0.0), // −0 equals +0
                Vec3::ONE,
            ],
            triangles: vec![[0, 1, 2], [3, 5, 2], [0, 4, 1]],
            ..TriMesh::default()
        };
        let bare = m.clone();
        // The file's normals, equal on both faces: smooth.
        m.normals = vec![Vec3::Z; 6];
        let dropped = m.weld();
        assert_eq!(dropped, 1);
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [1, 3, 2]]);
        assert_eq!(m.normals, vec![Vec3::Z; 4]);
        assert_eq!(m.position_ids, vec![0, 1, 2, 3]);
        // Without normals the faces meet at 54.7° (> 40°): the shared edge 1–2 is a crease,
        // its two vertices split in two, each with its face's normal.
        let mut m = bare;
        assert_eq!(m.weld(), 1);
        assert_eq!(m.position_ids, vec![0, 1, 1, 2, 2, 3]);
        assert_eq!(m.triangles, vec![[0, 1, 3], [2, 5, 4]]);
        assert_eq!(m.normals[1], Vec3::Z);
        assert!((m.normals[2] - Vec3::new(-1.0, -1.0, 1.0).normalize()).length() < 1e-6);
        assert_eq!(m.positions[1], m.positions[2]);
    }

    #[test]
    fn partition_covers_every_triangle_once_with_sizes_near_the_target() {
        let m = grid(40); // 3 200 triangles
        let patches = partition(&m, 400);
        let mut seen = vec![0; m.triangles.len()];
        for p in &patches {
            for &t in &p.source_triangles {
                seen[t as usize] += 1;
            }
            assert!(p.triangles.len() >= 100, "{}", p.triangles.len());
            assert!(p.triangles.len() <= 400 + 100, "{}", p.triangles.len());
            // Local triangles are the source triangles, renumbered.
            for (lt, &t) in p.triangles.iter().zip(&p.source_triangles) {
                let src = m.triangles[t as usize];
                for k in 0..3 {
                    assert_eq!(p.positions[lt[k] as usize], m.positions[src[k] as usize]);
                }
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
        assert!(
            patches.len() >= 6 && patches.len() <= 16,
            "{}",
            patches.len()
        );
    }

    #[test]
    fn border_loops_are_closed_and_cover_every_boundary_edge() {
        let m = grid(6);
        let patches = partition(&m, 20);
        for p in &patches {
            let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
            for t in &p.triangles {
                for k in 0..3 {
                    *uses.entry(edge(t[k], t[(k + 1) % 3])).or_default() += 1;
                }
            }
            let boundary: std::collections::HashSet<(u32, u32)> = uses
                .iter()
                .filter(|(_, c)| **c == 1)
                .map(|(e, _)| *e)
                .collect();
            let mut walked = std::collections::HashSet::new();
            for ring in &p.borders {
                for k in 0..ring.len() {
                    let e = edge(ring[k], ring[(k + 1) % ring.len()]);
                    assert!(
                        boundary.contains(&e),
                        "loop edge {e:?} is not a border edge"
                    );
                    walked.insert(e);
                }
            }
            assert_eq!(walked, boundary);
        }
        // A whole grid has one loop around it.
        let normals = vertex_normals(&m);
        let whole = extract(
            &m,
            &normals,
            &(0..m.triangles.len() as u32).collect::<Vec<_>>(),
            &edge_uses(&m.triangles),
        );
        assert_eq!(whole.normals.len(), whole.positions.len());
        assert!(whole.normals.iter().all(|n| (n.z - 1.0).abs() < 1e-6));
        assert_eq!(whole.borders.len(), 1);
        assert_eq!(whole.borders[0].len(), 24);
    }

    #[test]
    fn partitions_are_reproducible() {
        let m = grid(30);
        let a = partition(&m, 150);
        for _ in 0..3 {
            assert_eq!(partition(&m, 150), a);
        }
    }

    #[test]
    fn a_closed_mesh_has_no_border() {
        // Tetrahedron, consistently wound.
        let m = TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]],
            ..TriMesh::default()
        };
        let patches = partition(&m, 100);
        assert_eq!(patches.len(), 1);
        assert!(patches[0].borders.is_empty());
    }

    /// Two groups on one grid (left and right halves, interleaved in triangle order is not
    /// possible: groups are runs) share edges, yet no patch crosses them; welding a degenerate
    /// triangle away moves the group ends with it.
    #[test]
    fn patches_never_cross_groups_and_weld_keeps_group_ends() {
        let mut m = grid(16);
        let half = m.triangles.len() / 2;
        m.groups = vec![
            TriGroup {
                part: 0,
                color: Some([1.0, 0.0, 0.0]),
                end: half,
            },
            TriGroup {
                part: 1,
                color: None,
                end: m.triangles.len(),
            },
        ];
        m.part_names = vec!["a".into(), "b".into()];
        let of = m.triangle_groups();
        let patches = partition(&m, 400);
        for p in &patches {
            let g = of[p.source_triangles[0] as usize];
            assert!(
                p.source_triangles.iter().all(|&t| of[t as usize] == g),
                "a patch crosses the groups"
            );
        }
        // Ungrouped, one 400-triangle region spans both halves.
        let mut plain = m.clone();
        plain.groups.clear();
        let crossing = partition(&plain, 400).iter().any(|p| {
            let g = of[p.source_triangles[0] as usize];
            p.source_triangles.iter().any(|&t| of[t as usize] != g)
        });
        assert!(crossing, "the control: without groups a patch does cross");
        // A degenerate triangle in group 0 goes; group 0 ends one earlier.
        m.triangles[0] = [0, 0, 1];
        assert_eq!(m.weld(), 1);
        assert_eq!(m.groups[0].end, half - 1);
        assert_eq!(m.groups[1].end, m.triangles.len());
    }
}
