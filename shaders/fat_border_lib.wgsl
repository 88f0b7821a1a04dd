// Fat-border vertex expansion — Balázs, Guthe, Klein, "Fat Borders: Gap Filling for Efficient
// View-dependent LOD Rendering" (2004), section 3.1, equations (1)-(6) and step 4.
//
// A border vertex v_i with neighbours v_{i-1}, v_{i+1} on its (closed) border polyline is
// displaced by ε perpendicular to one of the directions s_i, t_i, s_{i-1} (or their negations)
// and to the direction d_i from v_i to the eye, then pushed away from the viewer by ε along d_i.
// Slot 0 is v_i itself (pushed back); slots 1..6 are v_i1..v_i6 of the paper.
// The viewer is given in homogeneous coordinates: (eye, 1) for a perspective view, the point at
// infinity (-forward, 0) for an orthographic one, whose d_i is then the same everywhere:
// d_i = normalize(viewer.xyz - v_i * viewer.w).
//
// The same function runs in the render shader (scene.wgsl) and in a compute twin used by the
// tests; its Rust CPU twin is `render::fat_border::expand`. Keep all three in step.

const FB_TINY: f32 = 1e-12;
// Bit 3 of a slot code: the joint at `cur` is straight (turns by less than ~8°, decided on the
// CPU by `render::fat_border::is_straight`). Slots 1-3 (and 4-6) then all sit at the mitre
// point ε·normalize(t × d)/cos(θ/2): the band stays at least ε wide and the joint fans have
// zero area (their triangles are not drawn).
const FB_STRAIGHT: u32 = 8u;
// Bit 10 of a slot code: the 2-triangle variant (`render::fat_border::CAP_FLAG`), one quad per
// segment from slots 1, 4 of v_i to slots 6, 3 of v_{i+1}, each quad its segment's own: the
// displaced vertices of slots 1, 4 (start of s_i) are moved back along s_i by the half-width,
// those of slots 3, 6 (end of s_{i-1}) on along s_{i-1}, both across the view. The segment
// extended by the half-width at both ends (the paper's §3.1: "extends the projected line
// segment by half a pixel in each direction"): every quad holds the whole half-width
// neighbourhood of its segment's projection, whatever the joint's turn.
const FB_CAPPED: u32 = 1024u;
// Bits 4..9 of a slot code (and of a border point's info): the fat border's half-width across
// the view as q / 63 of ε, q = 0 meaning ε (`render::fat_border::width_bits`).
const FB_WIDTH_SHIFT: u32 = 4u;
const FB_WIDTH_MASK: u32 = 1008u;

// `v` normalised, or `fallback` when `v` is (nearly) zero.
fn fb_normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let l2 = dot(v, v);
    if (l2 > FB_TINY * FB_TINY) {
        return v * (1.0 / sqrt(l2));
    }
    return fallback;
}

// Unit vector perpendicular to `dir` and to the view direction `d`: normalize(dir × d).
// When `dir` points along `d` (the segment is seen end-on) any direction perpendicular to `d`
// covers the projected point equally; one is chosen deterministically.
fn fb_side(dir: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let c = cross(dir, d);
    if (dot(c, c) > 1e-12) {
        return normalize(c);
    }
    var helper = vec3<f32>(1.0, 0.0, 0.0);
    if (abs(d.x) > 0.9) {
        helper = vec3<f32>(0.0, 1.0, 0.0);
    }
    return normalize(cross(helper, d));
}

// World position of the displaced vertex `code` (slot 0..6, plus FB_STRAIGHT or FB_CAPPED, plus
// the half-width) of the fat border of `cur`.
fn fat_border_position(
    prev: vec3<f32>,
    cur: vec3<f32>,
    next: vec3<f32>,
    viewer: vec4<f32>,
    eps: f32,
    code: u32,
) -> vec3<f32> {
    let slot = code & 7u;
    // Half-width across the view: q / 63 of ε from bits 4..9 (q = 0: ε); push-back ε.
    let q = (code & FB_WIDTH_MASK) >> FB_WIDTH_SHIFT;
    var width = eps;
    if (q != 0u) {
        width = eps * f32(q) / 63.0;
    }
    let d = fb_normalize_or(viewer.xyz - cur * viewer.w, vec3<f32>(0.0, 0.0, 1.0));
    let s_next0 = next - cur;
    let s_prev0 = cur - prev;
    let s_next = fb_normalize_or(s_next0, fb_normalize_or(s_prev0, vec3<f32>(1.0, 0.0, 0.0)));
    let s_prev = fb_normalize_or(s_prev0, s_next);
    let sum = s_prev + s_next;
    let t = fb_normalize_or(sum, s_next);
    var off = vec3<f32>(0.0, 0.0, 0.0);
    if ((code & FB_CAPPED) != 0u) {
        // Slots 1, 4: the start of s_i, moved back along it; 3, 6: the end of s_{i-1},
        // moved on. cross(d, n) is the segment's direction across the view (its projection,
        // unit), also where the segment is seen end-on and `fb_side` chose n.
        var dir = s_next;
        var along = -1.0;
        if (slot == 3u || slot == 6u) {
            dir = s_prev;
            along = 1.0;
        }
        var across = 1.0;
        if (slot == 4u || slot == 6u) {
            across = -1.0;
        }
        let n = fb_side(dir, d);
        if (slot == 1u || slot == 3u || slot == 4u || slot == 6u) {
            off = n * across + cross(d, n) * along;
        }
    } else if ((code & FB_STRAIGHT) != 0u) {
        // 1 / cos(θ/2), with cos(θ/2) = |s_{i-1} + s_i| / 2.
        let mitre = 2.0 / max(length(sum), 1.0);
        if (slot >= 1u && slot <= 3u) {
            off = fb_side(t, d) * mitre;
        } else if (slot >= 4u && slot <= 6u) {
            off = fb_side(-t, d) * mitre;
        }
    } else {
        switch slot {
            case 1u: { off = fb_side(s_next, d); }
            case 2u: { off = fb_side(t, d); }
            case 3u: { off = fb_side(s_prev, d); }
            case 4u: { off = fb_side(-s_next, d); }
            case 5u: { off = fb_side(-t, d); }
            case 6u: { off = fb_side(-s_prev, d); }
            default: { off = vec3<f32>(0.0, 0.0, 0.0); }
        }
    }
    return cur + width * off - eps * d;
}

// ---- Vertex pulling: the displaced vertices expanded from border points ----
//
// Every border vertex is stored once, ring after ring, as a `render::fat_border::BorderPoint`
// of FB_POINT_WORDS 32-bit words: cur (3 × f32), ε, normal (3 × f32), info, patch id, packed
// colour. info: FB_INFO_STRAIGHT | FB_INFO_FIRST | FB_INFO_LAST | FB_INFO_CLOSING | half-width
// (FB_WIDTH_MASK) | (ring length - 1) << FB_RING_SHIFT. Each ring is followed by a closing point, a copy of its
// first point. Vertex i of a draw is slot (i mod 8) of point (i div 8); the triangles come
// from an index pattern that depends only on the point's position (`render::fat_border::
// pattern`), so a ring's last segment reaches its closing point, whose slots 3 and 6 are
// those of the ring's first point and whose other slots coincide with them or with the next
// point's slot 6: every triangle of a closing point has zero area. CPU twin:
// `render::fat_border::resolve` and `position`.

const FB_POINT_WORDS: u32 = 10u;
const FB_INFO_STRAIGHT: u32 = 1u;
const FB_INFO_FIRST: u32 = 2u;
const FB_INFO_LAST: u32 = 4u;
const FB_INFO_CLOSING: u32 = 8u;
const FB_RING_SHIFT: u32 = 10u;

@group(1) @binding(0) var<storage, read> fb_points: array<u32>;

fn fb_word_f(k: u32, w: u32) -> f32 {
    return bitcast<f32>(fb_points[k * FB_POINT_WORDS + w]);
}

fn fb_cur(k: u32) -> vec3<f32> {
    return vec3<f32>(fb_word_f(k, 0u), fb_word_f(k, 1u), fb_word_f(k, 2u));
}

fn fb_normal(k: u32) -> vec3<f32> {
    return vec3<f32>(fb_word_f(k, 4u), fb_word_f(k, 5u), fb_word_f(k, 6u));
}

fn fb_info(k: u32) -> u32 {
    return fb_points[k * FB_POINT_WORDS + 7u];
}

fn fb_patch_id(k: u32) -> u32 {
    return fb_points[k * FB_POINT_WORDS + 8u];
}

fn fb_color(k: u32) -> vec4<f32> {
    return unpack4x8unorm(fb_points[k * FB_POINT_WORDS + 9u]);
}

// The ring neighbour of point k before it (after = false) or after it.
fn fb_neighbour(k: u32, after: bool) -> u32 {
    let info = fb_info(k);
    let span = info >> FB_RING_SHIFT;
    if (after) {
        if ((info & FB_INFO_LAST) != 0u) {
            return k - span;
        }
        return k + 1u;
    }
    if ((info & FB_INFO_FIRST) != 0u) {
        return k + span;
    }
    return k - 1u;
}

// The point and slot whose displaced vertex vertex i is (every variant's template names the
// paper's slots; the 2-triangle variant's is the segment quad of the others).
fn fb_resolve(i: u32) -> vec2<u32> {
    var p = i / 8u;
    var s = i % 8u;
    if ((fb_info(p) & FB_INFO_CLOSING) != 0u) {
        if (s == 1u || s == 4u || s == 5u) {
            p = p + 1u;
            s = 6u;
        } else if (s == 0u || s == 2u) {
            s = 3u;
        }
        let info = fb_info(p);
        if ((info & FB_INFO_CLOSING) != 0u) {
            p = p - (info >> FB_RING_SHIFT) - 1u;
        }
    }
    return vec2<u32>(p, s);
}

// Vertex i (of a template with `len` codes; 6: the 2-triangle variant, FB_CAPPED) for a
// viewer at `viewer` (homogeneous, see `fat_border_position`); `w` holds the point it is
// expanded from (its shading attributes).
fn fat_border_vertex(i: u32, len: u32, viewer: vec4<f32>) -> vec4<f32> {
    let r = fb_resolve(i);
    let p = r.x;
    var flag = 0u;
    if ((fb_info(p) & FB_INFO_STRAIGHT) != 0u) {
        flag = FB_STRAIGHT;
    }
    let prev = fb_cur(fb_neighbour(p, false));
    let next = fb_cur(fb_neighbour(p, true));
    if (len == 6u) {
        flag = flag | FB_CAPPED;
    }
    let code = r.y | flag | (fb_info(p) & FB_WIDTH_MASK);
    let pos = fat_border_position(prev, fb_cur(p), next, viewer, fb_word_f(p, 3u), code);
    return vec4<f32>(pos, bitcast<f32>(p));
}

// ---- Instanced parts: a shared mesh drawn once per placement ----
//
// A part placed k times is uploaded once in its surface's own coordinates and drawn with each
// placement (`render::resident`, instances; CPU twin `render::fat_border::place`). Placements
// are similarities (rotation or reflection, uniform scale, translation), given as the rows of
// the 3 × 4 matrix; the fat border of a placement is expanded in world space from its
// transformed ring points, with ε that of the shared mesh (already in the placement's units)
// plus the placement's own addition.

struct FbPlacement {
    x: vec4<f32>,
    y: vec4<f32>,
    z: vec4<f32>,
};

// Point p moved by placement m.
fn fb_place(m: FbPlacement, p: vec3<f32>) -> vec3<f32> {
    let h = vec4<f32>(p, 1.0);
    return vec3<f32>(dot(m.x, h), dot(m.y, h), dot(m.z, h));
}

// Unit normal n turned by placement m (a similarity: its linear part, normalised).
fn fb_turn(m: FbPlacement, n: vec3<f32>) -> vec3<f32> {
    let t = vec3<f32>(dot(m.x.xyz, n), dot(m.y.xyz, n), dot(m.z.xyz, n));
    return fb_normalize_or(t, vec3<f32>(0.0, 0.0, 0.0));
}

// As `fat_border_vertex`, for the points of a shared mesh drawn with placement m: the ring
// points are moved first, then expanded as every other border (ε + eps_added; a placement
// that adds to ε draws its fat borders the whole ε wide, not the shared mesh's border width).
fn fat_border_vertex_placed(
    i: u32,
    len: u32,
    viewer: vec4<f32>,
    m: FbPlacement,
    eps_added: f32,
) -> vec4<f32> {
    let r = fb_resolve(i);
    let p = r.x;
    var flag = 0u;
    if ((fb_info(p) & FB_INFO_STRAIGHT) != 0u) {
        flag = FB_STRAIGHT;
    }
    let prev = fb_place(m, fb_cur(fb_neighbour(p, false)));
    let next = fb_place(m, fb_cur(fb_neighbour(p, true)));
    let cur = fb_place(m, fb_cur(p));
    let eps = fb_word_f(p, 3u) + eps_added;
    if (len == 6u) {
        flag = flag | FB_CAPPED;
    }
    var code = r.y | flag;
    if (eps_added == 0.0) {
        code = code | (fb_info(p) & FB_WIDTH_MASK);
    }
    let pos = fat_border_position(prev, cur, next, viewer, eps, code);
    return vec4<f32>(pos, bitcast<f32>(p));
}
