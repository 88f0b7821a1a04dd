// Surfaces and fat borders of independently tessellated patches.
// Composed after fat_border_lib.wgsl (see `render::shaders`).

struct Globals {
    view_proj: mat4x4<f32>,
    // xyz: eye position; w: 1 for a perspective projection, 0 for an orthographic one.
    eye: vec4<f32>,
    // xyz: unit viewing axis (from the eye towards the target).
    forward: vec4<f32>,
    // xyz: unit direction towards the light.
    light: vec4<f32>,
    // rgb: colour for `flat` shading, and for `lit` shading of patches without their own.
    color: vec4<f32>,
    // x: shading mode (0 lit, 1 flat, 2 ids); y: codes of the fat-border template drawn (18,
    // 12 or 6; see `fat_border_vertex`); z: section planes in use (0–3); w: the edge bits a
    // border segment needs to be drawn as an edge (`vs_edge`; 0 none, 1 all, 2 feature).
    mode: vec4<u32>,
    // Section planes (`render::section`): (N, −N·P); the side N points into is removed.
    sections: array<vec4<f32>, 3>,
};

@group(0) @binding(0) var<uniform> globals: Globals;

// The viewer in homogeneous coordinates (see `fat_border_position`): the eye, or under an
// orthographic projection the point at infinity behind the camera.
fn viewer() -> vec4<f32> {
    if (globals.eye.w == 0.0) {
        return vec4<f32>(-globals.forward.xyz, 0.0);
    }
    return vec4<f32>(globals.eye.xyz, 1.0);
}

// Whether `p` lies in a removed half-space of a section plane (`Sections::removes`).
fn section_removes(p: vec3<f32>) -> bool {
    for (var i = 0u; i < globals.mode.z; i++) {
        let s = globals.sections[i];
        if (dot(s.xyz, p) + s.w > 0.0) {
            return true;
        }
    }
    return false;
}

// Where the ray from the viewer to the kept point `at` last entered the kept region through a
// section plane (xyz) and that plane's index (w), w = −1 when through none
// (`Sections::cap_point`, the CPU twin).
fn section_cap(at: vec3<f32>) -> vec4<f32> {
    let h = viewer();
    let perspective = h.w != 0.0;
    var dir = globals.forward.xyz;
    if (perspective) {
        dir = at - h.xyz;
    }
    var best = -3.0e38;
    var index = -1.0;
    for (var i = 0u; i < globals.mode.z; i++) {
        let s = globals.sections[i];
        let nd = dot(s.xyz, dir);
        if (nd >= 0.0) {
            continue;
        }
        let t = -(dot(s.xyz, at) + s.w) / nd;
        if (perspective && t <= -1.0) {
            continue;
        }
        if (t > best) {
            best = t;
            index = f32(i);
        }
    }
    if (index < 0.0) {
        return vec4<f32>(at, -1.0);
    }
    return vec4<f32>(at + dir * best, index);
}

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) patch_id: u32,
    // Where the fragment really is (differs from `world` on fat borders).
    @location(3) actual: vec3<f32>,
    // The patch's own colour; alpha 0 for "use globals.color".
    @location(4) @interpolate(flat) color: vec4<f32>,
};

@vertex
fn vs_surface(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) patch_id: u32,
    @location(3) color: vec4<f32>,
) -> VsOut {
    var out: VsOut;
    out.clip = globals.view_proj * vec4<f32>(position, 1.0);
    out.color = color;
    out.world = position;
    out.actual = position;
    out.normal = normal;
    out.patch_id = patch_id;
    return out;
}

// One displaced fat-border vertex, pulled from the border points (`fat_border_vertex`):
// vertex i of the template with globals.mode.y codes.
@vertex
fn vs_border(@builtin(vertex_index) i: u32) -> VsOut {
    let fb = fat_border_vertex(i, globals.mode.y, viewer());
    let k = bitcast<u32>(fb.w);
    var out: VsOut;
    out.clip = globals.view_proj * vec4<f32>(fb.xyz, 1.0);
    // Shading attributes come from the original border vertex (paper, step 6).
    out.world = fb_cur(k);
    out.actual = fb.xyz;
    out.normal = fb_normal(k);
    out.patch_id = fb_patch_id(k);
    out.color = fb_color(k);
    return out;
}

// Instanced parts (`render::resident`, instances): a shared mesh drawn once per placement.
// Each placed patch has a record (`render::resident::InstanceRecord`): the rows of its
// placement (`FbPlacement`) and x: patch id, y: packed colour (as the vertex attribute),
// z: bits of the ε the placement adds (fat borders). The instance attribute is the record's
// index.
struct PlacedRecord {
    x: vec4<f32>,
    y: vec4<f32>,
    z: vec4<f32>,
    extra: vec4<u32>,
};

@group(2) @binding(0) var<storage, read> records: array<PlacedRecord>;

@vertex
fn vs_surface_placed(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(4) record: u32,
) -> VsOut {
    let r = records[record];
    let m = FbPlacement(r.x, r.y, r.z);
    let world = fb_place(m, position);
    var out: VsOut;
    out.clip = globals.view_proj * vec4<f32>(world, 1.0);
    out.color = unpack4x8unorm(r.extra.y);
    out.world = world;
    out.actual = world;
    out.normal = fb_turn(m, normal);
    out.patch_id = r.extra.x;
    return out;
}

@vertex
fn vs_border_placed(@builtin(vertex_index) i: u32, @location(4) record: u32) -> VsOut {
    let r = records[record];
    let m = FbPlacement(r.x, r.y, r.z);
    let fb = fat_border_vertex_placed(i, globals.mode.y, viewer(), m, bitcast<f32>(r.extra.z));
    let k = bitcast<u32>(fb.w);
    var out: VsOut;
    out.clip = globals.view_proj * vec4<f32>(fb.xyz, 1.0);
    out.world = fb_place(m, fb_cur(k));
    out.actual = fb.xyz;
    out.normal = fb_turn(m, fb_normal(k));
    out.patch_id = r.extra.x;
    out.color = unpack4x8unorm(r.extra.y);
    return out;
}

// How much a fat border's lateral direction weighs against n·v when choosing the lit side
// (only surfaces within asin(CONTOUR_BIAS) ≈ 14° of grazing are affected).
const CONTOUR_BIAS: f32 = 0.25;

fn id_color(id: u32) -> vec3<f32> {
    let h = fract(f32(id) * 0.61803398875 + 0.13);
    let k = vec3<f32>(5.0, 3.0, 1.0);
    let p = abs(fract(vec3<f32>(h) + k / 6.0) * 6.0 - vec3<f32>(3.0));
    let rgb = clamp(p - vec3<f32>(1.0), vec3<f32>(0.0), vec3<f32>(1.0));
    return mix(vec3<f32>(1.0), rgb, 0.65) * 0.92;
}

// The triangle's own normal from the screen derivatives of the drawn position (zero where they
// vanish), for `section_cap_of`. Derivatives need uniform control flow: taken first thing.
fn drawn_normal(in: VsOut) -> vec3<f32> {
    return cross(dpdx(in.actual), dpdy(in.actual));
}

// The cap a kept fragment shows (`render::section`): where its outward normal faces away from
// the viewer, the viewer looks into the solid through the cut; the point and plane index of
// `section_cap`, w = −1 for no cap. A surface decides by its triangle's normal `drawn` (turned
// to the side of the interpolated outward normal), which is exact for the triangle drawn: two
// tessellations of one face agree on which of their triangles are seen from inside, also near
// grazing angles where interpolated normals differ. A fat border's triangles stand across the
// surface, so it decides by its border vertex's normal, as `fs_color` lights it.
fn section_cap_of(in: VsOut, drawn: vec3<f32>) -> vec4<f32> {
    if (globals.mode.z == 0u) {
        return vec4<f32>(in.actual, -1.0);
    }
    let h = viewer();
    let off = in.actual - in.world;
    var facing = 0.0;
    if (any(off != vec3<f32>(0.0))) {
        // As `fs_color` picks the lit side of a fat border: near a contour the fin's lateral
        // direction breaks the tie.
        let v = normalize(h.xyz - in.world * h.w);
        let side = fb_normalize_or(off - dot(off, v) * v, vec3<f32>(0.0));
        facing = dot(in.normal, v) + CONTOUR_BIAS * dot(in.normal, side);
    } else {
        var n = in.normal;
        if (dot(drawn, drawn) > 0.0) {
            n = select(drawn, -drawn, dot(drawn, in.normal) < 0.0);
        }
        facing = dot(n, h.xyz - in.actual * h.w);
    }
    if (facing >= 0.0) {
        return vec4<f32>(in.actual, -1.0);
    }
    return section_cap(in.actual);
}

// The colour of fragment `in`, or of the cap it shows (`cap`, w ≥ 0; see `section_cap_of`).
fn shade(in: VsOut, cap: vec4<f32>) -> vec4<f32> {
    let mode = globals.mode.x;
    if (mode == 1u) {
        return vec4<f32>(globals.color.rgb, 1.0);
    }
    if (mode == 2u) {
        return vec4<f32>(id_color(in.patch_id), 1.0);
    }
    // Two-sided lighting: CAD patches are not consistently oriented, so the side facing the
    // viewer is lit. A fat-border fragment is shaded as the surface it extends: with its
    // border vertex's normal and `v` from that vertex. Near a contour (n ⟂ v) the sign of n·v
    // at the border vertex is noise, and flipping there would swap the lit and the dark side
    // of the fin that sticks out of the silhouette; the surface that shows next to that fin
    // is the sheet facing the viewer, whose normal points outwards, the way the fin extends.
    // So the fin's lateral offset (zero on surfaces) breaks the tie near contours.
    let h_eye = viewer();
    var v = normalize(h_eye.xyz - in.world * h_eye.w);
    var n = normalize(in.normal);
    if (cap.w >= 0.0) {
        // A cap: flat, lit with its plane's normal (which faces the viewer: the ray entered
        // through it).
        n = globals.sections[u32(cap.w)].xyz;
        v = normalize(h_eye.xyz - cap.xyz * h_eye.w);
    } else {
        let off = in.actual - in.world;
        let side = fb_normalize_or(off - dot(off, v) * v, vec3<f32>(0.0));
        if (dot(n, v) + CONTOUR_BIAS * dot(n, side) < 0.0) {
            n = -n;
        }
    }
    let l = globals.light.xyz;
    let diffuse = max(dot(n, l), 0.0);
    let h = normalize(l + v);
    let spec = pow(max(dot(n, h), 0.0), 48.0);
    let base = select(globals.color.rgb, in.color.rgb, in.color.a > 0.5);
    let rgb = base * (0.22 + 0.78 * diffuse) + vec3<f32>(0.28 * spec);
    return vec4<f32>(min(rgb, vec3<f32>(1.0)), 1.0);
}

// Linear view-space depth (distance along the viewing axis) of `p`, for crack checks and
// --depth-out, as the bits of an f32 in an R32Uint target (32-bit float targets are not
// renderable on GL); 0 is left where nothing is drawn.
fn depth_bits(p: vec3<f32>) -> u32 {
    return bitcast<u32>(dot(p - globals.eye.xyz, globals.forward.xyz));
}

// Without section planes: no discard and no derivatives, so the depth test can run before
// the fragment shader (with them in every draw, the teapot's `bench --flythrough` on
// llvmpipe measured p50 136–159 ms a frame against 121 ms, on a loaded machine).
@fragment
fn fs_color(in: VsOut) -> @location(0) vec4<f32> {
    return shade(in, vec4<f32>(in.actual, -1.0));
}

// Patch ID + 1 per pixel (0 where nothing is drawn): which patches are visible.
@fragment
fn fs_id(in: VsOut) -> @location(0) u32 {
    return in.patch_id + 1u;
}

@fragment
fn fs_depth(in: VsOut) -> @location(0) u32 {
    return depth_bits(in.actual);
}

// With section planes (`render::section`; pipelines of their own): removed fragments
// discarded, caps shaded and at their plane's depth (the hardware depth stays the back
// face's).
@fragment
fn fs_color_cut(in: VsOut) -> @location(0) vec4<f32> {
    let drawn = drawn_normal(in);
    if (section_removes(in.actual)) {
        discard;
    }
    return shade(in, section_cap_of(in, drawn));
}

@fragment
fn fs_id_cut(in: VsOut) -> @location(0) u32 {
    if (section_removes(in.actual)) {
        discard;
    }
    return in.patch_id + 1u;
}

@fragment
fn fs_depth_cut(in: VsOut) -> @location(0) u32 {
    let drawn = drawn_normal(in);
    if (section_removes(in.actual)) {
        discard;
    }
    let cap = section_cap_of(in, drawn);
    return depth_bits(select(in.actual, cap.xyz, cap.w >= 0.0));
}

// ---- Edges of the model (issue 32): ~1 px lines along the border polylines ----
//
// The border points the fat borders are expanded from are the edges' polylines too, at the
// frame's level of detail. The segment from point s to point s + 1 is drawn when the edge
// bits of point s (the low two bits of its colour's alpha byte: 1 any edge, 2 a feature edge;
// `render::fat_border::edge_bits`) meet globals.mode.w, and s is no ring's closing point
// (whose next point opens the next ring). Vertex i of a line-list draw is end i mod 2 of
// segment i div 2; a segment not drawn is moved wholly outside the clip volume. CPU twin:
// `render::edges::segments`.
//
// Lines lie on their patch's own triangles, and a neighbour's tessellation may be up to its
// ε in front of them; each end is pulled EDGE_PULL × ε towards the viewer, along its ray (so
// it projects where it was), and is depth-tested without writing depth. Fat borders, pushed
// back by ε, stay behind the lines; a surface more than that in front of an edge hides it.

const EDGE_PULL: f32 = 2.0;
const EDGE_COLOR: vec3<f32> = vec3<f32>(0.06, 0.06, 0.07);

struct EdgeOut {
    @builtin(position) clip: vec4<f32>,
    // The unpulled world point, for the section planes (`fs_edge` discards what they remove).
    @location(0) world: vec3<f32>,
    // The patch's outward normal there (`fs_edge` hides back-facing edges of a cut model).
    @location(1) normal: vec3<f32>,
};

fn edge_drawn(s: u32) -> bool {
    let bits = fb_points[s * FB_POINT_WORDS + 9u] >> 24u;
    return (fb_info(s) & FB_INFO_CLOSING) == 0u && (bits & globals.mode.w) != 0u;
}

// World point p of a patch with error eps, pulled towards the viewer, in clip space.
fn edge_clip(p: vec3<f32>, eps: f32) -> vec4<f32> {
    let h = viewer();
    let d = fb_normalize_or(h.xyz - p * h.w, vec3<f32>(0.0, 0.0, 1.0));
    return globals.view_proj * vec4<f32>(p + EDGE_PULL * eps * d, 1.0);
}

// Outside the clip volume (right of it): a segment whose two ends are here draws nothing.
const EDGE_NOWHERE: vec4<f32> = vec4<f32>(2.0, 2.0, 2.0, 1.0);

// The end of an edge segment at world point p with outward normal n, of a patch with error
// eps; `drawn` false moves it outside the clip volume.
fn edge_end(drawn: bool, p: vec3<f32>, n: vec3<f32>, eps: f32) -> EdgeOut {
    var out: EdgeOut;
    out.clip = EDGE_NOWHERE;
    out.world = vec3<f32>(0.0, 0.0, 0.0);
    out.normal = vec3<f32>(0.0, 0.0, 0.0);
    if (drawn) {
        out.world = p;
        out.normal = n;
        out.clip = edge_clip(p, eps);
    }
    return out;
}

@vertex
fn vs_edge(@builtin(vertex_index) i: u32) -> EdgeOut {
    let s = i / 2u;
    let k = s + (i & 1u);
    return edge_end(edge_drawn(s), fb_cur(k), fb_normal(k), fb_word_f(s, 3u));
}

// As `vs_edge` for the points of a shared mesh drawn with a placement (instanced parts).
@vertex
fn vs_edge_placed(@builtin(vertex_index) i: u32, @location(4) record: u32) -> EdgeOut {
    let s = i / 2u;
    let k = s + (i & 1u);
    let r = records[record];
    let m = FbPlacement(r.x, r.y, r.z);
    let eps = fb_word_f(s, 3u) + bitcast<f32>(r.extra.z);
    return edge_end(edge_drawn(s), fb_place(m, fb_cur(k)), fb_turn(m, fb_normal(k)), eps);
}

// Cut (section planes in use), the model shows its inside, and its back faces with it, where
// the cap covers them in colour but not in hardware depth (the cap keeps its back face's own
// depth, `render::section`); an edge drawn from a patch facing away from the viewer there would
// show through the cap. Each face draws its own border, so an edge a front face shares is
// still drawn; a back-facing edge of a solid is seen only through a cut, where a cap hides it.
const EDGE_BACK_FACING: f32 = -0.02;

@fragment
fn fs_edge(in: EdgeOut) -> @location(0) vec4<f32> {
    if (section_removes(in.world)) {
        discard;
    }
    if (globals.mode.z > 0u) {
        let h = viewer();
        let v = fb_normalize_or(h.xyz - in.world * h.w, vec3<f32>(0.0, 0.0, 1.0));
        if (dot(fb_normalize_or(in.normal, v), v) < EDGE_BACK_FACING) {
            discard;
        }
    }
    return vec4<f32>(EDGE_COLOR, 1.0);
}
