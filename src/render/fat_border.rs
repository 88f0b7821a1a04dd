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
//! * 2 triangles ([`FatBorders::Two`], the paper's "2 vertices" by its cost): the segment quad
//!   alone, capped — see below.
//!
//! **The 2-vertex band cannot close every gap, so `Two` draws capped segment quads.** The
//! paper's 2-vertex band joins the segments at v_i2, v_i5 on the bisector: at a joint turning
//! by θ (on screen) it is ε·cos(θ/2) wide. Moving v_i2, v_i5 to the mitre points
//! (ε / cos(θ/2) from v_i, on both segments' offset lines) is the only way one pair of points
//! per joint keeps the band ε wide on both segments, and the mitre is unbounded: a border
//! that turns back on itself on screen (θ → 180°: a spike of a mesh border, or a segment seen
//! nearly end-on between two others) needs it arbitrarily long, and any limit L leaves the
//! band L·ε·cos(θ/2) wide at the tip. On screen, with the gap (·) the neighbour's border
//! leaves outside a spike of the border (—):
//!
//! ```text
//!  a spike: the border runs out to v_i and back (θ near 180°)
//!
//!    mitre points (both on the axis)          capped quads
//!    ┌───────────────────────.__              ┌──────────────────────────┐
//!    │ v_{i−1} ═══════════════════ v_i  ·     │ v_{i−1} ═════════════ v_i │
//!    └───────────────────────'‾‾              └──────────────────────────┘
//!    the band tapers to nothing at the tip:   ε all round: each quad is its
//!    the gap (·) beyond it stays open         segment ± ε across and along
//! ```
//!
//! A mitre taken from the segments' directions in space is also wrong on screen:
//! a zigzag mesh border seen at 60° turns sharper in its projection than in space
//! (`two_vertex_band_covers_the_eps_neighbourhood_of_a_zigzag_mesh_border`: hundreds of
//! points within 0.95 ε uncovered). So [`FatBorders::Two`] draws one quad per segment, its
//! own: slots 1, 4 of v_i (start of s_i) moved back along s_i by the half-width, slots 6, 3 of
//! v_{i+1} (end of s_i) moved on — the paper's §3.1 construction, "extending the line segment
//! in such a way that the projection … extends the projected line segment by half a pixel
//! in each direction". Each quad holds its segment's whole half-width neighbourhood on
//! screen (the stadium lies in the extended rectangle), whatever the turns, so the union
//! holds the polyline's. It keeps the variant's cost in triangles (2 per border vertex, no
//! fans) at 4 displaced vertices per point instead of 2. Directions along and across are taken
//! in the plane across the view (`n = normalize(s × d)`, `d × n` = the segment's projected
//! direction), so foreshortening does not matter.
//!
//! **No T-junctions.** The paper's fans have their apex at v_i, the midpoint of the segment
//! quad's edge v_i1–v_i4 (and of the previous quad's v_i3–v_i6): a T-junction, where the
//! rasterizer's shared-edge rule does not hold and a pixel centre on the seam could stay
//! uncovered (one per view or so under `check --stress`). Here the fans are drawn from the
//! far end of that edge instead — v_i3–v_i2–v_i1 from v_i4 and v_i6–v_i5–v_i4 from v_i1 —
//! so each fan shares the whole edge v_i1–v_i4 with the quad. The displaced vertices lie on
//! the circle of radius ε about v_i in the plane across the view, in angular order, so each
//! fan is convex, holds the paper's fan (its apex v_i is on the fan's edge v_i1–v_i4) and
//! reaches nothing farther than ε from v_i; the previous quad's edge v_i3–v_i6 runs inside
//! the two fans.
//!
//! **Straight joints** (the polyline turns by less than 8°, `STRAIGHT_COS`): v_i1, v_i2, v_i3
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
//! the code's [`WIDTH_MASK`] bits (`width_bits`).
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
    // joint fans around v_i, from the far end of the segment quad's edge v_i1–v_i4 (module
    // doc, "No T-junctions")
    c(0, 4),
    c(0, 3),
    c(0, 2),
    c(0, 4),
    c(0, 2),
    c(0, 1),
    c(0, 1),
    c(0, 6),
    c(0, 5),
    c(0, 1),
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
    c(0, 4),
    c(0, 3),
    c(0, 1),
    c(0, 1),
    c(0, 6),
    c(0, 4),
];

/// The segment quad alone, its corners capped ([`CAP_FLAG`]).
const TEMPLATE_2: [u32; 6] = [c(0, 1), c(0, 4), c(1, 6), c(0, 1), c(1, 6), c(1, 3)];

/// Triangle-list template drawn once per border vertex v_i, as codes (see `c`).
pub(crate) fn template(variant: FatBorders) -> &'static [u32] {
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

/// A fan triangle: all its corners are v_i's (the segment quad reaches v_{i+1}).
#[cfg(test)]
fn is_fan(tri: &[u32]) -> bool {
    tri.iter().all(|&code| decode(code).0 == 0)
}

const TINY: f32 = 1e-12;
/// Joints where consecutive segments turn by less than acos(0.99) ≈ 8.1° are straight (see the
/// module doc).
pub(crate) const STRAIGHT_COS: f32 = 0.99;
/// Flag in a slot code (bit 3): the border vertex's joint is straight (`FB_STRAIGHT` in WGSL).
pub const STRAIGHT_FLAG: u32 = 8;
/// Flag in a slot code (bit 10): the 2-triangle variant's draw ([`FatBorders::Two`]), whose
/// segment quads are capped: slots 1, 4 moved back along s_i, slots 3, 6 on along s_{i−1}, by
/// the half-width (`FB_CAPPED` in WGSL; see [`expand`] and the module doc).
pub const CAP_FLAG: u32 = 1 << 10;

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

/// Whether the border turns by less than acos(`STRAIGHT_COS`) at `cur`.
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
pub(crate) fn width_bits(width: f64, eps: f64) -> u32 {
    let narrower = width.is_finite() && eps > 0.0 && width < eps;
    if !narrower {
        return 0;
    }
    let q = ((width / eps) * 63.0).ceil().clamp(1.0, 63.0) as u32;
    if q >= 63 { 0 } else { q << WIDTH_SHIFT }
}

/// CPU twin of `fat_border_position` (WGSL). `code` = slot (0 = v_i pushed back, 1..6 = eq.
/// (1)–(6)) plus [`STRAIGHT_FLAG`] for a straight joint or [`CAP_FLAG`] in the 2-triangle
/// variant's draw (which ignores the straight flag) plus the half-width across the view
/// as a fraction of ε in [`WIDTH_MASK`] (`width_bits`; 0 = ε; the push-back along the view is
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
    let off = if code & CAP_FLAG != 0 {
        // Slots 1, 4: the start of s_i, moved back along it; 3, 6: the end of s_{i−1}, moved
        // on. d × n is the segment's direction across the view (its projection, unit), also
        // where the segment is seen end-on and `side` chose n.
        let (dir, along) = match slot {
            3 | 6 => (s_prev, 1.0),
            _ => (s_next, -1.0),
        };
        let across = if slot == 4 || slot == 6 { -1.0 } else { 1.0 };
        let n = side(dir, d);
        match slot {
            1 | 3 | 4 | 6 => n * across + d.cross(n) * along,
            _ => Vec3::ZERO,
        }
    } else if code & STRAIGHT_FLAG != 0 {
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
/// `RING_SHIFT` (the neighbours of a ring's ends wrap around).
pub const INFO_STRAIGHT: u32 = 1;
pub(crate) const INFO_FIRST: u32 = 2;
pub(crate) const INFO_LAST: u32 = 4;
pub const INFO_CLOSING: u32 = 8;
/// Bits 4..9 of [`BorderPoint::info`] and of an [`expand`] code: the fat border's half-width
/// across the view as q / 63 of ε (q = 0: ε), see `width_bits`.
pub const WIDTH_SHIFT: u32 = 4;
pub const WIDTH_MASK: u32 = 63 << WIDTH_SHIFT;
/// The ring's length − 1 sits above this bit: rings of up to 2²² points (a ring that long
/// holds 160 MiB of points, more than a storage binding: `RenderError::TooLarge` first).
pub(crate) const RING_SHIFT: u32 = 10;
/// Longest ring a [`BorderPoint`] can name (its length − 1 fills the bits above
/// [`RING_SHIFT`]); a longer one is refused by the renderer as too large.
pub(crate) const MAX_RING_POINTS: usize = 1 << (32 - RING_SHIFT);

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
    /// [`INFO_STRAIGHT`] | `INFO_FIRST` | `INFO_LAST` | [`INFO_CLOSING`] | half-width
    /// ([`WIDTH_MASK`]) | (ring length − 1) << `RING_SHIFT`.
    pub info: u32,
    pub patch_id: u32,
    /// The patch colour, packed (see `PatchMesh::color`); the alpha byte's two low bits are
    /// the edge modes that draw the segment from this point to the next (what it runs
    /// along, `model::edges::EdgeKind`: `edge_bits`), the rest of it says whether the
    /// colour is the patch's own (≥ 128) or the default (< 128).
    pub color: [u8; 4],
}

/// Mask of the edge bits in the alpha byte of [`BorderPoint::color`].
pub(crate) const EDGE_BITS: u8 = crate::model::edges::EDGE_ALL | crate::model::edges::EDGE_FEATURE;

/// The packed colour `color` of a border point whose segment to the next runs along `kind`.
pub(crate) fn edge_bits(color: [u8; 4], kind: crate::model::edges::EdgeKind) -> [u8; 4] {
    let [r, g, b, a] = color;
    [r, g, b, (a & !EDGE_BITS) | kind as u8]
}

/// Vertex indices per point: slot s of point k is vertex 8k + s.
pub const SLOTS_PER_POINT: usize = 8;

/// The triangle-list codes drawn once per point (see `c`): the variant's template.
pub fn pattern(variant: FatBorders) -> &'static [u32] {
    template(variant)
}

/// Index `pattern(variant)` for points `0..points`: code (end, slot) of point k is vertex
/// 8(k + end) + slot. One buffer of it serves every draw (offset by a base vertex).
pub(crate) fn pattern_indices(variant: FatBorders, points: usize) -> Vec<u32> {
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
/// `variant`'s draw is (the same for every variant: each template names the paper's slots).
/// A closing point's slots 3 and 6 are its ring's first point's; its other slots coincide
/// with them or with the next point's slot 6, so each of its triangles has two equal corners.
pub fn resolve(points: &[BorderPoint], _variant: FatBorders, i: usize) -> (usize, u32) {
    let (mut p, mut s) = (i / SLOTS_PER_POINT, (i % SLOTS_PER_POINT) as u32);
    if point(points, p).info & INFO_CLOSING != 0 {
        (p, s) = match s {
            1 | 4 | 5 => (p.wrapping_add(1), 6),
            0 | 2 => (p, 3),
            _ => (p, s),
        };
        let info = point(points, p).info;
        if info & INFO_CLOSING != 0 {
            p = p.wrapping_sub((info >> RING_SHIFT) as usize + 1);
        }
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
    pulled(points, variant, i, viewer, |p| p, 0.0)
}

/// Vertex `i` of `variant`'s draw expanded from ring points moved by `moved`, ε raised by
/// `eps_added` (a placement that adds to ε — a translated copy — draws the whole ε wide):
/// [`position`] and [`position_placed`].
fn pulled(
    points: &[BorderPoint],
    variant: FatBorders,
    i: usize,
    viewer: Vec4,
    moved: impl Fn(Vec3) -> Vec3,
    eps_added: f32,
) -> (Vec3, usize) {
    let (p, slot) = resolve(points, variant, i);
    let q = point(points, p);
    let flag = if q.info & INFO_STRAIGHT != 0 {
        STRAIGHT_FLAG
    } else {
        0
    };
    let width = if eps_added == 0.0 {
        q.info & WIDTH_MASK
    } else {
        0
    };
    let cap = if variant == FatBorders::Two {
        CAP_FLAG
    } else {
        0
    };
    let at = |k: usize| moved(Vec3::from(point(points, k).cur));
    let (prev, next) = (neighbour(points, p, false), neighbour(points, p, true));
    let eps = q.eps + eps_added;
    (
        expand(
            at(prev),
            at(p),
            at(next),
            viewer,
            eps,
            slot | flag | width | cap,
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
    pulled(points, variant, i, viewer, |p| place(rows, p), eps_added)
}

/// Fat-border geometry drawn by vertex pulling: every border vertex stored once
/// ([`BorderPoint`], ring after ring, each ring followed by its closing point), the
/// displaced vertices expanded from them in the vertex shader ([`resolve`], [`position`]),
/// the triangles indexed by a pattern that depends only on the point's position
/// (`pattern_indices`, shared by every draw). The triangles with nonzero area, their
/// vertices and their order are those of the paper's templates over each ring (§3.2; fans
/// of straight joints and every triangle of a closing point have zero area and are never
/// shaded), at 40 bytes per border vertex instead of seven 64-byte displaced vertices and
/// three index lists.
#[derive(Clone, Debug, Default)]
pub struct BorderGeometry {
    pub points: Vec<BorderPoint>,
    /// Points of the longest ring appended (≤ `MAX_RING_POINTS` to be drawable).
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
    pub(crate) fn points_of(m: &PatchMesh) -> usize {
        m.geometry()
            .borders
            .iter()
            .filter(|r| !r.is_empty())
            .map(|r| r.len() + 1)
            .sum()
    }

    /// Appends the border points of `m` (an instance's: of its world-space copy).
    pub(crate) fn append(&mut self, m: &PatchMesh) {
        let world = m.world();
        let m = world.as_ref();
        let eps = m.eps_border() as f32;
        let width = width_bits(m.border_width(), m.eps_border());
        let color = super::upload::packed_color(m.color);
        self.points.reserve(Self::points_of(m));
        for (r, ring) in m.borders.iter().enumerate().filter(|(_, r)| !r.is_empty()) {
            let kinds = m.border_kinds.get(r);
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
                // Unknown kinds: every segment a sharp edge.
                let kind = kinds.and_then(|ks| ks.get(k)).copied().unwrap_or_default();
                self.points.push(BorderPoint {
                    cur: at(0).into(),
                    eps,
                    normal: m.normals[ring[k] as usize].into(),
                    info,
                    patch_id: m.patch_id,
                    color: edge_bits(color, kind),
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
mod tests;
