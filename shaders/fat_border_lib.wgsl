// Fat-border vertex expansion — Balázs, Guthe, Klein, "Fat Borders: Gap Filling for Efficient
// View-dependent LOD Rendering" (2004), section 3.1, equations (1)-(6) and step 4.
//
// A border vertex v_i with neighbours v_{i-1}, v_{i+1} on its (closed) border polyline is
// displaced by ε perpendicular to one of the directions s_i, t_i, s_{i-1} (or their negations)
// and to the direction d_i from v_i to the eye, then pushed away from the viewer by ε along d_i.
// Slot 0 is v_i itself (pushed back); slots 1..6 are v_i1..v_i6 of the paper.
//
// The same function runs in the render shader (scene.wgsl) and in a compute twin used by the
// tests; its Rust CPU twin is `render::fat_border::expand`. Keep all three in step.

const FB_TINY: f32 = 1e-12;
// Where the polyline turns by less than about 2.5° (cos > 0.999), s_{i-1}, t_i and s_i give
// offsets within 0.1 % of each other: all three use t_i, so the joint fans of the 6- and
// 4-vertex variants collapse to zero area and the rasterizer drops them at setup.
const FB_STRAIGHT_COS: f32 = 0.999;

// `v` normalised, or `fallback` when `v` is (nearly) zero.
fn fb_normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let l2 = dot(v, v);
    if (l2 > FB_TINY * FB_TINY) {
        return v * inverseSqrt(l2);
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

// World position of slot `slot` (0..6) of the fat border of `cur`.
fn fat_border_position(
    prev: vec3<f32>,
    cur: vec3<f32>,
    next: vec3<f32>,
    eye: vec3<f32>,
    eps: f32,
    slot: u32,
) -> vec3<f32> {
    let d = fb_normalize_or(eye - cur, vec3<f32>(0.0, 0.0, 1.0));
    let s_next0 = next - cur;
    let s_prev0 = cur - prev;
    let s_next = fb_normalize_or(s_next0, fb_normalize_or(s_prev0, vec3<f32>(1.0, 0.0, 0.0)));
    let s_prev = fb_normalize_or(s_prev0, s_next);
    let t = fb_normalize_or(s_prev + s_next, s_next);
    var dir_next = s_next;
    var dir_prev = s_prev;
    if (dot(s_prev, s_next) > FB_STRAIGHT_COS) {
        dir_next = t;
        dir_prev = t;
    }
    var off = vec3<f32>(0.0, 0.0, 0.0);
    switch slot {
        case 1u: { off = fb_side(dir_next, d); }
        case 2u: { off = fb_side(t, d); }
        case 3u: { off = fb_side(dir_prev, d); }
        case 4u: { off = fb_side(-dir_next, d); }
        case 5u: { off = fb_side(-t, d); }
        case 6u: { off = fb_side(-dir_prev, d); }
        default: { off = vec3<f32>(0.0, 0.0, 0.0); }
    }
    return cur + eps * off - eps * d;
}
