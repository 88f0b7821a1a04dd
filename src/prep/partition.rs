//! Splitting a mesh into patches: breadth-first region growing over edge-adjacent triangles
//! to about a target size, small regions merged into a neighbour (load-time work for
//! [`super::mesh_scene`]).

use std::collections::HashMap;

use crate::model::mesh::{MeshPatch, TriMesh, edge, edge_uses, extract, normals_or_smooth};

/// For every triangle, the triangles sharing each of its edges (non-manifold edges: all of
/// them; boundary edges: none), sorted, as compressed rows: triangle `t`'s neighbours are
/// `list[start[t]..start[t + 1]]`. Built by grouping the (edge, triangle) pairs — no hash map,
/// no allocation per edge or triangle: counting sorts (the hash-map version took 0.4 s on
/// the bunny, mostly cache misses).
struct Adjacency {
    start: Vec<u32>,
    list: Vec<u32>,
}

impl Adjacency {
    fn of(&self, t: u32) -> &[u32] {
        &self.list[self.start[t as usize] as usize..self.start[t as usize + 1] as usize]
    }
}

/// Compressed rows of `items` grouped by `key(item) < groups` (a counting sort, stable).
fn rows<T: Copy>(groups: usize, items: &[T], key: impl Fn(&T) -> usize) -> (Vec<u32>, Vec<T>) {
    let mut start = vec![0u32; groups + 1];
    for x in items {
        start[key(x) + 1] += 1;
    }
    for g in 0..groups {
        start[g + 1] += start[g];
    }
    let mut fill = start.clone();
    let mut out = items.to_vec();
    for x in items {
        let k = key(x);
        out[fill[k] as usize] = *x;
        fill[k] += 1;
    }
    (start, out)
}

/// Edge adjacency within each [`TriMesh::groups`] run: triangles of different groups (parts
/// or colours) are never neighbours, so no patch crosses a group.
fn adjacency(mesh: &TriMesh) -> Adjacency {
    let tri_group = mesh.triangle_groups();
    let n = mesh.triangles.len();
    // Vertices split by their normals (a crease, `TriMesh::position_ids`) are one here: the
    // faces on both sides of a crease are neighbours, and a patch may hold both.
    let vertices = mesh
        .position_ids
        .iter()
        .map(|&p| p as usize + 1)
        .max()
        .unwrap_or(0);
    let vertices = vertices.max(mesh.positions.len());
    // (smaller position, larger position, triangle) of every edge, grouped by the smaller
    // one, then each group sorted: equal edges are adjacent.
    let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * n);
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let tri = tri.map(|v| mesh.position_id(v));
        for k in 0..3 {
            let (a, b) = edge(tri[k], tri[(k + 1) % 3]);
            edges.push((a, b, t as u32));
        }
    }
    let (start, mut edges) = rows(vertices, &edges, |e| e.0 as usize);
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(3 * n);
    for v in 0..vertices {
        let group = &mut edges[start[v] as usize..start[v + 1] as usize];
        group.sort_unstable();
        for same in group.chunk_by(|x, y| x.1 == y.1) {
            for &(_, _, a) in same {
                for &(_, _, b) in same {
                    if a != b && tri_group[a as usize] == tri_group[b as usize] {
                        pairs.push((a, b));
                    }
                }
            }
        }
    }
    let (start, mut pairs) = rows(n, &pairs, |p| p.0 as usize);
    for t in 0..n {
        pairs[start[t] as usize..start[t + 1] as usize].sort_unstable();
    }
    Adjacency {
        start,
        list: pairs.into_iter().map(|(_, b)| b).collect(),
    }
}

/// Splits `mesh` into patches of about `target` triangles (≥ 1). Every triangle lands in
/// exactly one patch; regions smaller than a quarter of the target are merged into an
/// edge-adjacent patch when they have one.
pub fn partition(mesh: &TriMesh, target: usize) -> Vec<MeshPatch> {
    let target = target.max(1);
    let n = mesh.triangles.len();
    let adj = adjacency(mesh);
    let mut label = vec![u32::MAX; n];
    let mut sizes: Vec<usize> = Vec::new();
    let mut queue = std::collections::VecDeque::new();
    for seed in 0..n {
        if label[seed] != u32::MAX {
            continue;
        }
        let id = sizes.len() as u32;
        let mut size = 0;
        label[seed] = id;
        queue.clear();
        queue.push_back(seed as u32);
        while let Some(t) = queue.pop_front() {
            size += 1;
            if size >= target {
                break;
            }
            for &u in adj.of(t) {
                if label[u as usize] == u32::MAX && size + queue.len() < target {
                    label[u as usize] = id;
                    queue.push_back(u);
                }
            }
        }
        // Triangles queued but not visited stay in the patch (they were labelled).
        size += queue.len();
        sizes.push(size);
    }
    // Merge small regions into the neighbour they share most edges with.
    let mut by_label: Vec<Vec<u32>> = vec![Vec::new(); sizes.len()];
    for (t, &l) in label.iter().enumerate() {
        by_label[l as usize].push(t as u32);
    }
    let mut merged: Vec<u32> = (0..sizes.len() as u32).collect();
    let find = |merged: &Vec<u32>, mut x: u32| {
        while merged[x as usize] != x {
            x = merged[x as usize];
        }
        x
    };
    for id in 0..sizes.len() as u32 {
        if sizes[id as usize] * 4 >= target {
            continue;
        }
        let root = find(&merged, id);
        let mut counts: HashMap<u32, usize> = HashMap::new();
        for &t in &by_label[id as usize] {
            for &u in adj.of(t) {
                let other = find(&merged, label[u as usize]);
                if other != root {
                    *counts.entry(other).or_default() += 1;
                }
            }
        }
        if let Some((&into, _)) = counts
            .iter()
            .max_by_key(|(k, c)| (**c, std::cmp::Reverse(**k)))
        {
            merged[root as usize] = into;
            sizes[into as usize] += sizes[root as usize];
        }
    }
    // Renumber the surviving regions 0.. in order of first triangle.
    let mut number: HashMap<u32, usize> = HashMap::new();
    let mut members: Vec<Vec<u32>> = Vec::new();
    for (t, &l) in label.iter().enumerate() {
        let root = find(&merged, l);
        let k = *number.entry(root).or_insert_with(|| {
            members.push(Vec::new());
            members.len() - 1
        });
        members[k].push(t as u32);
    }
    // A welded mesh has its normals (the file's or creased); a bare one smooth normals.
    let normals = normals_or_smooth(mesh);
    let uses = edge_uses(&mesh.triangles);
    members
        .iter()
        .map(|m| extract(mesh, &normals, m, &uses))
        .collect()
}
