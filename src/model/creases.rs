//! Vertex normals of a welded triangle mesh: the file's own where it gives them, else
//! area-weighted normals that stay smooth across an edge only when its dihedral angle is at
//! most `CREASE_ANGLE_DEG` (a hard edge keeps a normal per side, as a modeller's "auto
//! smooth" or OBJ smoothing groups would); then every position is split into one vertex per
//! distinct normal (a *wedge*, Hoppe's term in "Progressive meshes", SIGGRAPH 1996 §3).
//!
//! Splitting vertices rather than keeping normals per triangle corner keeps one index buffer
//! per patch. The MT hierarchies are built across the split
//! ([`crate::mt::MtHierarchy::build_across_seams`]): each position is one vertex of the
//! surface being simplified, so a crease is not a border (a region between creases, a step's
//! wall, can vanish once the error allows), and each collapse moves every vertex at the removed
//! position onto one at the target, so coarser cuts keep the original vertices with their
//! original normals — nothing is averaged. The original triangles (the crack check's
//! reference) keep each crease as two border loops, covered by fat borders as the gaps between
//! patches are (Balázs et al. 2004 §3).
//!
//! What it does not do: normals are not re-oriented (a face wound against its neighbours has
//! a normal beyond the crease angle from theirs, so their shared edge shades hard; lighting
//! is two-sided); normals the file gives are used as given (normalised), never checked
//! against the faces.

use glam::Vec3;

/// Largest dihedral angle (between the normals of two faces sharing an edge) shaded smooth
/// when the file gives no normals, in degrees. 40° keeps the facets of a cylinder tessellated
/// at ≥ 9 segments smooth and the 90° edges of a box (or a 45° chamfer's) hard.
pub(crate) const CREASE_ANGLE_DEG: f32 = 40.0;

/// Two normals at one position closer than this (degrees) are one vertex's: files that split
/// vertices for texture coordinates write the same normal with rounding differences.
pub(crate) const SAME_NORMAL_DEG: f32 = 1.0;

/// Whether a face's normal can be trusted: its corners are not collinear up to f32 rounding
/// (the angle test of [`crate::io::mesh::check_drawable`]).
fn reliable(a: Vec3, b: Vec3, c: Vec3, n: Vec3) -> bool {
    let (e1, e2) = (b - a, c - a);
    n.length() > 1e-6 * e1.length() * e2.length() && n.length_squared() > 0.0
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let up = parent[parent[x as usize] as usize];
        parent[x as usize] = up;
        x = up;
    }
    x
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    // The smaller corner is the root: the result does not depend on the order of unions.
    let (lo, hi) = (ra.min(rb), ra.max(rb));
    parent[hi as usize] = lo;
}

/// The normal of every triangle corner (`3 t + k`): the area-weighted sum of the face normals
/// around the corner's vertex that are reachable from the corner's face across edges of at
/// most `crease_deg` (unit length; zero where only faces without a reliable normal meet).
/// `triangles` index `positions` with welded vertices (one index per position).
pub(crate) fn creased_normals(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    crease_deg: f32,
) -> Vec<Vec3> {
    let n = triangles.len();
    let face: Vec<Vec3> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            // The cross product's length is twice the area: area weighting for free.
            (b - a).cross(c - a)
        })
        .collect();
    let ok: Vec<bool> = (triangles.iter().zip(&face))
        .map(|(t, &f)| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            reliable(a, b, c, f)
        })
        .collect();
    // (larger vertex, its corner, the other's corner) of every edge, grouped by the smaller
    // vertex (a counting sort: a global sort took 80 ms on the bunny), then each group
    // sorted: equal edges end up adjacent.
    let vertices = positions.len();
    let mut start = vec![0u32; vertices + 1];
    for tri in triangles {
        for k in 0..3 {
            start[tri[k].min(tri[(k + 1) % 3]) as usize + 1] += 1;
        }
    }
    for v in 0..vertices {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut edges: Vec<(u32, u32, u32)> = vec![(0, 0, 0); 3 * n];
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (ca, cb) = ((3 * t + k) as u32, (3 * t + (k + 1) % 3) as u32);
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let (lo, e) = if a < b {
                (a, (b, ca, cb))
            } else {
                (b, (a, cb, ca))
            };
            edges[fill[lo as usize] as usize] = e;
            fill[lo as usize] += 1;
        }
    }
    for v in 0..vertices {
        edges[start[v] as usize..start[v + 1] as usize].sort_unstable();
    }
    let cos = crease_deg.to_radians().cos();
    let mut parent: Vec<u32> = (0..3 * n as u32).collect();
    let groups = (0..vertices).map(|v| &edges[start[v] as usize..start[v + 1] as usize]);
    for same in groups.flat_map(|g| g.chunk_by(|x, y| x.0 == y.0)) {
        // Smooth only across a manifold edge between two trusted faces.
        let [(_, a1, b1), (_, a2, b2)] = same else {
            continue;
        };
        let (t1, t2) = ((a1 / 3) as usize, (a2 / 3) as usize);
        let (f1, f2) = (face[t1], face[t2]);
        if t1 != t2 && ok[t1] && ok[t2] && f1.dot(f2) >= cos * f1.length() * f2.length() {
            union(&mut parent, *a1, *a2);
            union(&mut parent, *b1, *b2);
        }
    }
    let mut sum = vec![Vec3::ZERO; 3 * n];
    for c in 0..3 * n {
        let root = find(&mut parent, c as u32) as usize;
        sum[root] += face[c / 3];
    }
    (0..3 * n)
        .map(|c| sum[find(&mut parent, c as u32) as usize].normalize_or_zero())
        .collect()
}

/// Vertices split by normal: `corner_normals` (one per corner of `triangles`, which index
/// `positions` — `positions` distinct positions) grouped per position, normals within
/// [`SAME_NORMAL_DEG`] of a group's first one joining it (a zero normal joins the position's
/// first group). Returns the triangles over the new vertices, each new vertex's position
/// index and its normal. New vertices come position by position, so a mesh without creases
/// keeps its vertex order; a position no triangle uses keeps one vertex (normal zero).
pub(crate) fn wedges(
    positions: usize,
    triangles: &[[u32; 3]],
    corner_normals: &[Vec3],
) -> (Vec<[u32; 3]>, Vec<u32>, Vec<Vec3>) {
    // Corners grouped by position (a counting sort; corners in order within a position).
    let mut start = vec![0u32; positions + 1];
    for t in triangles {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for p in 0..positions {
        start[p + 1] += start[p];
    }
    let mut fill = start.clone();
    let mut by_position = vec![0u32; 3 * triangles.len()];
    for (t, tri) in triangles.iter().enumerate() {
        for (k, &v) in tri.iter().enumerate() {
            by_position[fill[v as usize] as usize] = (3 * t + k) as u32;
            fill[v as usize] += 1;
        }
    }
    let cos = SAME_NORMAL_DEG.to_radians().cos();
    let mut wedge_of_corner = vec![0u32; 3 * triangles.len()];
    let mut position_of = Vec::with_capacity(positions);
    let mut normals: Vec<Vec3> = Vec::with_capacity(positions);
    for p in 0..positions {
        let corners = &by_position[start[p] as usize..start[p + 1] as usize];
        let first = normals.len();
        for &c in corners {
            let n = corner_normals[c as usize];
            if n == Vec3::ZERO {
                continue;
            }
            let found = (first..normals.len()).find(|&w| normals[w].dot(n) >= cos);
            wedge_of_corner[c as usize] = found.unwrap_or_else(|| {
                normals.push(n);
                position_of.push(p as u32);
                normals.len() - 1
            }) as u32;
        }
        if normals.len() == first {
            normals.push(Vec3::ZERO);
            position_of.push(p as u32);
        }
        for &c in corners {
            if corner_normals[c as usize] == Vec3::ZERO {
                wedge_of_corner[c as usize] = first as u32;
            }
        }
    }
    let tris = (0..triangles.len())
        .map(|t| [0, 1, 2].map(|k| wedge_of_corner[3 * t + k]))
        .collect();
    (tris, position_of, normals)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube's 12 triangles over its 8 corners, wound outwards.
    fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (p, t)
    }

    /// A cube's 90° edges are creases: each corner of the cube becomes three vertices, one per
    /// face, with that face's normal; with a crease angle above 90° every corner is smooth.
    #[test]
    fn a_cube_splits_at_its_edges_and_not_beyond_the_angle() {
        let (p, t) = cube();
        let normals = creased_normals(&p, &t, CREASE_ANGLE_DEG);
        for (tri, corner) in t.iter().zip(normals.chunks(3)) {
            let [a, b, c] = tri.map(|i| p[i as usize]);
            let face = (b - a).cross(c - a).normalize();
            for n in corner {
                assert!(n.dot(face) > 0.9999, "{n} vs the face's {face}");
            }
        }
        let (tris, at, ns) = wedges(p.len(), &t, &normals);
        assert_eq!(ns.len(), 24);
        assert_eq!(at.len(), 24);
        for (tri, src) in tris.iter().zip(&t) {
            for k in 0..3 {
                assert_eq!(at[tri[k] as usize], src[k]);
            }
        }
        let smooth = creased_normals(&p, &t, 100.0);
        let (_, _, ns) = wedges(p.len(), &t, &smooth);
        assert_eq!(ns.len(), 8, "every corner one vertex");
        for (&n, q) in ns.iter().zip(&p) {
            // The diagonal direction away from the centre.
            let out = (*q - Vec3::splat(0.5)).normalize();
            // (Area weighting: a corner meets one or two triangles of each face.)
            assert!(n.dot(out) > 0.9, "{n} at {q}");
        }
    }

    /// Normals a few ulps apart are one vertex; 2° apart they are two.
    #[test]
    fn nearly_equal_normals_are_one_vertex() {
        let t = [[0, 1, 2], [0, 2, 1]];
        let tilt = |deg: f32| Vec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos());
        let mut corners = vec![Vec3::Z; 6];
        corners[3] = tilt(0.001);
        assert_eq!(wedges(3, &t, &corners).2.len(), 3);
        corners[3] = tilt(2.0);
        let (tris, at, ns) = wedges(3, &t, &corners);
        assert_eq!(ns.len(), 4);
        assert_eq!(at, vec![0, 0, 1, 2]);
        assert_eq!(tris, vec![[0, 2, 3], [1, 3, 2]]);
    }

    /// A needle (collinear corners) takes part in no smoothing: it cannot bridge the two sides
    /// of a crease, and its corners take their position's first vertex.
    #[test]
    fn collinear_faces_neither_bridge_creases_nor_add_vertices() {
        // Face A in z = 0 and face B in y = 0 meet at 90° along the x axis, but share no
        // edge: a needle (0, 1, 4 on the x axis) shares edge 0–1 with A and 0–4 with B.
        let p = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            Vec3::new(2.0, 0.0, 0.0),
        ];
        let t = vec![[0, 1, 2], [1, 0, 4], [0, 4, 3]];
        let normals = creased_normals(&p, &t, CREASE_ANGLE_DEG);
        assert!(normals[0].dot(Vec3::Z) > 0.9999, "{}", normals[0]);
        assert!(normals[6].dot(-Vec3::Y) > 0.9999, "{}", normals[6]);
        assert_eq!(normals[3], Vec3::ZERO);
        let (tris, at, ns) = wedges(p.len(), &t, &normals);
        // Vertex 0 in two (A's and B's normal), the others one each; the needle's corner
        // at 0 takes A's.
        assert_eq!(ns.len(), 6);
        assert_eq!(at, vec![0, 0, 1, 2, 3, 4]);
        assert_eq!(tris[1][1], tris[0][0]);
    }
}
