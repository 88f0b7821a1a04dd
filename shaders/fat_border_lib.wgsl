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
// Bit 3 of a slot code: the joint at `cur` is straight (turns by less than ~8°, decided on the
// CPU by `render::fat_border::is_straight`). Slots 1-3 (and 4-6) then all sit at the mitre
// point ε·normalize(t × d)/cos(θ/2): the band stays at least ε wide and the joint fans have
// zero area (their triangles are not drawn).
const FB_STRAIGHT: u32 = 8u;

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

// World position of the displaced vertex `code` (slot 0..6, plus FB_STRAIGHT) of the fat
// border of `cur`.
fn fat_border_position(
    prev: vec3<f32>,
    cur: vec3<f32>,
    next: vec3<f32>,
    eye: vec3<f32>,
    eps: f32,
    code: u32,
) -> vec3<f32> {
    let slot = code & 7u;
    let d = fb_normalize_or(eye - cur, vec3<f32>(0.0, 0.0, 1.0));
    let s_next0 = next - cur;
    let s_prev0 = cur - prev;
    let s_next = fb_normalize_or(s_next0, fb_normalize_or(s_prev0, vec3<f32>(1.0, 0.0, 0.0)));
    let s_prev = fb_normalize_or(s_prev0, s_next);
    let sum = s_prev + s_next;
    let t = fb_normalize_or(sum, s_next);
    var off = vec3<f32>(0.0, 0.0, 0.0);
    if ((code & FB_STRAIGHT) != 0u) {
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
    return cur + eps * off - eps * d;
}
