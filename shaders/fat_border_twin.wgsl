// Compute twin of the fat-border vertex expansion: runs `fat_border_position` (from
// fat_border_lib.wgsl, composed before this file) on a list of inputs so tests can compare the
// GPU's positions with the Rust CPU twin.

struct TwinInput {
    prev: vec4<f32>,
    // xyz: v_i, w: ε.
    cur_eps: vec4<f32>,
    next: vec4<f32>,
    // The viewer, homogeneous: (eye, 1) or (-forward, 0).
    viewer: vec4<f32>,
    // x: slot code (slot | FB_STRAIGHT).
    code: vec4<u32>,
};

@group(0) @binding(0) var<storage, read> inputs: array<TwinInput>;
@group(0) @binding(1) var<storage, read_write> outputs: array<vec4<f32>>;

@compute @workgroup_size(64)
fn cs_expand(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= arrayLength(&inputs)) {
        return;
    }
    let q = inputs[i];
    let p = fat_border_position(q.prev.xyz, q.cur_eps.xyz, q.next.xyz, q.viewer, q.cur_eps.w, q.code.x);
    outputs[i] = vec4<f32>(p, 1.0);
}

// Compute twin of the vertex pulling: output i = vertex i over the border points (fb_points,
// group 1) for a template of `pull.len_count.x` codes.
struct Pull {
    // The viewer, homogeneous: (eye, 1) or (-forward, 0).
    viewer: vec4<f32>,
    // x: template codes, y: vertices.
    len_count: vec4<u32>,
};

@group(0) @binding(2) var<uniform> pull: Pull;

@compute @workgroup_size(64)
fn cs_pull(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= pull.len_count.y) {
        return;
    }
    outputs[i] = fat_border_vertex(i, pull.len_count.x, pull.viewer);
}

// Compute twin of the placed vertex pulling (instanced parts): as `cs_pull`, the points moved
// by the placement `placed` (rows of its 3 × 4 matrix; eps_added.x: ε it adds) first.
struct PullPlaced {
    x: vec4<f32>,
    y: vec4<f32>,
    z: vec4<f32>,
    eps_added: vec4<f32>,
};

@group(0) @binding(3) var<uniform> placed: PullPlaced;

@compute @workgroup_size(64)
fn cs_pull_placed(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= pull.len_count.y) {
        return;
    }
    let m = FbPlacement(placed.x, placed.y, placed.z);
    outputs[i] = fat_border_vertex_placed(i, pull.len_count.x, pull.viewer, m, placed.eps_added.x);
}
