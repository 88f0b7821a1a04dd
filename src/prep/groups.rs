//! Coarse groups of a mesh's patches (issue 30; what a group is and when it is drawn:
//! [`crate::mt::group`]). Level by level, adjacent units (patches, then groups) of one part
//! and colour are gathered breadth-first into groups of about [`UNITS_PER_GROUP`], groups
//! under half that merged into the neighbour they share most edges with — clusterlod's
//! "partition clusters into groups" step (`demo/clusterlod.h` in meshoptimizer), without its
//! border locking: fat borders cover the gaps. A unit left alone goes up a level as it is.
//! Each group is one [`MeshPatch`] of its members' *original* triangles, so its hierarchy's
//! errors are certified against the original surface like a patch's.
//!
//! Reproducible: units are visited in index order and neighbours in index order. Not done:
//! grouping disconnected pieces (units only join across a shared edge).

use crate::model::mesh::{MeshPatch, TriMesh, edge, edge_uses, extract, normals_or_smooth};
use crate::mt::group::Unit;
use crate::util::IntMap;

/// Units (patches, or groups of the level below) per group.
pub const UNITS_PER_GROUP: usize = 8;

/// Levels of groups above the patches at most: each costs one more hierarchy build over the
/// whole mesh; two make a bunny-sized mesh (96 patches) one or two units when far.
pub const GROUP_LEVELS: u32 = 2;

/// A group before its hierarchy is built.
#[derive(Debug)]
pub(crate) struct GroupPart {
    pub patch: MeshPatch,
    pub members: Vec<Unit>,
    pub level: u32,
}

/// What a patch may be grouped with: its part and colour (bits).
pub(crate) type GroupKey = (u32, Option<[u32; 3]>);

/// The groups of `patches` (a partition of `mesh`, [`super::partition`]), members before
/// their groups; `keys[p]` says what patch `p` may be grouped with.
pub(crate) fn group_parts(
    mesh: &TriMesh,
    patches: &[MeshPatch],
    keys: &[GroupKey],
    per_group: usize,
    levels: u32,
) -> Vec<GroupPart> {
    let per_group = per_group.max(2);
    // Pairs of triangles of different patches sharing an edge (through positions, as the
    // partition's adjacency, so across creases).
    let mut tri_unit = vec![0u32; mesh.triangles.len()];
    for (p, patch) in patches.iter().enumerate() {
        for &t in &patch.source_triangles {
            tri_unit[t as usize] = p as u32;
        }
    }
    let mut first: IntMap<(u32, u32), u32> = IntMap::default();
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let tri = tri.map(|v| mesh.position_id(v));
        for k in 0..3 {
            let e = edge(tri[k], tri[(k + 1) % 3]);
            match first.get(&e) {
                Some(&s) if tri_unit[s as usize] != tri_unit[t] => pairs.push((s, t as u32)),
                Some(_) => {}
                None => {
                    first.insert(e, t as u32);
                }
            }
        }
    }
    drop(first);
    let normals = normals_or_smooth(mesh);
    let uses = edge_uses(&mesh.triangles);

    let mut units: Vec<Unit> = (0..patches.len() as u32).map(Unit::Patch).collect();
    let mut unit_tris: Vec<Vec<u32>> = patches.iter().map(|p| p.source_triangles.clone()).collect();
    let mut unit_key: Vec<GroupKey> = keys.to_vec();
    let mut out: Vec<GroupPart> = Vec::new();
    for level in 1..=levels {
        let label = gather(&units, &unit_key, &tri_unit, &pairs, per_group);
        let count = label.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
        if count == units.len() {
            break;
        }
        let mut gathered: Vec<Vec<usize>> = vec![Vec::new(); count];
        for (u, &l) in label.iter().enumerate() {
            gathered[l as usize].push(u);
        }
        let (mut next, mut next_tris, mut next_key) = (Vec::new(), Vec::new(), Vec::new());
        for members in gathered {
            let key = unit_key[members[0]];
            if members.len() == 1 {
                next.push(units[members[0]]);
                next_tris.push(std::mem::take(&mut unit_tris[members[0]]));
            } else {
                let mut tris: Vec<u32> = members
                    .iter()
                    .flat_map(|&u| unit_tris[u].iter().copied())
                    .collect();
                tris.sort_unstable();
                out.push(GroupPart {
                    patch: extract(mesh, &normals, &tris, &uses),
                    members: members.iter().map(|&u| units[u]).collect(),
                    level,
                });
                next.push(Unit::Group(out.len() as u32 - 1));
                next_tris.push(tris);
            }
            next_key.push(key);
        }
        for (u, tris) in next_tris.iter().enumerate() {
            for &t in tris {
                tri_unit[t as usize] = u as u32;
            }
        }
        (units, unit_tris, unit_key) = (next, next_tris, next_key);
    }
    out
}

/// A group label (0.., in order of first unit) for every unit: breadth-first from each
/// unlabelled unit over neighbours of its key up to `per_group` units, then groups under
/// half of that merged into the neighbouring group they share most edges with.
fn gather(
    units: &[Unit],
    keys: &[GroupKey],
    tri_unit: &[u32],
    pairs: &[(u32, u32)],
    per_group: usize,
) -> Vec<u32> {
    let n = units.len();
    // Shared edges between units, as sorted neighbour lists with counts.
    let mut shared: IntMap<(u32, u32), u32> = IntMap::default();
    for &(s, t) in pairs {
        let (a, b) = (tri_unit[s as usize], tri_unit[t as usize]);
        if a != b && keys[a as usize] == keys[b as usize] {
            *shared.entry((a, b)).or_default() += 1;
            *shared.entry((b, a)).or_default() += 1;
        }
    }
    let mut near: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
    for (&(a, b), &c) in &shared {
        near[a as usize].push((b, c));
    }
    for list in &mut near {
        list.sort_unstable();
    }
    let mut label = vec![u32::MAX; n];
    let mut sizes: Vec<usize> = Vec::new();
    let mut queue = std::collections::VecDeque::new();
    for seed in 0..n {
        if label[seed] != u32::MAX {
            continue;
        }
        let id = sizes.len() as u32;
        label[seed] = id;
        let mut size = 1;
        queue.clear();
        queue.push_back(seed as u32);
        while let Some(u) = queue.pop_front() {
            for &(v, _) in &near[u as usize] {
                if size < per_group && label[v as usize] == u32::MAX {
                    label[v as usize] = id;
                    size += 1;
                    queue.push_back(v);
                }
            }
        }
        sizes.push(size);
    }
    // Merge small groups (in order) into the neighbour group sharing most edges.
    let mut into: Vec<u32> = (0..sizes.len() as u32).collect();
    let find = |into: &Vec<u32>, mut x: u32| {
        while into[x as usize] != x {
            x = into[x as usize];
        }
        x
    };
    for g in 0..sizes.len() as u32 {
        let root = find(&into, g);
        if sizes[root as usize] * 2 >= per_group {
            continue;
        }
        let mut counts: IntMap<u32, u32> = IntMap::default();
        for u in (0..n).filter(|&u| find(&into, label[u]) == root) {
            for &(v, c) in &near[u] {
                let other = find(&into, label[v as usize]);
                if other != root {
                    *counts.entry(other).or_default() += c;
                }
            }
        }
        let best = counts
            .iter()
            .filter(|&(&o, _)| sizes[o as usize] + sizes[root as usize] <= 2 * per_group)
            .max_by_key(|&(&o, &c)| (c, std::cmp::Reverse(o)));
        if let Some((&other, _)) = best {
            into[root as usize] = other;
            sizes[other as usize] += sizes[root as usize];
        }
    }
    // Renumber in order of first unit.
    let mut number: IntMap<u32, u32> = IntMap::default();
    (0..n)
        .map(|u| {
            let root = find(&into, label[u]);
            let next = number.len() as u32;
            *number.entry(root).or_insert(next)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An n × n grid of unit squares, two triangles each.
    fn grid(n: u32) -> TriMesh {
        let mut m = TriMesh::default();
        for j in 0..=n {
            for i in 0..=n {
                m.positions.push(glam::Vec3::new(
                    i as f32,
                    j as f32,
                    ((i * j) % 3) as f32 * 0.1,
                ));
            }
        }
        let at = |i: u32, j: u32| j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                m.triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                m.triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        m.weld();
        m
    }

    /// The patches of every unit, by recursion through the groups.
    fn patches_of(groups: &[GroupPart], u: Unit, out: &mut Vec<u32>) {
        match u {
            Unit::Patch(p) => out.push(p),
            Unit::Group(g) => {
                for &m in &groups[g as usize].members {
                    patches_of(groups, m, out);
                }
            }
        }
    }

    #[test]
    fn groups_partition_their_members_exactly() {
        let mesh = grid(40);
        let patches = super::super::partition(&mesh, 100);
        let keys = vec![(0, None); patches.len()];
        let groups = group_parts(&mesh, &patches, &keys, 4, 2);
        assert!(patches.len() >= 30, "{} patches", patches.len());
        assert!(groups.iter().any(|g| g.level == 2), "two levels");
        let mut held = vec![0u32; patches.len()];
        let mut held_group = vec![0u32; groups.len()];
        for (k, g) in groups.iter().enumerate() {
            assert!(g.members.len() >= 2);
            let mut mine = Vec::new();
            for &m in &g.members {
                match m {
                    Unit::Patch(p) => held[p as usize] += 1,
                    Unit::Group(h) => {
                        assert!((h as usize) < k, "members come first");
                        held_group[h as usize] += 1;
                    }
                }
                patches_of(&groups, m, &mut mine);
            }
            // The group's triangles are exactly its members' original ones.
            let mut expect: Vec<u32> = mine
                .iter()
                .flat_map(|&p| patches[p as usize].source_triangles.iter().copied())
                .collect();
            expect.sort_unstable();
            assert_eq!(g.patch.source_triangles, expect, "group {k}");
        }
        assert!(held.iter().all(|&c| c <= 1), "a patch in two groups");
        assert!(held_group.iter().all(|&c| c <= 1), "a group in two groups");
        // Level-1 groups hold patches only.
        assert!(
            groups
                .iter()
                .filter(|g| g.level == 1)
                .all(|g| { g.members.iter().all(|m| matches!(m, Unit::Patch(_))) })
        );
    }

    #[test]
    fn groups_never_join_different_keys() {
        let mesh = grid(20);
        let patches = super::super::partition(&mesh, 50);
        // Left and right halves by the patch's first triangle: two parts.
        let keys: Vec<GroupKey> = patches
            .iter()
            .map(|p| {
                let t = mesh.triangles[p.source_triangles[0] as usize];
                (u32::from(mesh.positions[t[0] as usize].x >= 10.0), None)
            })
            .collect();
        let groups = group_parts(&mesh, &patches, &keys, 4, 2);
        assert!(!groups.is_empty());
        for g in &groups {
            let mut mine = Vec::new();
            for &m in &g.members {
                patches_of(&groups, m, &mut mine);
            }
            assert!(
                mine.iter()
                    .all(|&p| keys[p as usize] == keys[mine[0] as usize])
            );
        }
    }

    #[test]
    fn grouping_is_reproducible() {
        let mesh = grid(30);
        let patches = super::super::partition(&mesh, 80);
        let keys = vec![(0, None); patches.len()];
        let a = group_parts(&mesh, &patches, &keys, 8, 2);
        let b = group_parts(&mesh, &patches, &keys, 8, 2);
        let members = |g: &[GroupPart]| g.iter().map(|g| g.members.clone()).collect::<Vec<_>>();
        assert_eq!(members(&a), members(&b));
    }

    /// Group hierarchies are certified like patches': built from the members' original
    /// triangles, every cut of a level-1 and a level-2 group of bunny patches is within its ε
    /// of those triangles, densely measured (28 points per triangle); the same hierarchies
    /// with halved node errors are not (the check can fail).
    #[test]
    fn group_cuts_hold_a_dense_hausdorff_bound() {
        use crate::mt::fixtures::dense_hausdorff;
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/models/bunny.glb");
        let crate::io::Model::Mesh(mut mesh) =
            crate::io::read(std::path::Path::new(path)).expect("the bunny loads")
        else {
            panic!("the bunny is a mesh");
        };
        mesh.weld();
        let patches = super::super::partition(&mesh, 100);
        let keys = vec![(0, None); patches.len()];
        let groups = group_parts(&mesh, &patches, &keys, 3, 2);
        let picks = [
            groups
                .iter()
                .find(|g| g.level == 1)
                .expect("a level-1 group"),
            groups
                .iter()
                .find(|g| g.level == 2)
                .expect("a level-2 group"),
        ];
        let (mut worst, mut halved_worst) = (0.0f64, 0.0f64);
        for g in picks {
            let p = &g.patch;
            assert!(p.triangles.len() > 250, "{} triangles", p.triangles.len());
            let pos: Vec<glam::DVec3> = p.positions.iter().map(|v| v.as_dvec3()).collect();
            let mut patch = p.clone();
            patch.build_hierarchy(crate::mt::DEFAULT_ARC_SIZE);
            let h = &patch.hierarchy;
            let mut errors: Vec<f64> = h.node_error.iter().copied().filter(|&e| e > 0.0).collect();
            errors.sort_by(f64::total_cmp);
            let mut cut = Vec::new();
            let mut halved_parts = h.parts();
            for e in &mut halved_parts.node_error {
                *e *= 0.5;
            }
            let halved = crate::mt::MtHierarchy::from_parts(halved_parts, pos.len())
                .expect("a valid hierarchy");
            for q in [0.2, 0.5, 0.8, 1.0] {
                let eps = errors[((errors.len() - 1) as f64 * q) as usize];
                h.cut(eps, &mut cut);
                worst = worst.max(dense_hausdorff(&pos, &cut, &p.triangles, 6) / eps);
                halved.cut(eps, &mut cut);
                halved_worst = halved_worst.max(dense_hausdorff(&pos, &cut, &p.triangles, 6) / eps);
            }
        }
        assert!(worst <= 1.0 + 1e-9, "dense Hausdorff {worst:.4} ε");
        assert!(
            halved_worst > 1.2,
            "halved errors pass ({halved_worst:.3} ε)"
        );
    }
}
