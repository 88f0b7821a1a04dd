//! Splitting a mesh into patches: breadth-first region growing over edge-adjacent triangles
//! to about a target size, small regions merged into a neighbour (load-time work for
//! [`super::mesh_scene`]).

use std::collections::HashMap;

use crate::model::mesh::{MeshPatch, TriMesh, edge, extract, vertex_normals};

/// For every triangle, the triangles sharing each of its edges (non-manifold edges: all of
/// them; boundary edges: none).
fn adjacency(mesh: &TriMesh) -> Vec<Vec<u32>> {
    let mut by_edge: HashMap<(u32, u32), Vec<u32>> =
        HashMap::with_capacity(mesh.triangles.len() * 2);
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            by_edge
                .entry(edge(tri[k], tri[(k + 1) % 3]))
                .or_default()
                .push(t as u32);
        }
    }
    let mut adj = vec![Vec::with_capacity(3); mesh.triangles.len()];
    for list in by_edge.values() {
        for &a in list {
            for &b in list {
                if a != b {
                    adj[a as usize].push(b);
                }
            }
        }
    }
    // Hash-map order differs between runs: sort, so partitions are reproducible.
    for list in adj.iter_mut() {
        list.sort_unstable();
    }
    adj
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
            for &u in &adj[t as usize] {
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
            for &u in &adj[t as usize] {
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
    let normals = vertex_normals(mesh);
    members.iter().map(|m| extract(mesh, &normals, m)).collect()
}
