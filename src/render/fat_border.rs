//! Fat borders: the CPU twin of the WGSL expansion and the per-variant triangle templates.
//!
//! Balázs, Guthe, Klein, "Fat Borders" (2004), §3.1–3.2. Every border vertex v_i of a patch is
//! expanded into displaced vertices v_i + ε·normalize(dir × d_i), dir ∈ {s_i, t_i, s_{i−1},
//! −s_i, −t_i, −s_{i−1}}, all pushed back by ε along the view direction d_i. Triangles join
//! them into a band of half-width ε along the polyline plus fans at the joints:
//!
//! * 6 vertices: segment quad (v_i1, v_i4 → v_{i+1,3}, v_{i+1,6}) and fans v_i3–v_i2–v_i1 and
//!   v_i6–v_i5–v_i4 around v_i (6 triangles per border vertex);
//! * 4 vertices: the same without v_i2, v_i5 (4 triangles);
//! * 2 vertices: only v_i2, v_i5, one quad per segment (2 triangles).
//!
//! [`expand`] mirrors `fat_border_position` in `shaders/fat_border_lib.wgsl` operation by
//! operation, in f32; a test runs the WGSL function in a compute twin and compares.

use glam::Vec3;

use crate::tessellate::PatchMesh;

/// Which fat-border variant to draw (paper §3.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FatBorders {
    Off,
    #[default]
    Six,
    Four,
    Two,
}

impl FatBorders {
    pub const ALL_ON: [FatBorders; 3] = [FatBorders::Six, FatBorders::Four, FatBorders::Two];

    pub fn name(self) -> &'static str {
        match self {
            FatBorders::Off => "off",
            FatBorders::Six => "6",
            FatBorders::Four => "4",
            FatBorders::Two => "2",
        }
    }
}

impl std::str::FromStr for FatBorders {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "off" | "0" => Ok(FatBorders::Off),
            "6" => Ok(FatBorders::Six),
            "4" => Ok(FatBorders::Four),
            "2" => Ok(FatBorders::Two),
            _ => Err(format!("fat borders must be off, 6, 4 or 2, not {s:?}")),
        }
    }
}

impl std::fmt::Display for FatBorders {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Template code: bit 3 = which end of the segment (0 = v_i, 1 = v_{i+1}), bits 0..2 = slot.
const fn c(end: u32, slot: u32) -> u32 {
    (end << 3) | slot
}

const TEMPLATE_6: [u32; 18] = [
    // segment quad
    c(0, 1),
    c(0, 4),
    c(1, 6),
    c(0, 1),
    c(1, 6),
    c(1, 3),
    // joint fans around v_i
    c(0, 0),
    c(0, 3),
    c(0, 2),
    c(0, 0),
    c(0, 2),
    c(0, 1),
    c(0, 0),
    c(0, 6),
    c(0, 5),
    c(0, 0),
    c(0, 5),
    c(0, 4),
];

const TEMPLATE_4: [u32; 12] = [
    c(0, 1),
    c(0, 4),
    c(1, 6),
    c(0, 1),
    c(1, 6),
    c(1, 3),
    c(0, 0),
    c(0, 3),
    c(0, 1),
    c(0, 0),
    c(0, 6),
    c(0, 4),
];

const TEMPLATE_2: [u32; 6] = [c(0, 2), c(0, 5), c(1, 5), c(0, 2), c(1, 5), c(1, 2)];

/// Triangle-list template drawn once per border vertex (instance), as codes (see `c`).
pub fn template(variant: FatBorders) -> &'static [u32] {
    match variant {
        FatBorders::Off => &[],
        FatBorders::Six => &TEMPLATE_6,
        FatBorders::Four => &TEMPLATE_4,
        FatBorders::Two => &TEMPLATE_2,
    }
}

/// Splits a template code into (end, slot).
pub fn decode(code: u32) -> (u32, u32) {
    ((code >> 3) & 1, code & 7)
}

const TINY: f32 = 1e-12;
/// Below this turn (cos of the angle between segments) s_{i−1}, t_i, s_i all use t_i, so the
/// joint fans collapse to zero area (same constant as `FB_STRAIGHT_COS` in WGSL).
pub const STRAIGHT_COS: f32 = 0.999;

fn normalize_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let l2 = v.dot(v);
    if l2 > TINY * TINY {
        v * (1.0 / l2.sqrt())
    } else {
        fallback
    }
}

fn side(dir: Vec3, d: Vec3) -> Vec3 {
    let c = dir.cross(d);
    if c.dot(c) > 1e-12 {
        return c.normalize();
    }
    let helper = if d.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
    helper.cross(d).normalize()
}

/// CPU twin of `fat_border_position` (WGSL): slot 0 = v_i pushed back, slots 1..6 = eq. (1)–(6).
pub fn expand(prev: Vec3, cur: Vec3, next: Vec3, eye: Vec3, eps: f32, slot: u32) -> Vec3 {
    let d = normalize_or(eye - cur, Vec3::Z);
    let s_next0 = next - cur;
    let s_prev0 = cur - prev;
    let s_next = normalize_or(s_next0, normalize_or(s_prev0, Vec3::X));
    let s_prev = normalize_or(s_prev0, s_next);
    let t = normalize_or(s_prev + s_next, s_next);
    let (dir_next, dir_prev) = if s_prev.dot(s_next) > STRAIGHT_COS {
        (t, t)
    } else {
        (s_next, s_prev)
    };
    let off = match slot {
        1 => side(dir_next, d),
        2 => side(t, d),
        3 => side(dir_prev, d),
        4 => side(-dir_next, d),
        5 => side(-t, d),
        6 => side(-dir_prev, d),
        _ => Vec3::ZERO,
    };
    cur + eps * off - eps * d
}

/// One border vertex as the GPU gets it: its neighbours, normals, ε and patch.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BorderInstance {
    pub prev: [f32; 3],
    pub a: [f32; 3],
    pub b: [f32; 3],
    pub c: [f32; 3],
    pub normal_a: [f32; 3],
    pub normal_b: [f32; 3],
    pub eps: f32,
    pub patch_id: u32,
}

/// One displaced fat-border vertex as the GPU gets it: border vertex v_i (with its
/// neighbours, normal, ε, patch) and the slot (0 = v_i, 1..6 = v_i1..v_i6).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BorderVertex {
    pub prev: [f32; 3],
    pub cur: [f32; 3],
    pub next: [f32; 3],
    pub normal: [f32; 3],
    pub eps: f32,
    pub patch_id: u32,
    pub slot: u32,
}

/// Slots per border vertex in [`BorderGeometry::vertices`].
pub const SLOTS: usize = 7;

/// Fat-border geometry for one flat indexed draw: every border vertex expanded to its 7
/// slots, and per variant the triangle indices of the template (a triangle may use slots of
/// the next border vertex, so neighbouring border vertices share displaced vertices and each
/// is shaded once). Unused slots are never indexed, hence never shaded.
#[derive(Clone, Debug, Default)]
pub struct BorderGeometry {
    pub vertices: Vec<BorderVertex>,
    /// Indices for [`FatBorders::Six`], [`FatBorders::Four`], [`FatBorders::Two`].
    pub indices: [Vec<u32>; 3],
}

impl BorderGeometry {
    pub fn of(meshes: &[PatchMesh]) -> BorderGeometry {
        let mut g = BorderGeometry::default();
        for m in meshes {
            let eps = m.eps_border() as f32;
            for ring in &m.borders {
                let n = ring.len();
                let base = g.vertices.len() as u32;
                for k in 0..n {
                    let at = |o: usize| m.positions[ring[(k + o) % n] as usize].into();
                    for slot in 0..SLOTS as u32 {
                        g.vertices.push(BorderVertex {
                            prev: at(n - 1),
                            cur: at(0),
                            next: at(1),
                            normal: m.normals[ring[k] as usize].into(),
                            eps,
                            patch_id: m.patch_id,
                            slot,
                        });
                    }
                }
                for (v, variant) in FatBorders::ALL_ON.iter().enumerate() {
                    for k in 0..n {
                        g.indices[v].extend(template(*variant).iter().map(|&code| {
                            let (end, slot) = decode(code);
                            let j = (k + end as usize) % n;
                            base + (j * SLOTS) as u32 + slot
                        }));
                    }
                }
            }
        }
        g
    }

    pub fn indices(&self, variant: FatBorders) -> &[u32] {
        match variant {
            FatBorders::Off => &[],
            FatBorders::Six => &self.indices[0],
            FatBorders::Four => &self.indices[1],
            FatBorders::Two => &self.indices[2],
        }
    }
}

/// Border instances of every closed border loop of `meshes`, ε = each patch's
/// [`PatchMesh::eps_border`].
pub fn border_instances(meshes: &[PatchMesh]) -> Vec<BorderInstance> {
    let mut out = Vec::with_capacity(meshes.iter().map(PatchMesh::border_vertex_count).sum());
    for m in meshes {
        let eps = m.eps_border() as f32;
        for ring in &m.borders {
            let n = ring.len();
            for k in 0..n {
                let at = |o: usize| ring[(k + o) % n] as usize;
                let (p, a, b, c) = (at(n - 1), at(0), at(1), at(2));
                out.push(BorderInstance {
                    prev: m.positions[p].into(),
                    a: m.positions[a].into(),
                    b: m.positions[b].into(),
                    c: m.positions[c].into(),
                    normal_a: m.normals[a].into(),
                    normal_b: m.normals[b].into(),
                    eps,
                    patch_id: m.patch_id,
                });
            }
        }
    }
    out
}

/// The fat-border triangles of one instance, expanded on the CPU (world positions).
pub fn instance_triangles(inst: &BorderInstance, eye: Vec3, variant: FatBorders) -> Vec<[Vec3; 3]> {
    let v = |code: u32| {
        let (end, slot) = decode(code);
        let (p, a, b, c) = (
            Vec3::from(inst.prev),
            Vec3::from(inst.a),
            Vec3::from(inst.b),
            Vec3::from(inst.c),
        );
        if end == 0 {
            expand(p, a, b, eye, inst.eps, slot)
        } else {
            expand(a, b, c, eye, inst.eps, slot)
        }
    };
    template(variant)
        .chunks_exact(3)
        .map(|t| [v(t[0]), v(t[1]), v(t[2])])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn displaced_vertices_are_eps_away_and_pushed_back() {
        let (prev, cur, next) = (
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::ZERO,
            Vec3::new(1.0, 0.2, 0.0),
        );
        let eye = Vec3::new(0.0, 0.0, 10.0);
        let eps = 0.01;
        let d = (eye - cur).normalize();
        for slot in 1..=6 {
            let p = expand(prev, cur, next, eye, eps, slot);
            // Undo the push-back: the rest is an offset of length ε perpendicular to d.
            let off = p - cur + eps * d;
            assert!((off.length() - eps).abs() < 1e-6, "slot {slot}: {off:?}");
            assert!(off.dot(d).abs() < 1e-6);
        }
        let p0 = expand(prev, cur, next, eye, eps, 0);
        assert!((p0 - (cur - eps * d)).length() < 1e-7);
    }

    #[test]
    fn opposite_slots_are_on_opposite_sides() {
        let (prev, cur, next) = (
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::ZERO,
            Vec3::new(1.0, 0.5, 0.0),
        );
        let eye = Vec3::new(0.3, 0.1, 5.0);
        for (a, b) in [(1, 4), (2, 5), (3, 6)] {
            let pa = expand(prev, cur, next, eye, 0.1, a);
            let pb = expand(prev, cur, next, eye, 0.1, b);
            assert!((pa + pb - 2.0 * expand(prev, cur, next, eye, 0.1, 0)).length() < 1e-6);
        }
    }

    #[test]
    fn degenerate_inputs_stay_finite() {
        let eye = Vec3::new(0.0, 0.0, 5.0);
        let z = Vec3::ZERO;
        // Coincident neighbours, a segment pointing at the eye, eye on the vertex.
        let cases = [
            (z, z, z, eye),
            (z, z, Vec3::X, eye),
            (Vec3::new(0.0, 0.0, -1.0), z, Vec3::new(0.0, 0.0, 1.0), eye),
            (Vec3::X, z, -Vec3::X, z),
        ];
        for (p, c0, n, e) in cases {
            for slot in 0..=6 {
                assert!(expand(p, c0, n, e, 0.1, slot).is_finite());
            }
        }
    }

    #[test]
    fn geometry_indices_expand_to_the_cpu_twin_triangles() {
        // A square loop: the GPU index lists must name, per border vertex, exactly the
        // template's (end, slot) pairs.
        let mesh = PatchMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            normals: vec![Vec3::Z; 4],
            borders: vec![vec![0, 1, 2, 3]],
            eps_target: 0.1,
            ..PatchMesh::default()
        };
        let g = BorderGeometry::of(std::slice::from_ref(&mesh));
        assert_eq!(g.vertices.len(), 4 * SLOTS);
        let eye = Vec3::new(0.3, 0.2, 4.0);
        let gpu_like = |i: u32| {
            let v = g.vertices[i as usize];
            expand(
                v.prev.into(),
                v.cur.into(),
                v.next.into(),
                eye,
                v.eps,
                v.slot,
            )
        };
        let instances = border_instances(std::slice::from_ref(&mesh));
        for variant in FatBorders::ALL_ON {
            let idx = g.indices(variant);
            let cpu: Vec<[Vec3; 3]> = instances
                .iter()
                .flat_map(|i| instance_triangles(i, eye, variant))
                .collect();
            assert_eq!(idx.len(), cpu.len() * 3, "{variant}");
            for (t, tri) in idx.chunks_exact(3).zip(&cpu) {
                for c in 0..3 {
                    assert!((gpu_like(t[c]) - tri[c]).length() < 1e-6, "{variant}");
                }
            }
        }
    }

    #[test]
    fn templates_have_the_papers_sizes() {
        assert_eq!(template(FatBorders::Six).len() / 3, 6);
        assert_eq!(template(FatBorders::Four).len() / 3, 4);
        assert_eq!(template(FatBorders::Two).len() / 3, 2);
        assert!(template(FatBorders::Off).is_empty());
        // 4 vertices: v_i2 and v_i5 left out; 2 vertices: only those.
        let slots = |v| template(v).iter().map(|&c| decode(c).1).collect::<Vec<_>>();
        assert!(!slots(FatBorders::Four).iter().any(|&s| s == 2 || s == 5));
        assert!(slots(FatBorders::Two).iter().all(|&s| s == 2 || s == 5));
    }

    #[test]
    fn band_covers_points_within_eps_of_a_straight_segment() {
        // Looking straight down on a segment: every point within 0.9ε of it must lie in the
        // projection of some fat-border triangle, for each variant.
        let eye = Vec3::new(0.5, 0.0, 50.0);
        let inst = BorderInstance {
            prev: [-1.0, 0.0, 0.0],
            a: [0.0, 0.0, 0.0],
            b: [1.0, 0.0, 0.0],
            c: [2.0, 0.0, 0.0],
            eps: 0.05,
            ..BorderInstance::default()
        };
        for variant in FatBorders::ALL_ON {
            let tris = instance_triangles(&inst, eye, variant);
            for k in 0..=20 {
                for side in [-0.9f32, 0.0, 0.9] {
                    let q = glam::Vec2::new(k as f32 / 20.0, side * 0.05);
                    let covered = tris.iter().any(|t| inside_xy(q, t));
                    assert!(covered, "{variant}: {q:?} not covered");
                }
            }
        }
    }

    fn inside_xy(q: glam::Vec2, t: &[Vec3; 3]) -> bool {
        let p = t.map(|v| v.truncate());
        let s = |a: glam::Vec2, b: glam::Vec2| (b - a).perp_dot(q - a);
        let (d0, d1, d2) = (s(p[0], p[1]), s(p[1], p[2]), s(p[2], p[0]));
        let tol = 1e-6;
        (d0 >= -tol && d1 >= -tol && d2 >= -tol) || (d0 <= tol && d1 <= tol && d2 <= tol)
    }
}
