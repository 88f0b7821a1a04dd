// Copies a rendered frame (read back from the offscreen renderer and uploaded as a texture of
// the window's size) onto the window's surface: one triangle covering the viewport, one texel
// per pixel. The texture is sRGB when the surface is, so the copy is exact either way.

@group(0) @binding(0) var frame: texture_2d<f32>;

@vertex
fn vs_present(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // (-1,-1), (3,-1), (-1,3): covers the viewport.
    let x = f32(i32(i & 1u) * 4 - 1);
    let y = f32(i32(i >> 1u) * 4 - 1);
    return vec4<f32>(x, y, 0.0, 1.0);
}

@fragment
fn fs_present(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<i32>(textureDimensions(frame));
    let p = clamp(vec2<i32>(pos.xy), vec2<i32>(0), size - vec2<i32>(1));
    return textureLoad(frame, p, 0);
}
