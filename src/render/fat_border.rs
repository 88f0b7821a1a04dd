//! Fat borders: the CPU twin of the WGSL expansion, the per-variant triangle templates and the
//! border points the vertex shader pulls them from ([`BorderGeometry`]).
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
//! **Straight joints** (the polyline turns by less than 8°, [`STRAIGHT_COS`]): v_i1, v_i2, v_i3
//! (and v_i4, v_i5, v_i6) all become the mitre point `ε·normalize(t_i × d_i) / cos(θ/2)`. The band
//! is then at least ε wide perpendicular to both segments and covers the fan's round wedge (the
//! mitre contains it), the displaced vertices move by under 0.4 % of ε, and the fans have zero
//! area and are never shaded (a zero-area triangle covers no pixel): on the teapot about three joints
//! in four are straight, which cuts the 6-vertex variant from 6 to 2 drawn triangles there. The
//! decision is made once, on the CPU ([`is_straight`]), and passed to the shader as a flag in
//! the border point, so both twins agree by construction.
//!
//! **Width.** The push-back along d_i is ε, the patch's error; the displacement across the
//! view is the patch's [`PatchMesh::border_width`] (its measured border error when known,
//! at least ¼ ε): the crack lies between the neighbours' border polylines, so each needs
//! only its own border's error, and fins stick that much less out of silhouettes. It rides in
//! the code's [`WIDTH_MASK`] bits ([`width_bits`]).
//!
//! [`expand`] mirrors `fat_border_position` in `shaders/fat_border_lib.wgsl` operation by
//! operation, in f32, and [`resolve`] / [`position`] mirror the vertex pulling
//! (`fb_resolve`, `fat_border_vertex`); `tests/fat_border_twin.rs` runs the WGSL functions in
//! a compute twin and compares.

use glam::{Vec3, Vec4};

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

/// Triangle-list template drawn once per border vertex v_i, as codes (see `c`).
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

/// A fan triangle: it contains v_i itself (slot 0 at end 0).
#[cfg(test)]
fn is_fan(tri: &[u32]) -> bool {
    tri.contains(&c(0, 0))
}

const TINY: f32 = 1e-12;
/// Joints where consecutive segments turn by less than acos(0.99) ≈ 8.1° are straight (see the
/// module doc).
pub const STRAIGHT_COS: f32 = 0.99;
/// Flag in a slot code (bit 3): the border vertex's joint is straight (`FB_STRAIGHT` in WGSL).
pub const STRAIGHT_FLAG: u32 = 8;

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

/// Segment directions (s_{i−1}, s_i) at `cur`, with the same fallbacks as the shader.
fn segment_dirs(prev: Vec3, cur: Vec3, next: Vec3) -> (Vec3, Vec3) {
    let s_next0 = next - cur;
    let s_prev0 = cur - prev;
    let s_next = normalize_or(s_next0, normalize_or(s_prev0, Vec3::X));
    let s_prev = normalize_or(s_prev0, s_next);
    (s_prev, s_next)
}

/// Whether the border turns by less than acos([`STRAIGHT_COS`]) at `cur`.
pub fn is_straight(prev: Vec3, cur: Vec3, next: Vec3) -> bool {
    let (s_prev, s_next) = segment_dirs(prev, cur, next);
    s_prev.dot(s_next) > STRAIGHT_COS
}

/// The half-width across the view of a point whose code carries `code & WIDTH_MASK`: `eps`
/// scaled by the 6-bit fraction q / 63, where q = 0 means the full ε (see
/// [`PatchMesh::border_width`]).
fn width_of(eps: f32, code: u32) -> f32 {
    let q = (code & WIDTH_MASK) >> WIDTH_SHIFT;
    if q == 0 { eps } else { eps * q as f32 / 63.0 }
}

/// The width field of a code or [`BorderPoint::info`] for a half-width `width` ≤ `eps`:
/// rounded up to the next 63rd of ε (never narrower than measured), 0 (full) at ε.
pub fn width_bits(width: f64, eps: f64) -> u32 {
    let narrower = width.is_finite() && eps > 0.0 && width < eps;
    if !narrower {
        return 0;
    }
    let q = ((width / eps) * 63.0).ceil().clamp(1.0, 63.0) as u32;
    if q >= 63 { 0 } else { q << WIDTH_SHIFT }
}

/// CPU twin of `fat_border_position` (WGSL). `code` = slot (0 = v_i pushed back, 1..6 = eq.
/// (1)–(6)) plus [`STRAIGHT_FLAG`] for a straight joint plus the half-width across the view
/// as a fraction of ε in [`WIDTH_MASK`] ([`width_bits`]; 0 = ε; the push-back along the view is
/// always ε). `viewer` is the viewer in
/// homogeneous coordinates ([`crate::view::View::viewer`]): `(eye, 1)` under perspective, the
/// point at infinity `(−forward, 0)` under an orthographic projection; the view direction
/// d_i = normalize(viewer.xyz − v_i · viewer.w) is then the same at every border vertex, so
/// the push-back runs along the rays and leaves every vertex where it projects.
pub fn expand(prev: Vec3, cur: Vec3, next: Vec3, viewer: Vec4, eps: f32, code: u32) -> Vec3 {
    let slot = code & 7;
    let width = width_of(eps, code);
    let d = normalize_or(viewer.truncate() - cur * viewer.w, Vec3::Z);
    let (s_prev, s_next) = segment_dirs(prev, cur, next);
    let sum = s_prev + s_next;
    let t = normalize_or(sum, s_next);
    let off = if code & STRAIGHT_FLAG != 0 {
        // Mitre point: 1 / cos(θ/2), with cos(θ/2) = |s_{i−1} + s_i| / 2 ≥ 0.997 here.
        let mitre = 2.0 / sum.length().max(1.0);
        match slot {
            1..=3 => side(t, d) * mitre,
            4..=6 => side(-t, d) * mitre,
            _ => Vec3::ZERO,
        }
    } else {
        match slot {
            1 => side(s_next, d),
            2 => side(t, d),
            3 => side(s_prev, d),
            4 => side(-s_next, d),
            5 => side(-t, d),
            6 => side(-s_prev, d),
            _ => Vec3::ZERO,
        }
    };
    cur + width * off - eps * d
}

/// Bits of [`BorderPoint::info`]: the joint is straight ([`is_straight`]: its slots 1-3 and
/// 4-6 sit at the mitre points, so its fans have zero area), the point opens its ring,
/// closes its ring, is the ring's closing point (a copy of its first point, see
/// [`BorderGeometry`]); the half-width in [`WIDTH_MASK`]; the ring's length − 1 above
/// [`RING_SHIFT`] (the neighbours of a ring's ends wrap around).
pub const INFO_STRAIGHT: u32 = 1;
pub const INFO_FIRST: u32 = 2;
pub const INFO_LAST: u32 = 4;
pub const INFO_CLOSING: u32 = 8;
/// Bits 4..9 of [`BorderPoint::info`] and of an [`expand`] code: the fat border's half-width
/// across the view as q / 63 of ε (q = 0: ε), see [`width_bits`].
pub const WIDTH_SHIFT: u32 = 4;
pub const WIDTH_MASK: u32 = 63 << WIDTH_SHIFT;
/// The ring's length − 1 sits above this bit: rings of up to 2²² points (a ring that long
/// holds 160 MiB of points, more than a storage binding: `RenderError::TooLarge` first).
pub const RING_SHIFT: u32 = 10;
/// Longest ring a [`BorderPoint`] can name (its length − 1 fills the bits above
/// [`RING_SHIFT`]); a longer one is refused by the renderer as too large.
pub const MAX_RING_POINTS: usize = 1 << (32 - RING_SHIFT);

/// One border vertex v_i as the GPU stores it (40 bytes, read from a storage buffer by
/// `vs_border`): its position, its patch's ε, its normal, where it sits on its ring, and
/// its patch's id and packed colour. The shader expands the displaced vertices from it and
/// its ring neighbours.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BorderPoint {
    pub cur: [f32; 3],
    pub eps: f32,
    pub normal: [f32; 3],
    /// [`INFO_STRAIGHT`] | [`INFO_FIRST`] | [`INFO_LAST`] | [`INFO_CLOSING`] | half-width
    /// ([`WIDTH_MASK`]) | (ring length − 1) << [`RING_SHIFT`].
    pub info: u32,
    pub patch_id: u32,
    /// The patch colour, packed (see `PatchMesh::color`).
    pub color: [u8; 4],
}

/// Vertex indices per point: slot s of point k is vertex 8k + s.
pub const SLOTS_PER_POINT: usize = 8;

/// The 2-vertex variant's pattern: the paper's template with the next point's v2, v5 named
/// slots 3, 6 (which the shader maps to 2, 5), so a closing point can collapse its own v2,
/// v5 while the ring's last segment still reaches the first point's.
const PATTERN_2: [u32; 6] = [c(0, 2), c(0, 5), c(1, 6), c(0, 2), c(1, 6), c(1, 3)];

/// The triangle-list codes drawn once per point (see `c`): the templates of 6 and 4
/// vertices, and [`PATTERN_2`].
pub fn pattern(variant: FatBorders) -> &'static [u32] {
    match variant {
        FatBorders::Two => &PATTERN_2,
        v => template(v),
    }
}

/// Index `pattern(variant)` for points `0..points`: code (end, slot) of point k is vertex
/// 8(k + end) + slot. One buffer of it serves every draw (offset by a base vertex).
pub fn pattern_indices(variant: FatBorders, points: usize) -> Vec<u32> {
    let codes = pattern(variant);
    let mut out = Vec::with_capacity(points * codes.len());
    for k in 0..points {
        out.extend(codes.iter().map(|&code| {
            let (end, slot) = decode(code);
            ((k + end as usize) * SLOTS_PER_POINT) as u32 + slot
        }));
    }
    out
}

/// Point `k`, or a zero point past the end (the GPU's bounds-checked read).
fn point(points: &[BorderPoint], k: usize) -> BorderPoint {
    points.get(k).copied().unwrap_or_default()
}

/// Index of the ring neighbour before or after point `k` (`fb_neighbour` in WGSL).
pub fn neighbour(points: &[BorderPoint], k: usize, after: bool) -> usize {
    let info = point(points, k).info;
    let span = (info >> RING_SHIFT) as usize;
    match (after, info & INFO_FIRST != 0, info & INFO_LAST != 0) {
        (false, true, _) => k.wrapping_add(span),
        (false, false, _) => k.wrapping_sub(1),
        (true, _, true) => k.wrapping_sub(span),
        (true, _, false) => k.wrapping_add(1),
    }
}

/// CPU twin of `fb_resolve` (WGSL): the point and slot whose displaced vertex vertex `i` of
/// `variant`'s draw is. A closing point's slots 3 and 6 are its ring's first point's; its
/// other slots coincide with them or with the next point's slot 6, so each of its triangles
/// has two equal corners.
pub fn resolve(points: &[BorderPoint], variant: FatBorders, i: usize) -> (usize, u32) {
    let (mut p, mut s) = (i / SLOTS_PER_POINT, (i % SLOTS_PER_POINT) as u32);
    let two = variant == FatBorders::Two;
    if point(points, p).info & INFO_CLOSING != 0 {
        (p, s) = match (two, s) {
            (true, 2 | 5) | (false, 1) => (p.wrapping_add(1), 6),
            (false, 0 | 2) => (p, 3),
            (false, 4 | 5) => (p, 6),
            _ => (p, s),
        };
        let info = point(points, p).info;
        if info & INFO_CLOSING != 0 {
            p = p.wrapping_sub((info >> RING_SHIFT) as usize + 1);
        }
    }
    if two {
        s = match s {
            3 => 2,
            6 => 5,
            s => s,
        };
    }
    (p, s)
}

/// CPU twin of `fat_border_vertex` (WGSL): where vertex `i` of `variant`'s draw lands for a
/// viewer at `viewer` (homogeneous, see [`expand`]), and the point it is expanded from.
pub fn position(
    points: &[BorderPoint],
    variant: FatBorders,
    i: usize,
    viewer: Vec4,
) -> (Vec3, usize) {
    let (p, slot) = resolve(points, variant, i);
    let q = point(points, p);
    let flag = if q.info & INFO_STRAIGHT != 0 {
        STRAIGHT_FLAG
    } else {
        0
    };
    let at = |k: usize| Vec3::from(point(points, k).cur);
    let (prev, next) = (neighbour(points, p, false), neighbour(points, p, true));
    (
        expand(
            at(prev),
            at(p),
            at(next),
            viewer,
            q.eps,
            slot | flag | (q.info & WIDTH_MASK),
        ),
        p,
    )
}

/// CPU twin of `fb_place` (WGSL): `p` moved by a placement given as the rows of its 3 × 4
/// matrix (instanced parts, `render::resident::InstanceRecord::rows`).
pub fn place(rows: &[[f32; 4]; 3], p: Vec3) -> Vec3 {
    let h = p.extend(1.0);
    let [x, y, z] = rows.map(|r| glam::Vec4::from(r).dot(h));
    Vec3::new(x, y, z)
}

/// CPU twin of `fat_border_vertex_placed` (WGSL): as [`position`] for points drawn with the
/// placement `rows` — the ring points moved first, ε raised by `eps_added`.
pub fn position_placed(
    points: &[BorderPoint],
    variant: FatBorders,
    i: usize,
    viewer: Vec4,
    rows: &[[f32; 4]; 3],
    eps_added: f32,
) -> (Vec3, usize) {
    let (p, slot) = resolve(points, variant, i);
    let q = point(points, p);
    let flag = if q.info & INFO_STRAIGHT != 0 {
        STRAIGHT_FLAG
    } else {
        0
    };
    let at = |k: usize| place(rows, Vec3::from(point(points, k).cur));
    let (prev, next) = (neighbour(points, p, false), neighbour(points, p, true));
    let eps = q.eps + eps_added;
    // A placement that adds to ε (a translated copy) draws the whole ε wide.
    let width = if eps_added == 0.0 {
        q.info & WIDTH_MASK
    } else {
        0
    };
    (
        expand(at(prev), at(p), at(next), viewer, eps, slot | flag | width),
        p,
    )
}

/// Fat-border geometry drawn by vertex pulling: every border vertex stored once
/// ([`BorderPoint`], ring after ring, each ring followed by its closing point), the
/// displaced vertices expanded from them in the vertex shader ([`resolve`], [`position`]),
/// the triangles indexed by a pattern that depends only on the point's position
/// ([`pattern_indices`], shared by every draw). The triangles with nonzero area, their
/// vertices and their order are those of the paper's templates over each ring (§3.2; fans
/// of straight joints and every triangle of a closing point have zero area and are never
/// shaded), at 40 bytes per border vertex instead of seven 64-byte displaced vertices and
/// three index lists.
#[derive(Clone, Debug, Default)]
pub struct BorderGeometry {
    pub points: Vec<BorderPoint>,
    /// Points of the longest ring appended (≤ [`MAX_RING_POINTS`] to be drawable).
    pub longest_ring: usize,
}

impl BorderGeometry {
    /// The fat borders of every closed border loop of `meshes`, ε = each patch's
    /// [`PatchMesh::eps_border`], half-width across the view its [`PatchMesh::border_width`].
    pub fn of<'a>(meshes: impl IntoIterator<Item = &'a PatchMesh>) -> BorderGeometry {
        let mut g = BorderGeometry::default();
        for m in meshes {
            g.append(m);
        }
        g
    }

    /// Points [`BorderGeometry::append`] adds for `m`: its border vertices and a closing
    /// point per ring.
    pub fn points_of(m: &PatchMesh) -> usize {
        m.borders
            .iter()
            .filter(|r| !r.is_empty())
            .map(|r| r.len() + 1)
            .sum()
    }

    /// Appends the border points of `m`.
    pub fn append(&mut self, m: &PatchMesh) {
        let eps = m.eps_border() as f32;
        let width = width_bits(m.border_width(), m.eps_border());
        let color = super::upload::packed_color(m.color);
        self.points.reserve(Self::points_of(m));
        for ring in m.borders.iter().filter(|r| !r.is_empty()) {
            let n = ring.len();
            self.longest_ring = self.longest_ring.max(n);
            let span = ((n as u32 - 1) << RING_SHIFT) | width;
            let first = self.points.len();
            for k in 0..n {
                let at = |o: usize| m.positions[ring[(k + o) % n] as usize];
                let mut info = span;
                if is_straight(at(n - 1), at(0), at(1)) {
                    info |= INFO_STRAIGHT;
                }
                if k == 0 {
                    info |= INFO_FIRST;
                }
                if k + 1 == n {
                    info |= INFO_LAST;
                }
                self.points.push(BorderPoint {
                    cur: at(0).into(),
                    eps,
                    normal: m.normals[ring[k] as usize].into(),
                    info,
                    patch_id: m.patch_id,
                    color,
                });
            }
            let closing = BorderPoint {
                info: INFO_CLOSING | span,
                ..self.points[first]
            };
            self.points.push(closing);
        }
    }

    /// Indices of `variant`'s draw.
    pub fn index_count(&self, variant: FatBorders) -> usize {
        self.points.len() * pattern(variant).len()
    }

    /// The fat-border triangles with nonzero area for a viewer at `viewer` (homogeneous, see
    /// [`expand`]), expanded on the CPU (world positions), in draw order.
    pub fn triangles(&self, variant: FatBorders, viewer: Vec4) -> Vec<[Vec3; 3]> {
        pattern_indices(variant, self.points.len())
            .chunks_exact(3)
            .map(|t| {
                let v = |k: usize| position(&self.points, variant, t[k] as usize, viewer).0;
                [v(0), v(1), v(2)]
            })
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn narrower_width_moves_across_the_view_only() {
        let (prev, cur, next) = (
            Vec3::new(-1.0, 0.2, 0.0),
            Vec3::ZERO,
            Vec3::new(1.0, 0.1, 0.0),
        );
        let eye = Vec3::new(0.3, -0.4, 5.0);
        let d = (eye - cur).normalize();
        let eps = 0.01;
        for width in [0.0025f64, 0.004, 0.0098] {
            let bits = width_bits(width, eps as f64);
            assert_ne!(bits, 0, "{width}");
            for slot in 1..=6u32 {
                let p = expand(prev, cur, next, eye.extend(1.0), eps, slot | bits);
                let off = p - cur + eps * d;
                let w = off.length() as f64;
                // Rounded up to the next 63rd of ε: never narrower, at most ε / 63 wider.
                assert!(w >= width * (1.0 - 1e-5) && w <= width + eps as f64 / 63.0 + 1e-7);
                assert!(off.dot(d).abs() < 1e-6, "slot {slot}: not across the view");
            }
        }
        assert_eq!(width_bits(0.01, 0.01), 0);
        assert_eq!(width_bits(f64::NAN, 0.01), 0);
        assert_eq!(width_bits(0.005, 0.0), 0);
    }

    #[test]
    fn displaced_vertices_are_eps_away_and_pushed_back() {
        let (prev, cur, next) = (
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::ZERO,
            Vec3::new(1.0, 0.5, 0.0),
        );
        assert!(!is_straight(prev, cur, next));
        let eye = Vec3::new(0.0, 0.0, 10.0);
        let eps = 0.01;
        let d = (eye - cur).normalize();
        for slot in 1..=6 {
            let p = expand(prev, cur, next, eye.extend(1.0), eps, slot);
            // Undo the push-back: the rest is an offset of length ε perpendicular to d.
            let off = p - cur + eps * d;
            assert!((off.length() - eps).abs() < 1e-6, "slot {slot}: {off:?}");
            assert!(off.dot(d).abs() < 1e-6);
        }
        let p0 = expand(prev, cur, next, eye.extend(1.0), eps, 0);
        assert!((p0 - (cur - eps * d)).length() < 1e-7);
    }

    #[test]
    fn straight_joints_use_the_mitre_point() {
        let (prev, cur) = (Vec3::new(-1.0, 0.0, 0.0), Vec3::ZERO);
        let next = Vec3::new(1.0, 0.1, 0.0); // 5.7° turn
        assert!(is_straight(prev, cur, next));
        let eye = Vec3::new(0.0, 0.0, 10.0);
        let eps = 0.01;
        let d = (eye - cur).normalize();
        let m: Vec<Vec3> = (1..=3)
            .map(|s| expand(prev, cur, next, eye.extend(1.0), eps, s | STRAIGHT_FLAG))
            .collect();
        assert!(m[0] == m[1] && m[1] == m[2], "collapsed fan: {m:?}");
        // At least ε from both segment lines (in the view plane), at most 0.4 % more.
        let off = m[0] - cur + eps * d;
        for s in [Vec3::X, (next - cur).normalize()] {
            let dist = (off - s * off.dot(s)).length();
            assert!(dist >= eps * (1.0 - 1e-5) && dist <= eps * 1.004, "{dist}");
        }
    }

    #[test]
    fn opposite_slots_are_on_opposite_sides() {
        let (prev, cur, next) = (
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::ZERO,
            Vec3::new(1.0, 0.5, 0.0),
        );
        let eye = Vec3::new(0.3, 0.1, 5.0);
        for flag in [0, STRAIGHT_FLAG] {
            for (a, b) in [(1, 4), (2, 5), (3, 6)] {
                let pa = expand(prev, cur, next, eye.extend(1.0), 0.1, a | flag);
                let pb = expand(prev, cur, next, eye.extend(1.0), 0.1, b | flag);
                let centre = expand(prev, cur, next, eye.extend(1.0), 0.1, flag);
                assert!((pa + pb - 2.0 * centre).length() < 1e-6);
            }
        }
    }

    #[test]
    fn degenerate_inputs_stay_finite() {
        let eye = Vec3::new(0.0, 0.0, 5.0);
        let z = Vec3::ZERO;
        // Coincident neighbours, a segment pointing at the eye, eye on the vertex, a U-turn.
        let cases = [
            (z, z, z, eye),
            (z, z, Vec3::X, eye),
            (Vec3::new(0.0, 0.0, -1.0), z, Vec3::new(0.0, 0.0, 1.0), eye),
            (Vec3::X, z, -Vec3::X, z),
            (Vec3::X, z, Vec3::X, eye),
        ];
        for (p, c0, n, e) in cases {
            for code in (0..=6).chain((0..=6).map(|s| s | STRAIGHT_FLAG)) {
                assert!(expand(p, c0, n, e.extend(1.0), 0.1, code).is_finite());
                // Orthographic viewers: along the segment, and a zero direction.
                for viewer in [e.extend(0.0), Vec3::Z.extend(0.0), Vec4::ZERO] {
                    assert!(expand(p, c0, n, viewer, 0.1, code).is_finite());
                }
            }
        }
    }

    /// Orthographic: the viewer is the point at infinity (−forward, 0). Every border vertex is
    /// pushed back along the one viewing axis, so v_i itself stays where it projects and every
    /// displaced vertex lands ε from it in the image plane, however far from the axis. Pushed
    /// along the perspective direction from an eye point instead, a vertex off the axis
    /// drifts sideways in the image (the mutation this test catches).
    #[test]
    fn orthographic_push_back_runs_along_the_axis() {
        let forward = Vec3::new(0.2, -0.3, -1.0).normalize();
        let viewer = (-forward).extend(0.0);
        let eps = 0.05;
        // In the image plane: the part of an offset perpendicular to the axis.
        let lateral = |v: Vec3| v - forward * v.dot(forward);
        for cur in [
            Vec3::ZERO,
            Vec3::new(8.0, 5.0, -3.0),
            Vec3::new(-40.0, 2.0, 7.0),
        ] {
            let prev = cur - Vec3::new(1.0, 0.2, 0.0);
            // A sharp joint and a straight one, flagged as the CPU decides.
            for next in [
                cur + Vec3::new(0.9, 0.7, 0.1),
                cur + Vec3::new(1.0, 0.21, 0.0),
            ] {
                let flag = if is_straight(prev, cur, next) {
                    STRAIGHT_FLAG
                } else {
                    0
                };
                let p0 = expand(prev, cur, next, viewer, eps, flag);
                assert!(lateral(p0 - cur).length() < 1e-5, "{cur}: {p0}");
                assert!(((p0 - cur).dot(forward) - eps).abs() < 1e-5);
                for slot in 1..=6 {
                    let p = expand(prev, cur, next, viewer, eps, slot | flag);
                    let off = lateral(p - cur).length();
                    assert!(
                        off >= eps * 0.999 && off <= eps * 1.004,
                        "slot {slot}: {off}"
                    );
                }
            }
            // The perspective direction from an eye on the axis 10 units back is wrong here
            // for every vertex off the axis.
            let next = cur + Vec3::new(0.9, 0.7, 0.1);
            let eye = -forward * 10.0;
            let wrong = expand(prev, cur, next, eye.extend(1.0), eps, 0);
            let drift = lateral(wrong - cur).length();
            assert_eq!(drift > 1e-3, cur != Vec3::ZERO, "{cur}: {drift}");
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

    /// A closed loop in the plane z = 0: a long straight-ish bottom edge with gentle bends
    /// (straight joints), then sharp corners.
    fn loop_mesh(eps: f64) -> PatchMesh {
        let mut positions: Vec<Vec3> = (0..=10)
            .map(|k| {
                let x = k as f32 * 0.2;
                Vec3::new(x, 0.01 * (x * 3.0).sin(), 0.0)
            })
            .collect();
        positions.push(Vec3::new(2.0, 1.0, 0.0));
        positions.push(Vec3::new(0.0, 1.0, 0.0));
        let n = positions.len() as u32;
        PatchMesh {
            normals: vec![Vec3::Z; n as usize],
            positions,
            borders: vec![(0..n).collect()],
            eps_target: eps,
            ..PatchMesh::default()
        }
    }

    #[test]
    fn straight_joints_drop_their_fans() {
        let g = BorderGeometry::of(&[loop_mesh(0.05)]);
        let real = |p: &&BorderPoint| p.info & INFO_CLOSING == 0;
        let straight = g
            .points
            .iter()
            .filter(real)
            .filter(|p| p.info & INFO_STRAIGHT != 0)
            .count();
        assert!(straight >= 8, "{straight}");
        let n = g.points.iter().filter(real).count();
        assert_eq!(g.points.len(), n + 1);
        let eye = Vec3::new(1.0, 0.5, 20.0);
        let tris = |v| g.triangles(v, eye.extend(1.0)).len();
        assert_eq!(tris(FatBorders::Six), 6 * n - 4 * straight);
        assert_eq!(tris(FatBorders::Four), 4 * n - 2 * straight);
        assert_eq!(tris(FatBorders::Two), 2 * n);
    }

    /// The triangles of the indexed templates, expanded directly from the mesh's rings (fans
    /// of straight joints left out): what the vertex-pulling draw must reproduce, triangle
    /// by triangle, in order.
    fn indexed(meshes: &[PatchMesh], variant: FatBorders, eye: Vec3) -> Vec<[Vec3; 3]> {
        let mut out = Vec::new();
        for m in meshes {
            let eps = m.eps_border() as f32;
            let width = width_bits(m.border_width(), m.eps_border());
            for ring in &m.borders {
                let n = ring.len();
                let at = |k: usize| m.positions[ring[k % n] as usize];
                let flat = |k: usize| is_straight(at(k + n - 1), at(k), at(k + 1));
                let point = |k: usize, slot: u32| {
                    let flag = width | if flat(k) { STRAIGHT_FLAG } else { 0 };
                    expand(
                        at(k + n - 1),
                        at(k),
                        at(k + 1),
                        eye.extend(1.0),
                        eps,
                        slot | flag,
                    )
                };
                for k in 0..n {
                    for tri in template(variant).chunks_exact(3) {
                        if flat(k) && is_fan(tri) {
                            continue;
                        }
                        let v = |c: usize| {
                            let (end, slot) = decode(tri[c]);
                            point(k + end as usize, slot)
                        };
                        out.push([v(0), v(1), v(2)]);
                    }
                }
            }
        }
        out
    }

    #[test]
    fn pulled_triangles_are_the_indexed_templates_in_order() {
        let mut meshes = vec![loop_mesh(0.05), loop_mesh(0.02)];
        // A second ring on the first mesh, and rings of one and two points.
        meshes[0].borders.push(vec![3, 7, 12, 1]);
        meshes[1].borders.push(vec![5]);
        meshes[1].borders.push(vec![2, 9]);
        let g = BorderGeometry::of(&meshes);
        assert_eq!(
            g.points.len(),
            meshes.iter().map(BorderGeometry::points_of).sum::<usize>()
        );
        for eye in [Vec3::new(1.0, 0.5, 20.0), Vec3::new(-3.0, 4.0, 0.5)] {
            for variant in FatBorders::ALL_ON {
                let want: Vec<[Vec3; 3]> = indexed(&meshes, variant, eye)
                    .into_iter()
                    .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
                    .collect();
                assert_eq!(g.triangles(variant, eye.extend(1.0)), want, "{variant}");
            }
        }
    }

    #[test]
    fn closing_points_stand_for_their_rings_first_point() {
        let g = BorderGeometry::of(&[loop_mesh(0.05)]);
        let d = g.points.len() - 1;
        assert!(g.points[d].info & INFO_CLOSING != 0);
        let eye = Vec3::new(0.3, 0.2, 9.0);
        for variant in FatBorders::ALL_ON {
            for slot in [3, 6] {
                let (p, _) = resolve(&g.points, variant, d * SLOTS_PER_POINT + slot);
                assert_eq!(p, 0, "{variant} slot {slot}");
                assert_eq!(
                    position(
                        &g.points,
                        variant,
                        d * SLOTS_PER_POINT + slot,
                        eye.extend(1.0)
                    ),
                    position(&g.points, variant, slot, eye.extend(1.0))
                );
            }
        }
    }

    #[test]
    fn band_covers_points_within_eps_of_the_border() {
        // Looking straight down: every point within 0.95ε of the polyline must lie in the
        // projection of some fat-border triangle, for each variant (6 and 4 everywhere; 2 away
        // from the sharp corners, where the paper notes it is thinner).
        let eps = 0.05f32;
        let mesh = loop_mesh(eps as f64);
        let g = BorderGeometry::of(std::slice::from_ref(&mesh));
        let eye = Vec3::new(1.0, 0.5, 200.0);
        let ring: Vec<Vec3> = mesh.positions.clone();
        for variant in FatBorders::ALL_ON {
            let tris = g.triangles(variant, eye.extend(1.0));
            for w in 0..ring.len() {
                let (a, b) = (ring[w], ring[(w + 1) % ring.len()]);
                let dir = (b - a).normalize();
                let normal = Vec3::new(-dir.y, dir.x, 0.0);
                // The 2-vertex variant is thinner along segments ending at a sharp corner
                // (ε·cos(θ/2) there, as the paper notes): test it on the others.
                let corners = [0usize, 10, 11, 12];
                let at_corner = corners.contains(&w) || corners.contains(&((w + 1) % ring.len()));
                if variant == FatBorders::Two && at_corner {
                    continue;
                }
                for k in 0..=10 {
                    let f = k as f32 / 10.0;
                    let on = a + (b - a) * f;
                    for side in [-0.95f32, 0.0, 0.95] {
                        let q = (on + normal * side * eps).truncate();
                        let covered = tris.iter().any(|t| inside_xy(q, t));
                        assert!(covered, "{variant}: {q:?} (edge {w}) not covered");
                    }
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
