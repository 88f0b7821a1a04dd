//! Which pieces of the patches' borders are edges of the model, and which of those are
//! feature edges — what `--edges all` and `--edges feature` draw (issue 32).
//!
//! Every patch border is a polyline the frame already draws as fat borders; each of its
//! segments runs along something ([`EdgeKind`]):
//!
//! * **a sharp edge** — a free (boundary) edge, an edge where two faces meet at an angle, a
//!   crease of a mesh: drawn by both modes;
//! * **a smooth edge** — two faces meet with the same tangent plane along it (G1, as a
//!   fillet meets the faces it rounds): drawn by `all` only, as Open CASCADE's
//!   `Prs3d_Drawer::SetFaceBoundaryUpperContinuity(GeomAbs_C0)` leaves out edges of a higher
//!   continuity;
//! * **no edge** — where a mesh was cut into patches, the seam of a closed surface (a
//!   cylinder's: one face on both sides), the lines the tessellator adds to close a loop
//!   around a periodic surface: never drawn.
//!
//! Smoothness is decided once, at load, from the exact surfaces: along an edge shared by two
//! faces, their unit normals at `SAMPLES` points of the edge (a quarter, half and three
//! quarters along it) must agree within `SMOOTH_ANGLE_DEG` (1°) — as lines, since CAD faces
//! are not consistently oriented. Trimmed faces (STEP): an edge is shared when the file
//! shares its `EDGE_CURVE` (`classify_shared`; IGES faces share no edge entities, so all
//! their edges count as free and sharp). Bézier patches: a side is shared when another
//! patch's side has the same control points, in either direction (`bezier_sides`). Meshes:
//! an edge used once in the wedge-split mesh is a crease or a boundary, an edge two triangles
//! share a patch cut (`model::mesh::extract`).
//!
//! Counted against Open CASCADE's own continuity of the same files (`BRep_Tool::Continuity`
//! after its STEP reader, which encodes regularity at 0.01°; README, "Edges of the model"):
//! the same numbers of sharp and smooth edges where both see the same edges; with this angle
//! at 0.01° also on `corpus/Block.stp.gz` (1 305 sharp, 275 smooth), within 5 of 355 on the
//! crankshaft. 1° leaves out kinks shading cannot show either.
//!
//! What it does not do: faces that meet along an edge without sharing it (IGES, two solids
//! touching) are not paired; an edge whose faces agree at the three samples but not between
//! them counts as smooth; silhouettes are not edges.

use glam::DVec3;

use super::bezier::BezierPatch;

/// What a border segment runs along. The value's bits are the edge modes that draw it
/// (`EDGE_ALL`, `EDGE_FEATURE`).
#[repr(u8)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum EdgeKind {
    /// Not an edge of the model (a patch cut, a seam, a closing line): never drawn.
    None = 0,
    /// An edge between faces that meet tangentially (G1): drawn by `all`.
    Smooth = EDGE_ALL,
    /// A free edge, a crease, an edge at an angle: drawn by `all` and `feature`.
    #[default]
    Sharp = EDGE_ALL | EDGE_FEATURE,
}

/// Bit of an [`EdgeKind`]: drawn with `--edges all`.
pub(crate) const EDGE_ALL: u8 = 1;
/// Bit of an [`EdgeKind`]: drawn with `--edges feature`.
pub(crate) const EDGE_FEATURE: u8 = 2;

/// Largest angle between the normals of two faces along an edge that counts as smooth, in
/// degrees.
pub(crate) const SMOOTH_ANGLE_DEG: f64 = 1.0;

/// Where along an edge (fractions of its parameter range) the faces' normals are compared.
pub(crate) const SAMPLES: [f64; 3] = [0.25, 0.5, 0.75];

/// Unit normals of one face at the [`SAMPLES`] of one of its edges; `None` where the
/// surface has no normal (a pole) or the point could not be found on it.
pub(crate) type EdgeNormals = [Option<DVec3>; SAMPLES.len()];

/// Whether two faces with `a` and `b` along their common edge meet smoothly: every sample
/// has a normal on both sides, and they agree within `SMOOTH_ANGLE_DEG` as lines.
pub fn smooth(a: &EdgeNormals, b: &EdgeNormals) -> bool {
    let cos = SMOOTH_ANGLE_DEG.to_radians().cos();
    a.iter().zip(b).all(|(x, y)| match (x, y) {
        (Some(x), Some(y)) => x.dot(*y).abs() >= cos,
        _ => false,
    })
}

/// One face's use of an edge: the edge's key (a STEP `EDGE_CURVE` id), the face (any index
/// the caller keeps) and its normals along the edge.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EdgeUse {
    pub edge: u64,
    pub face: usize,
    pub normals: EdgeNormals,
}

/// The kind of every use in `uses`, in order: an edge used by one face is free (sharp), by
/// one face twice a seam (none), by two faces smooth or sharp by their normals
/// ([`smooth`]), by more faces sharp (non-manifold).
pub(crate) fn classify_shared(uses: &[EdgeUse]) -> Vec<EdgeKind> {
    let mut by_edge: std::collections::HashMap<u64, Vec<usize>> = Default::default();
    for (i, u) in uses.iter().enumerate() {
        by_edge.entry(u.edge).or_default().push(i);
    }
    let mut kinds = vec![EdgeKind::Sharp; uses.len()];
    for group in by_edge.values() {
        let kind = match *group.as_slice() {
            [a, b] if uses[a].face == uses[b].face => EdgeKind::None,
            [a, b] if smooth(&uses[a].normals, &uses[b].normals) => EdgeKind::Smooth,
            _ => EdgeKind::Sharp,
        };
        for &i in group {
            kinds[i] = kind;
        }
    }
    kinds
}

/// Control points of side `s` of a Bézier patch, in the direction its border loop runs
/// (`tessellate::bezier`: side 0 is u = 0 with v rising, 1 is v = 1 with u rising, 2 is
/// u = 1 with v falling, 3 is v = 0 with u falling), with the parameter of the side's
/// point at fraction `f` along it.
fn side(p: &BezierPatch, s: usize) -> (Vec<DVec3>, impl Fn(f64) -> (f64, f64)) {
    let (du, dv) = p.degree();
    let c = p.control_points();
    let at = |i: usize, j: usize| c[i * (dv + 1) + j];
    let points: Vec<DVec3> = match s {
        0 => (0..=dv).map(|j| at(0, j)).collect(),
        1 => (0..=du).map(|i| at(i, dv)).collect(),
        2 => (0..=dv).rev().map(|j| at(du, j)).collect(),
        _ => (0..=du).rev().map(|i| at(i, 0)).collect(),
    };
    let uv = move |f: f64| match s {
        0 => (0.0, f),
        1 => (f, 1.0),
        2 => (1.0, 1.0 - f),
        _ => (1.0 - f, 0.0),
    };
    (points, uv)
}

/// The kind of each side of each patch (sides as in `tessellate::bezier`'s border loop: u =
/// 0, v = 1, u = 1, v = 0): a side collapsed to a point (a pole) is none; a side whose
/// control points another side repeats (in either direction) is smooth or sharp by the two
/// patches' normals at [`SAMPLES`]; a side no other side repeats is free (sharp).
pub(crate) fn bezier_sides(patches: &[BezierPatch]) -> Vec<[EdgeKind; 4]> {
    // Each side (patch, side, run forwards) by the bits of its control points, in the
    // smaller of its two directions.
    type Sides = Vec<(usize, usize, bool)>;
    let mut by_key: std::collections::HashMap<Vec<[u64; 3]>, Sides> = Default::default();
    let mut kinds = vec![[EdgeKind::Sharp; 4]; patches.len()];
    for (k, (p, kind)) in patches.iter().zip(kinds.iter_mut()).enumerate() {
        for (s, kind) in kind.iter_mut().enumerate() {
            let (points, _) = side(p, s);
            if points.iter().all(|q| *q == points[0]) {
                *kind = EdgeKind::None;
                continue;
            }
            let bits: Vec<[u64; 3]> = points
                .iter()
                .map(|q| q.to_array().map(|x| (x + 0.0).to_bits()))
                .collect();
            let reversed: Vec<[u64; 3]> = bits.iter().rev().copied().collect();
            let forward = bits <= reversed;
            let key = if forward { bits } else { reversed };
            by_key.entry(key).or_default().push((k, s, forward));
        }
    }
    for group in by_key.values() {
        let &[(ka, sa, fa), (kb, sb, fb)] = group.as_slice() else {
            continue;
        };
        // Normals at the same points: fraction f of one side is 1 − f of the other when
        // the two run against each other.
        let normals = |k: usize, s: usize, flip: bool| -> EdgeNormals {
            let (_, uv) = side(&patches[k], s);
            SAMPLES.map(|f| {
                let (u, v) = uv(if flip { 1.0 - f } else { f });
                Some(patches[k].normal(u, v)).filter(|n| n.is_finite() && *n != DVec3::ZERO)
            })
        };
        let kind = if smooth(&normals(ka, sa, false), &normals(kb, sb, fa != fb)) {
            EdgeKind::Smooth
        } else {
            EdgeKind::Sharp
        };
        kinds[ka][sa] = kind;
        kinds[kb][sb] = kind;
    }
    kinds
}

#[cfg(test)]
mod tests {
    use super::*;

    fn n(x: f64, y: f64, z: f64) -> Option<DVec3> {
        Some(DVec3::new(x, y, z).normalize())
    }

    #[test]
    fn normals_within_one_degree_as_lines_are_smooth() {
        let up = [n(0.0, 0.0, 1.0); 3];
        let down = [n(0.0, 0.0, -1.0); 3];
        let half = 0.9f64.to_radians().tan();
        let tilted = [n(0.0, half, 1.0); 3];
        let over = [n(0.0, 1.1f64.to_radians().tan(), 1.0); 3];
        assert!(
            smooth(&up, &down),
            "opposite orientations are one tangent plane"
        );
        assert!(smooth(&up, &tilted));
        assert!(!smooth(&up, &over));
        assert!(!smooth(&up, &[n(0.0, 0.0, 1.0), None, n(0.0, 0.0, 1.0)]));
    }

    #[test]
    fn shared_edges_are_classified_by_their_uses() {
        let flat = [n(0.0, 0.0, 1.0); 3];
        let side = [n(1.0, 0.0, 0.0); 3];
        let u = |edge, face, normals| EdgeUse {
            edge,
            face,
            normals,
        };
        let uses = [
            u(1, 0, flat),
            u(1, 1, flat), // smooth
            u(2, 0, flat),
            u(2, 2, side), // sharp
            u(3, 0, flat), // free
            u(4, 3, side),
            u(4, 3, side), // a seam
            u(5, 0, flat),
            u(5, 1, flat),
            u(5, 2, flat), // non-manifold
        ];
        use EdgeKind::*;
        assert_eq!(
            classify_shared(&uses),
            [
                Smooth, Smooth, Sharp, Sharp, Sharp, None, None, Sharp, Sharp, Sharp
            ]
        );
    }

    /// Two bilinear patches side by side: flat across their common side (smooth), folded by
    /// 90° (sharp); free sides sharp.
    #[test]
    fn bezier_sides_shared_by_control_points() {
        let quad = |a: DVec3, b: DVec3, c: DVec3, d: DVec3| {
            // Row-major: (u, v) = (0, 0), (0, 1), (1, 0), (1, 1).
            BezierPatch::new(1, 1, vec![a, b, c, d]).expect("valid")
        };
        let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let left = quad(p(0., 0., 0.), p(0., 1., 0.), p(1., 0., 0.), p(1., 1., 0.));
        // Its u = 0 side is the left patch's u = 1 side, run the same way.
        let flat = quad(p(1., 0., 0.), p(1., 1., 0.), p(2., 0., 0.), p(2., 1., 0.));
        let folded = quad(p(1., 1., 0.), p(1., 0., 0.), p(1., 1., 1.), p(1., 0., 1.));
        use EdgeKind::*;
        let k = bezier_sides(&[left.clone(), flat]);
        assert_eq!(k[0], [Sharp, Sharp, Smooth, Sharp]);
        assert_eq!(k[1], [Smooth, Sharp, Sharp, Sharp]);
        let k = bezier_sides(&[left, folded]);
        assert_eq!(k[0][2], Sharp);
        assert_eq!(k[1][0], Sharp);
        // A side collapsed to a point is no edge.
        let cone = quad(p(0., 0., 0.), p(0., 0., 0.), p(1., 0., 0.), p(1., 1., 0.));
        assert_eq!(bezier_sides(&[cone])[0][0], None);
    }
}
